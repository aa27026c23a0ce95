#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "kg/motion/resample.hpp"
#include "kg/motion/rotations.hpp"
#include "motion_test_util.hpp"

using namespace kg::motion;
using kg::motion::test::channels_of;
using kg::motion::test::kPi;
using kg::motion::test::rotations_in;
using K = ChannelKind;

namespace {

// 12 channels: root 3 positions + ZXY (0..5), spine ZXY (6..8), knee X (9), wrist XZ (10, 11),
// toe none.
std::shared_ptr<const Skeleton> body() {
  auto s = std::make_shared<Skeleton>();
  auto add = [&](const char* name, int parent, std::vector<ChannelKind> kinds) {
    Joint j;
    j.name = name;
    j.parent = parent;
    j.offset = {0, 0.2, 0};
    j.channels = channels_of(kinds);
    return s->add_joint(std::move(j));
  };
  add("root", -1, {K::Xposition, K::Yposition, K::Zposition, K::Zrotation, K::Xrotation, K::Yrotation});
  add("spine", 0, rotations_in("ZXY"));
  add("knee", 1, rotations_in("X"));
  add("wrist", 2, rotations_in("XZ"));
  add("toe", 3, {});
  return s;
}

// Rotation channels of `joint` in frame `f` as a matrix.
Eigen::Matrix3d joint_rotation(const Motion& m, int joint, int f) {
  const Joint& j = m.skeleton->joint(joint);
  const RotationOrder order = rotation_order(j);
  const auto idx = rotation_channel_indices(j);
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  for (int r = 0; r < order.count; ++r)
    a[r] = m.values(f, j.first_channel + idx[static_cast<std::size_t>(r)]);
  return euler_to_matrix(order, a);
}

// Smooth curves that never wrap: positions in metres, angles within +-1.2 rad.
Motion smooth_clip(int frames, double fps) {
  Motion m{body(), FrameMatrix(frames, 12), fps, "smooth"};
  for (int f = 0; f < frames; ++f) {
    const double t = f / fps;
    for (int c = 0; c < 12; ++c) m.values(f, c) = (c < 3 ? 0.5 : 1.2) * std::sin(0.7 * t * (c + 1) + 0.3 * c);
  }
  return m;
}

// Largest change of any rotation channel between neighbouring frames.
double worst_rotation_step(const Motion& m) {
  double worst = 0;
  for (int c = 0; c < m.skeleton->channel_count(); ++c) {
    const auto [j, i] = m.skeleton->channel_owner(c);
    if (!is_rotation(m.skeleton->joint(j).channels[static_cast<std::size_t>(i)].kind)) continue;
    for (int f = 1; f < m.frame_count(); ++f)
      worst = std::max(worst, std::abs(m.values(f, c) - m.values(f - 1, c)));
  }
  return worst;
}

}  // namespace

TEST_CASE("120 -> 30 Hz keeps the frames at coincident times exactly", "[resample]") {
  const Motion m = smooth_clip(241, 120.0);
  const Motion r = resample(m, 30.0);
  REQUIRE(r.frame_count() == 61);
  CHECK(r.fps == 30.0);
  CHECK(r.name == "smooth");
  CHECK(r.skeleton == m.skeleton);
  CHECK_NOTHROW(r.check());
  for (int k = 0; k < r.frame_count(); ++k) {
    INFO("output frame " << k);
    CHECK((r.values.row(k) - m.values.row(4 * k)).isZero(0));
  }
  // A non-integer ratio: 120 -> 50 meets an input frame every 12 input frames.
  const Motion r50 = resample(m, 50.0);
  REQUIRE(r50.frame_count() == 101);
  for (int k = 0; k < r50.frame_count(); k += 5)
    CHECK((r50.values.row(k) - m.values.row(12 * k / 5)).isZero(0));
}

TEST_CASE("resampling preserves duration: floor(duration * fps) + 1 frames", "[resample]") {
  struct Case {
    int frames;
    double fps, new_fps;
    int expected;
  };
  for (const Case& c :
       {Case{241, 120, 30, 61}, Case{100, 120, 30, 25}, Case{31, 30, 120, 121}, Case{121, 120, 50, 51},
        Case{2, 120, 30, 1}, Case{1, 120, 30, 1}, Case{50, 29.97, 25, 41}, Case{101, 100, 33.3, 34}}) {
    INFO(c.frames << " frames " << c.fps << " -> " << c.new_fps);
    CHECK(resampled_frame_count(c.frames, c.fps, c.new_fps) == c.expected);
    const Motion m = smooth_clip(c.frames, c.fps);
    const Motion r = resample(m, c.new_fps);
    CHECK(r.frame_count() == c.expected);
    CHECK(r.duration() <= m.duration() + 1e-12);
    CHECK(r.duration() > m.duration() - 1.0 / c.new_fps);
    CHECK((r.values.row(r.frame_count() - 1) - pose_at(m, r.duration())).cwiseAbs().maxCoeff() < 1e-12);
  }
  CHECK(resampled_frame_count(0, 120, 30) == 0);
}

TEST_CASE("upsampling interpolates positions linearly and rotations along the great arc", "[resample]") {
  const Motion m = smooth_clip(31, 30.0);
  const Motion r = resample(m, 120.0);
  REQUIRE(r.frame_count() == 121);
  for (int k = 0; k + 1 < m.frame_count(); ++k) {
    for (int q = 1; q < 4; ++q) {
      const double u = q / 4.0;
      const int out = 4 * k + q;
      INFO("input frame " << k << " + " << u);
      for (int c = 0; c < 3; ++c)
        CHECK(r.values(out, c) == Approx((1 - u) * m.values(k, c) + u * m.values(k + 1, c)).margin(1e-15));
      // Three rotation channels: the slerp of the two frames' rotations.
      for (int joint : {0, 1}) {
        const Eigen::Quaterniond qa(joint_rotation(m, joint, k)), qb(joint_rotation(m, joint, k + 1));
        const Eigen::Matrix3d expected = qa.slerp(u, qb).toRotationMatrix();
        CHECK((joint_rotation(r, joint, out) - expected).cwiseAbs().maxCoeff() < 1e-12);
      }
      // One or two rotation channels: each angle linearly.
      for (int c : {9, 10, 11})
        CHECK(r.values(out, c) == Approx((1 - u) * m.values(k, c) + u * m.values(k + 1, c)).margin(1e-12));
    }
  }
}

TEST_CASE("a joint spinning past 180 degrees does not flip, at any rate", "[resample]") {
  // Every joint spins about one axis at 600 deg/s and tilts about another; the file stores the
  // angles wrapped to (-180, 180] as exporters do, so the stored curves jump by 360 degrees.
  const double fps = 30, omega = 600 * kPi / 180;
  auto truth = [&](double t) {
    Eigen::RowVectorXd v(12);
    v << 0.1 * t, 0.9, 0.0, 0.2 * std::sin(3 * t), 0.3 * std::sin(2 * t), omega * t,  // root Z X Y(spin)
        -omega * t, 0.25, 0.1,                                                        // spine Z(spin) X Y
        omega * t,                                                                    // knee X(spin)
        0.2, -omega * t;                                                              // wrist X Z(spin)
    return v;
  };
  Motion m{body(), FrameMatrix(61, 12), fps, "spin"};
  for (int f = 0; f < m.frame_count(); ++f) {
    m.values.row(f) = truth(f / fps);
    for (int c = 3; c < 12; ++c) m.values(f, c) = wrap_angle(m.values(f, c));
  }
  for (double new_fps : {120.0, 90.0, 47.0, 30.0, 24.0}) {
    const Motion r = resample(m, new_fps);
    INFO("-> " << new_fps << " fps");
    // Continuous curves: nothing like a 360 degree jump; the true steps are omega / new_fps.
    CHECK(worst_rotation_step(r) < 2 * omega / new_fps);
    // The rotations are the true ones at every output time (the short way between 20 degree steps).
    Motion truth_clip{m.skeleton, FrameMatrix(r.frame_count(), 12), new_fps, "truth"};
    for (int k = 0; k < r.frame_count(); ++k) truth_clip.values.row(k) = truth(k / new_fps);
    double worst = 0;
    for (int k = 0; k < r.frame_count(); ++k)
      for (int joint : {0, 1, 2, 3}) {
        const Eigen::Quaterniond got(joint_rotation(r, joint, k)), want(joint_rotation(truth_clip, joint, k));
        // Slerp of a spin about a tilted axis is exact for one axis; the others deviate a
        // little from the Euler curve between frames.
        worst = std::max(worst, got.angularDistance(want));
      }
    CHECK(worst < 0.02);
  }
}

TEST_CASE("slerp takes the short way when the quaternions lie in opposite hemispheres", "[resample]") {
  // Root ZXY at Y = 170 and -170 degrees: halfway is 180, not 0.
  Motion m{body(), FrameMatrix::Zero(2, 12), 10.0, "flip"};
  m.values(0, 5) = 170 * kPi / 180;
  m.values(1, 5) = -170 * kPi / 180;
  REQUIRE(euler_to_quaternion(parse_rotation_order("ZXY"), {0, 0, m.values(0, 5)})
              .dot(euler_to_quaternion(parse_rotation_order("ZXY"), {0, 0, m.values(1, 5)})) < 0);
  const Eigen::RowVectorXd mid = pose_at(m, 0.05);
  CHECK(std::abs(wrap_angle(mid[5])) == Approx(kPi).margin(1e-12));
  const Motion r = resample(m, 40.0);  // 0.1 s: frames at 170, 175, 180, 185, 190 degrees
  REQUIRE(r.frame_count() == 5);
  for (int k = 0; k < 5; ++k) CHECK(r.values(k, 5) == Approx((170 + 5 * k) * kPi / 180).margin(1e-12));
}

TEST_CASE("resampling through gimbal lock keeps rotations right and curves bounded", "[resample]") {
  // Spine ZXY with X passing through +90 degrees while Z and Y turn.
  Motion m{body(), FrameMatrix::Zero(41, 12), 120.0, "gimbal"};
  for (int f = 0; f < 41; ++f) {
    const double t = f / 40.0;
    m.values(f, 6) = 0.4 + 1.2 * t;    // spine Z
    m.values(f, 7) = kPi / 2 * 2 * t;  // spine X: 0 .. 180 degrees, 90 at t = 0.5
    m.values(f, 8) = -0.3 + 0.8 * t;   // spine Y
  }
  const Motion r = resample(m, 90.0);
  for (int k = 0; k < r.frame_count(); ++k) {
    const double s = k * 120.0 / 90.0;
    const int f0 = static_cast<int>(std::floor(s + 1e-9));
    const int f1 = std::min(f0 + 1, 40);
    const double u = s - f0 < 1e-9 ? 0 : s - f0;
    const Eigen::Quaterniond qa(joint_rotation(m, 1, f0)), qb(joint_rotation(m, 1, f1));
    CHECK((joint_rotation(r, 1, k) - qa.slerp(u, qb).toRotationMatrix()).cwiseAbs().maxCoeff() < 1e-9);
  }
  // Near the lock the outer angles may swap between themselves, but never by a half turn.
  CHECK(worst_rotation_step(r) < 1.0);
}

TEST_CASE("resampling keeps the input's Euler solution where an exporter switches it at gimbal lock",
          "[resample]") {
  // A knee-like spine ZXY bending from 60 to 120 degrees about X in 0.4 s, stored as exporters
  // store it (09_06.bvh's rShin): the middle angle within +-90, so past 90 the file switches to
  // the other solution (Z + 180, 180 - X, Y + 180). A displacement added to the resampled angles
  // (retarget.at_rate) means something only on the file's own solution.
  Motion m{body(), FrameMatrix::Zero(49, 12), 120.0, "knee"};
  for (int f = 0; f < m.frame_count(); ++f) {
    const double t = f / 48.0;
    double z = 0.05 + 0.1 * t, x = (60 + 60 * t) * kPi / 180, y = -0.08 + 0.1 * t;
    if (x > kPi / 2) {
      z = wrap_angle(z + kPi);
      x = kPi - x;
      y = wrap_angle(y + kPi);
    }
    m.values(f, 6) = z;
    m.values(f, 7) = x;
    m.values(f, 8) = y;
  }
  for (double new_fps : {25.0, 50.0, 47.0}) {
    INFO("-> " << new_fps << " fps");
    const Motion r = resample(m, new_fps);
    int compared = 0;
    for (int k = 0; k < r.frame_count(); ++k) {
      const double s = k * 120.0 / new_fps;
      const int f0 = static_cast<int>(std::floor(s + 1e-9));
      const int f1 = std::min(f0 + 1, m.frame_count() - 1);
      const double u = s - f0 < 1e-9 ? 0 : s - f0;
      const Eigen::Quaterniond qa(joint_rotation(m, 1, f0)), qb(joint_rotation(m, 1, f1));
      CHECK((joint_rotation(r, 1, k) - qa.slerp(u, qb).toRotationMatrix()).cwiseAbs().maxCoeff() < 1e-9);
      // Away from the switch, every angle is the file's own, interpolated.
      bool same_solution = true;
      for (int c = 6; c <= 8; ++c)
        same_solution &= std::abs(std::remainder(m.values(f1, c) - m.values(f0, c), 2 * kPi)) < 0.2;
      if (!same_solution) continue;
      ++compared;
      for (int c = 6; c <= 8; ++c) {
        const double own = m.values(f0, c) + u * std::remainder(m.values(f1, c) - m.values(f0, c), 2 * kPi);
        CHECK(std::abs(std::remainder(r.values(k, c) - own, 2 * kPi)) < 0.01);
      }
    }
    CHECK(compared >= r.frame_count() - 1);
  }
}

TEST_CASE("pose_at samples frames, clamps the ends and refuses nonsense", "[resample]") {
  const Motion m = smooth_clip(25, 24.0);
  for (int f = 0; f < m.frame_count(); ++f) CHECK((pose_at(m, f / 24.0) - m.values.row(f)).isZero(0));
  CHECK((pose_at(m, -3.0) - m.values.row(0)).isZero(0));
  CHECK((pose_at(m, 1e6) - m.values.row(24)).isZero(0));
  // With a reference whole turns away, angles follow it and positions do not.
  Eigen::RowVectorXd ref = m.values.row(3);
  ref.tail(9).array() += 2 * kPi;
  Eigen::RowVectorXd out(12);
  pose_at(m, 3.5 / 24.0, ref, out);
  const Eigen::RowVectorXd plain = pose_at(m, 3.5 / 24.0);
  CHECK((out.head(3) - plain.head(3)).isZero(0));
  CHECK(((out.tail(9) - plain.tail(9)).array() - 2 * kPi).abs().maxCoeff() < 1e-9);
  // out may be the reference itself.
  Eigen::RowVectorXd both = ref;
  pose_at(m, 3.5 / 24.0, both, both);
  CHECK((both - out).cwiseAbs().maxCoeff() < 1e-12);

  Motion empty{m.skeleton, FrameMatrix(0, 12), 24.0, "empty"};
  CHECK_THROWS_WITH(pose_at(empty, 0.0), Catch::Contains("motion 'empty' has no frames"));
  CHECK_THROWS_WITH(pose_at(m, std::nan("")), Catch::Contains("time is not finite"));
  Eigen::RowVectorXd wrong(5);
  CHECK_THROWS_WITH(pose_at(m, 0.1, wrong), Catch::Contains("out has 5 values"));
}

TEST_CASE("resample refuses bad frame rates and bad clips", "[resample]") {
  const Motion m = smooth_clip(10, 120.0);
  for (double fps : {0.0, -30.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    INFO("fps " << fps);
    CHECK_THROWS_WITH(resample(m, fps), Catch::Contains("expected finite numbers > 0"));
  }
  Motion bad = m;
  bad.values(4, 7) = std::nan("");
  CHECK_THROWS_WITH(resample(bad, 30.0), Catch::Contains("frame 4, channel spine.Xrotation is nan"));
  Motion empty{m.skeleton, FrameMatrix(0, 12), 120.0, "empty"};
  CHECK_THROWS_WITH(resample(empty, 30.0), Catch::Contains("has no frames"));
  CHECK_THROWS_WITH(resample(m, 1e12), Catch::Contains("would become 75000000001 frames"));
  CHECK_THROWS_WITH(resample(m, 3e9), Catch::Contains("more than 2^31 values"));
}
