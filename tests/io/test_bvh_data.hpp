// The BVH files of ../shared/data and the facts SOURCES.md states about them, shared by the
// BVH tests. Tests read the files in place and skip with a visible WARN when they are absent.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace kg::test {

struct BvhDataFile {
  const char* path;  // under KG_DATA_DIR
  int frames;
  double frame_time;  // seconds, as the header says
  int joints;         // ROOT + JOINT
  int end_sites;
  int channels;       // per frame
  const char* units;  // what units: auto must pick
};

// SOURCES.md's tables.
inline const std::vector<BvhDataFile>& bvh_data_files() {
  static const std::vector<BvhDataFile> files = {
      {"cmu/bvh_cmu_names/16_01.bvh", 322, 0.033333, 31, 7, 96, "asf"},
      {"cmu/bvh_motionbuilder/16_15.bvh", 471, 0.00833333, 29, 7, 90, "cm"},
      {"cmu/bvh_daz/02_01.bvh", 344, 0.00833333, 43, 14, 132, "cm"},
      {"cmu/bvh_daz/02_03.bvh", 174, 0.00833333, 43, 14, 132, "cm"},
      {"cmu/bvh_daz/07_05.bvh", 518, 0.00833333, 43, 14, 132, "cm"},
      {"cmu/bvh_daz/09_06.bvh", 142, 0.00833333, 43, 14, 132, "cm"},
      {"cmu/bvh_daz/13_11.bvh", 416, 0.00833333, 43, 14, 132, "cm"},
      {"cmu/bvh_daz/13_13.bvh", 440, 0.00833333, 43, 14, 132, "cm"},
      // Daz cm x 1/128: about 1.2 units tall, so no physical unit; m is the closest guess.
      {"cmu/bvh_daz_two_person/60_10_scaled.bvh", 1197, 0.008333, 43, 14, 132, "m"},
      {"cmu/bvh_daz_two_person/61_10_scaled.bvh", 1197, 0.008333, 43, 14, 132, "m"},
      {"cmu/bvh_iclone_cc_rig/007_05.bvh", 259, 0.016667, 100, 41, 303, "cm"},
      {"cmu/bvh_iclone_cc_rig/002_06.bvh", 1118, 0.016667, 100, 41, 303, "cm"},
      {"cmu/bvh_iclone_cc_rig/002_03.bvh", 86, 0.016667, 101, 41, 306, "cm"},
      {"other_skeletons/bandai_namco/dataset-1_run_normal_001.bvh", 24, 0.0333333, 22, 5, 132, "cm"},
      {"other_skeletons/bandai_namco/dataset-1_dash_normal_001.bvh", 20, 0.0333333, 22, 5, 132, "cm"},
      {"other_skeletons/games105/walk60.bvh", 182, 0.016667, 20, 5, 63, "m"},
      {"other_skeletons/games105/run_forward.bvh", 45, 0.016667, 20, 5, 63, "m"},
  };
  return files;
}

inline std::filesystem::path data_dir() {
  return KG_DATA_DIR;
}

// The file's path, or nothing (and the caller skips) when ../shared/data lacks it.
inline std::optional<std::filesystem::path> data_file(const std::string& relative) {
  std::filesystem::path p = data_dir() / relative;
  if (!std::filesystem::exists(p)) return std::nullopt;
  return p;
}

}  // namespace kg::test
