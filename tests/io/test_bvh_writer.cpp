// The BVH writer: round trips exact to the printed precision on every real file, units, Z-up
// files written in file coordinates, ASF-style axis joints re-expressed as BVH Euler angles.
#include <catch2/catch.hpp>

#include <charconv>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "../support/temp_dir.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/io/bvh.hpp"
#include "kg/motion/frame_time.hpp"
#include "kg/motion/kinematics.hpp"
#include "test_bvh_data.hpp"

using kg::io::BvhWriteOptions;
using kg::io::parse_bvh;
using kg::io::read_bvh;
using kg::io::write_bvh_string;
using kg::motion::ChannelKind;

namespace {

std::vector<std::string_view> tokens(std::string_view text) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    std::size_t b = i;
    while (i < text.size() && !std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    if (i > b) out.push_back(text.substr(b, i - b));
  }
  return out;
}

bool as_number(std::string_view t, double& v) {
  auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  return ec == std::errc() && p == t.data() + t.size();
}

// Digits after the point the source prints (12 for exponent notation, which fixed decimals
// can only match to the writer's maximum).
int source_decimals(std::string_view text) {
  int most = 0;
  for (std::string_view t : tokens(text.substr(text.find("MOTION")))) {
    if (t.find_first_of("eE") != std::string_view::npos) return 12;
    std::size_t dot = t.find('.');
    if (dot != std::string_view::npos) most = std::max(most, static_cast<int>(t.size() - dot - 1));
  }
  return std::max(most, 1);
}

// Every word of `written` equals the source's, numbers to within half a unit of the last
// printed decimal (plus a few ulps of the source value).
void check_same_to_precision(std::string_view source, std::string_view written, int precision) {
  const auto a = tokens(source), b = tokens(written);
  REQUIRE(a.size() == b.size());
  const double half = 0.5 * std::pow(10.0, -precision);
  int mismatches = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    double x = 0, y = 0;
    if (i > 0 && a[i - 1] == "Time:" && as_number(a[i], x) && as_number(b[i], y)) {
      // The frame time is written as 1 / fps to 9 digits, fps being the rate the source's
      // printed digits stand for (0.033333 is 1/30 s): the same rate, not the same text.
      if (std::abs(1 / y - kg::motion::rate_of_printed_frame_time(a[i], x)) > 1e-7 / y)
        if (++mismatches < 5) FAIL_CHECK("frame time: source " << a[i] << ", written " << b[i]);
    } else if (as_number(a[i], x) && as_number(b[i], y)) {
      if (std::abs(x - y) > half + 8 * std::abs(x) * 2.2e-16) {
        if (++mismatches < 5) FAIL_CHECK("word " << i << ": source " << a[i] << ", written " << b[i]);
      }
    } else if (a[i] != b[i] && !(a[i] == "Frames:" || a[i] == "Time:")) {
      if (++mismatches < 5) FAIL_CHECK("word " << i << ": source '" << a[i] << "', written '" << b[i] << "'");
    }
  }
  CHECK(mismatches == 0);
}

kg::motion::Joint make_joint(const std::string& name, int parent, const Eigen::Vector3d& offset) {
  kg::motion::Joint j;
  j.name = name;
  j.parent = parent;
  j.offset = offset;
  return j;
}

}  // namespace

TEST_CASE("bvh writer: numbers, frame time and layout") {
  const char* text =
      "HIERARCHY\nROOT hip\n{\n OFFSET 0 -0.0000001 1.50\n CHANNELS 4 Xposition Zrotation Yrotation "
      "Xrotation\n"
      " End Site\n {\n  OFFSET 0 10 0\n }\n}\nMOTION\nFrames: 2\nFrame Time: 0.00833333\n"
      "-0.0000004 90 -45.25 1e-13\n2 0.5 -0 12.3456789\n";
  auto clip = parse_bvh(text, "n.bvh");
  const std::string out = write_bvh_string(clip.motion, {.precision = 6, .exact = true});
  CHECK(out ==
        "HIERARCHY\nROOT hip\n{\n\tOFFSET 0 0 1.5\n\tCHANNELS 4 Xposition Zrotation Yrotation Xrotation\n"
        "\tEnd Site\n\t{\n\t\tOFFSET 0 10 0\n\t}\n}\nMOTION\nFrames: 2\nFrame Time: 0.00833333333\n"
        "0 90 -45.25 0\n2 0.5 0 12.345679\n");  // 0.00833333 is 1/120 s to its digits
  CHECK(clip.motion.fps == 120);
  kg::motion::Motion m = clip.motion;
  m.fps = 120;
  CHECK(write_bvh_string(m).find("Frame Time: 0.00833333333\n") != std::string::npos);
  CHECK_THROWS_AS(write_bvh_string(m, {.precision = 0}), std::invalid_argument);
  CHECK_THROWS_AS(write_bvh_string(m, {.precision = 13}), std::invalid_argument);
  CHECK_THROWS_AS(write_bvh_string(m, {.units = "furlong"}), std::invalid_argument);
  m.values(0, 0) = std::nan("");
  CHECK_THROWS_AS(write_bvh_string(m), std::invalid_argument);
}

TEST_CASE("bvh writer: every file of ../shared/data round-trips exactly to the printed precision") {
  int seen = 0;
  for (const auto& f : kg::test::bvh_data_files()) {
    auto path = kg::test::data_file(f.path);
    if (!path) {
      WARN("skipped: " << f.path << " not found");
      continue;
    }
    ++seen;
    INFO(f.path);
    const std::string source = kg::test::read_file(*path);
    auto clip = parse_bvh(source, path->string());

    // Written at the source's precision, every value equals the source's.
    const int p = std::min(12, source_decimals(source));
    const std::string written = write_bvh_string(clip.motion, {.precision = p});
    check_same_to_precision(source, written, p);

    // read -> write -> read -> write gives the same text, at the default and the finest precision.
    for (int precision : {6, 12}) {
      const std::string once = write_bvh_string(clip.motion, {.precision = precision});
      const std::string twice =
          write_bvh_string(parse_bvh(once, "once.bvh").motion, {.precision = precision});
      CHECK(once == twice);
    }

    // Imported (metres, maybe Z-up) and written back in the source unit: the same text as the
    // file-unit clip, so scaling is undone and file_to_world is not written.
    kg::io::ImportedMotion in = kg::io::import_bvh(*path, {.trim = "none"});
    CHECK(write_bvh_string(in.motion) == write_bvh_string(clip.motion));
  }
  if (seen == 0) WARN("skipped: no BVH file of ../shared/data found");
}

TEST_CASE("bvh writer: other units scale lengths only") {
  auto path = kg::test::data_file("cmu/bvh_motionbuilder/16_15.bvh");
  if (!path) {
    WARN("skipped: cmu/bvh_motionbuilder/16_15.bvh not found");
    return;
  }
  kg::io::ImportedMotion in = kg::io::import_bvh(*path, {.trim = "none"});
  REQUIRE(in.motion.skeleton->source_unit_metres == 0.01);
  const std::string m = write_bvh_string(in.motion, {.units = "m", .precision = 8});
  CHECK(m.find("ROOT root\n{\n\tOFFSET 0.06939 0.97422 -1.51953\n") != std::string::npos);
  auto back = parse_bvh(m, "m.bvh");
  auto cm = read_bvh(*path);
  const auto& s = *cm.motion.skeleton;
  for (int j = 0; j < s.joint_count(); ++j)
    for (std::size_t c = 0; c < s.joint(j).channels.size(); ++c) {
      const int col = s.joint(j).first_channel + static_cast<int>(c);
      const double scale = kg::motion::is_rotation(s.joint(j).channels[c].kind) ? 1.0 : 0.01;
      CHECK((back.motion.values.col(col) - cm.motion.values.col(col) * scale).cwiseAbs().maxCoeff() < 1e-8);
    }
  // Inches for a tool that wants them: 97.422 cm = 38.3551 in.
  const std::string inch = write_bvh_string(in.motion, {.units = "inch", .precision = 4});
  CHECK(inch.find("\tOFFSET 2.7319 38.3551 -59.824\n") != std::string::npos);
}

TEST_CASE("bvh writer: a Z-up file is written in its own axes") {
  const char* text =
      "HIERARCHY\nROOT pelvis\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation "
      "Yrotation Xrotation\n"
      " JOINT spine\n {\n  OFFSET 0 0 60\n  CHANNELS 3 Zrotation Yrotation Xrotation\n  End Site\n  {\n   "
      "OFFSET 0 0 60\n  }\n }\n"
      " JOINT leg\n {\n  OFFSET 0 0 -50\n  CHANNELS 3 Zrotation Yrotation Xrotation\n  End Site\n  {\n   "
      "OFFSET 0 0 -45\n  }\n }\n}\n"
      "MOTION\nFrames: 1\nFrame Time: 0.01\n1 2 95 10 20 30 1 2 3 4 5 6\n";
  auto clip = parse_bvh(text, "z.bvh");
  kg::motion::Motion m = clip.motion;
  auto notes = kg::io::apply_import_options(m, {}, 100, "z.bvh");
  REQUIRE(kg::io::up_axis_name(m.skeleton->file_to_world) == "z");
  CHECK(write_bvh_string(m) == write_bvh_string(clip.motion));
  CHECK(write_bvh_string(m).find("\n1 2 95 10 20 30 1 2 3 4 5 6\n") != std::string::npos);
}

TEST_CASE("bvh writer: joints with an ASF axis become three Euler channels with the same poses") {
  using kg::motion::Joint;
  kg::motion::Skeleton s;
  auto axis = [](double x, double y, double z) {
    return (Eigen::AngleAxisd(x, Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(y, Eigen::Vector3d::UnitY()) *
            Eigen::AngleAxisd(z, Eigen::Vector3d::UnitZ()))
        .toRotationMatrix();
  };
  Joint root = make_joint("root", -1, {0, 0.9, 0});
  root.channels = {{ChannelKind::Xposition}, {ChannelKind::Yposition}, {ChannelKind::Zposition},
                   {ChannelKind::Zrotation}, {ChannelKind::Yrotation}, {ChannelKind::Xrotation}};
  root.axis = axis(0.1, -0.2, 0.3);
  s.add_joint(root);
  // Every Tait-Bryan order, a two-DOF and a one-DOF joint, each with its own axis.
  const std::vector<std::vector<ChannelKind>> orders = {
      {ChannelKind::Xrotation, ChannelKind::Yrotation, ChannelKind::Zrotation},
      {ChannelKind::Xrotation, ChannelKind::Zrotation, ChannelKind::Yrotation},
      {ChannelKind::Yrotation, ChannelKind::Xrotation, ChannelKind::Zrotation},
      {ChannelKind::Yrotation, ChannelKind::Zrotation, ChannelKind::Xrotation},
      {ChannelKind::Zrotation, ChannelKind::Xrotation, ChannelKind::Yrotation},
      {ChannelKind::Zrotation, ChannelKind::Yrotation, ChannelKind::Xrotation},
      {ChannelKind::Xrotation, ChannelKind::Zrotation},
      {ChannelKind::Yrotation}};
  int parent = 0;
  for (std::size_t i = 0; i < orders.size(); ++i) {
    std::string name = "j";
    name += std::to_string(i);
    Joint j = make_joint(name, parent, {0.02 * i, 0.1, -0.03});
    for (ChannelKind k : orders[i]) j.channels.push_back({k});
    j.axis = axis(0.3 * i, 0.7 - 0.1 * i, -0.4 + 0.05 * i);
    j.end_sites = {{0.05, 0.05, 0.0}};
    parent = s.add_joint(j);
  }
  // Rotations about the axis' own Y commute with it: Y = +-90 degrees locks the written XYZ gimbal.
  Joint locked = make_joint("locked", parent, {0, 0.1, 0});
  locked.channels = {{ChannelKind::Xrotation}, {ChannelKind::Yrotation}, {ChannelKind::Zrotation}};
  locked.axis = axis(0, 0.3, 0);
  locked.end_sites = {{0.1, 0.02, 0.03}};
  const int lock = s.add_joint(locked);
  const int lock_y = s.joint(lock).first_channel + 1;
  kg::motion::Motion m;
  m.skeleton = std::make_shared<const kg::motion::Skeleton>(s);
  m.fps = 120;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-3.0, 3.0);
  const int frames = 200;
  m.values.resize(frames, s.channel_count());
  for (int f = 0; f < frames; ++f)
    for (int c = 0; c < s.channel_count(); ++c) m.values(f, c) = c < 3 ? 0.1 * angle(rng) : angle(rng);
  m.values.row(frames - 1).setZero();
  m.values(frames - 1, lock_y) = std::numbers::pi / 2;
  m.values.row(frames - 2).setZero();
  m.values(frames - 2, lock_y) = -std::numbers::pi / 2;

  const std::string text = write_bvh_string(m, {.precision = 12});
  CHECK(text.find("JOINT j6\n") != std::string::npos);
  CHECK(text.find("CHANNELS 3 Xrotation Zrotation Yrotation\n") != std::string::npos);  // j1 and j6
  CHECK(text.find("CHANNELS 3 Yrotation Xrotation Zrotation\n") != std::string::npos);  // j2 and j7
  auto back = parse_bvh(text, "axis.bvh");
  const auto& t = *back.motion.skeleton;
  REQUIRE(t.joint_count() == s.joint_count());
  for (int j = 0; j < t.joint_count(); ++j) CHECK(t.joint(j).axis.isIdentity());
  std::vector<Eigen::Isometry3d> wa(static_cast<std::size_t>(s.joint_count())), wb(wa.size());
  double worst = 0;
  for (int f = 0; f < frames; ++f) {
    kg::motion::forward_kinematics(s, m.values.row(f), wa);
    kg::motion::forward_kinematics(t, back.motion.values.row(f), wb);
    for (std::size_t j = 0; j < wa.size(); ++j) {
      worst = std::max(worst, (wa[j].translation() - wb[j].translation()).norm());
      worst = std::max(worst, (wa[j].linear() - wb[j].linear()).cwiseAbs().maxCoeff());
    }
  }
  CHECK(worst < 1e-9);
  // Written angles move continuously where the pose does: no jump to the other Euler solution
  // (about pi) or across the +-pi cut (2 pi) between frames. Steps of 0.03 rad turn into up to
  // ~0.2 rad where this path passes near gimbal lock.
  const int c0 = t.joint(1).first_channel;
  m.values.setZero();
  for (int f = 0; f < frames; ++f) m.values(f, 6) = -3.0 + 6.0 * f / (frames - 1);  // j0's X: -172..172 deg
  auto smooth = parse_bvh(write_bvh_string(m, {.precision = 9}), "smooth.bvh");
  double jump = 0;
  for (int f = 1; f < frames; ++f)
    for (int c = c0; c < c0 + 3; ++c)
      jump = std::max(jump, std::abs(smooth.motion.values(f, c) - smooth.motion.values(f - 1, c)));
  CHECK(jump < 0.5);
}

TEST_CASE("bvh writer: a skeleton not in depth-first order is written depth first, values following") {
  kg::motion::Skeleton s;
  auto add = [&](const std::string& name, int parent, Eigen::Vector3d offset,
                 std::vector<ChannelKind> kinds) {
    kg::motion::Joint j = make_joint(name, parent, offset);
    for (ChannelKind k : kinds) j.channels.push_back({k});
    return s.add_joint(j);
  };
  const int root = add("root", -1, {0, 1, 0}, {ChannelKind::Yposition, ChannelKind::Yrotation});
  const int a = add("a", root, {0.2, 0, 0}, {ChannelKind::Zrotation});
  add("b", root, {-0.2, 0, 0}, {ChannelKind::Xrotation});
  add("a1", a, {0, -0.4, 0}, {ChannelKind::Xrotation, ChannelKind::Zrotation});
  kg::motion::Motion m;
  m.skeleton = std::make_shared<const kg::motion::Skeleton>(s);
  m.fps = 50;
  m.values.resize(2, 6);
  m.values << 0.9, 0.1, 0.2, 0.3, 0.4, 0.5,  //
      1.0, -0.1, -0.2, -0.3, -0.4, -0.5;
  const std::string text = write_bvh_string(m, {.precision = 9, .exact = true});
  CHECK(text.find("JOINT a\n\t{\n\t\tOFFSET 0.2 0 0\n\t\tCHANNELS 1 Zrotation\n\t\tJOINT a1\n") !=
        std::string::npos);
  auto back = parse_bvh(text, "dfs.bvh");
  const auto& t = *back.motion.skeleton;
  CHECK(t.joint(2).name == "a1");
  CHECK(t.joint(3).name == "b");
  const auto pa = kg::motion::joint_world_positions(m), pb = kg::motion::joint_world_positions(back.motion);
  for (int j = 0; j < 4; ++j) {
    const int k = t.find_joint(s.joint(j).name);
    CHECK((pa.middleCols(3 * j, 3) - pb.middleCols(3 * k, 3)).cwiseAbs().maxCoeff() < 1e-8);
  }
  CHECK(back.motion.values(1, 3) == Approx(-0.4));  // a1's Xrotation now precedes b's
}

namespace {

// The CHANNELS count of every joint of a BVH text, in file order.
std::vector<int> channel_counts(const std::string& text) {
  std::vector<int> counts;
  const auto words = tokens(text);
  for (std::size_t i = 0; i + 1 < words.size(); ++i)
    if (words[i] == "CHANNELS") counts.push_back(std::stoi(std::string(words[i + 1])));
  return counts;
}

// Worst distance (metres) between the joints of `a` and those of the same name in `b`.
double worst_joint_distance(const kg::motion::Motion& a, const kg::motion::Motion& b) {
  const auto pa = kg::motion::joint_world_positions(a), pb = kg::motion::joint_world_positions(b);
  double worst = 0;
  for (int j = 0; j < a.skeleton->joint_count(); ++j) {
    const int k = b.skeleton->find_joint(a.skeleton->joint(j).name);
    REQUIRE(k >= 0);
    worst = std::max(worst, (pa.middleCols(3 * j, 3) - pb.middleCols(3 * k, 3)).cwiseAbs().maxCoeff());
  }
  return worst;
}

}  // namespace

TEST_CASE(
    "bvh writer: by default every joint has three rotation channels, and three position channels or none") {
  // Blender 3.4 refused our ASF-sourced files (KeyError: (2, 1, None) on 2-channel clavicles).
  kg::motion::Skeleton s;
  auto add = [&](const std::string& name, int parent, Eigen::Vector3d offset,
                 std::vector<ChannelKind> kinds) {
    kg::motion::Joint j = make_joint(name, parent, offset);
    for (ChannelKind k : kinds) j.channels.push_back({k});
    return s.add_joint(j);
  };
  const int root = add("root", -1, {0.1, 1, 0.2}, {ChannelKind::Yposition, ChannelKind::Yrotation});
  const int a = add("a", root, {0.2, 0, 0}, {ChannelKind::Zrotation, ChannelKind::Xrotation});
  add("b", a, {0, -0.4, 0}, {});
  add("c", root, {-0.2, 0, 0}, {ChannelKind::Zrotation, ChannelKind::Xrotation, ChannelKind::Yrotation});
  kg::motion::Motion m;
  m.skeleton = std::make_shared<const kg::motion::Skeleton>(s);
  m.fps = 50;
  m.values.resize(2, 7);
  m.values << 0.9, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6,  //
      1.0, -0.1, -0.2, -1.3, -0.4, 2.5, -0.6;
  const std::string text = write_bvh_string(m, {.precision = 12});
  INFO(text);
  // The missing axes follow the joint's own, in X, Y, Z order; a lone Yposition gets X and Z from
  // the OFFSET, which it replaces.
  CHECK(text.find("ROOT root\n{\n\tOFFSET 0.1 1 0.2\n\tCHANNELS 6 Xposition Yposition Zposition Yrotation "
                  "Xrotation Zrotation\n") != std::string::npos);
  CHECK(text.find("CHANNELS 3 Zrotation Xrotation Yrotation\n") != std::string::npos);
  CHECK(channel_counts(text) == std::vector<int>{6, 3, 3, 3});
  CHECK(text.find("\n0.1 0.9 0.2 5.729577951308 0 0 ") != std::string::npos);
  const auto back = parse_bvh(text, "standard.bvh");
  CHECK(worst_joint_distance(m, back.motion) < 1e-10);
  // exact keeps the skeleton's own channels.
  CHECK(channel_counts(write_bvh_string(m, {.exact = true})) == std::vector<int>{2, 2, 0, 3});
}

TEST_CASE("bvh writer: an ASF/AMC clip is written with three rotation channels per joint, the same motion",
          "[data]") {
  const auto asf = kg::test::data_file("cmu/asf_amc/16.asf"),
             amc = kg::test::data_file("cmu/asf_amc/16_15.amc");
  if (!asf || !amc) {
    WARN("skipped: cmu/asf_amc/16.asf or 16_15.amc not found");
    return;
  }
  const kg::motion::Motion source = kg::io::import_asf_amc(asf->string(), amc->string(), {}).motion;
  const std::string text = write_bvh_string(source, {.units = "cm", .precision = 9});
  for (int count : channel_counts(text)) CHECK((count == 3 || count == 6));
  const kg::test::TempDir dir;
  const kg::io::ImportedMotion back = kg::io::import_bvh(dir.write("16_15.bvh", text), {.units = "cm"});
  CHECK(back.motion.frame_count() == source.frame_count());
  CHECK(worst_joint_distance(source, back.motion) < 1e-6);  // metres
}
