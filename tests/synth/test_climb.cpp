// The synthesized ladder climb, measured through the motion library's forward kinematics (the
// frames a consumer gets): holds exact and on their rungs and rails, three points always held,
// C1 channels, joints within human ranges, swinging feet clear of the rungs, bad options refused.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "synth_test_util.hpp"

using namespace kg;
using namespace kg::synth;
using namespace kg::synth::test;
using Catch::Matchers::Contains;

namespace {

constexpr double kDegree = std::numbers::pi / 180;

const Synthesis& default_climb() {
  static const Synthesis s = synthesize_climb({});
  return s;
}

// Distance of p from the line through a and b, and how far along from a (metres).
struct OnSegment {
  double off_line = 0, along = 0, length = 0;
};
OnSegment on_segment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d u = (b - a).normalized();
  const Eigen::Vector3d d = p - a;
  return {(d - u.dot(d) * u).norm(), u.dot(d), (b - a).norm()};
}

// Flexion of a one-channel hinge (knee, elbow) from its X rotation channel: knee positive, elbow
// written negated (the forearm bends forward).
double hinge(const Synthesis& s, int frame, int joint) {
  const motion::Skeleton& sk = *s.motion.skeleton;
  return s.motion.values(frame, sk.joint(joint).first_channel + 1);
}

// Angle of a joint's rotation relative to its parent, radians.
double relative_angle(const Kinematics& k, int frame, int parent, int joint) {
  const Eigen::Matrix3d r = k.world[std::size_t(frame)][std::size_t(parent)].rotation().transpose() *
                            k.world[std::size_t(frame)][std::size_t(joint)].rotation();
  return Eigen::AngleAxisd(r).angle();
}

const std::vector<ClimbOptions>& option_table() {
  static const std::vector<ClimbOptions> table{
      ClimbOptions{}, ClimbOptions{.rungs = 1, .fps = 30},
      ClimbOptions{.rungs = 5, .rung_spacing = 0.25, .rail_half_width = 0.18, .ladder_distance = 0.45},
      ClimbOptions{.rungs = 3, .rung_spacing = 0.35, .ladder_distance = 0.55, .stature = 2.0, .fps = 60},
      ClimbOptions{.rungs = 2, .rung_spacing = 0.22, .ladder_distance = 0.35, .stature = 1.3, .fps = 97}};
  return table;
}

}  // namespace

TEST_CASE("climb: every hold is exact, on its rung or rail, for its whole span", "[synth][climb]") {
  for (const ClimbOptions& o : option_table()) {
    CAPTURE(o.rungs, o.rung_spacing, o.rail_half_width, o.ladder_distance, o.stature, o.fps);
    const Synthesis s = synthesize_climb(o);
    const Kinematics k(s.motion);
    const Ladder& l = s.ladder;
    REQUIRE_FALSE(s.holds.empty());
    CHECK(s.plants.empty());
    CHECK(s.steps == o.rungs);
    CHECK(l.rung_spacing == o.rung_spacing);
    CHECK(l.distance == o.ladder_distance);
    int frames_checked = 0;
    for (const Hold& h : s.holds) {
      CAPTURE(h.name(), h.first_frame, h.last_frame);
      REQUIRE(h.first_frame <= h.last_frame);
      REQUIRE(h.last_frame < s.motion.frame_count());
      CHECK(h.joint == (h.hand ? s.figure.hand[h.side] : s.figure.toe[h.side]));
      // The segment is the rung's top line (from the right rail to the left) or the rail.
      if (h.hand) {
        CHECK(h.rung == 0);
        CHECK((h.segment_a - l.rail_a(h.side)).norm() == 0);
        CHECK((h.segment_b - l.rail_b(h.side)).norm() == 0);
      } else {
        REQUIRE(h.rung >= 1);
        REQUIRE(h.rung <= l.rung_count);
        CHECK((h.segment_a - l.rung_a(h.rung)).norm() == 0);
        CHECK((h.segment_b - l.rung_b(h.rung)).norm() == 0);
        CHECK(h.world.y() == Approx(h.rung * o.rung_spacing).margin(1e-12));
      }
      const OnSegment on = on_segment(h.world, h.segment_a, h.segment_b);
      CHECK(on.off_line < 1e-12);
      // Inside the ends: a foot at least 4 cm from a rail, a hand half a hand from a rail's end.
      CHECK(on.along > 0.04);
      CHECK(on.along < on.length - 0.04);
      for (int f = h.first_frame; f <= h.last_frame; ++f, ++frames_checked) {
        const Eigen::Vector3d p = k.point(f, h.joint, h.local);
        CHECK((p - h.world).norm() < 1e-9);
        CHECK(on_segment(p, h.segment_a, h.segment_b).off_line < 1e-9);
      }
    }
    INFO(frames_checked << " hold frames");
    CHECK(frames_checked > s.motion.frame_count() * 3);
  }
}

TEST_CASE("climb: starts and ends on one rung, climbs `rungs`, three limbs always hold", "[synth][climb]") {
  for (const ClimbOptions& o : option_table()) {
    CAPTURE(o.rungs, o.rung_spacing, o.stature, o.fps);
    const Synthesis s = synthesize_climb(o);
    const int last = s.motion.frame_count() - 1;
    std::vector<int> holding(static_cast<std::size_t>(last) + 1, 0);
    for (bool hand : {true, false}) {
      for (Side side : {kLeft, kRight}) {
        std::vector<const Hold*> limb;
        for (const Hold& h : s.holds)
          if (h.hand == hand && h.side == side) limb.push_back(&h);
        REQUIRE(limb.size() >= 2);
        // In time order, never overlapping, from the first frame to the last.
        CHECK(limb.front()->first_frame == 0);
        CHECK(limb.back()->last_frame == last);
        for (std::size_t i = 1; i < limb.size(); ++i) {
          CHECK(limb[i]->first_frame > limb[i - 1]->last_frame);
          CHECK(limb[i]->world.y() > limb[i - 1]->world.y());  // each move goes up
        }
        if (!hand) {
          CHECK(limb.front()->rung == 1);
          CHECK(limb.back()->rung == o.rungs + 1);
        }
        for (const Hold* h : limb)
          for (int f = h->first_frame; f <= h->last_frame; ++f) ++holding[std::size_t(f)];
      }
    }
    CHECK(*std::min_element(holding.begin(), holding.end()) >= 3);
    CHECK(holding.front() == 4);
    CHECK(holding.back() == 4);
    // Both hands end level, as do both feet; the root rose by rungs * spacing.
    const Kinematics k(s.motion);
    const int root = s.figure.hips;
    CHECK(k.joint(last, root).y() - k.joint(0, root).y() == Approx(o.rungs * o.rung_spacing).margin(1e-9));
  }
}

TEST_CASE("climb: every channel is continuous and C1", "[synth][climb]") {
  const Synthesis& s = default_climb();
  const ChannelSmoothness r = smoothness(s.motion, false);
  INFO("largest step " << r.max_step << " in " << s.motion.skeleton->channel_name(r.max_step_channel));
  CHECK(r.max_step < 0.1);  // per frame at 120 fps: under 12 rad/s or m/s
  // C1: the second difference over dt^2 stays bounded as the frame rate rises (a kink would make
  // it grow like 1 / dt, four times from 240 to 960 fps).
  const Synthesis lo = synthesize_climb({.fps = 240});
  const Synthesis hi = synthesize_climb({.fps = 960});
  const ChannelSmoothness a = smoothness(lo.motion, false), b = smoothness(hi.motion, false);
  INFO("max |second difference| / dt^2: "
       << a.max_accel << " at 240 fps (" << lo.motion.skeleton->channel_name(a.max_accel_channel) << "), "
       << b.max_accel << " at 960 fps (" << hi.motion.skeleton->channel_name(b.max_accel_channel) << ")");
  CHECK(b.max_accel < 1.5 * a.max_accel);
}

TEST_CASE("climb: frame rates sample the same climb", "[synth][climb]") {
  const Synthesis a = synthesize_climb({.rungs = 2, .fps = 30});
  const Synthesis b = synthesize_climb({.rungs = 2, .fps = 120});
  CHECK(a.motion.duration() == Approx(b.motion.duration()).margin(1 / 30.0));
  // Frame f at 30 fps is frame 4 f at 120 fps: the same instant, the same pose.
  const int common = std::min(a.motion.frame_count(), (b.motion.frame_count() - 1) / 4 + 1);
  REQUIRE(common > 100);
  for (int f = 0; f < common; ++f)
    CHECK((a.motion.values.row(f) - b.motion.values.row(4 * f)).cwiseAbs().maxCoeff() < 1e-9);
  REQUIRE(a.holds.size() == b.holds.size());
  for (std::size_t i = 0; i < a.holds.size(); ++i)
    CHECK((a.holds[i].world - b.holds[i].world).norm() < 1e-12);
}

TEST_CASE("climb: joints stay in human ranges, limbs within reach", "[synth][climb]") {
  for (const ClimbOptions& o : option_table()) {
    CAPTURE(o.rungs, o.rung_spacing, o.rail_half_width, o.ladder_distance, o.stature);
    const Synthesis s = synthesize_climb(o);
    const Kinematics k(s.motion);
    const Figure& fig = s.figure;
    CHECK(s.max_leg_extension <= 0.93 + 1e-6);
    CHECK(s.max_leg_extension > 0.8);
    CHECK(s.max_arm_extension <= 0.88 + 1e-6);
    CHECK(s.max_arm_extension > 0.75);
    double knee_lo = 1e9, knee_hi = -1e9, elbow_lo = 1e9, elbow_hi = -1e9, wrist = 0, ankle = 0;
    for (int f = 0; f < k.frames(); ++f) {
      for (Side side : {kLeft, kRight}) {
        const double knee = hinge(s, f, fig.leg[side]), elbow = -hinge(s, f, fig.forearm[side]);
        knee_lo = std::min(knee_lo, knee);
        knee_hi = std::max(knee_hi, knee);
        elbow_lo = std::min(elbow_lo, elbow);
        elbow_hi = std::max(elbow_hi, elbow);
        wrist = std::max(wrist, relative_angle(k, f, fig.forearm[side], fig.hand[side]));
        ankle = std::max(ankle, relative_angle(k, f, fig.leg[side], fig.foot[side]));
      }
    }
    INFO("knee " << knee_lo / kDegree << " to " << knee_hi / kDegree << " deg, elbow " << elbow_lo / kDegree
                 << " to " << elbow_hi / kDegree << " deg, wrist up to " << wrist / kDegree
                 << " deg, ankle up to " << ankle / kDegree << " deg");
    // Knees and elbows bend the right way, never locked straight nor folded shut.
    CHECK(knee_lo > 15 * kDegree);
    CHECK(knee_hi < 140 * kDegree);
    CHECK(elbow_lo > 10 * kDegree);
    CHECK(elbow_hi < 145 * kDegree);
    CHECK(wrist < 80 * kDegree);
    CHECK(ankle < 60 * kDegree);
  }
}

TEST_CASE("climb: a swinging foot never passes through a rung", "[synth][climb]") {
  for (const ClimbOptions& o : option_table()) {
    CAPTURE(o.rungs, o.rung_spacing, o.stature, o.fps);
    const Synthesis s = synthesize_climb(o);
    const Kinematics k(s.motion);
    const Ladder& l = s.ladder;
    // A rung is a round bar of rung_radius whose top is its rung line; the heel, the sole under
    // the ball and the toe tip stay outside every bar (1 mm slack for a foot resting on one).
    double closest = 1e9;
    for (int f = 0; f < k.frames(); ++f) {
      for (Side side : {kLeft, kRight}) {
        const SolePoints p = sole(k, s.figure, f, side);
        for (const Eigen::Vector3d& q : {p.heel, p.ball_sole, p.toe_tip}) {
          for (int r = 1; r <= l.rung_count; ++r) {
            const Eigen::Vector2d axis(l.rung_height(r) - l.rung_radius, l.distance);
            closest = std::min(closest, (Eigen::Vector2d(q.y(), q.z()) - axis).norm() - l.rung_radius);
          }
        }
      }
    }
    CHECK(closest > -1e-3);
  }
}

TEST_CASE("climb: bad options are refused with the option named", "[synth][climb]") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH(synthesize_climb({.rungs = 0}),
                    Contains("synthesize_climb: rungs 0") && Contains("expected 1 to 60"));
  CHECK_THROWS_WITH(synthesize_climb({.rungs = 61}), Contains("rungs 61"));
  CHECK_THROWS_WITH(synthesize_climb({.rung_spacing = 0.1}),
                    Contains("rung_spacing 0.1 m") && Contains("expected 0.2 to 0.4"));
  CHECK_THROWS_WITH(synthesize_climb({.rung_spacing = nan}), Contains("rung_spacing nan"));
  CHECK_THROWS_WITH(synthesize_climb({.rail_half_width = 0.5}), Contains("rail_half_width 0.5 m"));
  CHECK_THROWS_WITH(synthesize_climb({.ladder_distance = 1.0}), Contains("ladder_distance 1 m"));
  CHECK_THROWS_WITH(synthesize_climb({.stature = 0.9}), Contains("stature 0.9 m"));
  CHECK_THROWS_WITH(synthesize_climb({.fps = 5}), Contains("fps 5"));
  // In range, but the figure cannot span the ladder: said so, naming the option and the figure.
  CHECK_THROWS_AS(synthesize_climb({.rung_spacing = 0.4, .ladder_distance = 0.35, .stature = 1.2}),
                  std::invalid_argument);
  CHECK_THROWS_WITH(synthesize_climb({.rung_spacing = 0.4, .ladder_distance = 0.35, .stature = 1.2}),
                    Contains("rung_spacing 0.4 m is too large") && Contains("stature 1.2 m"));
  CHECK_THROWS_WITH(synthesize_climb({.rung_spacing = 0.2, .ladder_distance = 0.7, .stature = 1.2}),
                    Contains("ladder_distance 0.7 m is too far for the legs") && Contains("stature 1.2 m"));
  CHECK_THROWS_WITH(synthesize_climb({.ladder_distance = 0.45, .stature = 1.5}),
                    Contains("ladder_distance 0.45 m is too far for the arms") && Contains("stature 1.5 m"));
  CHECK_THROWS_WITH(synthesize_climb({.rung_spacing = 0.25, .ladder_distance = 0.35}),
                    Contains("ladder_distance 0.35 m is too close") && Contains("knees"));
  CHECK_THROWS_WITH(synthesize_climb({.rung_spacing = 0.2, .ladder_distance = 0.25, .stature = 2.2}),
                    Contains("ladder_distance 0.25 m is too close") && Contains("elbows"));
}
