// Writes the seed corpora of the fuzz harnesses: fuzz_seeds SOURCE_DIR OUT_DIR makes
// OUT_DIR/<harness>/<seed> for each harness of tests/fuzz. Seeds come from what the project and
// its tests contain, never from ../shared/data: synthesized clips written as BVH (and made-over
// as exporters write them: CRLF, tabs, a BOM, lower-case keywords, no frames), the tiny ASF/AMC
// pair of the io tests, every graph of graphs/ and of the tests' data, the target and constraint
// files of graphs/, and contact, constraint, target and body files in every form their headers
// document, on the synthesized figure's joints.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "../io/test_asf_amc_data.hpp"
#include "kg/io/bvh.hpp"
#include "kg/motion/motion.hpp"
#include "kg/synth/synthesize.hpp"

namespace fs = std::filesystem;

namespace {

fs::path out_dir;
int written = 0;

void seed(const std::string& harness, const std::string& name, const std::string& text) {
  const fs::path dir = out_dir / harness;
  fs::create_directories(dir);
  std::ofstream(dir / name, std::ios::binary) << text;
  ++written;
}

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A graph file without its prose: comment lines dropped, every `doc:` cut to one letter (a block
// scalar with its indented lines, a quoted flow value, a plain value ending its line). The prose
// is most of a graph's bytes, read by yaml-cpp and only checked to be text by us; without it the
// harness fuzzes the structure (nodes, params, variables, connections) about twice as fast, and
// the longest seed, which sets fuzz.sh's longest input, is half as long.
std::string without_prose(const std::string& text) {
  static const std::regex comment_line(R"(^\s*#.*$)");
  static const std::regex block_doc(R"(^(\s*)doc:\s*[>|][-+]?\s*$)");
  static const std::regex plain_doc(R"(^(\s*)doc:\s+[^"'{\[\s].*$)");
  static const std::regex quoted_doc(R"(doc:\s*"(?:[^"\\]|\\.)*")");
  std::istringstream in(text);
  std::string out;
  std::string line;
  std::size_t block_indent = std::string::npos;  // inside a block doc indented deeper than this
  while (std::getline(in, line)) {
    const std::size_t indent = line.find_first_not_of(' ');
    if (block_indent != std::string::npos) {
      if (indent == std::string::npos || indent > block_indent) continue;
      block_indent = std::string::npos;
    }
    std::smatch m;
    if (std::regex_match(line, comment_line)) continue;
    if (std::regex_match(line, m, block_doc)) {
      block_indent = static_cast<std::size_t>(m[1].length());
      out += m[1].str() + "doc: d\n";
    } else if (std::regex_match(line, m, plain_doc)) {
      out += m[1].str() + "doc: d\n";
    } else {
      out += std::regex_replace(line, quoted_doc, "doc: \"d\"") + "\n";
    }
  }
  return out;
}

// Files of `dir` (recursively) with extension `ext`, sorted, as seeds named after their path;
// graph files (harness "graph") without their prose.
void seed_files(const std::string& harness, const fs::path& root, const fs::path& dir,
                const std::string& ext) {
  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(root / dir))
    if (e.is_regular_file() && e.path().extension() == ext) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  for (const fs::path& f : files) {
    std::string name = fs::relative(f, root).string();
    std::replace(name.begin(), name.end(), '/', '_');
    seed(harness, name, harness == "graph" ? without_prose(read(f)) : read(f));
  }
}

std::string replaced_all(std::string text, const std::string& from, const std::string& to) {
  for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  return text;
}

void bvh_seeds(const kg::motion::Motion& walk) {
  const kg::motion::Motion jump = kg::synth::synthesize_jump({.fps = 30}).motion;
  const kg::motion::Motion climb = kg::synth::synthesize_climb({.rungs = 2, .fps = 30}).motion;
  const kg::motion::Motion short_walk = kg::motion::frame_range(walk, 0, 2);
  const std::string text = kg::io::write_bvh_string(short_walk);
  seed("bvh", "walk_3_frames.bvh", text);
  seed("bvh", "walk.bvh", kg::io::write_bvh_string(walk, {.precision = 3}));
  seed("bvh", "jump_cm.bvh", kg::io::write_bvh_string(kg::motion::frame_range(jump, 0, 4), {.units = "cm"}));
  seed("bvh", "climb.bvh", kg::io::write_bvh_string(kg::motion::frame_range(climb, 0, 4), {.precision = 4}));
  seed("bvh", "crlf.bvh", replaced_all(text, "\n", "\r\n"));
  seed("bvh", "tabs.bvh", replaced_all(text, "  ", "\t"));
  seed("bvh", "bom.bvh", "\xEF\xBB\xBF" + text);
  seed("bvh", "lower_case.bvh",
       replaced_all(replaced_all(replaced_all(text, "JOINT", "joint"), "End Site", "end site"), "OFFSET",
                    "offset"));
  seed("bvh", "no_frames.bvh", text.substr(0, text.find("Frames:")) + "Frames: 0\nFrame Time: 0.0333333\n");
  seed("bvh", "two_roots.bvh",
       "HIERARCHY\nROOT a\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation "
       "Yrotation\n  End Site\n  {\n    OFFSET 0 1 0\n  }\n}\nROOT b\n{\n  OFFSET 1 0 0\n  CHANNELS 3 "
       "Xposition Zposition Yposition\n  JOINT c\n  {\n    OFFSET 0 2 0\n    CHANNELS 2 Xrotation Xposition\n"
       "    End Site\n    {\n      OFFSET 0 0 1\n    }\n  }\n}\nMOTION\nFrames: 2\nFrame Time: .008333\n"
       "1 2 3 4 5 6 7 8 9 10 11\n-1 -2 -3 -4 -5 -6 -7 -8 -9 -10 -11\n");
}

void asf_amc_seeds() {
  const std::string& asf = kg::test::kTinyAsf;
  const std::string& amc = kg::test::kTinyAmc;
  seed("asf", "tiny.asf", asf);
  seed("asf", "tiny_crlf.asf", replaced_all(asf, "\n", "\r\n"));
  seed("asf", "tiny_radians.asf", replaced_all(asf, "angle deg", "angle rad"));
  seed("asf", "tiny_translating.asf",
       replaced_all(asf, "dof rx\n    limits (-10.0 170.0)\n",
                    "dof rx tx ty tz\n    limits (-10.0 170.0)\n"
                    "           (-inf inf)\n (-1 1)\n (-1 1)\n"));
  seed("amc", "tiny.amc", amc);
  seed("amc", "tiny_crlf.amc", replaced_all(amc, "\n", "\r\n"));
  seed("amc", "tiny_radians.amc", replaced_all(amc, ":DEGREES", ":RADIANS"));
  seed("amc", "tiny_one_frame.amc",
       ":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 17 0 0 0 0\nlfemur 10 0 0\nltibia 20\n");
}

// Files about the synthesized walk (kg::fuzz::walk(): two steps at 30 fps).
void clip_file_seeds(const kg::motion::Motion& walk) {
  const int last = walk.frame_count() - 1;
  const std::string mid = std::to_string(last / 2), end = std::to_string(last);
  seed("contacts", "frames.yaml",
       "version: 1\ndoc: both feet\npatches:\n  - name: left sole\n    joint: LeftFoot\n"
       "    vertices: [[0, -0.07, -0.05], [0.04, -0.07, 0.1], [-0.04, -0.07, 0.1]]\n"
       "    frames: [[0, " +
           mid + "], [" + mid + ", " + end +
           "]]\n  - joint: RightToeBase\n"
           "    vertices: [[0, 0, 0.03]]\n    frames: [2, " +
           mid + "]\n");
  seed(
      "contacts", "times.yaml",
      "version: 1\npatches:\n  - {joint: LeftToeBase, vertices: [[0, 0, 0]], times: [[0, 0.3], [0.5, 0.9]]}\n"
      "  - {joint: RightHand, vertices: [[0, -0.08, 0]], times: [0.1, 0.2]}\n");

  seed(
      "constraints", "kinds.yaml",
      "version: 1\ndoc: every built-in kind on the walk\nconstraints:\n"
      "  - kind: position\n    label: \"left toe\"\n    points: [{joint: LeftToeBase, offset: [0, 0, "
      "0.05]}]\n"
      "    params: [0.1, 0, 0.3]\n    frames: [0, " +
          mid +
          "]\n"
          "  - kind: same_place\n    points: [{joint: RightToeBase, end_site: true}]\n    params: [1, 0, 1]\n"
          "    frames: [1, 5]\n"
          "  - kind: region\n    points: [{joint: LeftFoot}]\n"
          "    params: [-1, 0, -1, 1, 2, 1]\n    at_frames: [3, 9, " +
          end +
          "]\n"
          "  - kind: parameter_range\n    channels: [\"LeftLeg.Xrotation\"]\n    params: [-1, 1]\n    times: "
          "[0.1, 0.4]\n"
          "    weight: 2.0\n  - {kind: parameter_range, channels: [{joint: Hips, channel: Yposition}], "
          "params: [0.9], "
          "frames: [0, 1]}\n"
          "  - kind: distance\n    relation: at_most\n    points: [{joint: LeftHand}, {joint: RightHand, "
          "frame_offset: 1}]\n"
          "    params: [0.5]\n    at_times: [0.2, 0.6]\n"
          "limits:\n  \"(Left|Right)(Leg|UpLeg)\": {Xrotation: [-160, 20]}\n  \"LeftFoot\": {Xrotation: "
          "[-45, .inf]}\n"
          "limits_character: 0\n");
  seed("constraints", "orientation_and_path.yaml",
       "version: 1\nconstraints:\n  - {kind: orientation, points: [{joint: Head}, {joint: Neck}], params: "
       "[0, 1, 0], "
       "frames: [0, 3]}\n  - {kind: follow_path, points: [{joint: LeftHand}, {joint: Hips}], params: [0, 1, "
       "0, 1, 1, 0], frames: [2, 8]}\n");

  seed("target", "bones.yaml",
       "version: 1\ndefault: 1.0\nbones:\n  \"(Left|Right)(Leg|Foot|ToeBase)\": 0.6\n  "
       "\"Spine|Chest|Neck|Head\": 1.3\n");
  seed("target", "lengths.yaml",
       "version: 1\ndefault: 0.9\nlengths:\n  \"LeftLeg|RightLeg\": 0.35\n  Head: 0.2\n");
  seed("target", "morph.yaml",
       "version: 1\ndefault: 1.0\nmorph:\n  - {time: 0.0, scale: 1.0}\n  - time: 0.5\n    bones: "
       "{\"Left.*\": 0.6}\n"
       "  - time: 0.9\n    default: 0.8\n    lengths: {Head: 0.25}\n");

  seed("body", "table.yaml",
       "version: 1\ntable: de_leva_female\nmass: 62\nclasses:\n  \"Spine|Chest\": trunk\n  \"LeftShoulder\": "
       "massless\n"
       "segments:\n  LeftUpLeg: {mass_scale: 10}\n  \"(Left|Right)Hand\": {mass: 0.5}\n"
       "  Head: {com: [0, 0.1, 0], inertia: [0.02, 0.02, 0.015]}\ntorque_limits:\n  \".*\": 400\n"
       "  \"(Left|Right)Leg\": [250, 250, 250]\nfriction: 0.7\ngravity: [0, -9.81, 0]\n");
  seed("body", "cylinders.yaml",
       "version: 1\ntable: cylinders\nmass: 0\nradii: {trunk: 0.13, thigh: 0.07}\n"
       "segments:\n  Neck: {radius: 0.05}\n  Chest: {inertia: [0.5, 0.4, 0.3, 0.01, 0, 0]}\ngravity: 1.62\n");
  seed("body", "dempster.yaml", "version: 1\ntable: dempster\n");
}

// The smallest robot: one link (tests/io/data has one with every joint type).
void urdf_seeds() {
  // fuzz_robot_csv's robot: hinge, slide, spin.
  seed("robot_csv", "three_frames.csv",
       "time,root_x,root_y,root_z,root_qx,root_qy,root_qz,root_qw,hinge,slide,spin\n"
       "0.0,0,0,0.8,0,0,0,1,0.1,0.05,0\n0.02,0.01,0,0.8,0,0,0.1,0.99,0.2,0.06,3.5\n"
       "0.04,0.02,0,0.81,0,0.1,0.2,0.97,0.3,0.07,7\n");
  seed("robot_csv", "columns_reordered.csv",
       "time,root_x,root_y,root_z,root_qx,root_qy,root_qz,root_qw,spin,hinge,slide\n0,0,0,0,0,0,0,1,1,0.5,0."
       "1\n");
  seed("urdf", "single.urdf", "<robot name=\"one\"><link name=\"base\"/></robot>\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: fuzz_seeds SOURCE_DIR OUT_DIR\n";
    return 2;
  }
  const fs::path source = argv[1];
  out_dir = argv[2];
  try {
    fs::remove_all(out_dir);
    const kg::motion::Motion walk = kg::synth::synthesize_walk({.steps = 2, .fps = 30}).motion;
    bvh_seeds(walk);
    seed_files("bvh", source, "tests/graphs/data", ".bvh");
    asf_amc_seeds();
    seed_files("graph", source, "graphs", ".yaml");
    seed_files("graph", source, "tests/graph/data", ".yaml");
    seed_files("graph", source, "tests/graphs/data", ".yaml");
    seed_files("target", source, "graphs/targets", ".yaml");
    seed_files("constraints", source, "graphs/ladder", ".yaml");
    clip_file_seeds(walk);
    urdf_seeds();
    seed_files("urdf", source, "tests/io/data", ".urdf");
  } catch (const std::exception& e) {
    std::cerr << "fuzz_seeds: " << e.what() << '\n';
    return 1;
  }
  std::cout << "fuzz_seeds: wrote " << written << " seeds in " << out_dir.string() << '\n';
  return 0;
}
