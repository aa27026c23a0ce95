// Contacts: the friction basis, N = Jᵀ P against virtual work, the detected feet's polygons and
// support phases on a real walk, contact files and their errors.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <sstream>

#include "../support/node_context.hpp"
#include "../support/temp_dir.hpp"
#include "kg/base/error.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/io/bvh.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/motion/resample.hpp"
#include "kg/retime/contacts.hpp"
#include "kg/retime/nodes.hpp"

using namespace kg;
using namespace kg::retime;
using namespace kg::body;

namespace {

const std::string kData = KG_DATA_DIR;

// Support phases: runs of frames with the same set of touching patches.
struct Phase {
  std::vector<int> patches;
  int first = 0, last = 0;
};

std::vector<Phase> phases(const Contacts& c) {
  std::vector<Phase> out;
  for (int f = 0; f < c.frame_count(); ++f) {
    const std::vector<int> p = c.frames[static_cast<std::size_t>(f)].patches();
    if (out.empty() || out.back().patches != p)
      out.push_back({p, f, f});
    else
      out.back().last = f;
  }
  return out;
}

std::string describe(const Contacts& c) {
  std::ostringstream out;
  for (const std::string& n : c.notes) out << n << "\n";
  for (const Phase& p : phases(c)) {
    out << p.first << "-" << p.last << ":";
    for (int i : p.patches) out << " " << c.patches[static_cast<std::size_t>(i)].name;
    out << "\n";
  }
  return out.str();
}

// A small figure for contact files: hips (6 channels), a left hand and a right foot below.
motion::Motion small_clip(int frames) {
  using motion::ChannelKind;
  auto sk = std::make_shared<motion::Skeleton>();
  sk->add_joint({.name = "hips",
                 .parent = -1,
                 .channels = {{ChannelKind::Xposition},
                              {ChannelKind::Yposition},
                              {ChannelKind::Zposition},
                              {ChannelKind::Zrotation},
                              {ChannelKind::Xrotation},
                              {ChannelKind::Yrotation}}});
  sk->add_joint(
      {.name = "lhand", .parent = 0, .offset = {0.3, 0.2, 0}, .channels = {{ChannelKind::Xrotation}}});
  sk->add_joint(
      {.name = "rfoot", .parent = 0, .offset = {-0.1, -0.9, 0}, .channels = {{ChannelKind::Xrotation}}});
  motion::Motion m{sk, motion::FrameMatrix::Zero(frames, sk->channel_count()), 30.0, "small"};
  for (int f = 0; f < frames; ++f) {
    m.values(f, 1) = 0.95 + 0.01 * f;
    m.values(f, 3) = 0.02 * f;
    m.values(f, 6) = 0.1 * std::sin(0.3 * f);
    m.values(f, 7) = -0.05 * f;
  }
  return m;
}

}  // namespace

TEST_CASE("The friction basis is inscribed in Coulomb's cone", "[contacts]") {
  for (double mu : {0.0, 0.3, 0.5, 1.2}) {
    const Eigen::Matrix<double, 3, 4> P = friction_basis(mu);
    for (int k = 0; k < 4; ++k) {
      CHECK(P.col(k).norm() == Approx(1));
      CHECK(P(1, k) == Approx(1 / std::sqrt(1 + mu * mu)));
      // On the cone: tangential over normal is exactly μ.
      CHECK(std::hypot(P(0, k), P(2, k)) == Approx(mu * P(1, k)).margin(1e-15));
    }
    CHECK((P.col(0) + P.col(1)).normalized().isApprox(Eigen::Vector3d::UnitY()));
    CHECK((P.col(2) + P.col(3)).normalized().isApprox(Eigen::Vector3d::UnitY()));
  }
  CHECK_THROWS_WITH(friction_basis(-0.1), Catch::Contains("friction coefficient"));
  CHECK_THROWS_WITH(friction_basis(std::nan("")), Catch::Contains("friction coefficient"));
}

TEST_CASE("N = Jᵀ P is the generalised force of the basis forces (virtual work)", "[contacts]") {
  const motion::Motion m = small_clip(5);
  const std::vector<ContactPatch> patches{{"sole", {{2, {0.05, -0.04, 0.1}}, {2, {-0.05, -0.04, -0.08}}}},
                                          {"palm", {{1, {0, -0.1, 0.02}}}}};
  const Contacts c = assemble_contacts(m, patches, std::vector<std::vector<bool>>(5, {true, true, true}));
  const int f = 3;
  const double mu = 0.6;
  Eigen::MatrixXd N;
  contact_generalised_forces(c.frames[f], c.channel_count(), mu, N);
  REQUIRE(N.rows() == m.skeleton->channel_count());
  REQUIRE(N.cols() == 12);
  const Eigen::Matrix<double, 3, 4> P = friction_basis(mu);
  // d(p(q) · b) / dq by central differences, p the point's world position.
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(m.skeleton->joint_count()));
  const double h = 1e-6;
  std::size_t i = 0;
  for (std::size_t p = 0; p < patches.size(); ++p)
    for (const ContactVertex& v : patches[p].vertices) {
      const ContactPoint& point = c.frames[f].points[i];
      CHECK(point.patch == static_cast<int>(p));
      motion::forward_kinematics(*m.skeleton, m.values.row(f), world);
      CHECK((point.world - world[static_cast<std::size_t>(v.joint)] * v.local).norm() < 1e-12);
      for (int ch = 0; ch < m.skeleton->channel_count(); ++ch) {
        Eigen::RowVectorXd q = m.values.row(f);
        q[ch] += h;
        motion::forward_kinematics(*m.skeleton, q, world);
        const Eigen::Vector3d plus = world[static_cast<std::size_t>(v.joint)] * v.local;
        q[ch] -= 2 * h;
        motion::forward_kinematics(*m.skeleton, q, world);
        const Eigen::Vector3d minus = world[static_cast<std::size_t>(v.joint)] * v.local;
        for (int k = 0; k < 4; ++k)
          CHECK(N(ch, 4 * static_cast<Eigen::Index>(i) + k) ==
                Approx((plus - minus).dot(P.col(k)) / (2 * h)).margin(1e-7));
      }
      ++i;
    }
  // A frame without contact: no column.
  const Contacts none =
      assemble_contacts(m, patches, std::vector<std::vector<bool>>(5, {false, false, false}));
  contact_generalised_forces(none.frames[0], none.channel_count(), mu, N);
  CHECK(N.rows() == m.skeleton->channel_count());
  CHECK(N.cols() == 0);
  CHECK(none.frames[0].patches().empty());
}

TEST_CASE("assemble_contacts refuses inconsistent input", "[contacts]") {
  const motion::Motion m = small_clip(3);
  const std::vector<std::vector<bool>> one(3, {true});
  CHECK_THROWS_WITH(assemble_contacts(m, {{"p", {}}}, std::vector<std::vector<bool>>(3)),
                    Catch::Contains("has no vertices"));
  CHECK_THROWS_WITH(assemble_contacts(m, {{"p", {{7, {0, 0, 0}}}}}, one), Catch::Contains("joint 7"));
  CHECK_THROWS_WITH(assemble_contacts(m, {{"p", {{0, {0, 0, 0}}}}, {"p", {{1, {0, 0, 0}}}}},
                                      std::vector<std::vector<bool>>(3, {true, true})),
                    Catch::Contains("two patches are named 'p'"));
  CHECK_THROWS_WITH(
      assemble_contacts(m, {{"p", {{0, {0, 0, 0}}}}}, std::vector<std::vector<bool>>(2, {true})),
      Catch::Contains("activity for 2 frames, the clip has 3"));
  CHECK_THROWS_WITH(
      assemble_contacts(m, {{"p", {{0, {0, 0, 0}}}}}, std::vector<std::vector<bool>>(3, {true, false})),
      Catch::Contains("activity for 2 vertices"));
}

TEST_CASE("Detected feet on a real walk: heel-to-toe soles and alternating support", "[contacts]") {
  const std::string asf = kData + "/cmu/asf_amc/16.asf", amc = kData + "/cmu/asf_amc/16_15.amc";
  if (!std::filesystem::exists(asf) || !std::filesystem::exists(amc)) {
    WARN("skipped: " << amc << " or " << asf << " not found");
    return;
  }
  const motion::Motion walk = io::import_asf_amc(asf, amc, {}).motion;
  const motion::Skeleton& sk = *walk.skeleton;

  SECTION("the sole of a CMU foot") {
    const int lfoot = sk.find_joint("lfoot"), ltoes = sk.find_joint("ltoes");
    ContactVertex heel, tip;
    const int flat = flattest_frame(walk, lfoot);
    const ContactPatch p = foot_patch(sk, walk.values.row(flat), lfoot, {}, &heel, &tip);
    REQUIRE(p.vertices.size() == 4);
    CHECK(p.vertices[0].joint == lfoot);
    CHECK(p.vertices[1].joint == ltoes);
    CHECK(p.vertices[2].joint == ltoes);
    CHECK(p.vertices[3].joint == lfoot);
    std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(sk.joint_count()));
    motion::forward_kinematics(sk, walk.values.row(flat), world);
    // The flattest frame is a stance: the sole is within a few centimetres of the floor.
    const Contacts detected = detect_contacts(walk, {.feet = {"lfoot"}});
    CHECK(detected.frames[static_cast<std::size_t>(flat)].touching(0));
    auto at = [&](const ContactVertex& v) { return world[static_cast<std::size_t>(v.joint)] * v.local; };
    const Eigen::Vector3d ankle = world[static_cast<std::size_t>(lfoot)].translation();
    const Eigen::Vector3d toe_tip =
        world[static_cast<std::size_t>(ltoes)] * sk.joint(ltoes).end_sites.front();
    // A flat rectangle on the sole, heel behind the ankle, tip at the toe tip.
    for (const ContactVertex& v : p.vertices) CHECK(at(v).y() == Approx(at(p.vertices[0]).y()).margin(1e-12));
    CHECK(at(p.vertices[0]).y() < ankle.y() - 0.02);
    Eigen::Vector3d d = toe_tip - ankle;
    d.y() = 0;
    const double length = (at(tip) - at(heel)).norm(), width = (at(p.vertices[1]) - at(p.vertices[2])).norm();
    CHECK(length == Approx(1.25 * d.norm()));
    CHECK(width == Approx(0.36 * length));
    CHECK((at(p.vertices[0]) - at(p.vertices[3])).norm() == Approx(width));
    CHECK((at(heel) - ankle).dot(d) < 0);
    CHECK(length > 0.18);  // a grown-up's foot
    CHECK(length < 0.32);
  }

  SECTION("support alternates: double, single on one foot, double, single on the other") {
    const Contacts c = detect_contacts(walk, {});
    INFO(describe(c));
    REQUIRE(c.patches.size() == 2);
    CHECK(c.patches[0].name == "lfoot");
    CHECK(c.patches[1].name == "rfoot");
    CHECK(c.source == "detected");
    const std::vector<Phase> ph = phases(c);
    int singles = 0, doubles = 0, last_single = -1;
    for (const Phase& p : ph) {
      REQUIRE_FALSE(p.patches.empty());  // a walk never flies
      if (p.patches.size() == 2) {
        ++doubles;
        // Double support lasts a fraction of a step (0.02 to 0.3 s).
        CHECK(p.last - p.first + 1 <= 0.3 * walk.fps);
      } else {
        ++singles;
        if (last_single >= 0) CHECK(p.patches[0] != last_single);  // feet take turns
        last_single = p.patches[0];
      }
    }
    for (std::size_t i = 1; i < ph.size(); ++i) CHECK(ph[i].patches.size() != ph[i - 1].patches.size());
    CHECK(singles >= 6);
    CHECK(doubles >= 5);
    // Heel strike: a foot's first frames after its swing touch with the heel only.
    int heel_strikes = 0;
    for (std::size_t i = 1; i < ph.size(); ++i)
      if (ph[i].patches.size() == 2) {
        const int landing = ph[i - 1].patches[0] == 0 ? 1 : 0;
        bool heel_only = true;
        for (const ContactPoint& p : c.frames[static_cast<std::size_t>(ph[i].first)].points)
          if (p.patch == landing && (p.vertex == 1 || p.vertex == 2)) heel_only = false;
        heel_strikes += heel_only ? 1 : 0;
      }
    CHECK(heel_strikes >= 4);
  }

  SECTION("named feet, and their errors") {
    const Contacts c = detect_contacts(walk, {.feet = {"rfoot"}});
    REQUIRE(c.patches.size() == 1);
    CHECK(c.patches[0].name == "rfoot");
    CHECK_THROWS_WITH(detect_contacts(walk, {.feet = {"lfot"}}),
                      Catch::Contains("unknown foot joint 'lfot'") && Catch::Contains("lfoot"));
    CHECK_THROWS_WITH(detect_contacts(walk, {.feet = {"lfoot"}, .width_ratio = 0}),
                      Catch::Contains("width_ratio"));
  }
}

TEST_CASE("A landing's impact touches though the feet still slide: the root is held up", "[contacts]") {
  // CMU 13_13 (Daz BVH), a forward jump: its feet strike the floor still moving forward, faster
  // than plants admit, while the floor already stops the fall (the root accelerates upwards).
  const std::string path = kData + "/cmu/bvh_daz/13_13.bvh";
  if (!std::filesystem::exists(path)) {
    WARN("skipped: " << path << " not found");
    return;
  }
  const motion::Motion captured = io::import_bvh(path, {}).motion;
  // At 30 Hz (the paper's rate) and at the capture's 120 Hz (second differences over 4 frames).
  const double fps = GENERATE(30.0, 120.0);
  CAPTURE(fps);
  const motion::Motion jump = fps == captured.fps ? captured : motion::resample(captured, fps);
  const int k = static_cast<int>(std::lround(fps / 30));
  const Contacts plain = detect_contacts(jump, {.support_acceleration = 0});
  const Contacts held = detect_contacts(jump, {});
  // The longest run without contact by plants alone: the jump's flight and its misread ends.
  const std::vector<Phase> before = phases(plain);
  Phase flight{{}, 0, -1};
  for (const Phase& p : before)
    if (p.patches.empty() && p.last - p.first > flight.last - flight.first) flight = p;
  INFO(describe(plain) << "-- with support:\n" << describe(held));
  REQUIRE(flight.last - flight.first + 1 >= 15 * k);
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(jump.skeleton->joint_count()));
  auto root_height = [&](int f) {
    motion::forward_kinematics(*jump.skeleton, jump.values.row(f), world);
    return world.front().translation().y();
  };
  int gained = 0, last_gained = -1;
  for (int f = 0; f < jump.frame_count(); ++f) {
    const bool was = !plain.frames[static_cast<std::size_t>(f)].points.empty();
    const bool is = !held.frames[static_cast<std::size_t>(f)].points.empty();
    CHECK((is || !was));  // support only adds
    if (is == was) continue;
    ++gained;
    last_gained = f;
    // Only where the root is held up (and, by construction, at the ends of runs without plants:
    // here the landing of the jump and the Daz T-pose's frame 1).
    const double acceleration =
        (root_height(f + k) - 2 * root_height(f) + root_height(f - k)) * (fps / k) * (fps / k);
    CHECK(acceleration > -9.81 + 4.9);
  }
  CHECK(gained >= 1);
  CHECK(last_gained == flight.last);  // the landing's impact
  // The flight itself stays without contact: at least 0.4 s of it.
  int still_flying = 0;
  for (int f = flight.first; f <= flight.last; ++f)
    still_flying += held.frames[static_cast<std::size_t>(f)].points.empty();
  CHECK(still_flying >= 12 * k);
  CHECK_THROWS_WITH(detect_contacts(jump, {.support_acceleration = -1}),
                    Catch::Contains("support_acceleration"));
}

TEST_CASE("Detected feet on the MotionBuilder BVH of the same walk", "[contacts]") {
  const std::string path = kData + "/cmu/bvh_motionbuilder/16_15.bvh";
  if (!std::filesystem::exists(path)) {
    WARN("skipped: " << path << " not found");
    return;
  }
  const motion::Motion walk = io::import_motion(path, "", {}).motion;
  const Contacts c = detect_contacts(walk, {});
  INFO(describe(c));
  REQUIRE(c.patches.size() == 2);
  CHECK(c.patches[0].name == "lfoot");
  // Its rest pose points the feet at the floor; the soles come from a stance frame instead.
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(walk.skeleton->joint_count()));
  const int flat = flattest_frame(walk, walk.skeleton->find_joint("lfoot"));
  motion::forward_kinematics(*walk.skeleton, walk.values.row(flat), world);
  auto at = [&](const ContactVertex& v) { return world[static_cast<std::size_t>(v.joint)] * v.local; };
  const double length = (at(c.patches[0].vertices[1]) - at(c.patches[0].vertices[0])).norm();
  CHECK(length > 0.18);
  CHECK(length < 0.32);
  int single = 0, both = 0;
  for (const ContactFrame& f : c.frames)
    (f.patches().size() == 2 ? both : single) += f.patches().size() > 0 ? 1 : 0;
  CHECK(single > 2 * both);
  CHECK(both > 0.1 * c.frame_count());
}

TEST_CASE("Contact files", "[contacts]") {
  const motion::Motion m = small_clip(60);
  SECTION("patches on named joints, frame and time ranges") {
    const Contacts c = read_contacts_string(R"(version: 1
doc: "a hand on a rail, a foot on the floor"
patches:
  - name: palm
    joint: lhand
    vertices: [[0, -0.1, 0.02], [0.02, -0.1, -0.02]]
    frames: [[0, 9], [30, 39]]
  - joint: rfoot
    vertices: [[0, -0.05, 0.1]]
    times: [0.5, 1.0]
)",
                                            "rail.yaml", m);
    CHECK(c.source == "rail.yaml");
    REQUIRE(c.patches.size() == 2);
    CHECK(c.patches[0].name == "palm");
    CHECK(c.patches[1].name == "rfoot");
    CHECK(c.patches[0].vertices[1].local == Eigen::Vector3d(0.02, -0.1, -0.02));
    CHECK(c.patches[0].vertices[0].joint == 1);
    REQUIRE(c.frame_count() == 60);
    auto touching = [&](int f, int p) { return c.frames[static_cast<std::size_t>(f)].touching(p); };
    CHECK(touching(0, 0));
    CHECK(touching(9, 0));
    CHECK_FALSE(touching(10, 0));
    CHECK(touching(35, 0));
    CHECK_FALSE(touching(40, 0));
    // times [0.5, 1.0] at 30 fps: frames 15..30.
    CHECK_FALSE(touching(14, 1));
    CHECK(touching(15, 1));
    CHECK(touching(30, 1));
    CHECK_FALSE(touching(31, 1));
    CHECK(c.frames[30].points.size() == 3);
    CHECK(c.frames[20].patches() == std::vector<int>{1});
    // Jacobians as the kinematics give them.
    std::vector<Eigen::Isometry3d> world(3);
    motion::forward_kinematics(*m.skeleton, m.values.row(30), world);
    Eigen::Matrix<double, 3, Eigen::Dynamic> J(3, m.skeleton->channel_count());
    motion::point_jacobian(*m.skeleton, m.values.row(30), world, 2, {0, -0.05, 0.1}, J);
    CHECK(c.frames[30].points[2].jacobian.isApprox(J));
  }

  SECTION("errors name the file, line, column and key") {
    struct Bad {
      std::string text, message, where;
    };
    const std::string patch = "patches:\n  - joint: lhand\n    vertices: [[0, 0, 0]]\n";
    const std::vector<Bad> bad{
        {"", "empty contact file", "bad.yaml:1:1"},
        {"[1, 2]", "must be a map", "bad.yaml:1:1"},
        {"version: 1\npatches: [\n", "malformed YAML", "bad.yaml:"},
        {"patches: []\n", "missing 'version: 1'", "bad.yaml:1:1"},
        {"version: 2\npatches: []\n", "unsupported version 2", "bad.yaml:1:10"},
        {"version: one\npatches: []\n", "version: expected an integer, got 'one'", "bad.yaml:1:10"},
        {"version: 1\n", "missing 'patches'", "bad.yaml:1:1"},
        {"version: 1\npatch: []\n", "unknown key 'patch' (did you mean 'patches'?)", "bad.yaml:2:1"},
        {"version: 1\npatches: {joint: lhand}\n", "patches: expected a list", "bad.yaml:2:10"},
        {"version: 1\npatches:\n  - 3\n", "patches[0]: expected a map", "bad.yaml:3:5"},
        {"version: 1\n" + patch + "    frames: [0, 5]\n    vertex: []\n",
         "unknown key 'patches[0].vertex' (did you mean 'vertices'?)", "bad.yaml:6:5"},
        {"version: 1\npatches:\n  - vertices: [[0, 0, 0]]\n    frames: [0, 5]\n",
         "patches[0]: missing 'joint'", "bad.yaml:3:5"},
        {"version: 1\npatches:\n  - joint: lhnd\n    vertices: [[0, 0, 0]]\n    frames: [0, 5]\n",
         "patches[0].joint: unknown joint 'lhnd' (did you mean 'lhand'?)", "bad.yaml:3:12"},
        {"version: 1\npatches:\n  - joint: lhand\n    frames: [0, 5]\n", "patches[0]: missing 'vertices'",
         "bad.yaml:3:5"},
        {"version: 1\npatches:\n  - joint: lhand\n    vertices: []\n    frames: [0, 5]\n",
         "patches[0].vertices: expected a non-empty list", "bad.yaml:4:15"},
        {"version: 1\npatches:\n  - joint: lhand\n    vertices: [[0, 0]]\n    frames: [0, 5]\n",
         "patches[0].vertices[0]: expected [x, y, z]", "bad.yaml:4:16"},
        {"version: 1\npatches:\n  - joint: lhand\n    vertices: [[0, zero, 0]]\n    frames: [0, 5]\n",
         "patches[0].vertices[0]: expected a number, got 'zero'", "bad.yaml:4:20"},
        {"version: 1\npatches:\n  - joint: lhand\n    vertices: [[0, .nan, 0]]\n    frames: [0, 5]\n",
         "patches[0].vertices[0]: expected a number, got '.nan'", "bad.yaml:4:20"},
        {"version: 1\npatches:\n  - joint: lhand\n    vertices: [[0, .inf, 0]]\n    frames: [0, 5]\n",
         "patches[0].vertices[0]: infinity is not allowed here (expected a finite number), got '.inf'",
         "bad.yaml:4:20"},
        {"version: 1\n" + patch + "    times: [0, -.inf]\n",
         "patches[0].times: infinity is not allowed here (expected a finite number), got '-.inf'",
         "bad.yaml:5:16"},
        {"version: 1\n" + patch, "patches[0]: missing 'frames' (or 'times')", "bad.yaml:3:5"},
        {"version: 1\n" + patch + "    frames: [0, 5]\n    times: [0, 1]\n",
         "give one of 'frames' and 'times'", "bad.yaml:6:12"},
        {"version: 1\n" + patch + "    frames: [9, 5]\n", "patches[0].frames: the range [9, 5] is reversed",
         "bad.yaml:5:13"},
        {"version: 1\n" + patch + "    frames: [[0, 5], [50, 60]]\n",
         "patches[0].frames[1]: frames [50, 60] are outside the clip (frames 0..59)", "bad.yaml:5:22"},
        {"version: 1\n" + patch + "    frames: [[0, 5, 6]]\n",
         "patches[0].frames[0]: expected [first, last] frames", "bad.yaml:5:14"},
        {"version: 1\n" + patch + "    frames: []\n",
         "patches[0].frames: expected a list of [first, last] ranges", "bad.yaml:5:13"},
        {"version: 1\n" + patch + "    frames: [0, 2.5]\n",
         "patches[0].frames: expected an integer, got '2.5'", "bad.yaml:5:17"},
        {"version: 1\n" + patch + "    times: [-1, 0.5]\n", "patches[0].times: a time must be >= 0 s",
         "bad.yaml:5:13"},
        {"version: 1\n" + patch + "    times: [0, 3]\n",
         "patches[0].times: 3 s is outside the clip (0..1.96667 s, frames 0..59 at 30 fps)", "bad.yaml:5:16"},
        {"version: 1\n" + patch + "    times: [3.0, 3.1]\n", "patches[0].times: 3 s is outside the clip",
         "bad.yaml:5:13"},
        // Fuzzing (issue 13): times whose frame overflowed int through lround and wrapped into the clip.
        {"version: 1\n" + patch + "    times: [35791394.2, 35791394.3]\n",
         "patches[0].times: 35791394.2 s is outside the clip (0..1.96667 s, frames 0..59 at 30 fps)",
         "bad.yaml:5:13"},
        {"version: 1\n" + patch + "    times: [1e300, 1e300]\n",
         "patches[0].times: 1e+300 s is outside the clip", "bad.yaml:5:13"},
        {"version: 1\n" + patch + "    times: [0, 1.99]\n", "patches[0].times: 1.99 s is outside the clip",
         "bad.yaml:5:16"},
        {"version: 1\n" + patch + "    frames: [0, 5]\n" +
             "  - joint: lhand\n    vertices: [[0, 0, 0]]\n    frames: [0, 5]\n",
         "patches[1].name: a patch named 'lhand' is already defined (name the patches apart)",
         "bad.yaml:6:5"},
    };
    for (const Bad& b : bad) {
      INFO(b.text);
      try {
        read_contacts_string(b.text, "bad.yaml", m);
        FAIL("no error");
      } catch (const kg::Error& e) {
        CHECK_THAT(e.what(), Catch::Contains(b.message));
        CHECK_THAT(e.what(), Catch::StartsWith(b.where));
      }
    }
    CHECK_THROWS_WITH(read_contacts_file("/nonexistent/contacts.yaml", m),
                      Catch::Contains("/nonexistent/contacts.yaml"));
  }
}

TEST_CASE("The retime.contacts node", "[contacts][nodes]") {
  const graph::Registry registry = test::registry_of(retime_contact_node_types());
  SECTION("from a file") {
    const motion::Motion m = small_clip(40);
    test::TempDir dir;
    const auto path =
        dir.write("c.yaml",
                  "version: 1\npatches:\n  - joint: rfoot\n    vertices: [[0, 0, 0], [0.1, 0, 0]]\n"
                  "    frames: [[0, 9], [20, 24]]\n");
    const test::NodeContext ctx = test::run_node(
        registry, "retime.contacts", test::params_for(registry, "retime.contacts", {{"path", path.string()}}),
        {{"motion", graph::Value::make(m)}});
    const Contacts& c = ctx.outputs.at("contacts").get<Contacts>();
    CHECK(c.frame_count() == 40);
    CHECK(std::get<std::int64_t>(ctx.figures.at("patches")) == 1);
    CHECK(std::get<std::int64_t>(ctx.figures.at("frames_one_patch")) == 15);
    CHECK(std::get<std::int64_t>(ctx.figures.at("frames_without_contact")) == 25);
    CHECK(std::get<std::int64_t>(ctx.figures.at("touching_vertices")) == 30);
    CHECK(std::get<std::string>(ctx.figures.at("source")) == path.string());
  }
  SECTION("detected, and bad params") {
    const std::string asf = kData + "/cmu/asf_amc/16.asf", amc = kData + "/cmu/asf_amc/16_15.amc";
    CHECK_THROWS_WITH(
        registry.create_node("retime.contacts",
                             test::params_for(registry, "retime.contacts", {{"floor", std::string("low")}})),
        Catch::Contains("floor 'low'"));
    if (!std::filesystem::exists(asf) || !std::filesystem::exists(amc)) {
      WARN("skipped: " << amc << " not found");
      return;
    }
    const motion::Motion walk = io::import_asf_amc(asf, amc, {}).motion;
    const test::NodeContext ctx =
        test::run_node(registry, "retime.contacts",
                       test::params_for(registry, "retime.contacts", {{"feet", std::string("lfoot, rfoot")}}),
                       {{"motion", graph::Value::make(walk)}});
    CHECK(std::get<std::int64_t>(ctx.figures.at("patches")) == 2);
    CHECK(std::get<std::int64_t>(ctx.figures.at("frames_without_contact")) == 0);
    CHECK(std::get<std::int64_t>(ctx.figures.at("frames_more_patches")) > 0);
    CHECK(ctx.logged("foot lfoot: heel on lfoot, tip on ltoes"));
  }
}

TEST_CASE("A given floor is where the soles touch", "[contacts]") {
  const std::string asf = kData + "/cmu/asf_amc/16.asf", amc = kData + "/cmu/asf_amc/16_15.amc";
  if (!std::filesystem::exists(asf) || !std::filesystem::exists(amc)) {
    WARN("skipped: " << amc << " or " << asf << " not found");
    return;
  }
  const motion::Motion walk = motion::resample(io::import_asf_amc(asf, amc, {}).motion, 30);
  auto touching_frames = [](const Contacts& c) {
    int n = 0;
    for (const ContactFrame& f : c.frames) n += !f.points.empty();
    return n;
  };
  const Contacts automatic = detect_contacts(walk, {});
  REQUIRE(touching_frames(automatic) == automatic.frame_count());  // a walk always has a foot down
  FootContactOptions at_floor;
  at_floor.plants.floor = 0.0026;  // the estimate's value, given
  CHECK(touching_frames(detect_contacts(walk, at_floor)) >= automatic.frame_count() - 2);
  // Half a metre below the feet: no sole comes near it.
  FootContactOptions below;
  below.plants.floor = -0.5;
  const Contacts none = detect_contacts(walk, below);
  INFO(describe(none));
  CHECK(touching_frames(none) == 0);
  CHECK(std::any_of(none.notes.begin(), none.notes.end(), [](const std::string& n) {
    return n.find("floor (given): -0.5 m") != std::string::npos;
  }));
}
