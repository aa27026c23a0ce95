// retime.dynamics, retime.hulls and retime.retime: thin adapters over dynamics.hpp, hulls.hpp,
// retime_clip.hpp and playback.hpp; and the sinks retime.write_curves and retime.write_forces,
// which write what the retiming found (the solver itself writes no file: DESIGN.md 13).
// A solve that misses its hulls is reported (figures, log), and fails the node only with `strict`.
#include <chrono>
#include <cmath>
#include <functional>
#include <sstream>
#include <stdexcept>

#include "kg/base/json.hpp"
#include "kg/base/text.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/graph/sink.hpp"
#include "kg/retime/contacts.hpp"
#include "kg/retime/dynamics.hpp"
#include "kg/retime/hulls.hpp"
#include "kg/retime/nodes.hpp"
#include "kg/retime/playback.hpp"
#include "kg/retime/retime_clip.hpp"
#include "kg/retime/torque_limits.hpp"

namespace kg::retime {
namespace {

using graph::NodeSpec;
using graph::NodeType;
using graph::Params;
using graph::ParamSpec;
using graph::ParamType;
using graph::RunContext;
using graph::sink_path_param;
using graph::write_sink_file;

std::string shown(double x) {
  std::ostringstream out;
  out << x;
  return out.str();
}

// "9.81" (straight down) or three numbers (a world vector), m/s²; empty: `fallback`.
Eigen::Vector3d gravity_from(const std::vector<double>& values, const Eigen::Vector3d& fallback) {
  if (values.empty()) return fallback;
  if (values.size() == 1) return Eigen::Vector3d(0, -values[0], 0);
  if (values.size() == 3) return Eigen::Vector3d(values[0], values[1], values[2]);
  throw std::invalid_argument("gravity: " + std::to_string(values.size()) +
                              " numbers (expected one magnitude, down, or a vector of three, m/s^2)");
}

class DynamicsNode final : public graph::Node {
 public:
  explicit DynamicsNode(const Params& p)
      : segment_(p.get<std::string>("segment")), smoothing_(p.get<double>("smoothing")) {}

  void run(RunContext& ctx) const override {
    const motion::Motion& clip = ctx.input<motion::Motion>("motion");
    const body::BodyModel& body = ctx.input<body::BodyModel>("body");
    if (body.skeleton != clip.skeleton &&
        (!body.skeleton || body.skeleton->channel_count() != clip.skeleton->channel_count()))
      throw std::invalid_argument("the body model was built for another skeleton than the motion's");
    int joint = -1;
    if (!segment_.empty()) {
      joint = clip.skeleton->find_joint(segment_);
      if (joint < 0)
        throw std::invalid_argument("segment " + text::in_quotes(segment_) +
                                    ": no such joint in the motion's skeleton");
      if (body.segments[static_cast<std::size_t>(joint)].mass == 0)
        throw std::invalid_argument("segment '" + segment_ +
                                    "' is massless in the body model: scaling its mass "
                                    "changes nothing");
    }
    const auto start = std::chrono::steady_clock::now();
    PathTorques torques = path_torques(body, clip, path_derivatives(clip, smoothing_), joint);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ctx.report("frames", static_cast<std::int64_t>(torques.frame_count()));
    ctx.report("us_per_frame", torques.frame_count() ? 1e6 * seconds / torques.frame_count() : 0.0);
    ctx.output("torques", std::move(torques));
  }

 private:
  std::string segment_;
  double smoothing_;
};

NodeType dynamics_node_type() {
  NodeSpec spec{
      .type = "retime.dynamics",
      .version = 1,
      .doc =
          "Inverse dynamics along the clip's path (McCann et al. 2006 §3.1, eq. 5 and 6): per frame, the "
          "generalised forces as coefficients of ṗ², p̈ and the gravity vector, from Featherstone's "
          "recursive Newton-Euler over a polynomial scalar; with `segment`, also their change with that "
          "segment's mass, so retime.hulls can make it heavier without running this again.",
      .inputs = {{"motion", "kg.Motion", true, "the clip (metres, radians)"},
                 {"body", "kg.BodyModel", true, "its masses and inertias (retime.body_model)"}},
      .outputs = {{"torques", "kg.PathTorques", true, "per frame: coefficients of ṗ², p̈ and g (N, N m)"}},
      .params = {
          {.name = "segment",
           .type = ParamType::String,
           .default_value = std::string(),
           .doc = "a joint whose mass retime.hulls may scale (e.g. lfemur); \"\" for none"},
          {.name = "smoothing",
           .type = ParamType::Float,
           .default_value = 0.04,
           .doc = "s: the Gaussian the path's derivatives are taken through (capture noise of a millimetre "
                  "is metres per second² at 120 Hz); 0: raw differences",
           .min = 0.0,
           .max = 10.0}}};
  return {std::move(spec), [](const Params& p) { return std::make_unique<DynamicsNode>(p); }};
}

class TorqueLimitsNode final : public graph::Node {
 public:
  explicit TorqueLimitsNode(const Params& p) {
    options_.margin = p.get<double>("margin");
    options_.floor = p.get<double>("floor");
    options_.symmetric = p.get<bool>("symmetric");
    if (options_.margin != 0) options_.validate();  // margin 0: the body's own limits, no estimate
  }

  void run(RunContext& ctx) const override {
    const body::BodyModel& body = ctx.input<body::BodyModel>("body");
    if (options_.margin == 0) {  // the body's own limits (from its file, or none)
      ctx.log("margin 0: the body's own torque limits are kept");
      ctx.output("body", body);
      return;
    }
    const Contacts& contacts = ctx.input<Contacts>("contacts");
    const PathTorques& torques = ctx.input<PathTorques>("torques");
    const TorqueLimitEstimate estimate = estimate_torque_limits(body, contacts, torques.frames, options_);
    for (const std::string& note : estimate.notes) ctx.log(note);
    ctx.report("frames_used", static_cast<std::int64_t>(estimate.count(FrameUse::Original) +
                                                        estimate.count(FrameUse::Nearest) +
                                                        estimate.count(FrameUse::Flight)));
    ctx.report("frames_skipped", static_cast<std::int64_t>(estimate.count(FrameUse::Skipped)));
    double largest = 0;
    for (Eigen::Index c = 0; c < estimate.body.torque_max.size(); ++c)
      if (std::isfinite(estimate.body.torque_max[c]))
        largest = std::max(largest, estimate.body.torque_max[c]);
    ctx.report("largest_limit", largest);
    ctx.output("body", estimate.body);
  }

 private:
  TorqueLimitOptions options_;
};

NodeType torque_limits_node_type() {
  NodeSpec spec{
      .type = "retime.torque_limits",
      .version = 1,
      .doc =
          "Torque limits observed in the clip itself, as McCann et al. set theirs (§4): each actuated "
          "channel "
          "may exert `margin` times the largest generalised force the clip needs at its original timing "
          "(with the least contact force that explains it), at least `floor`. With margin >= 1 the original "
          "timing stays inside every hull it was inside before. margin 0 keeps the body's own limits.",
      .inputs = {{"body", "kg.BodyModel", true, "the body whose limits are set"},
                 {"contacts", "kg.Contacts", true, "the clip's contacts"},
                 {"torques", "kg.PathTorques", true, "the clip's torque coefficients (retime.dynamics)"}},
      .outputs = {{"body", "kg.BodyModel", true, "the same body with torque_min/torque_max set"}},
      .params = {{.name = "margin",
                  .type = ParamType::Float,
                  .default_value = 1.5,
                  .doc = "limit = margin x the observed peak per channel; 0: keep the body's limits",
                  .min = 0.0,
                  .max = 1e6},
                 {.name = "floor",
                  .type = ParamType::Float,
                  .default_value = 5.0,
                  .doc = "N m: the least limit of any actuated channel (one that never works still may)",
                  .min = 0.0,
                  .max = 1e9},
                 {.name = "symmetric",
                  .type = ParamType::Bool,
                  .default_value = false,
                  .doc = "left and right joints share the larger of their limits"}}};
  return {std::move(spec), [](const Params& p) { return std::make_unique<TorqueLimitsNode>(p); }};
}

class HullsNode final : public graph::Node {
 public:
  explicit HullsNode(const Params& p)
      : gravity_(p.get<std::vector<double>>("gravity")), mass_scale_(p.get<double>("mass_scale")) {
    options_.tolerance = p.get<double>("tolerance");
    options_.pddot_max = p.get<double>("pddot_max");
    options_.pdot2_max = p.get<double>("pdot2_max");
    gravity_from(gravity_, Eigen::Vector3d::Zero());  // refuse a bad list when the graph loads
    options_.validate();
  }

  void run(RunContext& ctx) const override {
    body::BodyModel body = ctx.input<body::BodyModel>("body");
    const Contacts& contacts = ctx.input<Contacts>("contacts");
    const PathTorques& source = ctx.input<PathTorques>("torques");
    if (contacts.frame_count() != source.frame_count())
      throw std::invalid_argument("the contacts have " + std::to_string(contacts.frame_count()) +
                                  " frames and the torques " + std::to_string(source.frame_count()));
    bool touches = false;
    for (const ContactFrame& frame : contacts.frames) touches = touches || !frame.points.empty();
    if (!touches)
      throw std::invalid_argument(
          "no frame of the clip touches anything (" + std::to_string(contacts.frame_count()) +
          " frames of flight): nothing could have moved its root, so no timing of it is physical. Check the "
          "feet the contacts found and their thresholds (retime.contacts: height_threshold, speed_threshold, "
          "floor), or give the contacts in a file (path)");
    body.gravity = gravity_from(gravity_, body.gravity);
    if (mass_scale_ != 1)
      ctx.log("segment " + source.segment + " weighs " + std::to_string(mass_scale_) + " times its mass");
    // The physical edits (§4.2) act on the coefficients: no inverse dynamics again.
    PathTorques edited{source.skeleton, source.fps, {}, "", {}};
    edited.frames.reserve(source.frames.size());
    for (int f = 0; f < source.frame_count(); ++f) edited.frames.push_back(source.edited(f, mass_scale_));
    const auto start = std::chrono::steady_clock::now();
    Hulls hulls = build_hulls(body, contacts, edited.frames, options_);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    long lps = 0;
    for (const FrameHull& h : hulls.frames) lps += h.lp_count;
    const int frames = static_cast<int>(hulls.frames.size());
    ctx.report("frames", static_cast<std::int64_t>(frames));
    ctx.report("feasible", static_cast<std::int64_t>(hulls.count(HullStatus::Feasible)));
    ctx.report("flight", static_cast<std::int64_t>(hulls.count(HullStatus::Flight)));
    ctx.report("infeasible", static_cast<std::int64_t>(hulls.count(HullStatus::Infeasible)));
    ctx.report("lps_per_frame", frames ? static_cast<double>(lps) / frames : 0.0);
    ctx.report("ms_per_frame", frames ? 1000 * seconds / frames : 0.0);
    std::ostringstream log;
    log << frames << " hulls: " << hulls.count(HullStatus::Feasible) << " feasible, "
        << hulls.count(HullStatus::Flight) << " in flight, " << hulls.count(HullStatus::Infeasible)
        << " not exactly physical (closest point); gravity (" << body.gravity.transpose() << ") m/s^2";
    ctx.log(log.str());
    ctx.output("hulls", std::move(hulls));
    ctx.output("torques", std::move(edited));
  }

 private:
  std::vector<double> gravity_;
  double mass_scale_;
  HullOptions options_;
};

NodeType hulls_node_type() {
  NodeSpec spec{
      .type = "retime.hulls",
      .version = 1,
      .doc =
          "Per frame, the timings (p̈, ṗ²) the body can follow the path at (McCann et al. 2006 §3.3, eq. 13): "
          "the projection of the polytope of contact forces within friction cones and torques within limits, "
          "found with GLPK by LPs in swept directions refined to `tolerance`, with λ at each vertex and the "
          "centre at the original timing (0, 1) of least contact force; the force model's fan (§3.4). Frames "
          "in flight and frames no contact forces can explain get their least-squares point, reported. The "
          "physical edits of §4.2 (`gravity`, a segment's `mass_scale`) change the coefficients, not the "
          "inverse dynamics. Nodes of one run with the same params and inputs (graphs/retime.yaml's "
          "reference and hulls when nothing is edited) build once: the executor shares their results.",
      .inputs = {{"body", "kg.BodyModel", true, "masses, torque limits, friction and gravity"},
                 {"contacts", "kg.Contacts", true, "which contact vertices touch at each frame"},
                 {"torques", "kg.PathTorques", true, "the torque coefficients per frame (retime.dynamics)"}},
      .outputs = {{"hulls", "kg.Hulls", true, "per frame: status, hull, λ at its vertices, centre, fan"},
                  {"torques", "kg.PathTorques", true,
                   "the coefficients the hulls were built with (edits applied)"}},
      .params = {
          {.name = "gravity",
           .type = ParamType::FloatList,
           .default_value = std::vector<double>{},
           .doc = "m/s^2: one number (straight down) or a world vector x y z (+Y up); empty: the body's"},
          {.name = "mass_scale",
           .type = ParamType::Float,
           .default_value = 1.0,
           .doc = "the modelled segment's mass (and inertia) times this (retime.dynamics' `segment`)",
           .min = 1e-6,
           .max = 1e6},
          {.name = "tolerance",
           .type = ParamType::Float,
           .default_value = 1e-3,
           .doc = "how far the true hull may reach beyond an edge found (plane units of p̈ and ṗ²)",
           .min = 1e-9,
           .max = 1.0},
          {.name = "pddot_max",
           .type = ParamType::Float,
           .default_value = 20.0,
           .doc = "the plane's box: |p̈| at most this (1/s)",
           .min = 1e-3,
           .max = 1e6},
          {.name = "pdot2_max",
           .type = ParamType::Float,
           .default_value = 16.0,
           .doc = "the plane's box: ṗ² at most this (16: four times the original speed)",
           .min = 1e-3,
           .max = 1e6}}};
  return {std::move(spec), [](const Params& p) { return std::make_unique<HullsNode>(p); }};
}

class RetimeNode final : public graph::Node {
 public:
  explicit RetimeNode(const Params& p)
      : duration_scale_(p.get<double>("duration_scale")),
        duration_(p.get<double>("duration")),
        fps_(p.get<double>("fps")),
        strict_(p.get<bool>("strict")) {
    const std::vector<double> sources = p.get<std::vector<double>>("pin_source");
    const std::vector<double> outputs = p.get<std::vector<double>>("pin_output");
    if (sources.size() != outputs.size())
      throw std::invalid_argument("pin_source has " + std::to_string(sources.size()) +
                                  " times and pin_output " + std::to_string(outputs.size()) +
                                  " (expected one output time per source time)");
    for (std::size_t i = 0; i < sources.size(); ++i) {
      if (!std::isfinite(sources[i]) || !std::isfinite(outputs[i]))
        throw std::invalid_argument("pin " + std::to_string(i) + ": pin_source " + shown(sources[i]) +
                                    " s, pin_output " + shown(outputs[i]) + " s (expected finite seconds)");
      options_.solve.pins.push_back({sources[i], outputs[i]});
    }
    const std::string objective = p.get<std::string>("objective");
    options_.target = objective == "minimal"     ? TorqueTarget::Zero
                      : objective == "reference" ? TorqueTarget::Reference
                                                 : TorqueTarget::Original;
    options_.mode =
        p.get<std::string>("mode") == "time_optimal" ? RetimeMode::TimeOptimal : RetimeMode::Optimise;
    options_.alpha = p.get<double>("alpha");
    options_.beta = p.get<double>("beta");
    options_.flight_weight = p.get<double>("flight_weight");
    options_.flights = p.get<std::string>("flights") == "free" ? FlightTiming::Free : FlightTiming::Hold;
    options_.solve.knot_spacing = options_.time_optimal.knot_spacing = p.get<double>("knot_spacing");
    options_.inside_tolerance = p.get<double>("inside_tolerance");
    if (duration_ > 0 && duration_ / options_.solve.knot_spacing > kMaxSegments)
      throw std::invalid_argument(
          "knot_spacing " + shown(options_.solve.knot_spacing) + " s cuts the " + shown(duration_) +
          " s duration into more than " + std::to_string(kMaxSegments) +
          " segments (expected knot_spacing >= " + shown(duration_ / kMaxSegments) + " s)");
    ClipRetimeOptions at_load = options_;  // without `duration`, the clip's duration scaled: known at run
    at_load.solve.duration = duration_ > 0 ? duration_ : at_load.solve.knot_spacing;
    at_load.validate();
  }

  void run(RunContext& ctx) const override {
    const motion::Motion& motion = ctx.input<motion::Motion>("motion");
    const Hulls& hulls = ctx.input<Hulls>("hulls");
    const PathTorques& torques = ctx.input<PathTorques>("torques");
    if (motion.frame_count() != static_cast<int>(hulls.frames.size()) ||
        torques.frame_count() != motion.frame_count())
      throw std::invalid_argument("the motion has " + std::to_string(motion.frame_count()) +
                                  " frames, the hulls " + std::to_string(hulls.frames.size()) +
                                  " and the torques " + std::to_string(torques.frame_count()) +
                                  " (expected the same clip)");
    ClipRetimeOptions options = options_;
    options.solve.duration = duration_ > 0 ? duration_ : duration_scale_ * motion.duration();
    std::vector<Eigen::VectorXd> reference;
    if (options.target == TorqueTarget::Reference) {
      if (!ctx.has_input("reference_hulls") || !ctx.has_input("reference_torques"))
        throw std::invalid_argument(
            "objective 'reference' needs reference_hulls and reference_torques connected");
      const PathTorques& rt = ctx.input<PathTorques>("reference_torques");
      reference = original_torques(ctx.input<Hulls>("reference_hulls"), rt.frames);
    }
    const ClipRetime r = retime_clip(hulls, torques.frames, motion.fps, options, *motion.skeleton, reference);
    // The solve time is logged, not put in the message: the message goes into the written report,
    // which --reproducible keeps the same on every run.
    ctx.log(r.message + " Solved in " + text::significant(r.solve.seconds * 1000, 3) + " ms.");
    ctx.report("duration", r.warp.duration);
    ctx.report("source_duration", motion.duration());
    ctx.report("converged", options.mode == RetimeMode::TimeOptimal ? r.feasible : r.solve.converged);
    ctx.report("iterations", static_cast<std::int64_t>(r.solve.iterations));
    ctx.report("solve_seconds", r.solve.seconds);
    ctx.report("objective_feasibility", r.feasibility);
    ctx.report("objective_torque", r.torque);
    ctx.report("torque_scale", r.torque_scale);
    ctx.report("share_inside", r.share_inside);
    ctx.report("share_at_point", r.share_at_point);
    ctx.report("flights_held", static_cast<std::int64_t>(r.flights_held));
    if (r.shortest && r.shortest->feasible) ctx.report("shortest_duration", r.shortest->duration);
    if (r.duration_holding_flights) ctx.report("duration_holding_flights", *r.duration_holding_flights);
    ctx.report("message", r.message);
    // Time-optimal with no feasible timing, or a strict request out of reach: the report says why
    // (and the shortest feasible duration), nothing else is written.
    const bool failed = r.warp.controls.empty() || (strict_ && !r.feasible);
    const double fps = fps_ > 0 ? fps_ : motion.fps;
    const int frames = failed ? 0 : output_frame_count(r.warp, fps);  // refuses a count too large first
    Report report;
    {
      kg::JsonWriter w(report);
      w.begin_object();
      w.field("clip", motion.name);
      w.field("objective", to_string(options.target));
      w.field("mode", options.mode == RetimeMode::TimeOptimal ? "time_optimal" : "match");
      w.field("flights", to_string(options.flights));
      if (options.flights == FlightTiming::Hold) w.field("flights_found", r.flights);
      w.field("flights_held", r.flights_held);
      if (r.duration_holding_flights) w.field("duration_holding_flights", *r.duration_holding_flights);
      if (r.flights_held > 0) w.field("held_speed", r.held_speed);
      w.field("source_duration", motion.duration());
      w.field("duration", r.warp.duration);
      w.field("converged", options.mode == RetimeMode::TimeOptimal ? r.feasible : r.solve.converged);
      w.field("iterations", r.solve.iterations);
      w.field("solve_seconds", ctx.reproducible() ? std::optional<double>() : r.solve.seconds);
      w.field("objective_feasibility", r.feasibility);
      w.field("objective_torque", r.torque);
      w.field("torque_scale_nm", r.torque_scale);
      w.field("share_inside", r.share_inside);
      w.field("share_at_point", r.share_at_point);
      w.field("fps", fps);
      w.field("output_frames", frames);  // as played out
      w.field("frames_feasible", hulls.count(HullStatus::Feasible));
      w.field("frames_flight", hulls.count(HullStatus::Flight));
      w.field("frames_infeasible", hulls.count(HullStatus::Infeasible));
      if (r.shortest && r.shortest->feasible) w.field("shortest_duration", r.shortest->duration);
      w.field("feasible", r.feasible);
      w.field("failed", failed);
      w.field("message", r.message);
      w.end_object();
    }
    // Kept on failure: the sink writes why (io.write_report).
    ctx.output("report", std::move(report));
    if (failed) throw std::runtime_error(r.message);

    ctx.output("warp", r.warp);
    ctx.output("motion", retimed_motion(motion, r.warp, fps));
  }

 private:
  double duration_scale_, duration_, fps_;
  bool strict_;
  ClipRetimeOptions options_;
};

NodeType retime_node_type() {
  NodeSpec spec{
      .type = "retime.retime",
      .version = 4,
      .doc =
          "Physics-based retiming (McCann et al. 2006): the strictly increasing playback p(t), a cubic "
          "spline, "
          "that minimises α·(distance to each frame's hull)² + β·|τ − τ'|² over the output (eq. 14, baked "
          "per "
          "frame and sector), with the ends kept, the duration given and any pins (source moments at output "
          "times) met exactly, by L-BFGS; τ' keeps the look (match), least effort (minimal) or another "
          "clip's "
          "(reference). mode time_optimal finds the shortest playback within the hulls instead. The result "
          "reports the share of output frames inside their hulls and, when the duration asks the impossible, "
          "the shortest feasible one. Files are written by sinks: io.write_report (the report), "
          "retime.write_curves (p(t)), retime.write_forces (per-frame forces).",
      .inputs = {{"motion", "kg.Motion", true, "the source clip (the one the hulls were built for)"},
                 {"hulls", "kg.Hulls", true, "per-frame hulls and force model (retime.hulls)"},
                 {"torques", "kg.PathTorques", true,
                  "the coefficients the hulls were built with (retime.hulls)"},
                 {"reference_hulls", "kg.Hulls", false, "objective reference: the other clip's hulls"},
                 {"reference_torques", "kg.PathTorques", false,
                  "objective reference: the other clip's torques"}},
      .outputs =
          {{"motion", "kg.Motion", true, "the retimed clip at `fps`"},
           {"warp", "kg.TimeWarp", true, "p(t): output seconds to source seconds"},
           {.name = "report",
            .type = "kg.Report",
            .doc = "the objective's parts, share of frames inside their hulls, convergence, output_frames "
                   "at `fps`, solve_seconds (null with --reproducible); set also when the node fails "
                   "(failed: true, feasible, shortest_duration) and then still delivered, for "
                   "io.write_report to say why",
            .kept_on_failure = true}},
      .params = {
          {.name = "duration_scale",
           .type = ParamType::Float,
           .default_value = 0.5,
           .doc = "output duration as a multiple of the source's (used when `duration` is 0)",
           .min = 1e-3,
           .max = 1e3},
          {.name = "duration",
           .type = ParamType::Float,
           .default_value = 0.0,
           .doc = "output duration, s; 0: duration_scale times the source's",
           .min = 0.0,
           .max = 1e6},
          {.name = "pin_source",
           .type = ParamType::FloatList,
           .default_value = std::vector<double>{},
           .doc = "source moments (s) pinned to the output times of pin_output, pairwise"},
          {.name = "pin_output",
           .type = ParamType::FloatList,
           .default_value = std::vector<double>{},
           .doc = "output times (s) at which the pin_source moments play"},
          {.name = "objective",
           .type = ParamType::Enum,
           .default_value = std::string("match"),
           .doc =
               "τ': match (the clip's own torques: keep the look), minimal (zero: least effort), reference "
               "(another clip's: wire reference_hulls and reference_torques)",
           .choices = {"match", "minimal", "reference"}},
          {.name = "mode",
           .type = ParamType::Enum,
           .default_value = std::string("match"),
           .doc = "match (eq. 14 for the requested duration and pins; optimise is an older name of it) or "
                  "time_optimal "
                  "(the shortest feasible playback; duration and pins ignored)",
           .choices = {"match", "time_optimal", "optimise"}},
          {.name = "alpha",
           .type = ParamType::Float,
           .default_value = 1000.0,
           .doc = "weight of the squared distance to the hulls (plane units²)",
           .min = 0.0,
           .max = 1e12},
          {.name = "beta",
           .type = ParamType::Float,
           .default_value = 1.0,
           .doc = "weight of the squared torque error, in units of the source's RMS joint torque",
           .min = 0.0,
           .max = 1e12},
          {.name = "flight_weight",
           .type = ParamType::Float,
           .default_value = 1.0,
           .doc = "multiplies alpha on flight frames: above 1, when no timing meets every hull, the flight "
                  "keeps "
                  "its speed (a wrong gravity shows at once) and the ground phases take the excess",
           .min = 0.0,
           .max = 1e12},
          {.name = "flights",
           .type = ParamType::Enum,
           .default_value = std::string("hold"),
           .doc = "hold: every flight played exactly at the one ballistic speed, √(|g| / 9.81) with the "
                  "hulls' gravity g (1x unedited; p̈ = 0), the ground phases taking the rest of the "
                  "duration (the paper's fig. 1); free: flights weighed like other frames (flight_weight). "
                  "Gravity not straight down: free, said in the log",
           .choices = {"hold", "free"}},
          {.name = "knot_spacing",
           .type = ParamType::Float,
           .default_value = 0.1,
           .doc = "output seconds between the spline's control points (at most 4096 segments over the "
                  "duration)",
           .min = 1e-3,
           .max = 1e3},
          {.name = "inside_tolerance",
           .type = ParamType::Float,
           .default_value = 0.01,
           .doc = "a timing this close to its hull (plane units) counts as inside, in the share reported",
           .min = 0.0,
           .max = 1e3},
          {.name = "fps",
           .type = ParamType::Float,
           .default_value = 0.0,
           .doc = "frame rate of the retimed clip; 0: the source's",
           .min = 0.0,
           .max = 1e5},
          {.name = "strict",
           .type = ParamType::Bool,
           .default_value = false,
           .doc = "fail (non-zero exit, no motion or warp; the report only, saying why) when "
                  "an output frame lies outside its hull"}}};
  return {std::move(spec), [](const Params& p) { return std::make_unique<RetimeNode>(p); }};
}

class WriteCurvesNode final : public graph::Node {
 public:
  explicit WriteCurvesNode(const Params& p) : path_(p.get<std::string>("path")) {}

  void run(RunContext& ctx) const override {
    const TimeWarp& warp = ctx.input<TimeWarp>("warp");
    const motion::Motion& played = ctx.input<motion::Motion>("motion");
    const bool json = path_.size() >= 5 && path_.substr(path_.size() - 5) == ".json";
    // A row per frame played, past the warp's end too (played_sample).
    write_sink_file(ctx, path_, [&](std::ostream& os) {
      json ? write_warp_json(os, warp, played.fps, played.frame_count())
           : write_warp_csv(os, warp, played.fps, played.frame_count());
    });
  }

 private:
  std::string path_;
};

NodeType write_curves_node_type() {
  NodeSpec spec{.type = "retime.write_curves",
                .version = 1,
                .doc =
                    "Writes a retiming's p(t), ṗ(t) and p̈(t) at each output frame of the retimed clip: CSV "
                    "(t, p, pdot, "
                    "pddot), or JSON when the path ends in .json (the warp's controls too).",
                .inputs = {{"warp", "kg.TimeWarp", true, "p(t) (retime.retime)"},
                           {"motion", "kg.Motion", true,
                            "the retimed clip (retime.retime): its frame rate sets the frames"}},
                .params = {sink_path_param("the .csv or .json file; \"\" writes none")},
                .side_effects = true};
  return {std::move(spec), [](const Params& p) { return std::make_unique<WriteCurvesNode>(p); }};
}

class WriteForcesNode final : public graph::Node {
 public:
  explicit WriteForcesNode(const Params& p) : path_(p.get<std::string>("path")) {}

  void run(RunContext& ctx) const override {
    const Hulls& hulls = ctx.input<Hulls>("hulls");
    const PathTorques& torques = ctx.input<PathTorques>("torques");
    const TimeWarp& warp = ctx.input<TimeWarp>("warp");
    if (static_cast<int>(hulls.frames.size()) != torques.frame_count())
      throw std::invalid_argument("the hulls have " + std::to_string(hulls.frames.size()) +
                                  " frames and the torques " + std::to_string(torques.frame_count()) +
                                  " (expected the same clip)");
    write_sink_file(ctx, path_, [&](std::ostream& os) {
      write_forces_json(os, hulls, torques.frames, warp, torques.fps);
    });
  }

 private:
  std::string path_;
};

NodeType write_forces_node_type() {
  NodeSpec spec{
      .type = "retime.write_forces",
      .version = 1,
      .doc =
          "Writes, per source frame of a retiming, the hull, the timing (p̈, ṗ²) the warp plays it at and "
          "whether "
          "that lies inside, the contact forces per patch there and the generalised forces (JSON).",
      .inputs = {{"hulls", "kg.Hulls", true, "the hulls the retiming used (retime.hulls)"},
                 {"torques", "kg.PathTorques", true, "the coefficients they were built with (retime.hulls)"},
                 {"warp", "kg.TimeWarp", true, "p(t) (retime.retime)"}},
      .params = {sink_path_param("the JSON file; \"\" writes none")},
      .side_effects = true};
  return {std::move(spec), [](const Params& p) { return std::make_unique<WriteForcesNode>(p); }};
}

}  // namespace
}  // namespace kg::retime

namespace kg {

std::vector<graph::NodeType> retime_node_types() {
  std::vector<graph::NodeType> out;
  out.push_back(retime::dynamics_node_type());
  out.push_back(retime::torque_limits_node_type());
  out.push_back(retime::hulls_node_type());
  out.push_back(retime::retime_node_type());
  out.push_back(retime::playback_node_type());
  out.push_back(retime::write_curves_node_type());
  out.push_back(retime::write_forces_node_type());
  return out;
}

}  // namespace kg
