// Metrics (metrics.hpp) on cases computed by hand: a known violation per kind (inequality rows
// counted only when violated), a known foot skate, the RMS jerk of a sampled sine, unwrapping,
// the energy above the key cut-off of DCT basis signals and of a B-spline displacement, the JSON
// document and the retarget.metrics node.
#include <cmath>
#include <cstdint>
#include <fstream>
#include <numbers>
#include <random>
#include <span>
#include <sstream>

#include <catch2/catch.hpp>

#include "../support/node_context.hpp"
#include "../support/temp_dir.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/motion/filters.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/key_spacing.hpp"
#include "kg/retarget/metrics.hpp"
#include "kg/retarget/nodes.hpp"

using Catch::Matchers::Contains;
using namespace kg;
using namespace kg::retarget;
using motion::ChannelKind;
using motion::Motion;

namespace {

constexpr double kPi = std::numbers::pi;

// One root joint "hip": Xposition Yposition Zposition Zrotation Xrotation Yrotation, all zero, and
// a child "foot" 1 m below it without channels.
Motion blank(int frames, double fps) {
  auto s = std::make_shared<motion::Skeleton>();
  motion::Joint hip;
  hip.name = "hip";
  for (ChannelKind k : {ChannelKind::Xposition, ChannelKind::Yposition, ChannelKind::Zposition,
                        ChannelKind::Zrotation, ChannelKind::Xrotation, ChannelKind::Yrotation})
    hip.channels.push_back({k});
  s->add_joint(hip);
  motion::Joint foot;
  foot.name = "foot";
  foot.parent = 0;
  foot.offset = {0, -1, 0};
  s->add_joint(foot);
  return Motion{s, motion::FrameMatrix::Zero(frames, 6), fps, "blank"};
}

Constraint on_foot(const std::string& kind, std::vector<double> params, int first, int last,
                   std::string label) {
  Constraint c;
  c.kind = kind;
  c.label = std::move(label);
  c.points = {{.joint = 1}};
  c.params = std::move(params);
  for (int f = first; f <= last; ++f) c.samples.push_back({.frames = {f}});
  return c;
}

const ConstraintKindTable& builtin_kinds() {
  static const ConstraintKindTable table = ConstraintKindTable::builtin();
  return table;
}

}  // namespace

TEST_CASE("metrics: violation per kind, inequality rows counted only when violated", "[metrics]") {
  Motion m = blank(10, 30);
  for (int f = 0; f < 10; ++f) m.values(f, 1) = 1.0;  // the foot at the origin
  const double inf = std::numeric_limits<double>::infinity();
  ConstraintSet set;
  // 3 cm off on X at frames 2..3 (the other two axes met): worst 3 cm, mean over 6 rows 1 cm.
  set.constraints.push_back(on_foot("position", {0.03, 0, 0}, 2, 3, "plant"));
  // Above y = 0.02 at frame 5 (violated by 2 cm), above y = -1 at frame 6 (met: not counted).
  set.constraints.push_back(on_foot("region", {-inf, 0.02, -inf, inf, inf, inf}, 5, 5, "floor a"));
  set.constraints.push_back(on_foot("region", {-inf, -1, -inf, inf, inf, inf}, 6, 6, "floor b"));
  const RetargetMetrics r = compute_metrics({.result = &m, .constraints = &set, .kinds = &builtin_kinds()});
  REQUIRE(r.kinds.size() == 2);
  const KindMetrics& position = r.kinds[0];
  const KindMetrics& region = r.kinds[1];
  CHECK(position.violation.kind == "position");
  CHECK(position.in_metres);
  CHECK(position.violation.worst == Approx(0.03));
  CHECK(position.violation.mean == Approx(0.01));
  CHECK(region.violation.kind == "region");
  CHECK(region.violation.worst == Approx(0.02));
  CHECK(region.violation.counted_rows == 1);
  CHECK(region.violation.mean == Approx(0.02));
  CHECK(r.worst_violation_metres == Approx(0.03));

  std::ostringstream json;
  write_metrics_json(json, r);
  CHECK_THAT(json.str(), Contains("\"worst_cm\": 3") && Contains("\"kind\": \"region\"") &&
                             Contains("\"solve_seconds\": null") &&
                             Contains("\"energy_above_cutoff\": null"));
}

TEST_CASE("metrics: foot skate is the greatest horizontal travel from the plant's first frame", "[metrics]") {
  Motion m = blank(30, 30);
  for (int f = 0; f < 30; ++f) {
    m.values(f, 0) = 0.01 * f;                  // 1 cm per frame along X
    m.values(f, 1) = 1.0 + 0.05 * std::sin(f);  // vertical motion does not count
    m.values(f, 2) = f >= 15 ? 0.03 : 0.0;      // a 3 cm slip on Z from frame 15
  }
  ConstraintSet set;
  // One plant in two flavours: floor height (position, Y only) and non-skid (same_place) over
  // frames 10..20: one point, one run, counted once.
  set.constraints.push_back(on_foot("position", {0, 0, 0, 0, 1, 0}, 10, 20, "LeftHeel plant"));
  Constraint skid;
  skid.kind = "same_place";
  skid.label = "LeftHeel non-skid";
  skid.points = {{.joint = 1}, {.joint = 1}};
  skid.params = {1, 0, 1};
  for (int f = 11; f <= 20; ++f) skid.samples.push_back({.frames = {10, f}});
  set.constraints.push_back(skid);
  // A second run of the same point later on, still: no skate.
  set.constraints.push_back(on_foot("position", {0, 0, 0, 0, 1, 0}, 25, 25, "LeftHeel plant 2"));
  const SkateSummary s = foot_skate(set, PoseCache(std::span<const Motion>(&m, 1)));
  REQUIRE(s.plants.size() == 2);
  CHECK(s.plants[0].label == "LeftHeel plant");
  CHECK(s.plants[0].first_frame == 10);
  CHECK(s.plants[0].last_frame == 20);
  CHECK(s.plants[0].travel == Approx(std::hypot(0.10, 0.03)));
  CHECK(s.plants[0].worst_frame == 20);
  CHECK(s.plants[1].first_frame == 25);
  CHECK(s.plants[1].travel == 0);
  CHECK(s.worst == Approx(std::hypot(0.10, 0.03)));
  CHECK(s.mean == Approx(std::hypot(0.10, 0.03) / 2));

  // Two plants of one foot that touch (as a brief lift does at a coarse rate) stay two, each
  // with its own label: the slip between them is no skate.
  ConstraintSet touching;
  touching.constraints.push_back(on_foot("position", {0, 0, 0, 0, 1, 0}, 2, 6, "LeftHeel plant 1"));
  touching.constraints.push_back(on_foot("position", {0, 0, 0, 0, 1, 0}, 7, 9, "LeftHeel plant 2"));
  const SkateSummary ts = foot_skate(touching, PoseCache(std::span<const Motion>(&m, 1)));
  REQUIRE(ts.plants.size() == 2);
  CHECK(ts.plants[0].label == "LeftHeel plant 1");
  CHECK(ts.plants[0].last_frame == 6);
  CHECK(ts.plants[1].label == "LeftHeel plant 2");
  CHECK(ts.plants[1].first_frame == 7);
  CHECK(ts.plants[1].travel == Approx(0.02));

  // Other kinds and moving targets are no plants.
  ConstraintSet others;
  others.constraints.push_back(on_foot("region", {-1, -1, -1, 1, 1, 1}, 0, 29, "box"));
  Constraint moving = on_foot("position", {0, 0, 0}, 0, 5, "moving hand");
  for (Sample& sample : moving.samples) sample.params = {0.01 * sample.frames[0], 0, 0};
  others.constraints.push_back(moving);
  CHECK(find_plants(others).empty());

  // A plant whose height target and point offset change per sample (a morphing foot) is one:
  // its travel is measured at each frame's own offset.
  ConstraintSet morph;
  Constraint shrinking = on_foot("position", {0, 0, 0, 0, 1, 0}, 10, 20, "LeftHeel plant");
  for (Sample& sample : shrinking.samples) {
    sample.params = {0, 1.0 - 0.01 * sample.frames[0], 0, 0, 1, 0};
    sample.locals = {Eigen::Vector3d(-0.01 * (sample.frames[0] - 10), 0, 0)};  // cancels the 1 cm/frame on X
  }
  morph.constraints.push_back(shrinking);
  const SkateSummary ms = foot_skate(morph, PoseCache(std::span<const Motion>(&m, 1)));
  REQUIRE(ms.plants.size() == 1);
  CHECK(ms.plants[0].travel == Approx(0.03));  // only the slip on Z is left
}

TEST_CASE("metrics: RMS jerk of a sampled sine", "[metrics]") {
  const double fps = 120, amplitude = 0.2, hz = 2.0, w = 2 * kPi * hz;
  // 3 s: the 357 third differences span whole periods of the sine only approximately; 363 frames
  // make 360 = 6 periods of 60 samples exactly.
  Motion m = blank(363, fps);
  for (int f = 0; f < m.frame_count(); ++f) {
    m.values(f, 0) = amplitude * std::sin(w * f / fps);      // metres
    m.values(f, 3) = 2 * amplitude * std::sin(w * f / fps);  // radians
  }
  const JerkFigures j = rms_jerk(m);
  const double dt = 1 / fps;
  const double discrete = amplitude * std::pow(2 * std::sin(w * dt / 2) / dt, 3) / std::sqrt(2.0);
  CHECK(j.samples == 360);
  CHECK(j.translation_channels == 3);
  CHECK(j.rotation_channels == 3);
  // One of three position channels moves: RMS over channels is 1/sqrt(3) of that channel's.
  CHECK(j.translation == Approx(discrete / std::sqrt(3.0)).epsilon(1e-9));
  CHECK(j.rotation == Approx(2 * discrete / std::sqrt(3.0)).epsilon(1e-9));
  // ... which is A w^3 / sqrt 2 up to the difference operator's response at w dt = 0.1.
  CHECK(discrete == Approx(amplitude * w * w * w / std::sqrt(2.0)).epsilon(2e-3));

  SECTION("displacement jerk and wrapped angles") {
    Motion shifted = m;
    for (int f = 0; f < m.frame_count(); ++f) {
      shifted.values(f, 0) += 0.5;                                           // a constant: no jerk
      shifted.values(f, 3) = std::remainder(m.values(f, 3) + 3.0, 2 * kPi);  // wrapped: unwrapped back
    }
    CHECK(rms_jerk(shifted).rotation == Approx(j.rotation).epsilon(1e-9));
    const JerkFigures d = rms_jerk_of_displacement(shifted, m);
    CHECK(d.translation == Approx(0).margin(1e-6));
    CHECK(d.rotation == Approx(0).margin(1e-6));
  }
  SECTION("a linear angle wrapping at pi has no jerk") {
    Motion spin = blank(100, 30);
    for (int f = 0; f < 100; ++f) spin.values(f, 4) = std::remainder(0.3 * f, 2 * kPi);
    CHECK(rms_jerk(spin).rotation == Approx(0).margin(1e-6));
    Eigen::VectorXd u = spin.values.col(4);
    motion::unwrap_angles(std::span<double>(u.data(), 100));
    CHECK(u(99) == Approx(0.3 * 99));
  }
  CHECK(rms_jerk(blank(3, 30)).samples == 0);
  CHECK(rms_jerk(blank(3, 30)).rotation == 0);
}

TEST_CASE("metrics: energy above the key cut-off", "[metrics]") {
  CHECK(key_cutoff_hz(30, 4) == Approx(3.75));
  CHECK(key_cutoff_hz(120, 2) == Approx(30));
  CHECK_THROWS(key_cutoff_hz(30, 0));

  SECTION("DCT basis signals: the fraction is exact") {
    const int n = 200;
    const double fps = 30;
    // Bin m is m fps / (2 n) Hz = 0.075 m Hz; cut-off 3.75 Hz is bin 50.
    Eigen::VectorXd x(n);
    for (int k = 0; k < n; ++k)
      x(k) = 3.0 * std::cos(kPi * 20 * (k + 0.5) / n) + 1.0 * std::cos(kPi * 80 * (k + 0.5) / n);
    const BandEnergy e = energy_above(x, fps, key_cutoff_hz(fps, 4));
    CHECK(e.total == Approx(x.squaredNorm()));
    CHECK(e.fraction == Approx(1.0 / 10.0).epsilon(1e-9));  // 1^2 / (3^2 + 1^2)
    CHECK(energy_above(x, fps, key_cutoff_hz(fps, 1)).fraction == Approx(0).margin(1e-12));
    CHECK(energy_above(Eigen::VectorXd::Zero(n), fps, 1.0).fraction == 0);
    // A constant or a line has no energy above the cut-off to speak of (even extension: no edge jump).
    Eigen::VectorXd line(n);
    for (int k = 0; k < n; ++k) line(k) = 0.01 * k;
    CHECK(energy_above(line, fps, key_cutoff_hz(fps, 4)).fraction < 1e-3);
  }

  SECTION("a cubic B-spline displacement with keys every 4 frames stays below the cut-off") {
    Motion initial = blank(121, 30);
    Motion result = initial;
    std::mt19937 rng(7);
    std::normal_distribution<double> normal(0, 0.05);
    auto basis = [](double t) {  // uniform cubic B-spline, support [-2, 2]
      t = std::abs(t);
      if (t < 1) return (4 - 6 * t * t + 3 * t * t * t) / 6;
      if (t < 2) return (2 - t) * (2 - t) * (2 - t) / 6;
      return 0.0;
    };
    for (int c = 0; c < 6; ++c) {
      std::vector<double> controls(33);
      for (double& v : controls) v = normal(rng);
      for (int f = 0; f < 121; ++f) {
        double d = 0;
        for (int i = 0; i < 33; ++i)
          d += controls[static_cast<std::size_t>(i)] * basis((f - 4.0 * (i - 1)) / 4.0);
        result.values(f, c) += d;
      }
    }
    const AddedEnergy smooth = energy_above_cutoff(result, initial, {4});
    CAPTURE(smooth.translation.fraction, smooth.rotation.fraction);
    CHECK(smooth.translation.fraction < 0.02);
    CHECK(smooth.rotation.fraction < 0.02);
    CHECK(smooth.min_cutoff_hz == Approx(3.75));
    // The same displacement with frame-to-frame jitter over 20 frames (each frame its own mix,
    // as per-frame IK inside a plant): far more above. (A lone step would not do: its spectrum
    // falls as 1/f, so it holds little energy above the cut-off.)
    Motion snapped = result;
    for (int f = 60; f < 80; ++f) snapped.values.row(f).array() += f % 2 ? 0.02 : -0.02;
    const AddedEnergy snap = energy_above_cutoff(snapped, initial, {4});
    CHECK(snap.rotation.fraction > 2 * smooth.rotation.fraction);
    // Per-channel spacing: keys every frame put the cut-off at Nyquist, nothing above.
    CHECK(energy_above_cutoff(snapped, initial, std::vector<int>(6, 1)).rotation.above == 0);
    CHECK_THROWS_WITH(energy_above_cutoff(snapped, initial, {4, 4}), Contains("2 entries"));
    CHECK_THROWS_WITH(energy_above_cutoff(snapped, blank(120, 30), {4}), Contains("differ in shape"));
  }
}

TEST_CASE("retarget.metrics node: figures and the JSON report io.write_report writes", "[metrics]") {
  graph::Registry registry = test::registry_of(retarget_metrics_node_types());
  for (graph::NodeType& type : report_node_types()) registry.add_node(std::move(type));
  Motion source = blank(40, 30);
  for (int f = 0; f < 40; ++f) source.values(f, 1) = 1.0;
  Motion result = source;
  for (int f = 0; f < 40; ++f) result.values(f, 4) = 0.1 * std::sin(0.5 * f);
  ConstraintSet set;
  set.constraints.push_back(on_foot("position", {0.0, 0.0, 0.02, 1, 1, 1}, 5, 10, "plant"));
  test::TempDir dir;
  const std::string path = (dir.path() / "out" / "metrics.json").string();
  KeySpacing keys{std::vector<int>(6, 2), "by hand"};
  const test::NodeContext ctx =
      test::run_node(registry, "retarget.metrics", test::params_for(registry, "retarget.metrics"),
                     {{"motion", graph::Value::make(result)},
                      {"constraints", graph::Value::make(set)},
                      {"source", graph::Value::make(source)},
                      {"keys", graph::Value::make(keys)},
                      {"solve_seconds", graph::Value::make(0.25)}});
  CHECK(std::get<double>(ctx.figures.at("worst_position_cm")) > 0);
  CHECK(std::get<double>(ctx.figures.at("jerk_rotation_increase")) > 0);
  CHECK(std::get<double>(ctx.figures.at("solve_seconds")) == 0.25);
  CHECK(std::get<std::int64_t>(ctx.figures.at("plants")) == 1);
  const kg::Report& report = ctx.outputs.at("report").get<kg::Report>();
  const test::NodeContext written = test::run_node(
      registry, "io.write_report", test::params_for(registry, "io.write_report", {{"path", path}}),
      {{"report", ctx.outputs.at("report")}});
  CHECK(std::get<bool>(written.figures.at("written")));
  std::ifstream in(path);
  REQUIRE(in);
  std::stringstream text;
  text << in.rdbuf();
  CHECK(text.str() == report.text() + "\n");  // the document, then a blank line
  CHECK_THAT(text.str(), Contains("\"version\": 1") && Contains("\"reference\": \"source\"") &&
                             Contains("\"cutoff_hz_min\": 7.5") && Contains("\"solve_seconds\": 0.25"));
  // No path: nothing written, and said so.
  const test::NodeContext none =
      test::run_node(registry, "io.write_report", test::params_for(registry, "io.write_report"),
                     {{"report", ctx.outputs.at("report")}});
  CHECK_FALSE(std::get<bool>(none.figures.at("written")));
  CHECK(none.logged("nothing written"));

  // Bad input names what is wrong.
  Constraint other = on_foot("position", {0, 0, 0}, 1, 1, "partner hand");
  other.points[0].character = 1;
  ConstraintSet two;
  two.constraints.push_back(other);
  CHECK_THROWS_WITH(
      test::run_node(registry, "retarget.metrics", test::params_for(registry, "retarget.metrics"),
                     {{"motion", graph::Value::make(result)}, {"constraints", graph::Value::make(two)}}),
      Contains("partner hand") && Contains("character 1"));
  CHECK_THROWS_WITH(
      test::run_node(registry, "retarget.metrics", test::params_for(registry, "retarget.metrics"),
                     {{"motion", graph::Value::make(result)},
                      {"constraints", graph::Value::make(set)},
                      {"initial", graph::Value::make(blank(39, 30))}}),
      Contains("differ in shape"));
}
