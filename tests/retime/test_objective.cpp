#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "kg/retime/force_model.hpp"
#include "kg/retime/objective.hpp"
#include "kg/retime/retime_clip.hpp"

using namespace kg::retime;
using namespace kg::body;

namespace {

// A 2 s clip at 30 fps of a body with two channels and no contact columns: τ = (ṗ² − 1, 0.5 p̈),
// so the torque term against τ' = 0 is (ṗ² − 1)² + 0.25 p̈² (times 0.01). Its hull is a box
// |p̈| <= 60, 0.1 <= ṗ² <= 30, except for a flight second (source 0.5 to 1.5 s) whose polytope is
// empty: the single point (0, 1).
struct BoxAndFlight {
  kg::motion::Skeleton skeleton;  // a root with the two channels
  Hulls hulls;
  std::vector<FrameTorques> torques;
  std::vector<Eigen::VectorXd> targets;
};

BoxAndFlight box_and_flight() {
  BoxAndFlight c;
  c.skeleton.add_joint({.name = "root",
                        .channels = {{.kind = kg::motion::ChannelKind::Xposition},
                                     {.kind = kg::motion::ChannelKind::Yposition}}});
  FrameTorques t;
  t.velocity = Eigen::Vector2d(1, 0);
  t.acceleration = Eigen::Vector2d(0, 0.5);
  t.gravity = Eigen::Matrix<double, Eigen::Dynamic, 3>::Zero(2, 3);
  t.gravity(0, 1) = 1 / 9.81;  // g = (0, -9.81, 0) gives -1
  for (int f = 0; f <= 60; ++f) {
    FrameHull hull;
    hull.N = Eigen::MatrixXd::Zero(2, 0);
    if (f >= 15 && f <= 45) {
      hull.status = HullStatus::Flight;
      hull.vertices = {{0.0, 1.0}};
    } else {
      hull.vertices = {{-60, 0.1}, {60, 0.1}, {60, 30}, {-60, 30}};
    }
    hull.lambda.assign(hull.vertices.size(), Eigen::VectorXd());
    hull.on_box.assign(hull.vertices.size(), 0);
    hull.centre_lambda = Eigen::VectorXd();
    build_fan(hull);
    c.hulls.frames.push_back(hull);
    c.torques.push_back(t);
    c.targets.push_back(Eigen::Vector2d::Zero());
  }
  return c;
}

// Random hulls of every kind the objective meets, with contact columns (so each fan sector has
// its own quadratic), in runs of three frames: a polygon with the centre inside, at a vertex, on
// an edge; a polygon without columns; a segment with the centre in the middle, at an end; an
// infeasible point; a flight point. Five channels, the first three the root's.
struct Mixed {
  kg::motion::Skeleton skeleton;
  Hulls hulls;
  std::vector<FrameTorques> torques;
  std::vector<Eigen::VectorXd> targets;
};

Mixed mixed(int frames, unsigned seed) {
  using kg::motion::ChannelKind;
  Mixed c;
  c.skeleton.add_joint(
      {.name = "root",
       .channels = {{ChannelKind::Xposition}, {ChannelKind::Yposition}, {ChannelKind::Zposition}}});
  c.skeleton.add_joint(
      {.name = "arm", .parent = 0, .channels = {{ChannelKind::Xrotation}, {ChannelKind::Zrotation}}});
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1), signed_unit(-1, 1);
  const int channels = 5, columns = 4;
  auto random_vector = [&](int n, double scale) {
    Eigen::VectorXd v(n);
    for (int i = 0; i < n; ++i) v[i] = scale * signed_unit(rng);
    return v;
  };
  auto random_lambda = [&] {
    Eigen::VectorXd l(columns);
    for (int i = 0; i < columns; ++i) l[i] = 100 * unit(rng);
    return l;
  };
  for (int f = 0; f < frames; ++f) {
    const int kind = (f / 3) % 8;
    FrameHull h;
    h.N = kind == 3 || kind == 7 ? Eigen::MatrixXd::Zero(channels, 0)
                                 : Eigen::MatrixXd(Eigen::MatrixXd::Random(channels, columns));
    const int k = static_cast<int>(h.N.cols());
    auto lambda = [&] { return k ? random_lambda() : Eigen::VectorXd(); };
    const Eigen::Vector2d middle(4 * signed_unit(rng), 1 + unit(rng));
    if (kind <= 3) {
      // Points of an ellipse in angular order: a convex polygon, counter-clockwise.
      const int n = 3 + static_cast<int>(unit(rng) * 10);
      const double rx = 2 + 18 * unit(rng), ry = 0.5 + 4.5 * unit(rng),
                   turn = 2 * std::numbers::pi * unit(rng);
      std::vector<double> angles;
      for (int i = 0; i < n; ++i) angles.push_back(turn + 2 * std::numbers::pi * unit(rng));
      std::sort(angles.begin(), angles.end());
      for (double a : angles)
        h.vertices.push_back(middle + Eigen::Vector2d(rx * std::cos(a), ry * std::sin(a)));
      const int j = static_cast<int>(unit(rng) * n);
      if (kind == 1) {
        h.centre = h.vertices[static_cast<std::size_t>(j)];
      } else if (kind == 2) {
        h.centre = 0.5 * (h.vertices[static_cast<std::size_t>(j)] +
                          h.vertices[static_cast<std::size_t>((j + 1) % n)]);
      } else {
        Eigen::Vector2d sum = Eigen::Vector2d::Zero();
        double total = 0;
        for (const Eigen::Vector2d& v : h.vertices) {
          const double w = unit(rng);
          sum += w * v, total += w;
        }
        h.centre = sum / total;
      }
    } else if (kind <= 5) {
      h.vertices = {middle, middle + Eigen::Vector2d(10 * signed_unit(rng), 2 * signed_unit(rng))};
      h.centre = kind == 4 ? Eigen::Vector2d(0.5 * (h.vertices[0] + h.vertices[1])) : h.vertices[1];
    } else {
      h.status = kind == 6 ? HullStatus::Infeasible : HullStatus::Flight;
      h.vertices = {middle};
      h.centre = middle;
    }
    for (std::size_t i = 0; i < h.vertices.size(); ++i) h.lambda.push_back(lambda());
    h.on_box.assign(h.vertices.size(), 0);
    h.centre_lambda = lambda();
    build_fan(h);
    c.hulls.frames.push_back(std::move(h));
    FrameTorques t;
    t.velocity = random_vector(channels, 50);
    t.acceleration = random_vector(channels, 20);
    t.gravity = Eigen::Matrix<double, Eigen::Dynamic, 3>::Random(channels, 3) * 10;
    c.torques.push_back(std::move(t));
    c.targets.push_back(random_vector(channels, 100));
  }
  return c;
}

// One frame's integrand and gradient as the objective defines it, computed the plain way: the
// sector searched from 0, the closest point by looking at every edge.
struct Reference {
  double value, d_a, d_b;
};
Reference reference_frame(const BakedObjective& o, const FrameHull& h, int f, const Eigen::Vector2d& x,
                          double alpha) {
  const Quadratic& q = o.quadratic(f, find_sector(h, x, 0));
  const double a = x.x(), b = x.y();
  Reference r{q[0] * b * b + q[1] * a * a + q[2] * a * b + q[3] * b + q[4] * a + q[5],
              2 * q[1] * a + q[2] * b + q[4], 2 * q[0] * b + q[2] * a + q[3]};
  if (h.status == HullStatus::Flight) {
    const Quadratic& w = o.flight_quadratic(f);
    r.value += alpha * (w[0] * b * b + w[1] * a * a + w[2] * a * b + w[3] * b + w[4] * a + w[5]);
    r.d_a += alpha * (2 * w[1] * a + w[2] * b + w[4]);
    r.d_b += alpha * (2 * w[0] * b + w[2] * a + w[3]);
    return r;
  }
  const HullPoint c = closest_point_on_polygon(h.vertices, x);
  if (!c.inside) {
    const Eigen::Vector2d gap = x - c.point;
    r.value += alpha * gap.squaredNorm();
    r.d_a += 2 * alpha * gap.x();
    r.d_b += 2 * alpha * gap.y();
  }
  return r;
}

}  // namespace

TEST_CASE("the baked objective agrees with a plain evaluation everywhere, whatever the hint") {
  const double fps = 30, alpha = 1000;
  const Mixed c = mixed(96, 11);
  const BakedObjective o(c.hulls, c.torques, c.targets, c.skeleton, fps,
                         {.alpha = alpha, .beta = 1, .torque_scale = 40});
  const int last = static_cast<int>(c.hulls.frames.size()) - 1;
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> unit(0, 1);
  int checked = 0, outside = 0;
  // At a fan's centre, or on a ray between two sectors (through a vertex), more than one sector
  // holds x, the torque term has a kink and its gradient is that of the sector the search
  // meets first: only the value is compared there.
  auto check = [&](double p, const Eigen::Vector2d& x, int& hint, bool on_ray = false) {
    const double s = std::clamp(p * fps, 0.0, static_cast<double>(last));
    const int f = std::min(static_cast<int>(s), last - 1);
    const double u = s - f;
    const Reference r0 = reference_frame(o, c.hulls.frames[static_cast<std::size_t>(f)], f, x, alpha);
    const Reference r1 = reference_frame(o, c.hulls.frames[static_cast<std::size_t>(f) + 1], f + 1, x, alpha);
    const SampleCost got = o.evaluate(p, x.x(), x.y(), hint);
    const double value = (1 - u) * r0.value + u * r1.value;
    // 1e-12 of the quantities each result is made of.
    const double scale = 1e-12 * (std::abs(r0.value) + std::abs(r1.value) + 1);
    INFO("p " << p << " frame " << f << " x (" << x.x() << ", " << x.y() << ")");
    CHECK(std::abs(got.value - value) <= scale);
    CHECK(std::abs(got.d_p - (r1.value - r0.value) * fps) <= scale * fps);
    if (!on_ray) {
      CHECK(std::abs(got.d_pddot - ((1 - u) * r0.d_a + u * r1.d_a)) <= scale);
      CHECK(std::abs(got.d_pdot2 - ((1 - u) * r0.d_b + u * r1.d_b)) <= scale);
    }
    ++checked;
    outside += !closest_point_on_polygon(c.hulls.frames[static_cast<std::size_t>(f)].vertices, x).inside;
  };
  const double duration = o.source_duration();
  // A retimer's sweep: p rising, (p̈, ṗ²) wandering, one hint carried along, from a few starts.
  for (int start : {0, 7, -3, 123456789}) {
    int hint = start;
    Eigen::Vector2d x(0, 1);
    std::normal_distribution<double> step(0, 0.4);
    for (double p = 0; p <= duration; p += 0.2 / fps) {
      x += Eigen::Vector2d(3 * step(rng), step(rng));
      x = x.cwiseMax(Eigen::Vector2d(-40, -6)).cwiseMin(Eigen::Vector2d(40, 30));
      check(p, x, hint);
    }
  }
  // Random jumps with random hints.
  std::uniform_int_distribution<int> any_int;
  for (int i = 0; i < 3000; ++i) {
    int hint = i % 3 == 0 ? 0 : any_int(rng) - (i % 3 == 1 ? 0 : (1 << 30));
    check(duration * unit(rng), Eigen::Vector2d(-40 + 80 * unit(rng), -6 + 36 * unit(rng)), hint);
  }
  // Near each hull's vertices and edges, inside and out, at the centre and at p beyond the clip.
  for (int f = 0; f <= last; ++f) {
    const FrameHull& h = c.hulls.frames[static_cast<std::size_t>(f)];
    const auto n = h.vertices.size();
    int hint = 0;
    for (int i = 0; i < 40; ++i) {
      const Eigen::Vector2d& v = h.vertices[static_cast<std::size_t>(i) % n];
      const Eigen::Vector2d& w = h.vertices[(static_cast<std::size_t>(i) + 1) % n];
      const double t = i % 2 ? unit(rng) : 0.0,
                   offset = std::pow(10.0, -9 * unit(rng)) * (unit(rng) < 0.5 ? -1 : 1);
      const Eigen::Vector2d direction(std::cos(7.0 * i), std::sin(7.0 * i));
      const double p = (f + (i % 4 == 0 ? 0.0 : unit(rng))) / fps;
      check(p, v + t * (w - v) + offset * direction, hint);
    }
    check(f / fps, h.centre, hint, true);
    check(f / fps, h.vertices[0], hint, true);
  }
  int hint = 0;
  check(-1, Eigen::Vector2d(0.5, 2), hint);
  check(duration + 1, Eigen::Vector2d(-50, -3), hint);
  CHECK(checked > 8000);
  CHECK(outside > checked / 4);
}

TEST_CASE("bake_quadratic reproduces |τ − τ'|²") {
  const Eigen::Vector3d t0(1, 2, 3), ta(0.5, -1, 2), tb(-2, 0.3, 1), target(0.1, 0.2, -0.3);
  const Quadratic q = bake_quadratic(t0, ta, tb, target, 2.0);
  for (double a : {-1.0, 0.3}) {
    for (double b : {0.5, 2.0}) {
      const double direct = 2.0 * (t0 + ta * a + tb * b - target).squaredNorm();
      CHECK(q[0] * b * b + q[1] * a * a + q[2] * a * b + q[3] * b + q[4] * a + q[5] == Approx(direct));
    }
  }
}

TEST_CASE("the baked objective's partial derivatives match finite differences, inside and outside hulls") {
  const BoxAndFlight c = box_and_flight();
  const BakedObjective objective(c.hulls, c.torques, c.targets, c.skeleton, 30, {.alpha = 10, .beta = 0.01});
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> p(0.02, 1.98), a(-4, 4), b(-0.5, 7);
  for (int i = 0; i < 200; ++i) {
    const double pp = p(rng), aa = a(rng), bb = b(rng), h = 1e-6;
    int hint = 0;
    const SampleCost c = objective.evaluate(pp, aa, bb, hint);
    auto value = [&](double x, double y, double z) {
      int k = 0;
      return objective.evaluate(x, y, z, k).value;
    };
    CHECK(c.d_pddot ==
          Approx((value(pp, aa + h, bb) - value(pp, aa - h, bb)) / (2 * h)).epsilon(1e-5).margin(1e-6));
    CHECK(c.d_pdot2 ==
          Approx((value(pp, aa, bb + h) - value(pp, aa, bb - h)) / (2 * h)).epsilon(1e-5).margin(1e-6));
    // Within a frame interval the value is linear in p; across a frame time d_p jumps, so only
    // points off the frame times are checked.
    const double x = pp * 30 - std::floor(pp * 30);
    if (x > 1e-3 && x < 1 - 1e-3)
      CHECK(c.d_p ==
            Approx((value(pp + h, aa, bb) - value(pp - h, aa, bb)) / (2 * h)).epsilon(1e-5).margin(1e-6));
  }
}

TEST_CASE("the baked torque term is the force model's |τ − τ'|² in every sector") {
  const BoxAndFlight c = box_and_flight();
  const BakedObjective objective(c.hulls, c.torques, c.targets, c.skeleton, 30,
                                 {.alpha = 1, .beta = 2, .torque_scale = 0.5});
  for (int f : {3, 20}) {
    for (const Eigen::Vector2d& x :
         {Eigen::Vector2d(0, 1), Eigen::Vector2d(5, 3), Eigen::Vector2d(-100, -2)}) {
      const Eigen::VectorXd tau = c.torques[static_cast<std::size_t>(f)].at(x.y(), x.x(), c.hulls.gravity);
      CHECK(objective.parts(f, x.x(), x.y()).torque == Approx(2 * tau.squaredNorm() / 0.25));
    }
  }
  CHECK(objective.parts(3, 0, 1).inside);
  // The flight's admissible timings do not depend on α: with α = 0 the region is still there.
  const BakedObjective no_alpha(c.hulls, c.torques, c.targets, c.skeleton, 30, {.alpha = 0, .beta = 1});
  CHECK(no_alpha.admissible_region(20, 0.1).size() == 16);
  CHECK(no_alpha.flight_excess(20, 0, 1.5) == Approx(0.25));
  CHECK_FALSE(objective.parts(20, 0, 1.5).inside);
  CHECK(objective.parts(20, 0, 1.5).feasibility == Approx(0.25));
  // The flight weight multiplies α on flight frames only, value and gradient alike.
  const BakedObjective flight_heavy(c.hulls, c.torques, c.targets, c.skeleton, 30,
                                    {.alpha = 1, .beta = 2, .torque_scale = 0.5, .flight = 7});
  CHECK(flight_heavy.parts(20, 0, 1.5).feasibility == Approx(7 * 0.25));
  CHECK(flight_heavy.parts(20, 0, 1.5).torque == Approx(objective.parts(20, 0, 1.5).torque));
  CHECK(flight_heavy.parts(3, 30, 40).feasibility == Approx(objective.parts(3, 30, 40).feasibility));
  CHECK(objective.parts(3, 30, 40).feasibility > 0);
  int h0 = 0, h1 = 0;
  const double p20 = 20.0 / 30;
  const SampleCost light = objective.evaluate(p20, 0.5, 1.5, h0),
                   heavy = flight_heavy.evaluate(p20, 0.5, 1.5, h1);
  const Eigen::VectorXd tau = c.torques[20].at(1.5, 0.5, c.hulls.gravity);
  const double torque = 2 * tau.squaredNorm() / 0.25;
  CHECK(heavy.value - torque == Approx(7 * (light.value - torque)));
  CHECK_THROWS_WITH(BakedObjective(c.hulls, c.torques, c.targets, c.skeleton, 30, {.flight = -1}),
                    Catch::Contains("flight weight"));
}

TEST_CASE("retiming a clip with a flight to a shorter duration keeps the flight at source speed") {
  // 2 s of source into 1.3 s: the flight second keeps its second, the other second of source
  // plays in 0.3 s.
  const BoxAndFlight c = box_and_flight();
  const BakedObjective objective(c.hulls, c.torques, c.targets, c.skeleton, 30,
                                 {.alpha = 1000, .beta = 0.01});
  const RetimeResult r = retime(objective, {.duration = 1.3, .knot_spacing = 0.05});
  INFO(r.message);
  CHECK(r.converged);
  int flight = 0, flight_at_speed = 0;
  double worst_outside = 0;  // plane units, on the ground
  for (double t = 0; t <= 1.3; t += 0.005) {
    const WarpSample s = r.warp.sample(t);
    const int f = static_cast<int>(std::lround(s.p * 30));
    if (f >= 18 && f <= 42) ++flight, flight_at_speed += std::abs(s.pdot - 1) < 0.1;
    if (f < 15 || f > 45)
      worst_outside =
          std::max(worst_outside, std::sqrt(objective.parts(f, s.pddot, s.pdot * s.pdot).feasibility / 1000));
  }
  CHECK(flight_at_speed == flight);
  CHECK(worst_outside < 0.5);  // against a box 120 wide and 30 high: the speed-up after landing
}

TEST_CASE("retime_clip solves a clip with flight from two starts and keeps the lower objective") {
  const BoxAndFlight c = box_and_flight();
  const ClipRetimeOptions options{.solve = {.duration = 1.3, .knot_spacing = 0.05}};
  const ClipRetime r = retime_clip(c.hulls, c.torques, 30, options, c.skeleton);
  INFO(r.message);
  CHECK_THAT(r.message, Catch::Contains("the better of two starts (constant speed; flights at source speed"));
  // The same objective solved from constant speed alone: the kept solution is no worse.
  const std::vector<Eigen::VectorXd> targets = original_torques(c.hulls, c.torques);
  const BakedObjective objective(
      c.hulls, c.torques, targets, c.skeleton, 30,
      {.alpha = options.alpha, .beta = options.beta, .torque_scale = torque_scale(c.skeleton, targets)});
  const RetimeResult single = retime(objective, options.solve);
  auto value = [&](const TimeWarp& w) { return integrate(objective, w, sample_grid(w, 30, 4)); };
  CHECK(value(r.warp) <= value(single.warp) * (1 + 1e-12));
  CHECK(r.solve.iterations > single.iterations);  // both solves counted
  // Pins: one start only (a playback through them is the constant-speed one).
  ClipRetimeOptions pinned = options;
  pinned.solve.pins = {{.source_time = 1.0, .output_time = 0.5}};
  CHECK_THAT(retime_clip(c.hulls, c.torques, 30, pinned, c.skeleton).message, !Catch::Contains("two starts"));
  // A clip of nothing but flight (a library caller's: retime.hulls refuses it) has no rest to
  // speed up: one start.
  BoxAndFlight all_flight = c;
  for (FrameHull& hull : all_flight.hulls.frames) {
    hull.status = HullStatus::Flight;
    hull.vertices = {{0.0, 1.0}};
    hull.lambda.assign(1, Eigen::VectorXd());
    hull.on_box.assign(1, 0);
    build_fan(hull);
  }
  // Longer than the source: the flight at source speed would leave time with nothing to play.
  const ClipRetimeOptions longer{.solve = {.duration = 2.5, .knot_spacing = 0.05}};
  const ClipRetime flying =
      retime_clip(all_flight.hulls, all_flight.torques, 30, longer, all_flight.skeleton);
  CHECK_THAT(flying.message, !Catch::Contains("two starts"));
  CHECK(flying.warp.strictly_increasing());
}
