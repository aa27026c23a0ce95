// Import speed, one thread, best of several runs.
// BVH: parse + units/axes + forward kinematics of every joint in every frame, against Blender
// 3.4's BVH importer on the same files timed in the same run (a `blender -b` subprocess timing
// only bpy.ops.import_anim.bvh with perf_counter).
// ASF/AMC: parsing an AMC already in memory against its ASF, and that parse plus forward
// kinematics of every joint in every frame, for two CMU takes of ../shared/data.
//
//   bench_import [file.bvh ...]     (default BVH files: three clips of ../shared/data)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "bench_timing.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/io/bvh.hpp"
#include "kg/motion/kinematics.hpp"

namespace {

using kg::bench::best_seconds;
namespace fs = std::filesystem;

// Forward kinematics of every frame; returns a sum of positions so the work cannot be elided.
double all_fk(const kg::motion::Motion& m, std::vector<Eigen::Isometry3d>& world) {
  double sum = 0;
  for (int f = 0; f < m.frame_count(); ++f) {
    kg::motion::forward_kinematics(*m.skeleton, m.values.row(f), world);
    for (const auto& w : world) sum += w.translation().sum();
  }
  return sum;
}

// Blender's importer on each file, best of `runs` in one Blender process; seconds per file,
// empty when blender is missing or failed.
std::map<std::string, double> blender_seconds(const std::vector<fs::path>& files, int runs) {
  if (std::system("command -v blender >/dev/null 2>&1") != 0) return {};
  std::string files_py;
  for (const auto& f : files) files_py += "r\"" + f.string() + "\",";
  // Debian's Blender 3.4 (Python 3.11) refuses the importer's open(..., "rU"): drop the "U".
  const std::string expr =
      "import builtins, time, bpy\n"
      "_open = builtins.open\n"
      "def _o(file, mode=\"r\", *a, **k):\n"
      "    return _open(file, mode.replace(\"U\", \"\") or \"r\", *a, **k)\n"
      "builtins.open = _o\n"
      "for path in [" +
      files_py +
      "]:\n"
      "    best = float(\"inf\")\n"
      "    for run in range(" +
      std::to_string(runs) +
      "):\n"
      "        for o in list(bpy.data.objects): bpy.data.objects.remove(o, do_unlink=True)\n"
      "        for a in list(bpy.data.actions): bpy.data.actions.remove(a)\n"
      "        for a in list(bpy.data.armatures): bpy.data.armatures.remove(a)\n"
      "        t0 = time.perf_counter()\n"
      "        bpy.ops.import_anim.bvh(filepath=path)\n"
      "        best = min(best, time.perf_counter() - t0)\n"
      "    print(\"KG_BLENDER_SECONDS\", best, path, flush=True)\n";
  const std::string command =
      "blender -b --factory-startup --python-exit-code 1 --python-expr '" + expr + "' 2>&1";
  std::map<std::string, double> out;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return out;
  char line[4096];
  while (std::fgets(line, sizeof line, pipe)) {
    double seconds = 0;
    char path[4000];
    if (std::sscanf(line, "KG_BLENDER_SECONDS %lf %3999[^\n]", &seconds, path) == 2) out[path] = seconds;
  }
  pclose(pipe);
  return out;
}

// The BVH table: read, import, FK and the whole path per file, and Blender's importer beside it.
void bench_bvh(const std::vector<fs::path>& files, int runs) {
  std::printf("BVH import, one thread, best of %d runs (Blender: best of 3)\n", runs);
  std::printf("%-22s %6s %6s %7s | %9s %9s %9s %10s | %9s %8s\n", "file", "frames", "joints", "MB", "read ms",
              "import ms", "FK ms", "FK Mjnt/s", "Blender s", "ratio");

  struct Row {
    fs::path path;
    double read, import, fk, total;
    int frames, joints;
  };
  std::vector<Row> rows;
  double sink = 0;
  for (const fs::path& path : files) {
    Row r{path, 0, 0, 0, 0, 0, 0};
    kg::io::ImportedMotion in = kg::io::import_bvh(path, {});
    r.frames = in.motion.frame_count();
    r.joints = in.motion.skeleton->joint_count();
    std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(r.joints));
    r.read = best_seconds(runs, [&] { sink += kg::io::read_bvh(path).motion.values(0, 0); });
    r.import = best_seconds(runs, [&] { sink += kg::io::import_bvh(path, {}).motion.values(0, 0); });
    r.fk = best_seconds(runs, [&] { sink += all_fk(in.motion, world); });
    // What the ratio uses: the whole path from file to every joint's world transform.
    r.total = best_seconds(runs, [&] {
      kg::io::ImportedMotion x = kg::io::import_bvh(path, {});
      sink += all_fk(x.motion, world);
    });
    rows.push_back(r);
  }
  const std::map<std::string, double> blender = blender_seconds(files, 3);
  for (const Row& r : rows) {
    const double mb = static_cast<double>(fs::file_size(r.path)) / 1e6;
    const double jps = static_cast<double>(r.frames) * r.joints / r.fk / 1e6;
    std::printf("%-22s %6d %6d %7.2f | %9.3f %9.3f %9.3f %10.1f |", r.path.filename().c_str(), r.frames,
                r.joints, mb, r.read * 1e3, r.import * 1e3, r.fk * 1e3, jps);
    auto it = blender.find(r.path.string());
    if (it != blender.end())
      std::printf(" %9.3f %7.0fx\n", it->second, it->second / r.total);
    else
      std::printf(" %9s %8s\n", "-", "-");
    std::printf("%-22s parse + units + FK of every joint in every frame: %.3f ms\n", "", r.total * 1e3);
  }
  if (blender.empty())
    std::printf("Blender: skipped (blender not installed or its import failed; apt-get install blender)\n");
  std::printf("(checksum %g)\n", sink);
}

// The AMC takes timed, with their skeletons (under KG_DATA_DIR/cmu/asf_amc).
void bench_asf_amc(int runs) {
  const fs::path dir = fs::path(KG_DATA_DIR) / "cmu" / "asf_amc";
  std::printf("\nASF/AMC import, one thread, best of %d runs (the AMC text already in memory)\n", runs);
  std::printf("%-22s %6s %6s %7s | %9s %9s %12s\n", "file", "frames", "joints", "MB", "parse ms", "MB/s",
              "parse+FK ms");
  double sink = 0;
  for (const auto& [asf_name, amc_name] :
       {std::pair{"16.asf", "16_15.amc"}, std::pair{"09.asf", "09_06.amc"}}) {
    const fs::path asf_path = dir / asf_name, amc_path = dir / amc_name;
    if (!fs::exists(asf_path) || !fs::exists(amc_path)) {
      std::printf("%-22s skipped: %s or %s not found under %s\n", amc_name, asf_name, amc_name, dir.c_str());
      continue;
    }
    const kg::io::AsfSkeleton asf = kg::io::read_asf(asf_path.string());
    std::ifstream in(amc_path, std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const kg::motion::Motion m = kg::io::parse_amc(text, amc_name, asf);
    std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(m.skeleton->joint_count()));
    const double parse =
        best_seconds(runs, [&] { sink += kg::io::parse_amc(text, amc_name, asf).values(0, 0); });
    const double parse_fk =
        best_seconds(runs, [&] { sink += all_fk(kg::io::parse_amc(text, amc_name, asf), world); });
    const double mb = static_cast<double>(text.size()) / 1e6;
    std::printf("%-22s %6d %6d %7.2f | %9.3f %9.1f %12.3f\n", amc_name, m.frame_count(),
                m.skeleton->joint_count(), mb, parse * 1e3, mb / parse, parse_fk * 1e3);
  }
  std::printf("(checksum %g)\n", sink);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<fs::path> files;
  for (int i = 1; i < argc; ++i) files.emplace_back(argv[i]);
  if (files.empty()) {
    const fs::path data = KG_DATA_DIR;
    for (const char* rel : {"cmu/bvh_daz_two_person/60_10_scaled.bvh", "cmu/bvh_iclone_cc_rig/002_06.bvh",
                            "cmu/bvh_daz/07_05.bvh"})
      if (fs::exists(data / rel)) files.push_back(fs::weakly_canonical(data / rel));
    if (files.empty()) {
      std::cout << "skipped: no BVH file of ../shared/data found under " << data
                << "; pass files as arguments\n";
    }
  }
  const int runs = 15;
  if (!files.empty()) bench_bvh(files, runs);
  bench_asf_amc(runs);
  return 0;
}
