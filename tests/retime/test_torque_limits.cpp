// Torque limits observed in the source motion (torque_limits.hpp): a hand-made body whose torques
// are known in closed form (stance, a foot slipping beyond friction, flight, an infeasible frame,
// several clips), the margin's linearity, the guarantee that the clip's timing stays inside its
// hulls, mirrored joints, bad input, and the CMU walk 16_15.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <string>

#include "hull_test_bodies.hpp"
#include "kg/body/body_build.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/motion/resample.hpp"
#include "kg/retime/dynamics.hpp"
#include "kg/retime/force_model.hpp"
#include "kg/retime/torque_limits.hpp"

using namespace kg;
using namespace kg::retime;
using namespace kg::body;

namespace {

const std::string kData = KG_DATA_DIR;
constexpr double kInf = INFINITY;

// The hand-made body. A point mass m with moment of inertia I about world Z at the root's origin
// (root channels X, Y, Z position and Z rotation); a massless leg: "hip" (Z rotation at the root)
// and "shin" (Y position, offset (d, −L, 0) from the hip) whose origin is the foot; a massless
// "arm" turning about the root's Z axis carrying a disc of inertia J about that axis (no mass);
// a massless "finger" on the arm that nothing ever loads. Channels: 0-2 root position, 3 root
// rotation, 4 hip, 5 shin, 6 arm, 7 finger. With the foot force f at r = (d, −L, 0) from the root,
// at the original timing:
//   root: m q''_root − m g = f;   (I + J) α + J β = d f_y + L f_x   (α, β: root and arm q'')
//   hip: τ = −(d f_y + L f_x);   shin: τ = −f_y;   arm: τ = J (α + β);   finger: 0.
constexpr double kMass = 60, kInertia = 10, kDisc = 1, kSide = 0.1, kLeg = 1, kMu = 0.5, kG = 9.81;
constexpr int kHip = 4, kShin = 5, kArm = 6, kFinger = 7;

struct HandFrame {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();  // root q'' (position)
  Eigen::Vector3d v = Eigen::Vector3d::Zero();  // root q' (position)
  double alpha = 0, omega = 0;                  // root rotation q'', q'
  double beta = 0, beta_dot = 0;                // arm q'', q'
  bool contact = true;
};

FrameTorques hand_torques(const HandFrame& f) {
  const double turning = kInertia + kDisc;
  FrameTorques t;
  t.velocity = Eigen::VectorXd::Zero(8);
  t.acceleration = Eigen::VectorXd::Zero(8);
  t.gravity = Eigen::Matrix<double, Eigen::Dynamic, 3>::Zero(8, 3);
  t.velocity.head<3>() = kMass * f.a;
  t.velocity[3] = turning * f.alpha + kDisc * f.beta;
  t.velocity[kArm] = kDisc * (f.alpha + f.beta);
  t.acceleration.head<3>() = kMass * f.v;
  t.acceleration[3] = turning * f.omega + kDisc * f.beta_dot;
  t.acceleration[kArm] = kDisc * (f.omega + f.beta_dot);
  t.gravity.topRows<3>() = -kMass * Eigen::Matrix3d::Identity();
  return t;
}

// A stance frame captured consistently: the root's turning matches the foot's moment at (0, 1).
HandFrame stance(double ax, double ay) {
  HandFrame f;
  f.a = {ax, ay, 0};
  const double fx = kMass * ax, fy = kMass * (ay + kG);
  f.alpha = (kSide * fy + kLeg * fx) / (kInertia + kDisc);
  return f;
}
double stance_hip(double ax, double ay) {
  return std::abs(kSide * kMass * (ay + kG) + kLeg * kMass * ax);
}

// The foot accelerating at 6 m/s² with friction 0.5: (0, 1) needs 6 m > μ m g; the root's turning
// pins ṗ² = 1, so the nearest timing slows down: p̈ = μ g − 6, where f_x = μ m g.
HandFrame slipping() {
  HandFrame f;
  f.a = {6, 0, 0};
  f.v = {1, 0, 0};
  f.alpha = (kSide * kMass * kG + 6 * kLeg * kMass) / (kInertia + kDisc);
  f.omega = kLeg * kMass / (kInertia + kDisc);
  return f;
}

// Ballistic root, the arm whipping (β = 300): the root's turning row J β ṗ² = 0 and its vertical
// row m g (1 − ṗ²) = 0 disagree, so the least-squares point is not (0, 1).
HandFrame flying() {
  HandFrame f;
  f.a = {0, -kG, 0};
  f.v = {1, 0, 0};
  f.beta = 300;
  f.contact = false;
  return f;
}

// Infeasible at every timing: standing still (no turning) on a foot d to the side, the moment d m g
// unbalanced whatever the timing; pushing up (a_y = 5) only adds to it.
HandFrame infeasible() {
  HandFrame f;
  f.a = {0, 5, 0};
  return f;
}

struct HandClip {
  std::vector<FrameTorques> torques;
  Contacts contacts;
  ClipLoads loads() const { return {&contacts, torques, ""}; }
};

struct HandBody {
  std::shared_ptr<const motion::Skeleton> skeleton;
  BodyModel body;

  HandClip clip(const std::vector<HandFrame>& frames) const {
    Eigen::RowVectorXd pose = Eigen::RowVectorXd::Zero(8);
    pose[1] = kLeg;  // the root at the leg's height: the foot on the floor
    pose[kShin] = -kLeg;
    motion::Motion m{skeleton, motion::FrameMatrix(static_cast<Eigen::Index>(frames.size()), 8), 30.0,
                     "hand"};
    std::vector<std::vector<bool>> active;
    HandClip c;
    for (std::size_t f = 0; f < frames.size(); ++f) {
      m.values.row(static_cast<Eigen::Index>(f)) = pose;
      active.push_back({frames[f].contact});
      c.torques.push_back(hand_torques(frames[f]));
    }
    c.contacts = assemble_contacts(m, {{"foot", {{2, {0, 0, 0}}}}}, active);  // the shin's origin
    return c;
  }
};

HandBody hand_body() {
  using motion::ChannelKind;
  auto sk = kg::test::skeleton_of(
      {{.name = "body",
        .parent = -1,
        .channels = {{ChannelKind::Xposition},
                     {ChannelKind::Yposition},
                     {ChannelKind::Zposition},
                     {ChannelKind::Zrotation}}},
       {.name = "hip", .parent = 0, .channels = {{ChannelKind::Zrotation}}},
       {.name = "shin", .parent = 1, .offset = {kSide, -kLeg, 0}, .channels = {{ChannelKind::Yposition}}},
       {.name = "arm", .parent = 0, .channels = {{ChannelKind::Zrotation}}},
       {.name = "finger", .parent = 3, .offset = {0.3, 0, 0}, .channels = {{ChannelKind::Zrotation}}}});
  HandBody h{sk, kg::test::body_of(sk, kMu)};
  h.body.segments[0].mass = kMass;
  h.body.segments[0].inertia = kInertia * Eigen::Matrix3d::Identity();
  // The coefficients above are the physics (the arm's disc has no mass to put in a segment);
  // the body model carries the skeleton, friction and limits: the root unactuated, the rest free.
  h.body.torque_min.tail(4).setConstant(-kInf);
  h.body.torque_max.tail(4).setConstant(kInf);
  return h;
}

// Every frame the estimate observed at its hull centre keeps that centre inside its new hull (up
// to the tolerance); returns how many frames had (0, 1) within the tolerance.
int check_guarantee(const BodyModel& limited, const TorqueLimitEstimate& e, std::size_t clip_index,
                    const Contacts& contacts, std::span<const FrameTorques> torques) {
  const HullOptions o;
  const Hulls h = build_hulls(limited, contacts, torques, o);
  int original = 0;
  for (std::size_t f = 0; f < h.frames.size(); ++f) {
    const ObservedFrame& seen = e.frames[clip_index][f];
    const FrameHull& hull = h.frames[f];
    const HullPoint c = closest_point_on_polygon(hull.vertices, {0, 1});
    if (hull.status == HullStatus::Feasible && std::sqrt(c.distance_squared) <= o.tolerance) ++original;
    if (seen.use != FrameUse::Original && seen.use != FrameUse::Nearest) continue;
    INFO("frame " << f << " observed " << to_string(seen.use) << " at (" << seen.timing.x() << ", "
                  << seen.timing.y() << "); hull: " << to_string(hull.status) << " " << hull.message);
    REQUIRE(hull.status == HullStatus::Feasible);
    const HullPoint p = closest_point_on_polygon(hull.vertices, seen.timing);
    CHECK(std::sqrt(p.distance_squared) <= o.tolerance);
  }
  return original;
}

}  // namespace

TEST_CASE("A hand-made body: limits from the torques its frames are known to need", "[torque_limits]") {
  const HandBody hb = hand_body();
  const HandClip a = hb.clip({stance(0, 0), stance(2, 1), stance(-3, 0), slipping(), flying()});
  const TorqueLimitEstimate e = estimate_torque_limits(
      hb.body, a.contacts, a.torques, {.margin = 1.5, .floor = 5, .position_channels = true});
  INFO(e.notes[0] << "; " << e.notes[1]);

  SECTION("how each frame was observed") {
    REQUIRE(e.frames.size() == 1);
    REQUIRE(e.frames[0].size() == 5);
    for (int f : {0, 1, 2}) {
      CHECK(e.frames[0][static_cast<std::size_t>(f)].use == FrameUse::Original);
      CHECK(e.frames[0][static_cast<std::size_t>(f)].timing == Eigen::Vector2d(0, 1));
    }
    CHECK(e.frames[0][3].use == FrameUse::Nearest);
    CHECK(e.frames[0][3].timing.x() == Approx(kMu * kG - 6).epsilon(1e-6));
    CHECK(e.frames[0][3].timing.y() == Approx(1).epsilon(1e-6));
    CHECK(e.frames[0][4].use == FrameUse::Flight);
    CHECK(e.frames[0][4].timing == Eigen::Vector2d(0, 1));
    CHECK(e.count(FrameUse::Original) == 3);
  }

  SECTION("peaks and limits") {
    // hip: the slipping foot at its nearest timing, m g (d + μ L) (at (0, 1) it would be d m g + 6 L m).
    const double hip = kMass * kG * (kSide + kMu * kLeg);
    CHECK(hip > stance_hip(2, 1));
    CHECK(e.peak[kHip] == Approx(hip).epsilon(1e-6));
    CHECK(e.peak_frame[kHip] == 3);
    CHECK(e.peak_clip[kHip] == 0);
    // shin: the largest floor force, m (1 + 9.81) in frame 1.
    CHECK(e.peak[kShin] == Approx(kMass * (1 + kG)).epsilon(1e-6));
    CHECK(e.peak_frame[kShin] == 1);
    // arm: the flight frame at (0, 1), J β; the least-squares point would give J β ṗ², ṗ² ≈ 0.79.
    CHECK(e.peak[kArm] == Approx(kDisc * 300).epsilon(1e-9));
    CHECK(e.peak_frame[kArm] == 4);
    const FrameHull air =
        build_frame_hull(without_torque_limits(hb.body), a.contacts.frames[4], a.torques[4], {});
    REQUIRE(air.status == HullStatus::Flight);
    const double s = std::pow(kMass * kG, 2) / (std::pow(kMass * kG, 2) + std::pow(kDisc * 300, 2));
    CHECK(air.vertices[0].y() == Approx(s).epsilon(1e-6));
    // finger: never loaded: the floor.
    CHECK(e.peak[kFinger] == 0);
    CHECK(e.peak_frame[kFinger] == -1);

    for (int c = 0; c < 4; ++c) {
      CHECK(e.body.torque_min[c] == 0);
      CHECK(e.body.torque_max[c] == 0);
      CHECK_FALSE(e.estimated[static_cast<std::size_t>(c)]);
    }
    CHECK(e.body.torque_max[kHip] == Approx(1.5 * hip).epsilon(1e-6));
    CHECK(e.body.torque_min[kHip] == -e.body.torque_max[kHip]);
    CHECK(e.body.torque_max[kShin] == Approx(1.5 * kMass * (1 + kG)).epsilon(1e-6));
    CHECK(e.body.torque_max[kArm] == Approx(450).epsilon(1e-9));
    CHECK(e.body.torque_max[kFinger] == 5);
    CHECK(e.body.torque_min[kFinger] == -5);
    CHECK(e.notes.back().find("finger.Zrotation") != std::string::npos);
    // The rest of the body is the input's.
    CHECK(e.body.friction == hb.body.friction);
    CHECK(e.body.segments[0].mass == kMass);
    check_body_model(e.body);
  }

  SECTION("position channels keep the body's bounds unless asked") {
    const TorqueLimitEstimate r = estimate_torque_limits(hb.body, a.contacts, a.torques, {.floor = 5});
    CHECK_FALSE(r.estimated[kShin]);
    CHECK(r.body.torque_max[kShin] == kInf);
    CHECK(r.body.torque_min[kShin] == -kInf);
    CHECK(r.peak[kShin] == 0);
    CHECK(r.body.torque_max[kHip] == Approx(e.body.torque_max[kHip]).epsilon(1e-9));
    BodyModel bounded = hb.body;
    bounded.torque_min[kShin] = -2000;
    bounded.torque_max[kShin] = 2000;
    CHECK(estimate_torque_limits(bounded, a.contacts, a.torques, {}).body.torque_max[kShin] == 2000);
  }

  SECTION("a channel the body bounds to [0, 0] stays unactuated") {
    BodyModel pinned = hb.body;
    pinned.torque_min[kArm] = pinned.torque_max[kArm] = 0;
    const TorqueLimitEstimate r = estimate_torque_limits(pinned, a.contacts, a.torques, {.floor = 5});
    CHECK_FALSE(r.estimated[kArm]);
    CHECK(r.body.torque_max[kArm] == 0);
    CHECK(r.body.torque_min[kArm] == 0);
  }
}

TEST_CASE("Several clips: each channel's limit comes from its largest peak over all of them",
          "[torque_limits]") {
  const HandBody hb = hand_body();
  const HandClip a = hb.clip({stance(0, 0), stance(2, 1), stance(-3, 0), slipping(), flying()});
  const HandClip b = hb.clip({stance(5, 3), stance(1, 0)});  // 300 N against μ f_y = 384 N
  const ClipLoads clips[] = {a.loads(), {&b.contacts, b.torques, "push"}};
  const TorqueLimitEstimate e =
      estimate_torque_limits(hb.body, clips, {.margin = 2, .position_channels = true});
  REQUIRE(e.frames.size() == 2);
  CHECK(e.frames[1].size() == 2);
  CHECK(e.peak[kHip] == Approx(stance_hip(5, 3)).epsilon(1e-6));
  CHECK(e.peak_clip[kHip] == 1);
  CHECK(e.peak_frame[kHip] == 0);
  CHECK(e.peak[kShin] == Approx(kMass * (3 + kG)).epsilon(1e-6));
  CHECK(e.peak_clip[kShin] == 1);
  CHECK(e.peak[kArm] == Approx(300).epsilon(1e-9));  // still clip 0's flight
  CHECK(e.peak_clip[kArm] == 0);
  CHECK(e.body.torque_max[kHip] == Approx(2 * stance_hip(5, 3)).epsilon(1e-6));
  CHECK(e.body.torque_max[kFinger] == 0);  // floor 0: pinned, as the header warns
  CHECK(e.notes[0].find("over 2 clips") != std::string::npos);
}

TEST_CASE("Infeasible frames: skipped, or observed at their least-squares point", "[torque_limits]") {
  const HandBody hb = hand_body();
  const HandClip c = hb.clip({infeasible()});
  const FrameHull h =
      build_frame_hull(without_torque_limits(hb.body, true), c.contacts.frames[0], c.torques[0], {});
  REQUIRE(h.status == HullStatus::Infeasible);

  const TorqueLimitEstimate skip =
      estimate_torque_limits(hb.body, c.contacts, c.torques, {.floor = 7, .position_channels = true});
  CHECK(skip.frames[0][0].use == FrameUse::Skipped);
  CHECK(skip.count(FrameUse::Skipped) == 1);
  CHECK(skip.peak.isZero());
  for (int ch : {kHip, kShin, kArm, kFinger}) CHECK(skip.body.torque_max[ch] == 7);

  const TorqueLimitEstimate ls = estimate_torque_limits(
      hb.body, c.contacts, c.torques,
      {.floor = 7, .position_channels = true, .infeasible = InfeasibleFrames::LeastSquares});
  CHECK(ls.frames[0][0].use == FrameUse::LeastSquares);
  // The least squares of the root's rows over f and ṗ² >= 0 stops the clip (ṗ² = 0: the push only
  // adds to the unbalanced moment) and leans on friction: f_y = m g / (1 + d²/(1 + L²)),
  // f_x = −L d f_y / (1 + L²); hip τ = −(d f_y + L f_x) = −d f_y / (1 + L²).
  // (The hulls' tie-breaking Tikhonov term, 1e-9 of the problem's scale towards λ = 0, moves the
  // forces by a few 1e-5 of themselves.)
  CHECK(ls.frames[0][0].timing.x() == Approx(0).margin(1e-6));
  CHECK(ls.frames[0][0].timing.y() == Approx(0).margin(1e-6));
  const double fy = kMass * kG / (1 + kSide * kSide / (1 + kLeg * kLeg));
  CHECK(ls.peak[kShin] == Approx(fy).epsilon(2e-4));
  CHECK(ls.peak[kHip] == Approx(kSide * fy / (1 + kLeg * kLeg)).epsilon(2e-4));
  CHECK(ls.body.torque_max[kShin] == Approx(1.5 * ls.peak[kShin]).epsilon(1e-12));
  CHECK(ls.peak[kFinger] == 0);
}

TEST_CASE("The margin scales the limits linearly", "[torque_limits]") {
  const HandBody hb = hand_body();
  const HandClip a = hb.clip({stance(0, 0), stance(2, 1), stance(-3, 0), slipping(), flying()});
  const TorqueLimitEstimate one = estimate_torque_limits(hb.body, a.contacts, a.torques, {.margin = 1});
  for (double margin : {0.5, 1.5, 3.0}) {
    const TorqueLimitEstimate e = estimate_torque_limits(hb.body, a.contacts, a.torques, {.margin = margin});
    INFO("margin " << margin);
    CHECK(e.peak == one.peak);
    for (int ch : {kHip, kArm}) {
      CHECK(e.body.torque_max[ch] == Approx(margin * one.body.torque_max[ch]).epsilon(1e-12));
      CHECK(e.body.torque_min[ch] == Approx(margin * one.body.torque_min[ch]).epsilon(1e-12));
    }
  }
  // The floor takes over where margin x peak falls below it.
  const TorqueLimitEstimate floored =
      estimate_torque_limits(hb.body, a.contacts, a.torques, {.margin = 1, .floor = 320});
  CHECK(floored.body.torque_max[kArm] == 320);
  CHECK(floored.body.torque_max[kHip] == Approx(one.body.torque_max[kHip]));
}

TEST_CASE("With margin >= 1 the clip's own timing stays inside every hull it was observed in",
          "[torque_limits]") {
  const HandBody hb = hand_body();
  const HandClip a = hb.clip({stance(0, 0), stance(2, 1), stance(-3, 0), slipping(), flying()});
  for (double margin : {1.0, 1.5}) {
    INFO("margin " << margin);
    const TorqueLimitEstimate e =
        estimate_torque_limits(hb.body, a.contacts, a.torques, {.margin = margin, .position_channels = true});
    CHECK(check_guarantee(e.body, e, 0, a.contacts, a.torques) == 3);
  }
  // Below 1 the peak frames fall out: the shin cannot hold the body up at (0, 1) in frame 1.
  const TorqueLimitEstimate weak =
      estimate_torque_limits(hb.body, a.contacts, a.torques, {.margin = 0.9, .position_channels = true});
  const Hulls h = build_hulls(weak.body, a.contacts, a.torques, {});
  const bool outside = h.frames[1].status != HullStatus::Feasible ||
                       closest_point_on_polygon(h.frames[1].vertices, {0, 1}).distance_squared > 1e-6;
  CHECK(outside);
}

TEST_CASE("Mirrored joints pair by their names", "[torque_limits]") {
  using motion::ChannelKind;
  const std::vector<motion::Channel> rxyz{
      {ChannelKind::Xrotation}, {ChannelKind::Yrotation}, {ChannelKind::Zrotation}};
  std::vector<motion::Joint> joints{{.name = "root", .parent = -1, .channels = rxyz}};
  for (const char* name :
       {"lfemur", "rfemur", "LeftUpLeg", "RightUpLeg", "CC_Base_L_Thigh", "CC_Base_R_Thigh", "Thigh_R",
        "Thigh_L", "lThigh", "rThigh", "lowerback", "UpperLeg.L", "UpperLeg.R"})
    joints.push_back({.name = name, .parent = 0, .channels = rxyz});
  joints.push_back({.name = "lhand", .parent = 0, .channels = rxyz});
  joints.push_back({.name = "rhand", .parent = 0, .channels = {{ChannelKind::Xrotation}}});  // kinds differ
  const auto sk = kg::test::skeleton_of(joints);
  std::vector<std::pair<std::string, std::string>> names;
  for (const auto& [a, b] : mirrored_joints(*sk)) names.emplace_back(sk->joint(a).name, sk->joint(b).name);
  const std::vector<std::pair<std::string, std::string>> expected{
      {"lfemur", "rfemur"},   {"LeftUpLeg", "RightUpLeg"}, {"CC_Base_L_Thigh", "CC_Base_R_Thigh"},
      {"Thigh_R", "Thigh_L"}, {"lThigh", "rThigh"},        {"UpperLeg.L", "UpperLeg.R"}};
  CHECK(names == expected);
}

TEST_CASE("Bad input to estimate_torque_limits", "[torque_limits]") {
  const HandBody hb = hand_body();
  const HandClip a = hb.clip({stance(0, 0), stance(2, 1)});
  auto message = [&](auto&& f) -> std::string {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(nothing thrown)";
  };
  auto with = [&](TorqueLimitOptions o) {
    return message([&] { estimate_torque_limits(hb.body, a.contacts, a.torques, o); });
  };
  CHECK_THAT(with({.margin = 0}),
             Catch::Contains("TorqueLimitOptions.margin = 0.0: expected > 0 and finite"));
  CHECK_THAT(with({.margin = -1.5}), Catch::Contains("margin"));
  CHECK_THAT(with({.margin = NAN}), Catch::Contains("margin"));
  CHECK_THAT(with({.margin = kInf}), Catch::Contains("margin"));
  CHECK_THAT(with({.floor = -1}),
             Catch::Contains("TorqueLimitOptions.floor = -1.0: expected >= 0 and finite (N m)"));
  CHECK_THAT(with({.floor = kInf}), Catch::Contains("floor"));
  CHECK_THAT(with({.hulls = {.tolerance = 0}}), Catch::Contains("tolerance"));

  CHECK_THAT(message([&] { estimate_torque_limits(hb.body, std::span<const ClipLoads>{}, {}); }),
             Catch::Contains("no clip"));
  const ClipLoads no_contacts{nullptr, a.torques, "walk"};
  CHECK_THAT(message([&] { estimate_torque_limits(hb.body, std::span(&no_contacts, 1), {}); }),
             Catch::Contains("clip 'walk' has no contacts"));
  CHECK_THAT(message([&] { estimate_torque_limits(hb.body, a.contacts, std::span(a.torques).first(1), {}); }),
             Catch::Contains("clip 0 has 2 contact frames but 1 frames of torque coefficients"));
  std::vector<FrameTorques> short_frame = a.torques;
  short_frame[1].velocity.resize(5);
  CHECK_THAT(message([&] { estimate_torque_limits(hb.body, a.contacts, short_frame, {}); }),
             Catch::Contains("clip 0 frame 1") && Catch::Contains("the body has 8"));
  std::vector<FrameTorques> nan_frame = a.torques;
  nan_frame[0].gravity(2, 1) = NAN;
  CHECK_THAT(message([&] { estimate_torque_limits(hb.body, a.contacts, nan_frame, {}); }),
             Catch::Contains("clip 0 frame 0: torque coefficients not finite"));
  const ClipLoads second[] = {a.loads(), {&a.contacts, std::span(a.torques).first(1), "b"}};
  CHECK_THAT(message([&] { estimate_torque_limits(hb.body, second, {}); }),
             Catch::Contains("clip 'b' has 2 contact"));

  BodyModel short_limits = hb.body;
  short_limits.torque_max.resize(3);
  CHECK_THAT(message([&] { estimate_torque_limits(short_limits, a.contacts, a.torques, {}); }),
             Catch::Contains("torque limits") && Catch::Contains("3"));
  const HandBody other = hand_body();
  motion::Motion m{
      kg::test::skeleton_of({{.name = "p", .parent = -1, .channels = {{motion::ChannelKind::Xposition}}}}),
      motion::FrameMatrix::Zero(2, 1), 30.0, "p"};
  const Contacts narrow = assemble_contacts(m, {{"p", {{0, {0, 0, 0}}}}}, {{true}, {true}});
  CHECK_THAT(message([&] { estimate_torque_limits(other.body, narrow, a.torques, {}); }),
             Catch::Contains("contacts' skeleton has 1 channels, the body 8"));
}

TEST_CASE("CMU 16_15 at 30 Hz: limits from the walk, and the walk inside its hulls", "[torque_limits]") {
  const std::string asf = kData + "/cmu/asf_amc/16.asf", amc = kData + "/cmu/asf_amc/16_15.amc";
  if (!std::filesystem::exists(asf) || !std::filesystem::exists(amc)) {
    WARN("skipped: " << amc << " or " << asf << " not found");
    return;
  }
  const motion::Motion walk = motion::resample(io::import_asf_amc(asf, amc, {}).motion, 30.0);
  const motion::Skeleton& sk = *walk.skeleton;
  const BodySpec spec{.table = BodyTable::DeLevaMale, .mass = 70};
  const BodyModel body = build_body_model(walk.skeleton, spec).body;
  const Contacts contacts = detect_contacts(walk, {});
  const PathTorques torques = path_torques(body, walk, path_derivatives(walk, 0.04));
  const TorqueLimitOptions options{.margin = 1.5, .floor = 5};
  const TorqueLimitEstimate e = estimate_torque_limits(body, contacts, torques.frames, options);
  INFO(e.notes[0] << "; " << e.notes[1]);
  const int channels = sk.channel_count();
  auto channel = [&](const std::string& joint, int k) {
    const int j = sk.find_joint(joint);
    REQUIRE(j >= 0);
    return sk.joint(j).first_channel + k;
  };

  SECTION("channels: root unactuated, the rest margin x peak or the floor") {
    for (int c = 0; c < channels; ++c) {
      INFO(sk.channel_name(c) << " peak " << e.peak[c]);
      const bool root = sk.channel_owner(c).first == 0;
      CHECK(e.estimated[static_cast<std::size_t>(c)] == !root);
      if (root) {
        CHECK(e.body.torque_max[c] == 0);
        CHECK(e.body.torque_min[c] == 0);
        continue;
      }
      CHECK(e.body.torque_max[c] == Approx(std::max(1.5 * e.peak[c], 5.0)).epsilon(1e-12));
      CHECK(e.body.torque_min[c] == -e.body.torque_max[c]);
    }
    // A walk: no flight; the knees and hips do the work. Sagittal (rx) peaks of a 70 kg walker at
    // its own pace are tens of newton metres, not hundreds (Winter: knee ~ 0.5-1 N m/kg, hip ~ 1).
    CHECK(e.count(FrameUse::Flight) == 0);
    CHECK(e.count(FrameUse::Original) > walk.frame_count() / 2);
    for (const char* j : {"ltibia", "rtibia", "lfemur", "rfemur"}) {
      INFO(j);
      CHECK(e.peak[channel(j, 0)] > 10);
      CHECK(e.peak[channel(j, 0)] < 250);
    }
    // The fingers (53 g of de Leva's hand) need a few hundredths of a newton metre: the floor.
    CHECK(e.peak[channel("lfingers", 0)] > 0);
    CHECK(e.peak[channel("lfingers", 0)] < 0.5);
    CHECK(e.body.torque_max[channel("lfingers", 0)] == 5);
    CHECK(e.notes.back().find("lfingers.Xrotation") != std::string::npos);
    check_body_model(e.body);
  }

  SECTION("the guarantee: every frame observed at its centre keeps it inside its new hull") {
    const int original = check_guarantee(e.body, e, 0, contacts, torques.frames);
    CHECK(original >= e.count(FrameUse::Original));
    // And the limits bite: the hulls shrink (the fastest ṗ² each frame allows, on average).
    auto fastest = [&](const BodyModel& b) {
      double sum = 0;
      for (const FrameHull& h : build_hulls(b, contacts, torques.frames, {}).frames) {
        double most = 0;
        for (const Eigen::Vector2d& v : h.vertices) most = std::max(most, v.y());
        sum += most;
      }
      return sum;
    };
    CHECK(fastest(e.body) < 0.8 * fastest(without_torque_limits(body)));
  }

  SECTION("two halves as two clips observe the same peaks") {
    const int n = walk.frame_count(), half = n / 2;
    Contacts first = contacts, second = contacts;
    first.frames.resize(static_cast<std::size_t>(half));
    second.frames.erase(second.frames.begin(), second.frames.begin() + half);
    const std::span<const FrameTorques> all(torques.frames);
    const ClipLoads clips[] = {{&first, all.first(static_cast<std::size_t>(half)), "first"},
                               {&second, all.subspan(static_cast<std::size_t>(half)), "second"}};
    const TorqueLimitEstimate two = estimate_torque_limits(body, clips, options);
    for (int c = 0; c < channels; ++c) {
      INFO(sk.channel_name(c));
      CHECK(two.peak[c] == Approx(e.peak[c]).epsilon(1e-9));
      if (e.peak_frame[static_cast<std::size_t>(c)] < 0) continue;
      CHECK(two.peak_clip[static_cast<std::size_t>(c)] ==
            (e.peak_frame[static_cast<std::size_t>(c)] >= half ? 1 : 0));
    }
  }

  SECTION("symmetric: left and right share the larger limit") {
    TorqueLimitOptions o = options;
    o.symmetric = true;
    const TorqueLimitEstimate s = estimate_torque_limits(body, contacts, torques.frames, o);
    // hipjoint, femur, tibia, foot, toes, clavicle, humerus, radius, wrist, hand, fingers, thumb.
    CHECK(s.mirrored_joints.size() == 12);
    for (const char* j : {"femur", "tibia", "foot", "humerus"}) {
      const std::string l = std::string("l") + j, r = std::string("r") + j;
      for (int k = 0; k < static_cast<int>(sk.joint(sk.find_joint(l)).channels.size()); ++k) {
        INFO(l << " channel " << k);
        const int cl = channel(l, k), cr = channel(r, k);
        CHECK(s.body.torque_max[cl] == s.body.torque_max[cr]);
        CHECK(s.body.torque_max[cl] ==
              Approx(std::max({1.5 * e.peak[cl], 1.5 * e.peak[cr], 5.0})).epsilon(1e-12));
      }
    }
    CHECK(s.notes[2].find("lfemur/rfemur") != std::string::npos);
  }
}
