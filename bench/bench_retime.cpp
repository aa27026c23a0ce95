// Retiming figures, one thread (McCann et al. 2006 §3.5, §3.6, §4.1, §4.3), in three sections.
//
// 1. fig12: per source frame, after the paper's fig. 12, on a CMU walk (16_15.amc on 16.asf, 120
//    fps, 62 channels, a rod along every bone at 10 kg/m, path derivatives through a 0.04 s
//    Gaussian as graphs/retime.yaml takes them) and chains of 10, 100 and 1,000 links of three
//    rotation channels each (C10, C100, C1000: fixed bases, 120 frames of smooth random swinging).
//      KDL RNEA     one plain inverse dynamics call of KDL (ChainIdSolver_RNE on the chains, three
//                   one-DOF segments per link, two of them massless; TreeIdSolver_RNE on the walk's
//                   tree, root channels as six joints from KDL's base), q̇ = q', q̈ = q'';
//      RNEA         our inverse_dynamics, the same numbers (dynamics.hpp);
//      Force        frame_torques: every coefficient of τ(ṗ², p̈, g), the paper's "Force";
//      Force (k)    frame_torques_mass_scale: the same and their change with one segment's mass;
//      Feasible     build_frame_hull: the hull of feasible timings (GLPK) and the force model's fan
//                   of one frame (hulls.hpp, force_model.hpp), with the frame's coefficients and
//                   contacts already made (16_15: detect_contacts' two feet, torque limits ±300 N m;
//                   the chains: fixed bases without contact, every channel limited to 1.5 times its
//                   largest |τ| along the clip at the original timing, the paper's limits
//                   "observed" in the motion, so their hulls come from torque limits alone);
//      Bake         the BakedObjective constructor over the clip (sector torques and the six
//                   coefficients of every sector, the flight terms), divided by the frames;
//      Obj          BakedObjective::evaluate (value and gradient) at every sample of the retimer's
//                   final grid (RetimeResult::grid: per spline segment, at least 4 samples per
//                   source frame at that segment's fastest playback, sample_grid, refined where the
//                   solve sped a segment up) along the warp the retimer returns for 0.8 times the
//                   clip's duration, in order with the retimer's sector hint; the time of the whole
//                   grid divided by the source frames. "Per frame" thus covers every sample falling
//                   in one source frame (the samples per frame are printed); per evaluation is
//                   printed below the table;
//      NP-Obj       the same integrand and gradient without baking: per evaluation and per channel
//                   τ = t0 + Ta p̈ + Tb ṗ² from the sector's torques (sector_torques, precomputed per
//                   sector, not reduced to six coefficients) and its squared error; the feasibility
//                   term as Obj's;
//      Naive        everything recomputed per evaluation: inverse_dynamics at the state (q̇ = q' ṗ,
//                   q̈ = q'' ṗ² + q' p̈) with the contact forces of the fan's λ interpolation as
//                   external forces, the squared error, the feasibility term (value only: a
//                   gradient would cost at least two more inverse dynamics per frame).
//    Times are the median over 9 batches of the mean time per frame, each batch running the whole
//    clip as often as needed to last 20 ms. The paper's Naive (78 ms for 16_16, ≈ Force + Feasible)
//    also rebuilt the hulls; ours does not (add the Feasible row for that).
// 2. optimiser: retime_clip to 0.8 times the duration of CMU 07_05 (AMC at 120 Hz resampled to
//    60 Hz: 259 frames) and 16_15 (resampled to 30 Hz: 118 frames), the pipeline of
//    graphs/retime.yaml (de Leva male 70 kg, detected contacts, smoothing 0.04 s, default hulls,
//    objective match): iterations, evaluations, the final grid's samples, the objective the
//    solve reached (RetimeResult::objective, on that grid), solve time (median of 3 solves), the
//    share of output frames inside their hulls.
// 3. jump: the CMU jumps 16_01 (its header says 30 fps, it is 120), 13_11 and 13_13 (Daz BVH)
//    through the same pipeline at 30 Hz, retimed to 0.5 and 0.65 of their duration, and to 0.5 with
//    graphs/retime/jump_half.yaml's flight weight (fig. 1's experiment: the flight weighs more than
//    the ground phases, which take what no timing can fit in their hulls): the playback
//    speed ṗ at the output time each flight frame (HullStatus::Flight) plays, and the vertical
//    acceleration of the root (and of the body's centre of mass) in the output motion at 30 Hz
//    during flight, by second differences over output frames whose neighbours also play flight;
//    with the source's own figures for comparison. Per flight frame (and two on either side) the
//    source's accelerations show frames detected as flight that are not ballistic.
//
//   bench_retime [NAME]   (only the cases whose "section name" contains NAME: "fig12", "C100",
//                          "optimiser", "07_05", "jump", "13_11", ...)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#ifdef KG_HAVE_KDL
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <kdl/treeidsolver_recursive_newton_euler.hpp>

#include "../tests/support/kdl_body.hpp"
#endif

#include "kg/body/body_build.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/motion/resample.hpp"
#include "kg/retime/contacts.hpp"
#include "kg/retime/dynamics.hpp"
#include "kg/retime/force_model.hpp"
#include "kg/retime/hulls.hpp"
#include "kg/retime/objective.hpp"
#include "kg/retime/path.hpp"
#include "kg/retime/playback.hpp"
#include "kg/retime/retime_clip.hpp"

using namespace kg;
using body::BodyModel;

namespace {

constexpr double kLink = 0.3;                  // metres per chain link
constexpr double kSmoothing = 0.04;            // s: graphs/retime.yaml's path smoothing
constexpr double kJumpHalfFlightWeight = 300;  // graphs/retime/jump_half.yaml's flight_weight
constexpr double kSampleScale = 0.8;           // the duration whose solution gives the Obj rows' samples

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

volatile double g_sink = 0;  // keeps results observable

// How many passes over the clip make a batch of at least 20 ms (after a warm-up pass).
int passes_for(int frames, const std::function<void(int)>& work) {
  for (int f = 0; f < frames; ++f) work(f);
  const double t0 = now();
  int passes = 0;
  do {
    for (int f = 0; f < frames; ++f) work(f);
    ++passes;
  } while (now() - t0 < 0.02);
  return passes;
}

// Mean seconds per call of work(f) over `passes` passes over the clip.
double batch(int frames, int passes, const std::function<void(int)>& work) {
  const double t0 = now();
  for (int p = 0; p < passes; ++p)
    for (int f = 0; f < frames; ++f) work(f);
  return (now() - t0) / (passes * frames);
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// Median over 9 batches of the mean seconds per call of work(f), f running over every frame.
double seconds_per_frame(int frames, const std::function<void(int)>& work) {
  const int passes = passes_for(frames, work);
  std::vector<double> batches;
  for (int b = 0; b < 9; ++b) batches.push_back(batch(frames, passes, work));
  return median(batches);
}

// Median over 9 pairs of batches, run back to back, of time(a) / time(b): a ratio that holds when
// the machine's load drifts between rows.
double paired_ratio(int frames, const std::function<void(int)>& a, const std::function<void(int)>& b) {
  const int pa = passes_for(frames, a), pb = passes_for(frames, b);
  std::vector<double> ratios;
  for (int i = 0; i < 9; ++i) ratios.push_back(batch(frames, pa, a) / batch(frames, pb, b));
  return median(ratios);
}

// A rod of `mass` kg from the joint's origin to `tip` (joint frame): centre of mass halfway, inertia
// of a cylinder of radius 4 cm.
body::SegmentInertia rod(double mass, const Eigen::Vector3d& tip) {
  body::SegmentInertia s;
  s.mass = mass;
  s.com = tip / 2;
  const double l = tip.norm(), r = 0.04;
  const Eigen::Vector3d u = l > 0 ? Eigen::Vector3d(tip / l) : Eigen::Vector3d::UnitY();
  const double along = mass * r * r / 2, across = mass * (3 * r * r + l * l) / 12;
  s.inertia = across * Eigen::Matrix3d::Identity() + (along - across) * u * u.transpose();
  return s;
}

// One point of the retimer's grid: source time and retiming state.
struct Sample {
  double p = 0, pddot = 0, pdot2 = 0;
};

struct Case {
  std::string name;
  BodyModel body;
  motion::Motion clip;
  retime::PathDerivatives d;
  int heavy = 0;  // the segment whose mass the Force (k) row scales
#ifdef KG_HAVE_KDL
  std::vector<std::array<KDL::JntArray, 3>> kdl_frames;  // q, q', q'' in KDL's joint order
  std::function<void(int, KDL::JntArray&)> kdl;          // τ of one frame, KDL's joint order
#endif

  // The retiming problem (prepare_problem), made once outside every timing.
  bool prepared = false;
  BodyModel limited;                          // body with torque limits
  retime::Contacts contacts;                  // detected feet, or none (a fixed base)
  std::vector<retime::FrameTorques> torques;  // frame_torques of every frame
  retime::Hulls hulls;
  std::vector<Eigen::VectorXd> targets;  // τ' = original_torques (keep the look)
  retime::ObjectiveWeights weights;      // retime_clip's defaults
  retime::ClipRetime solution;           // retime_clip at kSampleScale
  std::vector<Sample> samples;           // its grid
  std::vector<int> first_sample;         // per source frame (frames + 1): its samples' range
};

#ifdef KG_HAVE_KDL
// The clip's q, q', q'' in KDL's joint order (DynamicsTopology's), converted once outside the timing.
void kdl_frames(Case& c) {
  const std::vector<int> order = body::DynamicsTopology::of(*c.body.skeleton).order;
  const auto n = static_cast<unsigned>(order.size());
  for (int f = 0; f < c.clip.frame_count(); ++f) {
    std::array<KDL::JntArray, 3> a{KDL::JntArray(n), KDL::JntArray(n), KDL::JntArray(n)};
    for (unsigned i = 0; i < n; ++i) {
      a[0](i) = c.clip.values(f, order[i]);
      a[1](i) = c.d.first(f, order[i]);
      a[2](i) = c.d.second(f, order[i]);
    }
    c.kdl_frames.push_back(std::move(a));
  }
}
#endif

// "C10" (built piecewise: g++ 12 warns falsely on "C" + std::to_string(n)).
std::string chain_name(int links) {
  std::string name = std::to_string(links);
  name.insert(0, 1, 'C');
  return name;
}

// A fixed root and `links` joints of X, Y, Z rotation channels hanging 0.3 m apart, 2 kg rods;
// 120 frames at 120 fps of smooth random swinging.
std::unique_ptr<Case> chain_case(int links) {
  auto c = std::make_unique<Case>();
  c->name = chain_name(links);
  auto s = std::make_shared<motion::Skeleton>();
  s->add_joint({.name = "base"});
  for (int i = 1; i <= links; ++i)
    s->add_joint({.name = "link" + std::to_string(i),
                  .parent = i - 1,
                  .offset = i == 1 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(0, -kLink, 0),
                  .channels = {{motion::ChannelKind::Xrotation},
                               {motion::ChannelKind::Yrotation},
                               {motion::ChannelKind::Zrotation}}});
  c->body.skeleton = s;
  c->body.segments.push_back({});
  for (int i = 1; i <= links; ++i) c->body.segments.push_back(rod(2.0, {0, -kLink, 0}));
  c->heavy = links / 2;
  const int frames = 120;
  c->clip = {s, motion::FrameMatrix(frames, s->channel_count()), 120, c->name};
  std::mt19937 rng(links);
  std::uniform_real_distribution<double> freq(0.5, 2), phase(0, 2 * M_PI);
  for (int ch = 0; ch < s->channel_count(); ++ch) {
    const double w = 2 * M_PI * freq(rng), p = phase(rng);
    for (int f = 0; f < frames; ++f) c->clip.values(f, ch) = 0.5 * std::sin(w * f / 120.0 + p);
  }
  c->d = retime::path_derivatives(c->clip);
#ifdef KG_HAVE_KDL
  // Three one-DOF segments per link; the third carries the rod (in its tip frame, 0.3 m down)
  // and the offset to the next link.
  auto chain = std::make_shared<KDL::Chain>();
  const body::SegmentInertia r = rod(2.0, {0, -kLink, 0});
  const KDL::RigidBodyInertia inertia(
      r.mass, test::kdl(Eigen::Vector3d(r.com - Eigen::Vector3d(0, -kLink, 0))),
      KDL::RotationalInertia(r.inertia(0, 0), r.inertia(1, 1), r.inertia(2, 2), r.inertia(0, 1),
                             r.inertia(0, 2), r.inertia(1, 2)));
  for (int i = 1; i <= links; ++i) {
    chain->addSegment(KDL::Segment(KDL::Joint(KDL::Joint::RotX)));
    chain->addSegment(KDL::Segment(KDL::Joint(KDL::Joint::RotY)));
    chain->addSegment(
        KDL::Segment(KDL::Joint(KDL::Joint::RotZ), KDL::Frame(KDL::Vector(0, -kLink, 0)), inertia));
  }
  auto solver = std::make_shared<KDL::ChainIdSolver_RNE>(*chain, KDL::Vector(0, -9.81, 0));
  auto wrenches = std::make_shared<KDL::Wrenches>(chain->getNrOfSegments(), KDL::Wrench::Zero());
  kdl_frames(*c);
  Case* raw = c.get();
  c->kdl = [raw, chain, solver, wrenches](int f, KDL::JntArray& tau) {
    const auto& a = raw->kdl_frames[static_cast<std::size_t>(f)];
    solver->CartToJnt(a[0], a[1], a[2], *wrenches, tau);
  };
#endif
  return c;
}

// CMU 16_15 on 16.asf: a rod along every bone (to its End Site, or its first child), 10 kg per metre.
std::unique_ptr<Case> walk_case() {
  const std::string asf = std::string(KG_DATA_DIR) + "/cmu/asf_amc/16.asf";
  const std::string amc = std::string(KG_DATA_DIR) + "/cmu/asf_amc/16_15.amc";
  if (!std::filesystem::exists(asf) || !std::filesystem::exists(amc)) {
    std::printf("skipped 16_15: %s or %s not found\n", asf.c_str(), amc.c_str());
    return nullptr;
  }
  auto c = std::make_unique<Case>();
  c->name = "16_15";
  c->clip = io::import_motion(amc, asf, {}).motion;
  const motion::Skeleton& s = *c->clip.skeleton;
  c->body.skeleton = c->clip.skeleton;
  for (int j = 0; j < s.joint_count(); ++j) {
    Eigen::Vector3d tip = Eigen::Vector3d::Zero();
    if (!s.joint(j).end_sites.empty()) tip = s.joint(j).end_sites[0];
    for (int k = j + 1; k < s.joint_count() && tip.isZero(); ++k)
      if (s.joint(k).parent == j) tip = s.joint(k).offset;
    c->body.segments.push_back(rod(10.0 * tip.norm(), tip));
  }
  c->heavy = std::max(0, s.find_joint("lfemur"));
  c->d = retime::path_derivatives(c->clip, kSmoothing);
#ifdef KG_HAVE_KDL
  auto k = std::make_shared<test::KdlBody>(test::kdl_body(c->body));
  auto solver = std::make_shared<KDL::TreeIdSolver_RNE>(k->tree, KDL::Vector(0, -9.81, 0));
  auto wrenches = std::make_shared<KDL::WrenchMap>();
  kdl_frames(*c);
  Case* raw = c.get();
  c->kdl = [raw, k, solver, wrenches](int f, KDL::JntArray& tau) {
    const auto& a = raw->kdl_frames[static_cast<std::size_t>(f)];
    solver->CartToJnt(a[0], a[1], a[2], *wrenches, tau);
  };
#endif
  return c;
}

// Channels of the joints without a parent (their rows are fixed at 0 in the hulls).
std::vector<int> root_rows(const motion::Skeleton& s) {
  std::vector<int> rows;
  for (const motion::Joint& j : s.joints())
    if (j.parent < 0)
      for (std::size_t i = 0; i < j.channels.size(); ++i)
        rows.push_back(j.first_channel + static_cast<int>(i));
  return rows;
}

// The case's retiming problem, once: torque limits, contacts, coefficients, hulls, τ', and the
// retimer's grid on its solution at kSampleScale of the duration.
void prepare_problem(Case& c) {
  if (c.prepared) return;
  c.prepared = true;
  const motion::Skeleton& s = *c.clip.skeleton;
  const int frames = c.clip.frame_count(), channels = s.channel_count();
  const Eigen::Vector3d g = c.body.gravity;
  retime::DynamicsWorkspace ws;
  c.torques.resize(static_cast<std::size_t>(frames));
  for (int f = 0; f < frames; ++f)
    retime::frame_torques(c.body, c.clip, c.d, f, ws, c.torques[static_cast<std::size_t>(f)]);
  c.limited = c.body;
  const bool floating = !s.joint(0).channels.empty();
  c.limited.torque_min = Eigen::VectorXd::Constant(channels, -300.0);
  c.limited.torque_max = Eigen::VectorXd::Constant(channels, 300.0);
  if (!floating)
    for (int ch = 0; ch < channels; ++ch) {
      double most = 1e-3;
      for (const retime::FrameTorques& t : c.torques) most = std::max(most, std::abs(t.at(1, 0, g)[ch]));
      c.limited.torque_min[ch] = -1.5 * most;
      c.limited.torque_max[ch] = 1.5 * most;
    }
  for (int ch : root_rows(s)) c.limited.torque_min[ch] = c.limited.torque_max[ch] = 0;
  if (floating) {
    c.contacts = retime::detect_contacts(c.clip, {});
  } else {
    c.contacts.skeleton = c.clip.skeleton;
    c.contacts.fps = c.clip.fps;
    c.contacts.frames.resize(static_cast<std::size_t>(frames));
  }
  c.hulls = retime::build_hulls(c.limited, c.contacts, c.torques, {});
  c.targets = retime::original_torques(c.hulls, c.torques);
  const retime::ClipRetimeOptions options{.solve = {.duration = kSampleScale * c.clip.duration()}};
  c.weights = {
      .alpha = options.alpha, .beta = options.beta, .torque_scale = retime::torque_scale(s, c.targets)};
  c.solution = retime::retime_clip(c.hulls, c.torques, c.clip.fps, options, s);
  const retime::TimeWarp& warp = c.solution.warp;
  c.first_sample.assign(static_cast<std::size_t>(frames) + 1, 0);
  retime::for_each_sample(c.solution.solve.grid, warp.duration, [&](double t, double) {
    const retime::WarpSample w = warp.sample(t);
    c.samples.push_back({w.p, w.pddot, w.pdot * w.pdot});
    const int f = std::clamp(static_cast<int>(w.p * c.clip.fps), 0, frames - 1);
    ++c.first_sample[static_cast<std::size_t>(f) + 1];
  });
  for (int f = 0; f < frames; ++f)
    c.first_sample[static_cast<std::size_t>(f) + 1] += c.first_sample[static_cast<std::size_t>(f)];
}

double cross(const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
  return u.x() * v.y() - u.y() * v.x();
}

// BakedObjective's feasibility term off flight: α |x − c|² with its gradient, the same shortcut
// (a point in its sector's fan triangle is inside) and the same closest point.
void feasibility_term(const retime::FrameHull& hull, int sector, const Eigen::Vector2d& x, double alpha,
                      double& value, double& d_a, double& d_b) {
  const retime::FanSector& s = hull.sectors[static_cast<std::size_t>(sector)];
  const int n = static_cast<int>(hull.vertices.size());
  if (s.in_hull && n >= 3) {
    const Eigen::Vector2d& u = hull.vertices[static_cast<std::size_t>(s.edge)];
    const Eigen::Vector2d& v = hull.vertices[static_cast<std::size_t>((s.edge + 1) % n)];
    if (cross(v - u, x - u) >= 0) return;
  }
  int probe = sector;
  const retime::HullPoint c = retime::closest_point(hull, x, probe);
  if (c.inside) return;
  const Eigen::Vector2d gap = x - c.point;
  value += alpha * gap.squaredNorm();
  d_a += 2 * alpha * gap.x();
  d_b += 2 * alpha * gap.y();
}

// The flight term's constants as BakedObjective makes them: the body's weight W (the root rows'
// norm at rest) and the term's value at the frame's point, so that α |r|² / W² − that is 0 there.
struct FlightConstants {
  double inverse_weight2 = 0, offset = 0;
};
FlightConstants flight_constants(const retime::FrameHull& hull, const retime::FrameTorques& ft,
                                 const Eigen::Vector3d& gravity, const std::vector<int>& roots,
                                 double alpha) {
  const auto n = static_cast<Eigen::Index>(roots.size());
  Eigen::VectorXd r0(n), ra(n), rb(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const int c = roots[static_cast<std::size_t>(i)];
    r0[i] = ft.gravity.row(c).dot(gravity);
    ra[i] = ft.acceleration[c];
    rb[i] = ft.velocity[c];
  }
  const double weight = std::max(r0.norm(), 1e-9);
  const retime::Quadratic q =
      retime::bake_quadratic(r0, ra, rb, Eigen::VectorXd::Zero(n), alpha / (weight * weight));
  return {1.0 / (weight * weight), retime::evaluate(q, hull.vertices[0].x(), hull.vertices[0].y())};
}

// The NP-Obj row: the integrand of BakedObjective, evaluated per channel from each sector's torques.
class UnbakedObjective final : public retime::PathObjective {
 public:
  explicit UnbakedObjective(const Case& c)
      : c_(c),
        roots_(root_rows(*c.clip.skeleton)),
        w_(c.weights.beta / (c.weights.torque_scale * c.weights.torque_scale)) {
    const std::size_t frames = c.hulls.frames.size();
    sectors_.resize(frames);
    flight_.resize(frames);
    for (std::size_t f = 0; f < frames; ++f) {
      const retime::FrameHull& hull = c.hulls.frames[f];
      sectors_[f].resize(hull.sectors.size());
      for (std::size_t s = 0; s < hull.sectors.size(); ++s)
        retime::sector_torques(hull, static_cast<int>(s), c.torques[f], c.hulls.gravity, sectors_[f][s]);
      if (hull.status == retime::HullStatus::Flight && !roots_.empty())
        flight_[f] = flight_constants(hull, c.torques[f], c.hulls.gravity, roots_, c.weights.alpha);
    }
  }

  retime::SampleCost evaluate(double p, double pddot, double pdot_squared, int& hint) const override {
    const int last = static_cast<int>(sectors_.size()) - 1;
    const double x = std::clamp(p * c_.clip.fps, 0.0, static_cast<double>(last));
    const int f = std::min(static_cast<int>(x), last - 1);
    const double u = x - f;
    int sector = hint;
    double v0 = 0, a0 = 0, b0 = 0, v1 = 0, a1 = 0, b1 = 0;
    frame_cost(f, pddot, pdot_squared, sector, v0, a0, b0);
    hint = sector;
    frame_cost(f + 1, pddot, pdot_squared, sector, v1, a1, b1);
    return {.value = (1 - u) * v0 + u * v1,
            .d_p = (v1 - v0) * c_.clip.fps,
            .d_pddot = (1 - u) * a0 + u * a1,
            .d_pdot2 = (1 - u) * b0 + u * b1};
  }
  double source_duration() const override { return c_.clip.duration(); }
  double source_fps() const override { return c_.clip.fps; }

 private:
  void frame_cost(int f, double a, double b, int& hint, double& value, double& d_a, double& d_b) const {
    const retime::FrameHull& hull = c_.hulls.frames[static_cast<std::size_t>(f)];
    const Eigen::Vector2d x(a, b);
    hint = retime::find_sector(hull, x, hint);
    const retime::SectorTorques& t = sectors_[static_cast<std::size_t>(f)][static_cast<std::size_t>(hint)];
    const Eigen::VectorXd& target = c_.targets[static_cast<std::size_t>(f)];
    double sum = 0, sa = 0, sb = 0;
    for (Eigen::Index i = 0; i < target.size(); ++i) {
      const double e = t.t0[i] + t.pddot[i] * a + t.pdot2[i] * b - target[i];
      sum += e * e;
      sa += e * t.pddot[i];
      sb += e * t.pdot2[i];
    }
    value = w_ * sum;
    d_a = 2 * w_ * sa;
    d_b = 2 * w_ * sb;
    if (hull.status == retime::HullStatus::Flight && !roots_.empty()) {
      // The root's residual (no contact in flight: the root rows of τ).
      const FlightConstants& k = flight_[static_cast<std::size_t>(f)];
      double r2 = 0, ra = 0, rb = 0;
      for (int c : roots_) {
        const double r = t.t0[c] + t.pddot[c] * a + t.pdot2[c] * b;
        r2 += r * r;
        ra += r * t.pddot[c];
        rb += r * t.pdot2[c];
      }
      const double s = c_.weights.alpha * k.inverse_weight2;
      value += s * r2 - k.offset;
      d_a += 2 * s * ra;
      d_b += 2 * s * rb;
      return;
    }
    feasibility_term(hull, hint, x, c_.weights.alpha, value, d_a, d_b);
  }

  const Case& c_;
  std::vector<int> roots_;
  double w_;
  std::vector<std::vector<retime::SectorTorques>> sectors_;  // per frame, per sector
  std::vector<FlightConstants> flight_;                      // per frame (flight frames only)
};

// The Naive row: inverse dynamics with the interpolated contact forces at every evaluation.
class NaiveObjective final : public retime::PathObjective {
 public:
  explicit NaiveObjective(const Case& c)
      : c_(c),
        roots_(root_rows(*c.clip.skeleton)),
        w_(c.weights.beta / (c.weights.torque_scale * c.weights.torque_scale)),
        qd_(c.clip.values.cols()),
        qdd_(c.clip.values.cols()),
        tau_(c.clip.values.cols()) {
    const std::size_t frames = c.hulls.frames.size();
    joint_.resize(frames);
    flight_.resize(frames);
    for (std::size_t f = 0; f < frames; ++f) {
      const retime::FrameHull& hull = c.hulls.frames[f];
      // Which segment each λ column pushes: column 4 i + k is touching point i's basis force k.
      for (int j = 0; j < hull.column_count(); ++j) {
        const retime::ContactPoint& point = c.contacts.frames[f].points[static_cast<std::size_t>(j / 4)];
        joint_[f].push_back(c.contacts.patches[static_cast<std::size_t>(point.patch)]
                                .vertices[static_cast<std::size_t>(point.vertex)]
                                .joint);
      }
      if (hull.status == retime::HullStatus::Flight && !roots_.empty())
        flight_[f] = flight_constants(hull, c.torques[f], c.hulls.gravity, roots_, c.weights.alpha);
    }
  }

  // Value only (the gradient is left 0).
  retime::SampleCost evaluate(double p, double pddot, double pdot_squared, int& hint) const override {
    const int last = static_cast<int>(joint_.size()) - 1;
    const double x = std::clamp(p * c_.clip.fps, 0.0, static_cast<double>(last));
    const int f = std::min(static_cast<int>(x), last - 1);
    const double u = x - f;
    int sector = hint;
    const double v0 = frame_value(f, pddot, pdot_squared, sector);
    hint = sector;
    const double v1 = frame_value(f + 1, pddot, pdot_squared, sector);
    return {.value = (1 - u) * v0 + u * v1};
  }
  double source_duration() const override { return c_.clip.duration(); }
  double source_fps() const override { return c_.clip.fps; }

 private:
  double frame_value(int f, double a, double b, int& hint) const {
    const retime::FrameHull& hull = c_.hulls.frames[static_cast<std::size_t>(f)];
    const Eigen::Vector2d x(a, b);
    const double pdot = std::sqrt(std::max(b, 0.0));
    qd_.noalias() = c_.d.first.row(f) * pdot;
    qdd_.noalias() = c_.d.second.row(f) * b + c_.d.first.row(f) * a;
    retime::lambda_at(hull, x, hint, lambda_);
    external_.clear();
    const std::vector<int>& joints = joint_[static_cast<std::size_t>(f)];
    for (Eigen::Index j = 0; j < lambda_.size(); ++j)
      if (lambda_[j] != 0)
        external_.push_back({.joint = joints[static_cast<std::size_t>(j)],
                             .point = hull.points.col(j),
                             .force = hull.force_directions.col(j) * lambda_[j]});
    body::inverse_dynamics(c_.limited, c_.clip.values.row(f), qd_, qdd_, c_.hulls.gravity, external_, ws_,
                           tau_);
    double value = w_ * (tau_ - c_.targets[static_cast<std::size_t>(f)]).squaredNorm();
    if (hull.status == retime::HullStatus::Flight && !roots_.empty()) {
      const FlightConstants& k = flight_[static_cast<std::size_t>(f)];
      double r2 = 0;
      for (int c : roots_) r2 += tau_[c] * tau_[c];
      return value + c_.weights.alpha * k.inverse_weight2 * r2 - k.offset;
    }
    double d_a = 0, d_b = 0;
    feasibility_term(hull, hint, x, c_.weights.alpha, value, d_a, d_b);
    return value;
  }

  const Case& c_;
  std::vector<int> roots_;
  double w_;
  std::vector<std::vector<int>> joint_;  // per frame, per λ column
  std::vector<FlightConstants> flight_;
  mutable retime::DynamicsWorkspace ws_;
  mutable Eigen::RowVectorXd qd_, qdd_;
  mutable Eigen::VectorXd tau_, lambda_;
  mutable std::vector<body::ExternalForce> external_;
};

// Seconds per source frame of evaluating `objective` at the case's grid samples (all of them
// over the clip, divided by frames).
double objective_seconds_per_frame(const Case& c, const retime::PathObjective& objective) {
  int hint = 0;
  return seconds_per_frame(c.clip.frame_count(), [&](int f) {
    for (int k = c.first_sample[static_cast<std::size_t>(f)];
         k < c.first_sample[static_cast<std::size_t>(f) + 1]; ++k) {
      const Sample& s = c.samples[static_cast<std::size_t>(k)];
      g_sink = objective.evaluate(s.p, s.pddot, s.pdot2, hint).value;
    }
  });
}

// Where Obj's time goes: the two find_sector calls of each evaluation alone (seconds per source
// frame, as objective_seconds_per_frame), and the share of those frame costs whose point is not
// in its sector's fan triangle, so that the closest point of the hull is searched.
double sector_seconds_per_frame(const Case& c) {
  int hint = 0;
  const double fps = c.clip.fps;
  const int last = c.clip.frame_count() - 1;
  return seconds_per_frame(c.clip.frame_count(), [&](int f) {
    for (int k = c.first_sample[static_cast<std::size_t>(f)];
         k < c.first_sample[static_cast<std::size_t>(f) + 1]; ++k) {
      const Sample& s = c.samples[static_cast<std::size_t>(k)];
      const int i =
          std::min(static_cast<int>(std::clamp(s.p * fps, 0.0, static_cast<double>(last))), last - 1);
      const Eigen::Vector2d x(s.pddot, s.pdot2);
      hint = retime::find_sector(c.hulls.frames[static_cast<std::size_t>(i)], x, hint);
      g_sink = retime::find_sector(c.hulls.frames[static_cast<std::size_t>(i) + 1], x, hint);
    }
  });
}
double share_searched(const Case& c) {
  const double fps = c.clip.fps;
  const int last = c.clip.frame_count() - 1;
  int searched = 0, total = 0;
  for (const Sample& s : c.samples) {
    const int i = std::min(static_cast<int>(std::clamp(s.p * fps, 0.0, static_cast<double>(last))), last - 1);
    const Eigen::Vector2d x(s.pddot, s.pdot2);
    for (int f : {i, i + 1}) {
      const retime::FrameHull& hull = c.hulls.frames[static_cast<std::size_t>(f)];
      if (hull.status == retime::HullStatus::Flight) continue;
      ++total;
      const int k = retime::find_sector(hull, x, 0);
      const retime::FanSector& sector = hull.sectors[static_cast<std::size_t>(k)];
      const int n = static_cast<int>(hull.vertices.size());
      bool in_triangle = false;
      if (sector.in_hull && n >= 3) {
        const Eigen::Vector2d& u = hull.vertices[static_cast<std::size_t>(sector.edge)];
        const Eigen::Vector2d& v = hull.vertices[static_cast<std::size_t>((sector.edge + 1) % n)];
        in_triangle = cross(v - u, x - u) >= 0;
      }
      searched += !in_triangle;
    }
  }
  return total ? static_cast<double>(searched) / total : 0.0;
}

// The largest |other − baked| over the grid, relative to the mean |baked|.
double largest_difference(const Case& c, const retime::PathObjective& baked,
                          const retime::PathObjective& other) {
  int h0 = 0, h1 = 0;
  double worst = 0, mean = 0;
  for (const Sample& s : c.samples) {
    const double a = baked.evaluate(s.p, s.pddot, s.pdot2, h0).value;
    const double b = other.evaluate(s.p, s.pddot, s.pdot2, h1).value;
    worst = std::max(worst, std::abs(a - b));
    mean += std::abs(a);
  }
  mean /= static_cast<double>(c.samples.size());
  return mean > 0 ? worst / mean : worst;
}

struct Row {
  std::string name;
  // Seconds per frame for a case; nullopt when it does not apply (printed as "-").
  std::function<std::optional<double>(Case&)> time;
};

// Microseconds with the digits that matter.
void print_us(double seconds) {
  const double us = seconds * 1e6;
  if (us < 1)
    std::printf("%10.3f", us);
  else if (us < 100)
    std::printf("%10.2f", us);
  else
    std::printf("%10.1f", us);
}

// ---- sections 2 and 3: real clips through graphs/retime.yaml's pipeline -------------------------

double ms_since(double t0) {
  return (now() - t0) * 1000;
}

struct Clip {
  std::string name;
  std::string what;             // file and rates, for people
  motion::Motion source, clip;  // as imported, and resampled
  BodyModel body;
  retime::Contacts contacts;
  retime::PathTorques torques;
  retime::Hulls hulls;
  double import_ms = 0, body_ms = 0, contacts_ms = 0, force_ms = 0, hulls_ms = 0;
};

// import (fps override `source_fps` when > 0), resample to `fps`, de Leva male 70 kg with frame 0
// as reference pose, detected contacts, path_torques through a kSmoothing Gaussian, default hulls.
std::optional<Clip> load_clip(const std::string& name, const std::string& path, const std::string& skeleton,
                              double source_fps, double fps) {
  if (!std::filesystem::exists(path) || (!skeleton.empty() && !std::filesystem::exists(skeleton))) {
    std::printf("skipped %s: %s not found\n", name.c_str(), path.c_str());
    return std::nullopt;
  }
  Clip c;
  c.name = name;
  double t0 = now();
  io::ImportOptions options;
  options.fps = source_fps;
  c.source = io::import_motion(path, skeleton, options).motion;
  c.clip = motion::resample(c.source, fps);
  c.import_ms = ms_since(t0);
  char what[256];
  std::snprintf(what, sizeof what, "%s, %d frames at %.0f Hz resampled to %.0f Hz: %d frames, %.2f s",
                std::filesystem::path(path).filename().c_str(), c.source.frame_count(), c.source.fps, fps,
                c.clip.frame_count(), c.clip.duration());
  c.what = what;
  t0 = now();
  const Eigen::RowVectorXd reference = c.clip.values.row(0);
  c.body = body::build_body_model(c.clip.skeleton, {}, &reference).body;
  c.body_ms = ms_since(t0);
  t0 = now();
  c.contacts = retime::detect_contacts(c.clip, {});
  c.contacts_ms = ms_since(t0);
  t0 = now();
  c.torques = retime::path_torques(c.body, c.clip, retime::path_derivatives(c.clip, kSmoothing));
  c.force_ms = ms_since(t0);
  t0 = now();
  c.hulls = retime::build_hulls(c.body, c.contacts, c.torques.frames, {});
  c.hulls_ms = ms_since(t0);
  return c;
}

void print_clip(const Clip& c) {
  const int frames = c.clip.frame_count();
  std::printf("%s: %s\n", c.name.c_str(), c.what.c_str());
  int outside = 0;
  for (const retime::FrameHull& h : c.hulls.frames)
    outside += h.status == retime::HullStatus::Feasible && !h.centre_is_original;
  std::printf(
      "  hulls: %d feasible ((0, 1) outside %d of them), %d flight, %d infeasible; precompute per frame: "
      "Force %.3f ms, contacts %.3f ms, Feasible %.3f ms (%.0f ms for the clip)\n",
      c.hulls.count(retime::HullStatus::Feasible), outside, c.hulls.count(retime::HullStatus::Flight),
      c.hulls.count(retime::HullStatus::Infeasible), c.force_ms / frames, c.contacts_ms / frames,
      c.hulls_ms / frames, c.hulls_ms);
}

// retime_clip with the graph's defaults (objective match) to `scale` times the duration, `runs`
// times; the last result, with solve.seconds and the whole call's time replaced by their medians.
struct Timed {
  retime::ClipRetime r;
  double call_ms = 0;
};
Timed retime_timed(const Clip& c, double scale, int runs, double flight_weight = 1) {
  const retime::ClipRetimeOptions options{.solve = {.duration = scale * c.clip.duration()},
                                          .flight_weight = flight_weight};
  std::vector<double> solve, call;
  Timed out;
  for (int i = 0; i < runs; ++i) {
    const double t0 = now();
    out.r = retime::retime_clip(c.hulls, c.torques.frames, c.clip.fps, options, *c.clip.skeleton);
    call.push_back(ms_since(t0));
    solve.push_back(out.r.solve.seconds);
  }
  out.r.solve.seconds = median(solve);
  out.call_ms = median(call);
  return out;
}

void print_retime(const Timed& t, double scale, double duration, double flight_weight = 1) {
  const retime::ClipRetime& r = t.r;
  std::printf(
      "  to %.2fx (%.2f s), flight weight %g: %s, %d iterations, %d evaluations, %d samples, objective "
      "%.6g, solve %.1f ms (retime_clip %.1f ms)\n",
      scale, scale * duration, flight_weight, r.solve.converged ? "converged" : "NOT converged",
      r.solve.iterations, r.solve.evaluations, r.solve.samples, r.solve.objective, r.solve.seconds * 1000,
      t.call_ms);
  std::printf(
      "    inside their hulls: %.1f%% of feasible-hull output frames, at their point: %.1f%% of flight or "
      "infeasible ones (%d output frames at the source rate); objective: feasibility %.4g, torque %.4g "
      "(τ scale %.1f N m)",
      100 * r.share_inside, 100 * r.share_at_point, r.output_frames, r.feasibility, r.torque, r.torque_scale);
  if (r.shortest && r.shortest->feasible)
    std::printf("; shortest feasible duration %.3f s", r.shortest->duration);
  std::printf("\n    message: %s\n", r.message.c_str());
}

// The output time at which `warp` plays source time `p` (p(t) increases strictly: bisection).
double output_time_of(const retime::TimeWarp& warp, double p) {
  double lo = 0, hi = warp.duration;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (warp.at(mid) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// Per frame of `m`: the world height of joint 0's origin and of the body's centre of mass, metres.
void heights(const motion::Motion& m, const BodyModel& body, std::vector<double>& root,
             std::vector<double>& com) {
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(m.skeleton->joint_count()));
  root.clear();
  com.clear();
  for (int f = 0; f < m.frame_count(); ++f) {
    motion::forward_kinematics(*m.skeleton, m.values.row(f), world);
    root.push_back(world[0].translation().y());
    com.push_back(body::body_com(body, m.values.row(f)).y());
  }
}

// Second difference at frame k (m/s²); frames outside give NaN.
double second_difference(const std::vector<double>& y, int k, double fps) {
  if (k < 1 || k + 1 >= static_cast<int>(y.size())) return NAN;
  return (y[static_cast<std::size_t>(k) + 1] - 2 * y[static_cast<std::size_t>(k)] +
          y[static_cast<std::size_t>(k) - 1]) *
         fps * fps;
}

struct Stats {
  int n = 0;
  double mean = 0, lo = INFINITY, hi = -INFINITY;
  void add(double x) {
    if (!std::isfinite(x)) return;
    mean = (mean * n + x) / (n + 1);
    ++n;
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
};

// Mean vertical acceleration (root, CoM) over frames k of `m` whose neighbours and itself play
// flight (`flight(k)`), by second differences at m's rate.
std::pair<Stats, Stats> flight_acceleration(const motion::Motion& m, const BodyModel& body,
                                            const std::function<bool(int)>& flight) {
  std::vector<double> root, com;
  heights(m, body, root, com);
  Stats r, c;
  for (int k = 1; k + 1 < m.frame_count(); ++k)
    if (flight(k - 1) && flight(k) && flight(k + 1)) {
      r.add(second_difference(root, k, m.fps));
      c.add(second_difference(com, k, m.fps));
    }
  return {r, c};
}

void jump_section(const Clip& c) {
  print_clip(c);
  const int frames = c.clip.frame_count();
  const double fps = c.clip.fps;
  auto is_flight = [&](int f) {
    return f >= 0 && f < frames &&
           c.hulls.frames[static_cast<std::size_t>(f)].status == retime::HullStatus::Flight;
  };
  // The flight runs.
  std::vector<std::pair<int, int>> runs;
  for (int f = 0; f < frames; ++f)
    if (is_flight(f)) {
      if (runs.empty() || runs.back().second != f - 1)
        runs.push_back({f, f});
      else
        runs.back().second = f;
    }
  std::pair<int, int> longest{0, -1};  // the jump's own flight
  for (auto run : runs)
    if (run.second - run.first > longest.second - longest.first) longest = run;
  std::printf("  flight frames:");
  for (auto [a, b] : runs) std::printf(" %d-%d (%.3f s)", a, b, (b - a + 1) / fps);
  if (runs.empty()) std::printf(" none");
  const auto [src_root, src_com] = flight_acceleration(c.clip, c.body, is_flight);
  std::printf(
      "\n  source at %.0f Hz during flight: root ÿ mean %.2f m/s² (%d frames), CoM ÿ mean %.2f m/s²\n", fps,
      src_root.mean, src_root.n, src_com.mean);

  // graphs/retime.yaml's objective (flight weight 1) to 0.5 and 0.65, and graphs/retime/jump_half.yaml's
  // (flight weight kJumpHalfFlightWeight) to 0.5.
  const std::vector<std::pair<double, double>> settings = {
      {0.5, 1.0}, {0.65, 1.0}, {0.5, kJumpHalfFlightWeight}};
  std::vector<retime::TimeWarp> warps;
  for (const auto [scale, flight_weight] : settings) {
    const Timed t = retime_timed(c, scale, 1, flight_weight);
    print_retime(t, scale, c.clip.duration(), flight_weight);
    warps.push_back(t.r.warp);
    Stats pdot, jump;
    for (int f = 0; f < frames; ++f)
      if (is_flight(f)) {
        const double v = t.r.warp.sample(output_time_of(t.r.warp, f / fps)).pdot;
        pdot.add(v);
        if (f >= longest.first && f <= longest.second) jump.add(v);
      }
    const motion::Motion out = retime::retimed_motion(c.clip, t.r.warp, fps);
    const auto [root, com] = flight_acceleration(out, c.body, [&](int k) {
      const int f = std::clamp(static_cast<int>(std::lround(t.r.warp.at(k / fps) * fps)), 0, frames - 1);
      return is_flight(f);
    });
    std::printf(
        "    flight ṗ (target 1.0 ± 0.1; uniform %.2f): all %d flight frames mean %.3f, min %.3f, max %.3f; "
        "the jump's %d-%d mean %.3f, min %.3f, max %.3f\n",
        1 / scale, pdot.n, pdot.mean, pdot.lo, pdot.hi, longest.first, longest.second, jump.mean, jump.lo,
        jump.hi);
    std::printf(
        "    flight ÿ in the output at %.0f Hz (target -9.8 ± 1 m/s²; uniform ≈ %.1f): root mean %.2f (min "
        "%.2f, "
        "max %.2f, %d frames), CoM mean %.2f m/s²\n",
        fps, -9.81 / (scale * scale), root.mean, root.lo, root.hi, root.n, com.mean);
  }
  // Per flight frame and two frames either side: what the source does there.
  std::printf("  frame  status      source root ÿ  CoM ÿ (m/s²)   ṗ at 0.5x  ṗ at 0.65x  0.5x fw %g  hull\n",
              kJumpHalfFlightWeight);
  std::vector<double> root, com;
  heights(c.clip, c.body, root, com);
  for (auto [a, b] : runs)
    for (int f = std::max(0, a - 2); f <= std::min(frames - 1, b + 2); ++f) {
      std::printf("  %5d  %-10s  %13.2f  %12.2f", f,
                  retime::to_string(c.hulls.frames[static_cast<std::size_t>(f)].status),
                  second_difference(root, f, fps), second_difference(com, f, fps));
      for (const retime::TimeWarp& w : warps)
        std::printf("  %10.3f", w.sample(output_time_of(w, f / fps)).pdot);
      const retime::FrameHull& h = c.hulls.frames[static_cast<std::size_t>(f)];
      if (h.status == retime::HullStatus::Feasible)
        std::printf("  (0, 1) %s, %zu vertices\n", h.centre_is_original ? "inside" : "outside",
                    h.vertices.size());
      else
        std::printf("  point (p̈, ṗ²) = (%.2f, %.2f), residual %.0f\n", h.vertices[0].x(), h.vertices[0].y(),
                    h.residual);
    }
}

}  // namespace

int main(int argc, char** argv) {
  const std::string only = argc > 1 ? argv[1] : "";
  auto want = [&](const std::string& section, const std::string& name) {
    return only.empty() || (section + " " + name).find(only) != std::string::npos;
  };
  const std::string data = KG_DATA_DIR;
  // Timings suffer from other work on the machine: say how much there was.
  if (std::FILE* f = std::fopen("/proc/loadavg", "r")) {
    double a = 0, b = 0, c = 0;
    if (std::fscanf(f, "%lf %lf %lf", &a, &b, &c) == 3)
      std::printf("load average at start: %.2f %.2f %.2f (%u hardware threads)\n", a, b, c,
                  std::thread::hardware_concurrency());
    std::fclose(f);
  }

  // ---- 1. fig. 12 ----------------------------------------------------------------------------
  std::vector<std::unique_ptr<Case>> cases;
  if (want("fig12", "16_15"))
    if (auto c = walk_case()) cases.push_back(std::move(c));
  for (int links : {10, 100, 1000})
    if (want("fig12", chain_name(links))) cases.push_back(chain_case(links));
  const Eigen::Vector3d g(0, -9.81, 0);

  std::vector<Row> rows;
  rows.push_back({"KDL RNEA", [](Case& c) -> std::optional<double> {
#ifdef KG_HAVE_KDL
                    KDL::JntArray tau(static_cast<unsigned>(c.clip.skeleton->channel_count()));
                    return seconds_per_frame(c.clip.frame_count(), [&](int f) {
                      c.kdl(f, tau);
                      g_sink = tau(0);
                    });
#else
                    (void)c;
                    return std::nullopt;
#endif
                  }});
  rows.push_back({"RNEA", [&g](Case& c) -> std::optional<double> {
                    retime::DynamicsWorkspace ws;
                    Eigen::VectorXd tau(c.clip.skeleton->channel_count());
                    return seconds_per_frame(c.clip.frame_count(), [&](int f) {
                      body::inverse_dynamics(c.body, c.clip.values.row(f), c.d.first.row(f),
                                             c.d.second.row(f), g, {}, ws, tau);
                      g_sink = tau[0];
                    });
                  }});
  rows.push_back({"Force", [](Case& c) -> std::optional<double> {
                    retime::DynamicsWorkspace ws;
                    retime::FrameTorques out;
                    return seconds_per_frame(c.clip.frame_count(), [&](int f) {
                      retime::frame_torques(c.body, c.clip, c.d, f, ws, out);
                      g_sink = out.velocity[0];
                    });
                  }});
  rows.push_back({"Force (k)", [](Case& c) -> std::optional<double> {
                    retime::DynamicsWorkspace ws;
                    retime::MassScaleTorques out;
                    return seconds_per_frame(c.clip.frame_count(), [&](int f) {
                      retime::frame_torques_mass_scale(c.body, c.clip, c.d, f, c.heavy, ws, out);
                      g_sink = out.change.velocity[0];
                    });
                  }});
  rows.push_back({"Feasible", [](Case& c) -> std::optional<double> {
                    prepare_problem(c);
                    const retime::HullOptions options;
                    return seconds_per_frame(c.clip.frame_count(), [&](int f) {
                      const retime::FrameHull h =
                          retime::build_frame_hull(c.limited, c.contacts.frames[static_cast<std::size_t>(f)],
                                                   c.torques[static_cast<std::size_t>(f)], options);
                      g_sink = h.centre.y();
                    });
                  }});
  rows.push_back({"Bake", [](Case& c) -> std::optional<double> {
                    prepare_problem(c);
                    // One pass = the whole clip baked once.
                    return seconds_per_frame(1,
                                             [&](int) {
                                               const retime::BakedObjective o(c.hulls, c.torques, c.targets,
                                                                              *c.clip.skeleton, c.clip.fps,
                                                                              c.weights);
                                               g_sink = o.quadratic(0, 0)[5];
                                             }) /
                           c.clip.frame_count();
                  }});
  rows.push_back({"Obj", [](Case& c) -> std::optional<double> {
                    prepare_problem(c);
                    const retime::BakedObjective o(c.hulls, c.torques, c.targets, *c.clip.skeleton,
                                                   c.clip.fps, c.weights);
                    return objective_seconds_per_frame(c, o);
                  }});
  rows.push_back({"NP-Obj", [](Case& c) -> std::optional<double> {
                    prepare_problem(c);
                    return objective_seconds_per_frame(c, UnbakedObjective(c));
                  }});
  rows.push_back({"Naive", [](Case& c) -> std::optional<double> {
                    prepare_problem(c);
                    return objective_seconds_per_frame(c, NaiveObjective(c));
                  }});

  if (!cases.empty()) {
    std::printf("== fig12: per source frame, one thread, microseconds (median of 9 batches) ==\n%-14s", "");
    for (const auto& c : cases) std::printf("%10s", c->name.c_str());
    std::printf("\n%-14s", "channels");
    for (const auto& c : cases) std::printf("%10d", c->clip.skeleton->channel_count());
    std::printf("\n%-14s", "frames");
    for (const auto& c : cases) std::printf("%10d", c->clip.frame_count());
    std::printf("\n");
    std::vector<std::vector<std::optional<double>>> results;
    for (const Row& row : rows) {
      std::printf("%-14s", row.name.c_str());
      std::fflush(stdout);
      results.emplace_back();
      for (const auto& c : cases) {
        results.back().push_back(row.time(*c));
        if (results.back().back())
          print_us(*results.back().back());
        else
          std::printf("%10s", "-");
        std::fflush(stdout);
      }
      std::printf("\n");
    }
    // The target, from back-to-back batches of frame_torques and KDL (not the rows above,
    // which may have run under different loads).
    std::printf("%-14s", "Force / KDL");
    for (const auto& c : cases) {
#ifdef KG_HAVE_KDL
      retime::DynamicsWorkspace ws;
      retime::FrameTorques out;
      KDL::JntArray tau(static_cast<unsigned>(c->clip.skeleton->channel_count()));
      const double r = paired_ratio(
          c->clip.frame_count(),
          [&](int f) {
            retime::frame_torques(c->body, c->clip, c->d, f, ws, out);
            g_sink = out.velocity[0];
          },
          [&](int f) {
            c->kdl(f, tau);
            g_sink = tau(0);
          });
      std::printf("%10.2f", r);
#else
      std::printf("%10s", "-");
#endif
    }
    std::printf("\n");

    // What the objective rows' "per frame" covers, and per evaluation.
    std::printf(
        "-- the Obj, NP-Obj and Naive rows: the retimer's grid on its own solution at %.1fx duration --\n",
        kSampleScale);
    std::printf("%-14s", "hulls F/Fl/I");
    for (const auto& c : cases) {
      char s[32];
      std::snprintf(s, sizeof s, "%d/%d/%d", c->hulls.count(retime::HullStatus::Feasible),
                    c->hulls.count(retime::HullStatus::Flight),
                    c->hulls.count(retime::HullStatus::Infeasible));
      std::printf("%10s", s);
    }
    std::printf("\n%-14s", "sectors/frame");
    for (const auto& c : cases) {
      std::size_t n = 0;
      for (const retime::FrameHull& h : c->hulls.frames) n += h.sectors.size();
      std::printf("%10.1f", static_cast<double>(n) / c->clip.frame_count());
    }
    std::printf("\n%-14s", "solve");
    for (const auto& c : cases) {
      char s[32];
      std::snprintf(s, sizeof s, "%s%d it", c->solution.solve.converged ? "" : "!",
                    c->solution.solve.iterations);
      std::printf("%10s", s);
    }
    std::printf("\n%-14s", "solve ms");
    for (const auto& c : cases) std::printf("%10.1f", c->solution.solve.seconds * 1000);
    // A "!" says why: Ceres' reason, or the grid refined four times without catching up.
    for (const auto& c : cases)
      if (!c->solution.solve.converged)
        std::printf("\n  %s did not converge: %s", c->name.c_str(), c->solution.solve.message.c_str());
    std::printf("\n%-14s", "samples");
    for (const auto& c : cases) std::printf("%10zu", c->samples.size());
    std::printf("\n%-14s", "samples/frame");
    for (const auto& c : cases)
      std::printf("%10.2f", static_cast<double>(c->samples.size()) / c->clip.frame_count());
    // What sample_grid gives the solution afresh: the grid only grows during a solve, so segments
    // the solve slowed down keep the steps their starting playback needed.
    std::printf("\n%-14s", "fewest/frame");
    for (const auto& c : cases)
      std::printf("%10.2f", static_cast<double>(retime::sample_grid(c->solution.warp, c->clip.fps,
                                                                    retime::RetimeOptions{}.samples_per_frame)
                                                    .samples()) /
                                c->clip.frame_count());
    std::printf("\nper evaluation (ns):\n");
    for (std::size_t i = 0; i < rows.size(); ++i) {
      if (rows[i].name != "Obj" && rows[i].name != "NP-Obj" && rows[i].name != "Naive") continue;
      std::printf("%-14s", rows[i].name.c_str());
      for (std::size_t k = 0; k < cases.size(); ++k) {
        const auto& t = results[i][k];
        if (t)
          std::printf("%10.1f", *t * 1e9 * cases[k]->clip.frame_count() /
                                    static_cast<double>(cases[k]->samples.size()));
        else
          std::printf("%10s", "-");
      }
      std::printf("\n");
    }
    std::printf("%-14s", "  find_sector");
    for (const auto& c : cases)
      std::printf("%10.1f", sector_seconds_per_frame(*c) * 1e9 * c->clip.frame_count() /
                                static_cast<double>(c->samples.size()));
    std::printf("   (Obj's two sector searches alone)\n%-14s", "  searched %");
    for (const auto& c : cases) std::printf("%10.1f", 100 * share_searched(*c));
    std::printf("   (Obj's frame costs outside their fan triangle: closest point searched)\n");
    std::printf("agreement with Obj over the grid, largest |x − Obj| / mean |Obj|:\n");
    for (const char* which : {"NP-Obj", "Naive"}) {
      std::printf("%-14s", which);
      for (const auto& c : cases) {
        const retime::BakedObjective o(c->hulls, c->torques, c->targets, *c->clip.skeleton, c->clip.fps,
                                       c->weights);
        const double d = std::string(which) == "NP-Obj" ? largest_difference(*c, o, UnbakedObjective(*c))
                                                        : largest_difference(*c, o, NaiveObjective(*c));
        std::printf("%10.1e", d);
      }
      std::printf("\n");
    }

#ifdef KG_HAVE_KDL
    // The comparison is of equal work: the same torques, checked on every frame.
    std::printf("largest |τ − τ_KDL| / max|τ_KDL| over all frames:");
    for (const auto& c : cases) {
      const std::vector<int> order = body::DynamicsTopology::of(*c->body.skeleton).order;
      retime::DynamicsWorkspace ws;
      Eigen::VectorXd tau(c->clip.skeleton->channel_count());
      KDL::JntArray ktau(static_cast<unsigned>(order.size()));
      double worst = 0;
      for (int f = 0; f < c->clip.frame_count(); ++f) {
        body::inverse_dynamics(c->body, c->clip.values.row(f), c->d.first.row(f), c->d.second.row(f), g, {},
                               ws, tau);
        c->kdl(f, ktau);
        double diff = 0, scale = 0;
        for (std::size_t i = 0; i < order.size(); ++i) {
          diff = std::max(diff, std::abs(tau[order[i]] - ktau(static_cast<unsigned>(i))));
          scale = std::max(scale, std::abs(ktau(static_cast<unsigned>(i))));
        }
        worst = std::max(worst, diff / scale);
      }
      std::printf("  %s %.1e", c->name.c_str(), worst);
    }
    std::printf("\n");
#else
    std::printf("KDL rows skipped: built without KDL (Debian liborocos-kdl-dev)\n");
#endif
    std::printf(
        "targets: Bake <= 50 µs, Obj <= 0.2 µs per frame. The paper's fig. 12 (2006, ms -> µs; 16_16, C10, "
        "C100, C1000): Force 66000 33000 170000 1850000, Feasible 12000 5000 20000 250000, Bake 780 x 37 "
        "210, Obj 1.4 0.27 0.29 0.29, NP-Obj 4.4 0.76 4.6 50, Naive 78000 38000 190000 2100000\n");
  }

  // ---- 2. the optimiser ------------------------------------------------------------------------
  std::vector<std::function<std::optional<Clip>()>> optimiser;
  if (want("optimiser", "07_05"))
    optimiser.push_back([&] {
      return load_clip("07_05", data + "/cmu/asf_amc/07_05.amc", data + "/cmu/asf_amc/07.asf", 0, 60);
    });
  if (want("optimiser", "16_15"))
    optimiser.push_back([&] {
      return load_clip("16_15", data + "/cmu/asf_amc/16_15.amc", data + "/cmu/asf_amc/16.asf", 0, 30);
    });
  if (!optimiser.empty())
    std::printf(
        "\n== optimiser: retime_clip (objective match, α 1000, β 1, knots 0.1 s, 4 samples per frame), "
        "solve time the median of 3 (target: converged within 300 ms) ==\n");
  for (const auto& load : optimiser)
    if (const std::optional<Clip> c = load()) {
      print_clip(*c);
      print_retime(retime_timed(*c, 0.8, 3), 0.8, c->clip.duration());
    }

  // ---- 3. the jumps ----------------------------------------------------------------------------
  struct JumpFile {
    std::string name, path;
    double source_fps;
  };
  std::vector<JumpFile> jumps;
  for (const JumpFile& j : {JumpFile{"16_01", data + "/cmu/bvh_cmu_names/16_01.bvh", 120.0},
                            JumpFile{"13_11", data + "/cmu/bvh_daz/13_11.bvh", 0.0},
                            JumpFile{"13_13", data + "/cmu/bvh_daz/13_13.bvh", 0.0}})
    if (want("jump", j.name)) jumps.push_back(j);
  if (!jumps.empty())
    std::printf(
        "\n== jump: graphs/retime.yaml's pipeline at 30 Hz (de Leva male 70 kg, detected contacts, "
        "smoothing %.2f s, default hulls, objective match), retimed to 0.5 and 0.65 of the duration, and to "
        "0.5 with jump_half.yaml's flight weight ==\n",
        kSmoothing);
  for (const JumpFile& j : jumps)
    if (const std::optional<Clip> c = load_clip(j.name, j.path, "", j.source_fps, 30)) jump_section(*c);

  if (cases.empty() && optimiser.empty() && jumps.empty()) {
    std::printf(
        "nothing matches '%s' (fig12: 16_15 C10 C100 C1000; optimiser: 07_05 16_15; jump: 16_01 13_11 "
        "13_13)\n",
        only.c_str());
    return 1;
  }
  return 0;
}
