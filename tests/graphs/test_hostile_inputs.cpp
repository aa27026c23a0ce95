// Hostile inputs found by fuzzing and by hand (issue 13), each fed as the exact file through the
// CLI as a user runs it: a message at file:line, a non-zero exit, no output file, and bounded
// memory (the CLI runs under `ulimit -v`, except in sanitizer builds, whose shadow memory needs
// more address space than any limit) and time (CTest's timeout).
#include <filesystem>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "../support/process.hpp"
#include "kg/base/error.hpp"
#include "kg/io/bvh.hpp"
#include "kg/retarget/constraint_io.hpp"
#include "kg/retime/contacts.hpp"
#include "kg/synth/synthesize.hpp"

namespace {

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using kg::test::Result;
using kg::test::show;
using kg::test::TempDir;

const fs::path kSource = KG_SOURCE_DIR;

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif
#else
constexpr bool kSanitized = false;
#endif

// The CLI with at most 2 GiB of address space (a bad_alloc, not the machine's memory, if a file
// makes it allocate without bound).
Result bounded_kinegraph(const std::vector<std::string>& args) {
  const fs::path cli = fs::path(KG_BINARY_DIR) / "bin" / "kinegraph";
  if (kSanitized) return kg::test::run_program(cli, args);
  std::vector<std::string> shell_args{"-c", "ulimit -v 2097152 && exec \"$0\" \"$@\"", cli.string()};
  shell_args.insert(shell_args.end(), args.begin(), args.end());
  return kg::test::run_program("/bin/sh", shell_args);
}

// A synthesized walk, written as BVH, and a joint of it.
struct Clip {
  fs::path bvh;
  std::string joint;
  kg::motion::Motion motion;
};

Clip walk_clip(TempDir& dir) {
  kg::synth::WalkOptions options;
  Clip clip;
  clip.motion = kg::synth::synthesize_walk(options).motion;
  clip.joint = clip.motion.skeleton->joint(1).name;
  clip.bvh = dir.write("walk.bvh", kg::io::write_bvh_string(clip.motion));
  return clip;
}

void expect_refused(const Result& r, const std::vector<std::string>& fragments, const fs::path& output) {
  INFO(show(r));
  CHECK(r.code != 0);
  CHECK(r.code < 128);  // an exit, not a signal
  for (const std::string& f : fragments) CHECK_THAT(r.err, Contains(f));
  CHECK_FALSE(fs::exists(output));
}

}  // namespace

TEST_CASE("hostile constraint files: huge ranges, offsets and times are refused at their place",
          "[graphs][hostile]") {
  TempDir dir;
  const Clip clip = walk_clip(dir);
  const std::string point = "points: [{joint: " + clip.joint + "}], params: [0, 0, 0]";
  struct Case {
    const char* name;
    std::string constraint;
    std::vector<std::string> expected;
  };
  const std::vector<Case> cases = {
      {"frames [0, 300000000]",
       "{kind: position, " + point + ", frames: [0, 300000000]}",
       {"c.yaml:3:", "frame"}},
      {"frames [0, 2147483647]",
       "{kind: position, " + point + ", frames: [0, 2147483647]}",
       {"c.yaml:3:", "frame"}},
      {"frame_offset 2147483647",
       "{kind: position, points: [{joint: " + clip.joint +
           ", frame_offset: 2147483647}], params: [0, 0, 0], frames: [0, 1]}",
       {"c.yaml:3:", "frame_offset"}},
      {"at_times 1e300", "{kind: position, " + point + ", at_times: [1e300]}", {"c.yaml:3:", "1e+300"}},
      {"a key twice",
       "{kind: position, points: [{joint: " + clip.joint +
           ", joint: nosuch}], params: [0, 0, 0], frames: [0, 1]}",
       {"c.yaml:3:", "duplicate key 'joint' in 'constraints[0].points[0]'"}},
  };
  for (const Case& c : cases) {
    SECTION(c.name) {
      const fs::path file = dir.write("c.yaml", "version: 1\nconstraints:\n  - " + c.constraint + "\n");
      const fs::path output = dir / "out.bvh";
      const Result r =
          bounded_kinegraph({"run", (kSource / "graphs" / "retarget.yaml").string(), "--set",
                             "input=" + clip.bvh.string(), "--set", "constraints=" + file.string(), "--set",
                             "output=" + output.string(), "--set", "report=" + (dir / "m.json").string()});
      expect_refused(r, c.expected, output);
    }
  }
}

TEST_CASE("hostile graph variables: defaults nesting exponentially are refused at their size",
          "[graphs][hostile]") {
  TempDir dir;
  // v0 repeats v1 sixteen times, v1 repeats v2, ... nine deep: 16^9 bytes if expanded.
  std::string graph = "version: 1\nvariables:\n";
  for (int level = 0; level < 9; ++level) {
    std::string value;
    for (int k = 0; k < 16; ++k) value += "${v" + std::to_string(level + 1) + "}";
    graph += "  v" + std::to_string(level) + ": {default: \"" + value + "\"}\n";
  }
  graph += "  v9: {default: \"ha\"}\nnodes:\n  a: {type: io.import_motion, params: {path: \"${v0}\"}}\n";
  const fs::path file = dir.write("laughs.yaml", graph);
  const Result r = bounded_kinegraph({"validate", file.string()});
  INFO(show(r));
  CHECK(r.code == 3);
  CHECK_THAT(r.err, Contains("laughs.yaml:"));
  CHECK_THAT(r.err, Contains("bytes (the limit of a text after ${...} expansion)"));
  CHECK(r.err.size() < 2000);
}

TEST_CASE("hostile graph: an alias inside the map it names is refused at its anchor, not a stack overflow",
          "[graphs][hostile]") {
  // Found by fuzz_graph: yaml-cpp builds `params: &p {factor: *p}` as a map containing itself.
  const fs::path file = kSource / "tests/fuzz/regressions/graph/alias_inside_its_own_map.yaml";
  for (const char* verb : {"validate", "run"}) {
    const Result r = bounded_kinegraph({verb, file.string()});
    INFO(show(r));
    CHECK(r.code == 3);
    CHECK_THAT(r.err, Contains("alias_inside_its_own_map.yaml:5:13: an alias in 'nodes.scale.params.factor' "
                               "names a collection that contains it"));
  }
}

TEST_CASE("hostile path params: a path longer than the system's, or holding a NUL, is refused at its place",
          "[graphs][hostile]") {
  TempDir dir;
  // Found by fuzz_graph: variables expanding to a 676,000-byte path, under the expansion limit,
  // which the motion reader's message quoted whole.
  const fs::path fuzzed = kSource / "tests/fuzz/regressions/graph/path_of_676000_bytes.yaml";
  Result r = bounded_kinegraph({"validate", fuzzed.string()});
  INFO(show(r));
  CHECK(r.code == 3);
  CHECK_THAT(r.err, Contains("path_of_676000_bytes.yaml:10:"));
  CHECK_THAT(r.err, Contains("... (675840 bytes), longer than the system's longest (4095 bytes)"));
  CHECK(r.err.size() < 1000);

  // One byte under the limit is a path: refused for what it names (no reader claims it), the
  // message quoting it cut.
  const std::string longest(4095, 'x');
  const fs::path graph =
      dir.write("long_path.yaml",
                "version: 1\nnodes:\n  a: {type: io.import_motion, params: {path: " + longest + "}}\n");
  r = bounded_kinegraph({"validate", graph.string()});
  INFO(show(r));
  CHECK(r.code == 3);
  CHECK_THAT(r.err, Contains("long_path.yaml:3:"));
  CHECK_THAT(r.err, Contains("... (4095 bytes): no motion reader claims a file without an extension"));
  CHECK(r.err.size() < 1000);

  // "walk.bvh\0.amc": the system would open walk.bvh while the reader was chosen for .amc.
  const fs::path nul =
      dir.write("nul_path.yaml",
                "version: 1\nnodes:\n  a: {type: io.import_motion, params: {path: \"walk.bvh\\0.amc\"}}\n");
  r = bounded_kinegraph({"validate", nul.string()});
  INFO(show(r));
  CHECK(r.code == 3);
  CHECK_THAT(r.err, Contains("nul_path.yaml:3:"));
  CHECK_THAT(r.err, Contains("'walk.bvh\\x00.amc', which holds a NUL byte"));
}

TEST_CASE("hostile clip files: encodings, absurd numbers and frame times at their place",
          "[graphs][hostile]") {
  TempDir dir;
  const fs::path output = dir / "out.bvh";
  const fs::path convert = kSource / "graphs" / "convert.yaml";
  const auto run = [&](const fs::path& input, const std::vector<std::string>& more = {}) {
    std::vector<std::string> args{"run",   convert.string(),           "--set", "input=" + input.string(),
                                  "--set", "output=" + output.string()};
    args.insert(args.end(), more.begin(), more.end());
    return bounded_kinegraph(args);
  };

  SECTION("a UTF-16 BVH") {
    const std::string text("\xff\xfeH\0I\0E\0R\0A\0R\0C\0H\0Y\0\n\0", 22);
    const Result r = run(dir.write("u16.bvh", text));
    expect_refused(
        r, {"u16.bvh:1:1: BVH file is UTF-16 (little-endian) text", "mark '\\xff\\xfe')", "save it as UTF-8"},
        output);
    CHECK(r.err.find('\xff') == std::string::npos);  // bytes are escaped, never printed raw
  }
  SECTION("Frame Time: 1e-310") {
    const std::string bvh =
        "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Xposition Yposition Zposition\n"
        "  End Site\n  {\n    OFFSET 0 1 0\n  }\n}\nMOTION\nFrames: 1\nFrame Time: 1e-310\n0 0 0\n";
    expect_refused(run(dir.write("tiny.bvh", bvh)), {"tiny.bvh:13:"}, output);
  }
  SECTION("an ASF bone of direction 1e200 and length 1e200") {
    const std::string asf =
        ":version 1.10\n:name x\n:units\n  mass 1.0\n  length 0.45\n  angle deg\n:root\n"
        "  order TX TY TZ RX RY RZ\n  axis XYZ\n  position 0 0 0\n  orientation 0 0 0\n:bonedata\n"
        "  begin\n    id 1\n    name ltibia\n    direction 1e200 0 0\n    length 1e200\n    axis 0 0 0 XYZ\n"
        "    dof rx\n  end\n:hierarchy\n  begin\n    root ltibia\n  end\n";
    const fs::path skeleton = dir.write("x.asf", asf);
    const fs::path amc = dir.write("x.amc", ":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 0 0 0 0 0\nltibia 0\n");
    const Result r = run(amc, {"--set", "skeleton=" + skeleton.string()});
    expect_refused(r, {"x.asf:17:", "finite", "1e+200"}, output);
    CHECK(r.err.size() < 2000);
  }
}

TEST_CASE("every YAML reader refuses a key given twice (one shared check)", "[graphs][hostile]") {
  TempDir dir;
  const Clip clip = walk_clip(dir);
  const std::vector<kg::motion::Motion> characters{clip.motion};
  CHECK_THROWS_WITH(kg::retarget::read_constraints_string(
                        "version: 1\nconstraints:\n  - {kind: position, points: [{joint: " + clip.joint +
                            ", joint: nosuch}], params: [0, 0, 0], frames: [0, 1]}\n",
                        "c.yaml", characters),
                    Contains("c.yaml:3:") && Contains("duplicate key 'joint'"));
  const std::string patch = "  - {joint: " + clip.joint + ", vertices: [[0, 0, 0]], frames: [0, 1]}\n";
  CHECK_THROWS_WITH(kg::retime::read_contacts_string("version: 1\npatches:\n" + patch + "patches:\n" + patch,
                                                     "k.yaml", clip.motion),
                    Contains("k.yaml:4:1: duplicate key 'patches' at the top level (first at k.yaml:2:1)"));
  CHECK_THROWS_WITH(kg::retime::read_contacts_string("version: 1\npatches:\n  - {joint: " + clip.joint +
                                                         ", joint: " + clip.joint +
                                                         ", vertices: [[0, 0, 0]], frames: [0, 1]}\n",
                                                     "k.yaml", clip.motion),
                    Contains("k.yaml:3:") && Contains("duplicate key 'joint' in 'patches[0]'"));
}

TEST_CASE("contact times far outside the clip are refused, not wrapped to frames", "[graphs][hostile]") {
  TempDir dir;
  const Clip clip = walk_clip(dir);
  for (const char* times : {"[35791394.2, 35791394.3]", "[1e300, 1e300]", "[3000.0, 3000.1]"}) {
    INFO(times);
    CHECK_THROWS_WITH(kg::retime::read_contacts_string("version: 1\npatches:\n  - {joint: " + clip.joint +
                                                           ", vertices: [[0, 0, 0]], times: " + times + "}\n",
                                                       "k.yaml", clip.motion),
                      Contains("k.yaml:3:"));
  }
}
