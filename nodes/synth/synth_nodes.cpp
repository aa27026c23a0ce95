// motion.synthesize: a thin adapter over synthesize_walk / synthesize_jump / synthesize_climb
// (DESIGN.md 7).
#include <algorithm>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include "kg/base/text.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/motion/nodes.hpp"
#include "kg/synth/synthesize.hpp"

namespace kg {

namespace {

class SynthesizeNode final : public graph::Node {
 public:
  explicit SynthesizeNode(const graph::Params& p)
      : kind_(p.get<std::string>("kind")),
        walk_{static_cast<int>(p.get<std::int64_t>("steps")), p.get<double>("speed"),
              p.get<double>("stature"), p.get<double>("fps")},
        jump_options_{p.get<double>("jump_height"), p.get<double>("jump_distance"), p.get<double>("stature"),
                      p.get<double>("fps"), p.get<double>("gravity")},
        climb_{static_cast<int>(p.get<std::int64_t>("steps")),
               p.get<double>("rung_spacing"),
               p.get<double>("rail_half_width"),
               p.get<double>("ladder_distance"),
               p.get<double>("stature"),
               p.get<double>("fps")} {
    if (kind_ != "walk" && kind_ != "jump" && kind_ != "climb")
      throw std::invalid_argument("kind " + text::in_quotes(kind_) + ": expected walk, jump or climb");
    // `steps` means foot landings for a walk and rungs climbed for a climb, with their own
    // ranges; the param's declared range is their union, so each is checked here, at load time.
    const synth::Range steps = kind_ == "climb" ? synth::kClimbRungsRange : synth::kStepsRange;
    const auto n = p.get<std::int64_t>("steps");
    if (kind_ != "jump" && (n < steps.min || n > steps.max))
      throw std::invalid_argument("steps " + std::to_string(n) + ": a " + kind_ + " takes " +
                                  std::to_string(static_cast<int>(steps.min)) + " to " +
                                  std::to_string(static_cast<int>(steps.max)) +
                                  (kind_ == "climb" ? " (rungs climbed)" : " (foot landings)"));
    // The chosen figure's options, checked when the graph loads.
    if (kind_ == "jump")
      jump_options_.validate();
    else if (kind_ == "climb")
      climb_.validate();
    else
      walk_.validate();
  }

  void run(graph::RunContext& ctx) const override {
    synth::Synthesis s = kind_ == "jump"    ? synth::synthesize_jump(jump_options_)
                         : kind_ == "climb" ? synth::synthesize_climb(climb_)
                                            : synth::synthesize_walk(walk_);
    ctx.report("frames", static_cast<std::int64_t>(s.motion.frame_count()));
    ctx.report("seconds", s.motion.duration());
    ctx.report("plants", static_cast<std::int64_t>(s.plants.size()));
    ctx.report("max_leg_extension", s.max_leg_extension);
    if (kind_ == "jump") {
      ctx.report("flight_time", s.flight_end - s.flight_start);
      ctx.report("takeoff_velocity_up", s.takeoff_velocity_up);
      ctx.report("takeoff_velocity_forward", s.takeoff_velocity_forward);
    } else if (kind_ == "climb") {
      ctx.report("rungs_climbed", static_cast<std::int64_t>(s.steps));
      ctx.report("holds", static_cast<std::int64_t>(s.holds.size()));
      ctx.report("max_arm_extension", s.max_arm_extension);
      ctx.report("ladder_rungs", static_cast<std::int64_t>(s.ladder.rung_count));
      ctx.report("rail_top_m", s.ladder.rail_top);
    } else {
      ctx.report("steps", static_cast<std::int64_t>(s.steps));
      ctx.report("step_length", s.gait.step_length);
      ctx.report("cadence_steps_per_min", 60 / s.gait.step_time);
    }
    ctx.set_output("skeleton", graph::Value::share(s.figure.skeleton));
    ctx.output("motion", std::move(s.motion));
  }

 private:
  std::string kind_;
  synth::WalkOptions walk_;
  synth::JumpOptions jump_options_;
  synth::ClimbOptions climb_;
};

std::vector<graph::ParamSpec> synthesize_params() {
  using graph::ParamType;
  return {{.name = "kind",
           .type = ParamType::Enum,
           .default_value = std::string("walk"),
           .doc = "walk, jump or climb",
           .choices = {"walk", "jump", "climb"}},
          {.name = "steps",
           .type = ParamType::Int,
           .default_value = std::int64_t{8},
           .doc = "walk: foot landings, the first from standing, the last bringing the feet together "
                  "(2 to 200); climb: rungs climbed (1 to 60)",
           .min = std::min(synth::kStepsRange.min, synth::kClimbRungsRange.min),
           .max = std::max(synth::kStepsRange.max, synth::kClimbRungsRange.max)},
          {.name = "speed",
           .type = ParamType::Float,
           .default_value = 1.3,
           .doc = "walk: steady walking speed, m/s",
           .min = synth::kSpeedRange.min,
           .max = synth::kSpeedRange.max},
          {.name = "stature",
           .type = ParamType::Float,
           .default_value = 1.75,
           .doc = "standing height of the figure, m",
           .min = synth::kStatureRange.min,
           .max = synth::kStatureRange.max},
          {.name = "fps",
           .type = ParamType::Float,
           .default_value = 120.0,
           .doc = "frames per second",
           .min = synth::kFpsRange.min,
           .max = synth::kFpsRange.max},
          {.name = "jump_height",
           .type = ParamType::Float,
           .default_value = 0.3,
           .doc = "jump: rise of the planned root from takeoff to apex, m (the written root rises a few "
                  "percent less: the body is shifted so that its centre of mass flies ballistically)",
           .min = synth::kJumpHeightRange.min,
           .max = synth::kJumpHeightRange.max},
          {.name = "jump_distance",
           .type = ParamType::Float,
           .default_value = 0.8,
           .doc = "jump: forward travel of the feet, m (0: a vertical jump)",
           .min = synth::kJumpDistanceRange.min,
           .max = synth::kJumpDistanceRange.max},
          {.name = "gravity",
           .type = ParamType::Float,
           .default_value = 9.81,
           .doc = "jump: gravitational acceleration, m/s^2",
           .min = synth::kGravityRange.min,
           .max = synth::kGravityRange.max},
          {.name = "rung_spacing",
           .type = ParamType::Float,
           .default_value = 0.30,
           .doc = "climb: metres between rungs (and from the floor to the first)",
           .min = synth::kRungSpacingRange.min,
           .max = synth::kRungSpacingRange.max},
          {.name = "rail_half_width",
           .type = ParamType::Float,
           .default_value = 0.22,
           .doc = "climb: metres from the ladder's middle to each rail",
           .min = synth::kRailHalfWidthRange.min,
           .max = synth::kRailHalfWidthRange.max},
          {.name = "ladder_distance",
           .type = ParamType::Float,
           .default_value = 0.50,
           .doc = "climb: metres from the root's line (z = 0) ahead to the ladder's plane",
           .min = synth::kLadderDistanceRange.min,
           .max = synth::kLadderDistanceRange.max}};
}

graph::NodeType synthesize_type() {
  graph::NodeSpec spec{
      .type = "motion.synthesize",
      .version = 1,
      .doc =
          "Synthesizes a human figure and a motion with exactly planted feet, for pipelines without "
          "captured data. walk: starts standing, takes `steps` steps along +Z at `speed` (step length and "
          "cadence from a walk-ratio gait relation), ends standing with the feet together; heel strike, "
          "foot flat, heel off, toe off, pelvis bob/sway/rotation, arm swing. jump: countermovement, "
          "push-off, a flight whose centre of mass (de Leva's masses) is ballistic, landing and absorbing "
          "crouch. "
          "climb: stands on the first rung of a vertical ladder `ladder_distance` ahead (rungs every "
          "`rung_spacing`, rails at +-`rail_half_width`) and climbs `steps` rungs one limb at a time, feet "
          "passing each other, hands on the rails, every hold exact (Gleicher 1998 7.2 had such a clip). "
          "Metres, radians, world +Y up, floor y = 0.",
      .outputs =
          {{"motion", "kg.Motion", true, "the clip: 21 joints, ZXY rotation channels, metres, radians"},
           {"skeleton", "kg.Skeleton", true,
            "the figure (Hips, Spine, Chest, Neck, Head, Left/Right Shoulder, Arm, ForeArm, Hand, UpLeg, "
            "Leg, Foot, ToeBase)"}},
      .params = synthesize_params(),
  };
  return {spec, [](const graph::Params& p) { return std::make_unique<SynthesizeNode>(p); }};
}

}  // namespace

std::vector<graph::NodeType> synth_node_types() {
  return {synthesize_type()};
}

}  // namespace kg
