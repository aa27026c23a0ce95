// Figures of `kinegraph batch` (issue 5), printed:
//   walks     graphs/retarget.yaml over every walk and run in ../shared/data, BVH and ASF/AMC
//             (one batch of 14 clips; the CMU clips come in both): clips per second at 1 and
//             2 workers, and the parallel efficiency at 2 (rate at 2 / twice the rate at 1); the
//             median of 5 runs of each, the runs of 1 and 2 workers interleaved so that a change
//             in the machine's load touches both alike.
//   overhead  graphs/convert.yaml over 1,000 one-joint, two-frame BVH files: the batch's own cost
//             per item (forking, graph loading, hashing, manifest, scheduling), i.e. its wall time
//             less the graphs' own run times (the manifest's graph_seconds), at 1 worker.
// Usage: bench_batch [walks|overhead]... (default: both). Runs build/bin/kinegraph beside this
// program; the batches write under a temporary folder, removed at the end.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "kg/graph/manifest.hpp"

namespace {

namespace fs = std::filesystem;

const fs::path kData = KG_DATA_DIR;
const fs::path kSource = KG_SOURCE_DIR;

fs::path kinegraph() {
  return fs::read_symlink("/proc/self/exe").parent_path() / "kinegraph";
}

std::string quoted(const std::string& word) {
  return "'" + word + "'";
}

// Wall seconds of one batch; its manifest's records in `records`.
double run_batch(const fs::path& graph, const fs::path& list, const fs::path& out, int jobs,
                 std::vector<kg::graph::ManifestRecord>& records, const std::string& extra = "") {
  const std::string command = quoted(kinegraph().string()) + " batch " + quoted(graph.string()) +
                              " --input-list " + quoted(list.string()) + " --out " + quoted(out.string()) +
                              " --jobs " + std::to_string(jobs) + " --force " + extra + " > /dev/null 2> " +
                              quoted((out.string() + ".stderr"));
  const auto start = std::chrono::steady_clock::now();
  const int status = std::system(command.c_str());
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (status != 0)
    std::cerr << "  (batch exited with status " << status << "; see " << out.string() << ".stderr)\n";
  std::vector<std::string> problems;
  records = kg::graph::read_manifest(out / "manifest.jsonl", problems);
  return wall;
}

fs::path write_list(const fs::path& file, const std::vector<fs::path>& inputs) {
  std::ofstream os(file);
  for (const fs::path& input : inputs) os << input.string() << '\n';
  return file;
}

void walks(const fs::path& temp) {
  const std::vector<fs::path> batch = {kData / "cmu/bvh_daz/02_01.bvh",
                                       kData / "cmu/bvh_daz/02_03.bvh",
                                       kData / "cmu/bvh_daz/07_05.bvh",
                                       kData / "cmu/bvh_daz/09_06.bvh",
                                       kData / "cmu/bvh_motionbuilder/16_15.bvh",
                                       kData / "cmu/bvh_iclone_cc_rig/002_03.bvh",
                                       kData / "cmu/bvh_iclone_cc_rig/007_05.bvh",
                                       kData / "other_skeletons/games105/walk60.bvh",
                                       kData / "other_skeletons/games105/run_forward.bvh",
                                       kData / "other_skeletons/bandai_namco/dataset-1_run_normal_001.bvh",
                                       kData / "other_skeletons/bandai_namco/dataset-1_dash_normal_001.bvh",
                                       kData / "cmu/asf_amc/07_05.amc",
                                       kData / "cmu/asf_amc/09_06.amc",
                                       kData / "cmu/asf_amc/16_15.amc"};
  for (const fs::path& clip : batch) {
    if (!fs::exists(clip)) {
      std::cout << "walks: skipped: " << clip.string() << " is absent\n";
      return;
    }
  }
  const fs::path list = write_list(temp / "walks.txt", batch);
  const fs::path graph = kSource / "graphs" / "retarget.yaml";
  std::cout << "walks: graphs/retarget.yaml over every walk and run in ../shared/data\n";
  constexpr int kRuns = 5;
  std::vector<double> walls[3];
  std::size_t clips = 0, failed[3] = {0, 0, 0};
  for (int run = 0; run < kRuns; ++run) {
    for (int jobs : {1, 2}) {
      std::vector<kg::graph::ManifestRecord> records;
      walls[jobs].push_back(run_batch(graph, list, temp / ("walks_j" + std::to_string(jobs)), jobs, records));
      clips = records.size();
      for (const auto& r : records) failed[jobs] += !r.ok();
    }
  }
  double rate[3] = {0, 0, 0};
  for (int jobs : {1, 2}) {
    std::sort(walls[jobs].begin(), walls[jobs].end());
    const double wall = walls[jobs][kRuns / 2];
    rate[jobs] = clips / wall;
    std::printf(
        "  %d worker(s): %zu clips (%zu failed over %d runs), median %.2f s (%.2f to %.2f): %.2f clips/s\n",
        jobs, clips, failed[jobs], kRuns, wall, walls[jobs].front(), walls[jobs].back(), rate[jobs]);
  }
  std::printf("  parallel efficiency at 2 workers: %.0f%% (target >= 85%%)\n", 100 * rate[2] / (2 * rate[1]));
}

void overhead(const fs::path& temp) {
  constexpr int kItems = 1000;
  const fs::path inputs = temp / "tiny";
  fs::create_directories(inputs);
  std::vector<fs::path> files;
  for (int i = 0; i < kItems; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "tiny%04d.bvh", i);
    files.push_back(inputs / name);
    std::ofstream(files.back())
        << "HIERARCHY\nROOT hip\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition "
           "Zposition Zrotation Xrotation Yrotation\n  End Site\n  {\n    OFFSET 0 10 0\n  }\n}\n"
           "MOTION\nFrames: 2\nFrame Time: 0.0333333\n"
        << i << " 90 0 0 0 0\n"
        << i << " 91 0 0 0 5\n";
  }
  const fs::path list = write_list(temp / "tiny.txt", files);
  const fs::path graph = kSource / "graphs" / "convert.yaml";
  std::cout << "overhead: graphs/convert.yaml over " << kItems << " one-joint, two-frame BVH files\n";
  for (int jobs : {1, 2}) {
    std::vector<kg::graph::ManifestRecord> records;
    const double wall = run_batch(graph, list, temp / ("tiny_j" + std::to_string(jobs)), jobs, records,
                                  "--set units=cm --set up=y");
    double graph_seconds = 0, item_seconds = 0;
    std::size_t failed = 0;
    for (const auto& r : records) {
      graph_seconds += r.graph_seconds;
      item_seconds += r.wall_seconds;
      failed += !r.ok();
    }
    const double per_item_ms = 1000 * (wall * jobs - graph_seconds) / kItems;
    std::printf(
        "  %d worker(s): %zu items (%zu failed) in %.2f s; graphs' own time %.3f ms/item; batch overhead "
        "%.2f ms/item (worker-seconds less graph time; target <= 5 ms), of which inside the item's process "
        "%.2f ms\n",
        jobs, records.size(), failed, wall, 1000 * graph_seconds / kItems, per_item_ms,
        1000 * (item_seconds - graph_seconds) / kItems);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> sections(argv + 1, argv + argc);
  if (sections.empty()) sections = {"walks", "overhead"};
  const fs::path temp = fs::temp_directory_path() / ("kg_bench_batch_" + std::to_string(::getpid()));
  fs::create_directories(temp);
  for (const std::string& section : sections) {
    if (section == "walks") {
      walks(temp);
    } else if (section == "overhead") {
      overhead(temp);
    } else {
      std::cerr << "bench_batch: unknown section '" << section << "' (walks, overhead)\n";
      fs::remove_all(temp);
      return 2;
    }
  }
  fs::remove_all(temp);
  return 0;
}
