// retarget.metrics: a thin adapter over compute_metrics and metrics_report (metrics.hpp). It
// outputs the JSON document as a kg.Report; io.write_report writes it (DESIGN.md 13).
#include <cstdint>
#include <memory>

#include "kg/builtin_nodes.hpp"
#include "kg/retarget/key_spacing.hpp"
#include "kg/retarget/metrics.hpp"
#include "kg/retarget/nodes.hpp"
#include "kg/retarget/per_frame_ik.hpp"

namespace kg::retarget {
namespace {

using graph::ParamType;

class MetricsNode final : public graph::Node {
 public:
  explicit MetricsNode(const graph::Params& p)
      : key_spacing_(static_cast<int>(p.get<std::int64_t>("key_spacing"))),
        tolerance_(p.get<double>("tolerance_mm") / 1000.0) {}

  void run(graph::RunContext& ctx) const override {
    const ConstraintSet& set = ctx.input<ConstraintSet>("constraints");
    const ConstraintKindTable kinds = kinds_for(set, ctx);
    MetricsInputs in;
    in.result = &ctx.input<motion::Motion>("motion");
    if (ctx.has_input("motion2")) in.result2 = &ctx.input<motion::Motion>("motion2");
    in.constraints = &set;
    in.kinds = &kinds;
    if (ctx.has_input("source")) in.source = &ctx.input<motion::Motion>("source");
    if (ctx.has_input("initial")) in.initial = &ctx.input<motion::Motion>("initial");
    if (ctx.has_input("target")) in.target = &ctx.input<Target>("target");
    if (ctx.has_input("keys")) {
      in.frames_per_key = ctx.input<KeySpacing>("keys").frames_per_key;
      in.keys_fps = ctx.input<KeySpacing>("keys").fps;
    } else
      in.frames_per_key = {key_spacing_};
    if (ctx.has_input("solve_seconds")) in.solve_seconds = ctx.input<double>("solve_seconds");
    in.tolerance = tolerance_;
    const RetargetMetrics m = compute_metrics(in);

    ctx.report("worst_violation_cm", 100 * m.worst_violation_metres);
    for (const KindMetrics& k : m.kinds) {
      const double scale = k.in_metres ? 100.0 : 1.0;
      const std::string unit = k.in_metres ? "_cm" : "";
      ctx.report("worst_" + k.violation.kind + unit, scale * k.violation.worst);
      ctx.report("mean_" + k.violation.kind + unit, scale * k.violation.mean);
    }
    ctx.report("plants", static_cast<std::int64_t>(m.skate.plants.size()));
    ctx.report("skate_worst_cm", 100 * m.skate.worst);
    ctx.report("skate_mean_cm", 100 * m.skate.mean);
    if (m.initial_skate) ctx.report("initial_skate_worst_cm", 100 * m.initial_skate->worst);
    ctx.report("jerk_translation", m.jerk.translation);
    ctx.report("jerk_rotation", m.jerk.rotation);
    if (m.source_jerk) {
      ctx.report("jerk_translation_increase", m.jerk.translation - m.source_jerk->translation);
      ctx.report("jerk_rotation_increase", m.jerk.rotation - m.source_jerk->rotation);
      ctx.report("displacement_jerk_rotation", m.displacement_jerk->rotation);
    }
    if (m.energy) {
      ctx.report("energy_above_cutoff_translation", m.energy->translation.fraction);
      ctx.report("energy_above_cutoff_rotation", m.energy->rotation.fraction);
    }
    if (m.solve_seconds) ctx.report("solve_seconds", *m.solve_seconds);

    if (ctx.reproducible()) {
      RetargetMetrics timeless = m;
      timeless.solve_seconds.reset();
      ctx.output("report", metrics_report(timeless));
    } else {
      ctx.output("report", metrics_report(m));
    }
  }

 private:
  int key_spacing_;
  double tolerance_;
};

graph::NodeType metrics_node_type() {
  graph::NodeSpec spec{
      .type = "retarget.metrics",
      .version = 2,
      .doc =
          "Measures a retargeted motion (one character) and outputs them as a JSON report (written by "
          "io.write_report): worst and mean "
          "violation per constraint kind (cm for point kinds), foot skate (greatest horizontal "
          "travel of each planted point of position/same_place constraints during its run of "
          "frames, cm; beside it the initial estimate's, when wired: the scaled source's own), RMS jerk of "
          "position (m/s^3) and rotation (rad/s^3) channels, of the "
          "source and of the displacement from it, the fraction of the displacement's energy "
          "above the key spacing's cut-off fps / (2 k) (DCT of each channel; displacement from "
          "`initial` when wired, else from `source`), and the solve time when wired.",
      .inputs = {{"motion", "kg.Motion", true, "the result, on the target skeleton"},
                 {"constraints", "kg.Constraints", true, "the constraints it should meet"},
                 {"source", "kg.Motion", false, "the motion before adaptation, on its own skeleton"},
                 {"initial", "kg.Motion", false, "the initial estimate the solver started from"},
                 {"motion2", "kg.Motion", false,
                  "the second character's result, for constraints across characters"},
                 {"target", "kg.Target", false,
                  "the target character: a morphing one gives each frame its skeleton"},
                 {"keys", "kg.KeySpacing", false,
                  "the key spacing of the solve (else key_spacing), at the solve's rate"},
                 {"solve_seconds", "kg.Scalar", false, "the solver's time, s, passed through"}},
      .outputs = {{"report", "kg.Report", true,
                   "the JSON document (version 1; solve_seconds null with --reproducible)"}},
      .params = {{.name = "key_spacing",
                  .type = ParamType::Int,
                  .default_value = std::int64_t{4},
                  .doc = "frames per key for the energy cut-off when `keys` is not wired",
                  .min = 1.0,
                  .max = 1000.0},
                 {.name = "tolerance_mm",
                  .type = ParamType::Float,
                  .default_value = 1.0,
                  .doc = "rows violated by more than this count as violated_rows, mm (1e-3 rad per mm)",
                  .min = 0.0}}};
  return {std::move(spec), [](const graph::Params& p) { return std::make_unique<MetricsNode>(p); }};
}

}  // namespace

}  // namespace kg::retarget

namespace kg {

std::vector<graph::NodeType> retarget_metrics_node_types() {
  std::vector<graph::NodeType> out;
  out.push_back(retarget::per_frame_ik_node_type());
  out.push_back(retarget::metrics_node_type());
  return out;
}

}  // namespace kg
