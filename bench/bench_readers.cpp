// Reader scaling in the number of joints (issue 13): BVH texts of 20,000, 100,000 and 1,000,000
// sibling joints (one End Site each, three channels, a few frames) written to a temporary folder,
// each parsed through kg::io::read_bvh, best of a few runs. Beside the parse, the file's size and
// the time to read it into memory: a reader linear in joints parses in a small multiple of that.
// The parse time is read_bvh's whole call: reading the file (the read column's
// kg::read_input_file), the hierarchy into a Skeleton (with its checks and name index) and the
// frames into the motion matrix (degrees to radians); no import conversions (units, up axis:
// import_bvh's apply_import_options) and no kinematics. The target: 1,000,000 joints in at most
// kTargetSeconds, about the time of reading the file.
//
//   bench_readers [joints ...]     (default: 20000 100000 1000000)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <unistd.h>

#include "bench_timing.hpp"
#include "kg/base/atomic_file.hpp"
#include "kg/io/bvh.hpp"

namespace {

using kg::bench::best_seconds;
namespace fs = std::filesystem;

constexpr int kFrames = 3;
constexpr int kTargetJoints = 1000000;
constexpr double kTargetSeconds = 2.0;

// A root with `joints` - 1 sibling children, each with three rotation channels and an End Site.
std::string sibling_bvh(int joints) {
  std::string s;
  s.reserve(static_cast<std::size_t>(joints) * 150);
  s += "HIERARCHY\nROOT root\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n";
  for (int j = 1; j < joints; ++j) {
    s += "  JOINT j" + std::to_string(j) + "\n  {\n    OFFSET 1 0 0\n";
    s += "    CHANNELS 3 Zrotation Xrotation Yrotation\n";
    s += "    End Site\n    {\n      OFFSET 0 1 0\n    }\n  }\n";
  }
  s += "}\nMOTION\nFrames: " + std::to_string(kFrames) + "\nFrame Time: 0.033333\n";
  for (int f = 0; f < kFrames; ++f) {
    const std::string value = std::to_string(f) + ".5";
    for (int c = 0; c < 3 * joints; ++c) {
      s += c == 0 ? "" : " ";
      s += value;
    }
    s += '\n';
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> sizes;
  for (int i = 1; i < argc; ++i) sizes.push_back(std::atoi(argv[i]));
  if (sizes.empty()) sizes = {20000, 100000, 1000000};

  const fs::path dir = fs::temp_directory_path() / ("kg_bench_readers_" + std::to_string(::getpid()));
  fs::create_directories(dir);

  std::printf("BVH reader, sibling joints (one End Site each, 3 channels, %d frames); best of runs\n",
              kFrames);
  std::printf(
      "parse s: kg::io::read_bvh, which reads the file (read s) and parses it into a Skeleton and\n"
      "frames; no import conversions, no kinematics. Target: %d joints parsed in <= %.1f s\n",
      kTargetJoints, kTargetSeconds);
  // parse cpu s: the least process CPU time (std::clock) of the parses, steadier than wall time
  // on a machine shared with other work.
  std::printf("%10s %10s %10s %10s %12s %10s %12s\n", "joints", "MB", "read s", "parse s", "parse cpu s",
              "parse/read", "us/joint");
  for (int joints : sizes) {
    if (joints < 1) continue;
    const fs::path file = dir / ("siblings_" + std::to_string(joints) + ".bvh");
    {
      std::ofstream out(file, std::ios::binary);
      out << sibling_bvh(joints);
    }
    const double mb = static_cast<double>(fs::file_size(file)) / 1e6;
    const int runs = joints >= 1000000 ? 2 : 3;
    std::size_t bytes = 0;
    const double read_s = best_seconds(runs, [&] { bytes += kg::read_input_file(file, "BVH file").size(); });
    // The previous run's clip is freed before the clock starts: freeing is not parsing.
    int parsed = 0;
    kg::io::BvhClip clip;
    double parse_s = std::numeric_limits<double>::infinity();
    double parse_cpu_s = std::numeric_limits<double>::infinity();
    for (int r = 0; r < runs; ++r) {
      clip = kg::io::BvhClip{};
      const std::clock_t cpu0 = std::clock();
      parse_s = std::min(parse_s, best_seconds(1, [&] { clip = kg::io::read_bvh(file); }));
      parse_cpu_s = std::min(parse_cpu_s, static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC);
      parsed = clip.motion.skeleton->joint_count();
    }
    clip = kg::io::BvhClip{};
    if (parsed != joints || bytes == 0) {
      std::fprintf(stderr, "bench_readers: parsed %d joints of %d\n", parsed, joints);
      return 1;
    }
    std::printf("%10d %10.1f %10.4f %10.4f %12.4f %10.1f %12.3f%s\n", joints, mb, read_s, parse_s,
                parse_cpu_s, parse_s / read_s, 1e6 * parse_s / joints,
                joints != kTargetJoints     ? ""
                : parse_s <= kTargetSeconds ? "  (target met)"
                                            : "  (target missed)");
    std::fflush(stdout);
    fs::remove(file);
  }
  fs::remove_all(dir);
  return 0;
}
