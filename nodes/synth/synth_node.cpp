// motion.synthesize: a thin adapter over synthesize_walk / synthesize_jump (DESIGN.md 7).
#include <cstdint>
#include <memory>
#include <string>

#include "kg/builtin_nodes.hpp"
#include "kg/synth/synthesize.hpp"

namespace kg {

namespace {

class SynthesizeNode final : public graph::Node {
 public:
  explicit SynthesizeNode(const graph::Params& p)
      : jump_(p.get<std::string>("kind") == "jump"),
        walk_{static_cast<int>(p.get<std::int64_t>("steps")), p.get<double>("speed"),
              p.get<double>("stature"), p.get<double>("fps")},
        jump_options_{p.get<double>("jump_height"), p.get<double>("jump_distance"), p.get<double>("stature"),
                      p.get<double>("fps"), p.get<double>("gravity")} {
    const std::string& kind = p.get<std::string>("kind");
    if (kind != "walk" && kind != "jump")
      throw std::invalid_argument("kind '" + kind + "': expected walk or jump");
  }

  void run(graph::RunContext& ctx) const override {
    synth::Synthesis s = jump_ ? synth::synthesize_jump(jump_options_) : synth::synthesize_walk(walk_);
    ctx.report("frames", static_cast<std::int64_t>(s.motion.frame_count()));
    ctx.report("seconds", s.motion.duration());
    ctx.report("plants", static_cast<std::int64_t>(s.plants.size()));
    ctx.report("max_leg_extension", s.max_leg_extension);
    if (jump_) {
      ctx.report("flight_time", s.flight_end - s.flight_start);
      ctx.report("takeoff_velocity_up", s.takeoff_velocity_up);
      ctx.report("takeoff_velocity_forward", s.takeoff_velocity_forward);
    } else {
      ctx.report("steps", static_cast<std::int64_t>(s.steps));
      ctx.report("step_length", s.gait.step_length);
      ctx.report("cadence_steps_per_min", 60 / s.gait.step_time);
    }
    ctx.set_output("skeleton", graph::Value::share(s.figure.skeleton));
    ctx.output("motion", std::move(s.motion));
  }

 private:
  bool jump_;
  synth::WalkOptions walk_;
  synth::JumpOptions jump_options_;
};

graph::NodeType synthesize_type() {
  using graph::ParamType;
  graph::NodeSpec spec{
      .type = "motion.synthesize",
      .version = 1,
      .doc =
          "Synthesizes a human figure and a motion with exactly planted feet, for pipelines without "
          "captured data. walk: starts standing, takes `steps` steps along +Z at `speed` (step length and "
          "cadence from a walk-ratio gait relation), ends standing with the feet together; heel strike, "
          "foot flat, heel off, toe off, pelvis bob/sway/rotation, arm swing. jump: countermovement, "
          "push-off, ballistic flight of the root (y = y0 + v0 t - g t^2/2), landing and absorbing crouch. "
          "Metres, radians, world +Y up, floor y = 0.",
      .outputs =
          {{"motion", "kg.Motion", true, "the clip: 21 joints, ZXY rotation channels, metres, radians"},
           {"skeleton", "kg.Skeleton", true,
            "the figure (Hips, Spine, Chest, Neck, Head, Left/Right Shoulder, Arm, ForeArm, Hand, UpLeg, "
            "Leg, Foot, ToeBase)"}},
      .params = {{.name = "kind",
                  .type = ParamType::Enum,
                  .default_value = std::string("walk"),
                  .doc = "walk or jump",
                  .choices = {"walk", "jump"}},
                 {.name = "steps",
                  .type = ParamType::Int,
                  .default_value = std::int64_t{8},
                  .doc = "walk: foot landings, the first from standing, the last bringing the feet together",
                  .min = synth::kStepsRange.min,
                  .max = synth::kStepsRange.max},
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
                  .doc = "jump: rise of the root from takeoff to apex, m",
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
                  .max = synth::kGravityRange.max}},
  };
  return {spec, [](const graph::Params& p) { return std::make_unique<SynthesizeNode>(p); }};
}

}  // namespace

std::vector<graph::NodeType> synth_node_types() {
  return {synthesize_type()};
}

}  // namespace kg
