// The BVH reader: every real file of ../shared/data, the position-channel convention, a table
// of malformed inputs (each naming file:line and what was expected), and truncation fuzz.
#include <catch2/catch.hpp>

#include <charconv>
#include <cmath>
#include <cstring>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "../support/temp_dir.hpp"
#include "kg/base/error.hpp"
#include "kg/io/bvh.hpp"
#include "kg/motion/kinematics.hpp"
#include "test_bvh_data.hpp"

using kg::io::BvhClip;
using kg::io::parse_bvh;
using kg::io::read_bvh;
using kg::motion::ChannelKind;

namespace {

int end_site_count(const kg::motion::Skeleton& s) {
  int n = 0;
  for (const auto& j : s.joints()) n += static_cast<int>(j.end_sites.size());
  return n;
}

// A small valid file; the malformed cases below edit single lines of it.
const std::vector<std::string> kGoodLines = {
    "HIERARCHY",                                                                 // 1
    "ROOT hip",                                                                  // 2
    "{",                                                                         // 3
    "  OFFSET 0 0 0",                                                            // 4
    "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",  // 5
    "  JOINT knee",                                                              // 6
    "  {",                                                                       // 7
    "    OFFSET 0 -40 0",                                                        // 8
    "    CHANNELS 3 Zrotation Xrotation Yrotation",                              // 9
    "    End Site",                                                              // 10
    "    {",                                                                     // 11
    "      OFFSET 0 -40 0",                                                      // 12
    "    }",                                                                     // 13
    "  }",                                                                       // 14
    "}",                                                                         // 15
    "MOTION",                                                                    // 16
    "Frames: 2",                                                                 // 17
    "Frame Time: 0.0333333",                                                     // 18
    "0 90 0 0 0 0 10 0 0",                                                       // 19
    "1 90 0 0 0 0 20 0 0",                                                       // 20
};

std::string join(const std::vector<std::string>& lines, const char* eol = "\n") {
  std::string s;
  for (const std::string& l : lines) s += l + eol;
  return s;
}

// kGoodLines with line `line` (1-based) replaced; an empty replacement removes it.
std::string with_line(int line, const std::string& text, bool remove = false) {
  std::vector<std::string> lines = kGoodLines;
  if (remove)
    lines.erase(lines.begin() + (line - 1));
  else
    lines[static_cast<std::size_t>(line - 1)] = text;
  return join(lines);
}

std::string error_of(const std::string& text, const std::string& name = "t.bvh") {
  try {
    parse_bvh(text, name);
  } catch (const kg::Error& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST_CASE("bvh: the small file parses with the file's numbers, radians, End Sites") {
  BvhClip c = parse_bvh(join(kGoodLines), "dir/small.bvh");
  const auto& s = *c.motion.skeleton;
  REQUIRE(s.joint_count() == 2);
  CHECK(s.channel_count() == 9);
  CHECK(c.motion.frame_count() == 2);
  CHECK(c.frame_time == Approx(0.0333333));
  CHECK(c.motion.fps == Approx(1 / 0.0333333));
  CHECK(c.motion.name == "small");
  CHECK(s.source_unit_metres == 1.0);
  CHECK(s.file_to_world.isIdentity());
  CHECK(s.joint(1).name == "knee");
  CHECK(s.joint(1).parent == 0);
  CHECK(s.joint(1).offset.isApprox(Eigen::Vector3d(0, -40, 0)));
  REQUIRE(s.joint(1).end_sites.size() == 1);
  CHECK(s.joint(1).end_sites[0].isApprox(Eigen::Vector3d(0, -40, 0)));
  CHECK(s.joint(0).channels[3].kind == ChannelKind::Zrotation);
  CHECK(s.joint(0).channels[4].kind == ChannelKind::Xrotation);
  CHECK(s.joint(1).first_channel == 6);
  CHECK(c.motion.values(0, 1) == 90.0);  // a position: file units
  CHECK(c.motion.values(1, 0) == 1.0);
  CHECK(c.motion.values(1, 6) == Approx(20 * std::numbers::pi / 180));  // a rotation: radians
}

TEST_CASE("bvh: CRLF, tabs, blank lines, letter case, BOM, a name with blanks, several roots") {
  std::string text =
      "\xEF\xBB\xBFhierarchy\r\n"
      "ROOT\tleft arm {\r\n"
      "\tOFFSET\t1 2 3\r\n"
      "\tCHANNELS 2 zrotation XROTATION\r\n"
      "\tEnd Site\r\n"
      "\t{\r\n"
      "\t\tOFFSET 0 1 0\r\n"
      "\t}\r\n"
      "}\r\n"
      "ROOT second\r\n"
      "{\r\n"
      "\tOFFSET 0 0 0\r\n"
      "\tCHANNELS 1 Yposition\r\n"
      "\tJOINT child\r\n"
      "\t{\r\n"
      "\t\tOFFSET 5 6 7\r\n"
      "\t\tCHANNELS 0\r\n"
      "\t}\r\n"
      "}\r\n"
      "Motion\r\n"
      "FRAMES:\t3\r\n"
      "Frame Time:\t0.5\r\n"
      "\t1\t2   3 \r\n"
      "\r\n"
      "4 1e-400 +6\r\n"
      "7 8 9";  // no final line end
  BvhClip c = parse_bvh(text, "crlf.bvh");
  const auto& s = *c.motion.skeleton;
  REQUIRE(s.joint_count() == 3);
  CHECK(s.joint(0).name == "left arm");
  CHECK(s.joint(1).name == "second");
  CHECK(s.joint(1).parent == -1);
  CHECK(s.joint(2).parent == 1);
  CHECK(s.joint(2).channels.empty());
  CHECK(s.channel_count() == 3);
  REQUIRE(c.motion.frame_count() == 3);
  CHECK(c.motion.values(1, 2) == 6.0);
  CHECK(c.motion.values(1, 1) == 0.0);  // underflows to zero: a number, not an error
  CHECK(c.motion.values(2, 0) == Approx(7 * std::numbers::pi / 180));
  CHECK(c.motion.fps == 2.0);
}

TEST_CASE("bvh: position channels on a child joint replace only the OFFSET components they name") {
  std::string text =
      "HIERARCHY\nROOT r\n{\n OFFSET 0 0 0\n CHANNELS 0\n JOINT a\n {\n  OFFSET 1 2 3\n"
      "  CHANNELS 2 Yposition Zrotation\n  End Site\n  {\n   OFFSET 1 0 0\n  }\n }\n}\n"
      "MOTION\nFrames: 1\nFrame Time: 0.1\n7 90\n";
  BvhClip c = parse_bvh(text, "pos.bvh");
  std::vector<Eigen::Isometry3d> world(2);
  kg::motion::forward_kinematics(*c.motion.skeleton, c.motion.values.row(0), world);
  CHECK(world[1].translation().isApprox(Eigen::Vector3d(1, 7, 3)));
  // The End Site (1, 0, 0) turned 90 degrees about Z.
  CHECK((world[1] * Eigen::Vector3d(1, 0, 0)).isApprox(Eigen::Vector3d(1, 8, 3)));
}

TEST_CASE("bvh: a table of malformed inputs names file:line:column and what was expected") {
  struct Case {
    std::string text;
    std::string where;  // "t.bvh:LINE:" prefix of the message
    std::string says;   // a part of the message
  };
  const std::vector<Case> cases = {
      {"", "t.bvh:1:1:", "expected HIERARCHY at the start of a BVH file, got end of file"},
      {with_line(1, "HIERARCH"), "t.bvh:1:1:", "got 'HIERARCH'"},
      {with_line(2, "JOINT hip"), "t.bvh:2:1:", "expected ROOT after HIERARCHY, got 'JOINT'"},
      {with_line(2, "ROOT"), "t.bvh:2:5:", "expected a joint name after ROOT, got end of line"},
      {with_line(3, "", true), "t.bvh:3:3:", "expected '{' opening joint hip, got 'OFFSET'"},
      {with_line(4, "  OFFSET 0 0"), "t.bvh:4:13:", "OFFSET z of joint hip (a number), got end of line"},
      {with_line(4, "  OFFSET 0 abc 0"), "t.bvh:4:12:", "got 'abc'"},
      {with_line(4, "  OFFSET 0 nan 0"), "t.bvh:4:12:", "expected a finite number"},
      {with_line(4, "  OFFSET 0 0 0 0"), "t.bvh:4:16:", "expected end of line after the 3 OFFSET values"},
      {with_line(4, "  OFFSET 0 0 1e999"), "t.bvh:4:14:", "expected a finite number"},
      {with_line(5, "  CHANNELS 6 Xposition Yposition Zposition Zrotation Wrotation Yrotation"),
       "t.bvh:5:54:",
       "expected channel name 5 of 6 of joint hip (Xposition, Yposition, Zposition, Xrotation, Yrotation or "
       "Zrotation), got 'Wrotation'"},
      {
          with_line(5, "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation"),
          "t.bvh:5:",
          "expected channel name 6 of 6 of joint hip",
      },
      {with_line(9, "    CHANNELS 2 Zrotation Xrotation Yrotation"), "t.bvh:9:",
       "expected end of line after the 2 channel names of CHANNELS 2 of joint knee, got 'Yrotation'"},
      {with_line(9, "    CHANNELS 7 Zrotation Xrotation Yrotation"),
       "t.bvh:9:14:", "expected a channel count 0..6 after CHANNELS of joint knee, got '7'"},
      {with_line(9, "    CHANNELS"),
       "t.bvh:9:", "a channel count 0..6 after CHANNELS of joint knee, got end of line"},
      {with_line(9, "    CHANNELS 3 Zrotation Xrotation Zrotation"),
       "t.bvh:9:", "not given twice, got 'Zrotation'"},
      {with_line(6, "  JOINT hip"), "t.bvh:6:9:", "expected a joint name not used before, got 'hip'"},
      {with_line(10, "    End Sit"), "t.bvh:10:9:", "expected 'Site' after 'End' in joint knee, got 'Sit'"},
      {with_line(11, "", true),
       "t.bvh:11:7:", "expected '{' opening the End Site of joint knee, got 'OFFSET'"},
      {with_line(13, "    OFFSET 1 1 1"),
       "t.bvh:13:5:", "expected '}' closing the End Site of joint knee, got 'OFFSET'"},
      {with_line(14, "", true),
       "t.bvh:15:1:", "expected JOINT, End Site or '}' closing joint hip, got 'MOTION'"},
      {with_line(6, "  JIONT knee"),
       "t.bvh:6:3:", "expected JOINT, End Site or '}' closing joint hip, got 'JIONT'"},
      {with_line(16, "MOTON"), "t.bvh:16:1:", "expected ROOT or MOTION after the hierarchy, got 'MOTON'"},
      {join({kGoodLines.begin(), kGoodLines.begin() + 15}),
       "t.bvh:16:1:", "expected ROOT or MOTION after the hierarchy, got end of file"},
      {join({kGoodLines.begin(), kGoodLines.begin() + 10}),
       "t.bvh:11:1:", "expected '{' opening the End Site of joint knee, got end of file"},
      {with_line(17, "Frame: 2"), "t.bvh:17:1:", "expected 'Frames:' after MOTION, got 'Frame:'"},
      {with_line(17, "Frames: -1"),
       "t.bvh:17:9:", "expected a frame count (an integer >= 0) after 'Frames:', got '-1'"},
      {with_line(17, "Frames: 2.5"), "t.bvh:17:9:", "got '2.5'"},
      {with_line(17, "Frames:"),
       "t.bvh:17:8:", "a frame count (an integer >= 0) after 'Frames:', got end of line"},
      {with_line(18, "Frame Time: 0"), "t.bvh:18:13:", "expected a frame time of 1e-06..3600 seconds"},
      {with_line(18, "Frame Time: -0.03"), "t.bvh:18:13:", "expected a frame time of 1e-06..3600 seconds"},
      // Fuzzing (issue 13): a denormal passed '> 0' and failed later as 'no frame rate', no line.
      {with_line(18, "Frame Time: 1e-310"), "t.bvh:18:13:",
       "expected a frame time of 1e-06..3600 seconds (1e6 to 1/3600 frames per second), got '1e-310'"},
      {with_line(18, "Frame Time: 1e-7"), "t.bvh:18:13:", "got '1e-7'"},
      {with_line(18, "Frame Time: 1e9"), "t.bvh:18:13:", "expected a frame time of 1e-06..3600 seconds"},
      {with_line(18, "Frame Time: inf"), "t.bvh:18:13:", "expected a finite number for a frame time"},
      {with_line(18, "Frame Time: fast"), "t.bvh:18:13:", "got 'fast'"},
      {with_line(18, "Frame Tim: 0.1"), "t.bvh:18:7:", "expected 'Time:' after 'Frame', got 'Tim:'"},
      {with_line(18, "Frame Time: 0.1 0 90 0 0 0 0 10 0 0"),
       "t.bvh:18:17:", "expected end of line after the frame time, got '0'"},
      {with_line(20, "1 90 0 0 0 0 20 0"),
       "t.bvh:20:18:", "expected 9 values on frame 2, got end of line after 8"},
      {with_line(20, "1 90 0 0 0 0 20 0 0 5"),
       "t.bvh:20:21:", "expected end of line after the 9 values of frame 2, got '5'"},
      {with_line(20, "1 90 0 x 0 0 20 0 0"),
       "t.bvh:20:8:", "expected a number (value 4 of 9 of frame 2, channel hip.Zrotation), got 'x'"},
      {with_line(20, "1 90 0 1.5.3 0 0 20 0 0"), "t.bvh:20:8:", "got '1.5.3'"},
      {with_line(20, "1 90 0 +-1 0 0 20 0 0"), "t.bvh:20:8:", "got '+-1'"},
      {with_line(20, "1 90 0 nan 0 0 20 0 0"),
       "t.bvh:20:8:", "expected a finite number (value 4 of frame 2), got 'nan'"},
      {with_line(20, "1 90 0 -inf 0 0 20 0 0"), "t.bvh:20:8:", "expected a finite number"},
      {with_line(20, "1 90 0 1e400 0 0 20 0 0"), "t.bvh:20:8:", "expected a finite number"},
      {with_line(17, "Frames: 3"),
       "t.bvh:21:1:", "expected frame line 3 of 3 (Frames: 3 on line 17), got end of file"},
      {with_line(17, "Frames: 1"),
       "t.bvh:20:1:", "expected end of file after the 1 frames (Frames: 1 on line 17), got '1'"},
      {with_line(17, "Frames: 999999999999"), "t.bvh:17:9:", "a frame count"},
      {with_line(17, "Frames: 2000000000"), "t.bvh:21:1:", "expected frame line 3 of 2000000000"},
      {join({kGoodLines.begin(), kGoodLines.begin() + 19}) + "1 90 0 0 0",
       "t.bvh:20:11:", "expected 9 values on frame 2, got end of file after 5"},
  };
  for (const Case& c : cases) {
    const std::string message = error_of(c.text);
    INFO("message: " << message);
    CHECK(message.rfind(c.where, 0) == 0);
    CHECK(message.find(c.says) != std::string::npos);
  }
}

TEST_CASE("bvh: a hostile nesting depth is refused, not a stack overflow") {
  std::string text = "HIERARCHY\nROOT r\n{\nOFFSET 0 0 0\n";
  for (int i = 0; i < 5000; ++i) text += "JOINT j" + std::to_string(i) + "\n{\nOFFSET 0 1 0\n";
  const std::string message = error_of(text);
  CHECK(message.find("expected at most 1000 nested joints") != std::string::npos);
}

TEST_CASE("bvh: an unreadable file names the path") {
  try {
    read_bvh("/nonexistent/dir/walk.bvh");
    FAIL("no error");
  } catch (const kg::Error& e) {
    CHECK(std::string(e.what()).rfind("/nonexistent/dir/walk.bvh: no such BVH file", 0) == 0);
  }
}

TEST_CASE("bvh: every BVH in ../shared/data loads with SOURCES.md's counts") {
  int seen = 0;
  for (const auto& f : kg::test::bvh_data_files()) {
    auto path = kg::test::data_file(f.path);
    if (!path) {
      WARN("skipped: " << f.path << " not found under " << KG_DATA_DIR);
      continue;
    }
    ++seen;
    INFO(f.path);
    BvhClip c = read_bvh(*path);
    const auto& s = *c.motion.skeleton;
    CHECK(c.motion.frame_count() == f.frames);
    CHECK(c.frame_time == f.frame_time);
    CHECK(s.joint_count() == f.joints);
    CHECK(end_site_count(s) == f.end_sites);
    CHECK(s.channel_count() == f.channels);
    CHECK(c.motion.values.cols() == f.channels);
    CHECK_NOTHROW(c.motion.check());
  }
  if (seen == 0) WARN("skipped: no BVH file of ../shared/data found");
}

TEST_CASE("bvh: 16_15.bvh's root OFFSET equals frame 0 and is not added to it") {
  auto path = kg::test::data_file("cmu/bvh_motionbuilder/16_15.bvh");
  if (!path) {
    WARN("skipped: cmu/bvh_motionbuilder/16_15.bvh not found");
    return;
  }
  BvhClip c = read_bvh(*path);
  const auto& s = *c.motion.skeleton;
  CHECK(s.joint(0).offset.isApprox(Eigen::Vector3d(6.939, 97.422, -151.953)));
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(s.joint_count()));
  kg::motion::forward_kinematics(s, c.motion.values.row(0), world);
  CHECK(world[0].translation().y() == Approx(97.422));  // file units (cm); doubling would give 194.8
  // Channel order of this file: Zrotation Xrotation Yrotation.
  CHECK(s.joint(0).channels[3].kind == ChannelKind::Zrotation);
  CHECK(s.joint(0).channels[5].kind == ChannelKind::Yrotation);
}

TEST_CASE("bvh: truncated and corrupted real files fail with file:line, never crash") {
  std::vector<std::string> files = {"other_skeletons/games105/run_forward.bvh",
                                    "other_skeletons/bandai_namco/dataset-1_dash_normal_001.bvh",
                                    "cmu/bvh_motionbuilder/16_15.bvh"};
  std::mt19937 rng(12345);
  int tried = 0;
  for (const std::string& rel : files) {
    auto path = kg::test::data_file(rel);
    if (!path) {
      WARN("skipped: " << rel << " not found");
      continue;
    }
    const std::string text = kg::test::read_file(*path);
    // The only successful truncations cut inside the last value, or the blanks after it.
    std::size_t last_value = text.find_last_not_of(" \t\r\n");
    while (last_value > 0 && text[last_value - 1] != ' ' && text[last_value - 1] != '\t') --last_value;
    std::uniform_int_distribution<std::size_t> cut(0, text.size() - 1);
    std::vector<std::size_t> cuts;
    for (int i = 0; i < 150; ++i) cuts.push_back(cut(rng));
    const std::size_t motion = text.find("MOTION");
    for (std::size_t k = motion - 40; k < motion + 80; ++k) cuts.push_back(k);  // header and first frame
    for (std::size_t n : cuts) {
      ++tried;
      INFO(rel << " cut at " << n);
      try {
        parse_bvh(std::string_view(text).substr(0, n), "cut.bvh");
        CHECK(n > last_value);
      } catch (const kg::Error& e) {
        const std::string m = e.what();
        CHECK(m.rfind("cut.bvh:", 0) == 0);
        CHECK(m.find(": expected ") != std::string::npos);
      }
    }
    // Random single-byte corruptions: parse or a located error, nothing else.
    std::uniform_int_distribution<int> byte(0, 255);
    for (int i = 0; i < 150; ++i) {
      std::string bad = text;
      bad[cut(rng)] = static_cast<char>(byte(rng));
      try {
        BvhClip c = parse_bvh(bad, "bad.bvh");
        CHECK_NOTHROW(c.motion.check());
      } catch (const kg::Error& e) {
        CHECK(std::string(e.what()).rfind("bad.bvh:", 0) == 0);
      }
    }
  }
  if (tried == 0) WARN("skipped: no BVH file of ../shared/data found");
}

TEST_CASE("bvh: frame values read bit-identical to std::from_chars, whatever their digits") {
  std::mt19937_64 rng(99);
  std::vector<std::string> words = {"0",
                                    "-0",
                                    "1.",
                                    ".5",
                                    "-.25",
                                    "007.50",
                                    "1e3",
                                    "-2.5E-3",
                                    "9007199254740993",
                                    "0.1000000000000000055511151231257827",
                                    "123456789012345678901234567890",
                                    "4.9e-324",
                                    "1.7976931348623157e308",
                                    "0.00000000000000000000001",
                                    "12345.678901234567"};
  std::uniform_int_distribution<int> digits(1, 20), point(0, 20), sign(0, 1);
  for (int i = 0; i < 3000; ++i) {
    std::string w = sign(rng) ? "-" : "";
    const int n = digits(rng), dot = point(rng);
    for (int d = 0; d < n; ++d) {
      if (d == dot) w += '.';
      w += static_cast<char>('0' + rng() % 10);
    }
    words.push_back(w);
  }
  std::string text = "HIERARCHY\nROOT r\n{\nOFFSET 0 0 0\nCHANNELS 1 Xposition\n}\nMOTION\nFrames: " +
                     std::to_string(words.size()) + "\nFrame Time: 1\n";
  for (const std::string& w : words) text += w + "\n";
  BvhClip c = parse_bvh(text, "digits.bvh");
  for (std::size_t i = 0; i < words.size(); ++i) {
    double expected = 0;
    std::from_chars(words[i].data(), words[i].data() + words[i].size(), expected);
    INFO(words[i]);
    CHECK(std::memcmp(&expected, &c.motion.values(static_cast<int>(i), 0), sizeof(double)) == 0);
  }
}
