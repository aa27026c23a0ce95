// motion.synthesize: a thin adapter over synthesize_walk / synthesize_jump (DESIGN.md 7).
#include <cstdint>
#include <memory>
#include <string>

#include "kg/builtin_nodes.hpp"
#include "kg/synth/synthesize.hpp"

namespace kg {

namespace {

using graph::Node;
using graph::NodeSpec;
using graph::NodeType;
using graph::Params;
using graph::ParamSpec;
using graph::ParamType;
using graph::RunContext;

class SynthesizeNode final : public Node {
 public:
  explicit SynthesizeNode(const Params& p)
      : jump_(p.get<std::string>("kind") == "jump"),
        walk_{static_cast<int>(p.get<std::int64_t>("steps")), p.get<double>("speed"),
              p.get<double>("stature"), p.get<double>("fps")},
        jump_options_{p.get<double>("jump_height"), p.get<double>("jump_distance"), p.get<double>("stature"),
                      p.get<double>("fps"), p.get<double>("gravity")} {
    const std::string& kind = p.get<std::string>("kind");
    if (kind != "walk" && kind != "jump")
      throw std::invalid_argument("kind '" + kind + "': expected walk or jump");
  }

  void run(RunContext& ctx) const override {
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

ParamSpec float_param(const char* name, double value, synth::Range range, const char* doc) {
  ParamSpec p;
  p.name = name;
  p.type = ParamType::Float;
  p.default_value = value;
  p.doc = doc;
  p.min = range.min;
  p.max = range.max;
  return p;
}

NodeType synthesize_type() {
  NodeSpec spec;
  spec.type = "motion.synthesize";
  spec.version = 1;
  spec.doc =
      "Synthesizes a human figure and a motion with exactly planted feet, for pipelines without captured "
      "data. walk: starts standing, takes `steps` steps along +Z at `speed` (step length and cadence from a "
      "walk-ratio gait relation), ends standing with the feet together; heel strike, foot flat, heel off, "
      "toe "
      "off, pelvis bob/sway/rotation, arm swing. jump: countermovement, push-off, ballistic flight of the "
      "root "
      "(y = y0 + v0 t - g t^2/2), landing and absorbing crouch. Metres, radians, world +Y up, floor y = 0.";
  spec.outputs = {
      {"motion", "kg.Motion", true, "the clip: 21 joints, ZXY rotation channels, metres, radians"},
      {"skeleton", "kg.Skeleton", true,
       "the figure (Hips, Spine, Chest, Neck, Head, Left/Right Shoulder, Arm, ForeArm, Hand, UpLeg, "
       "Leg, Foot, ToeBase)"}};
  ParamSpec kind;
  kind.name = "kind";
  kind.type = ParamType::Enum;
  kind.default_value = std::string("walk");
  kind.doc = "walk or jump";
  kind.choices = {"walk", "jump"};
  ParamSpec steps;
  steps.name = "steps";
  steps.type = ParamType::Int;
  steps.default_value = std::int64_t{8};
  steps.doc = "walk: foot landings, the first from standing, the last bringing the feet together";
  steps.min = synth::kStepsRange.min;
  steps.max = synth::kStepsRange.max;
  spec.params = {
      kind,
      steps,
      float_param("speed", 1.3, synth::kSpeedRange, "walk: steady walking speed, m/s"),
      float_param("stature", 1.75, synth::kStatureRange, "standing height of the figure, m"),
      float_param("fps", 120, synth::kFpsRange, "frames per second"),
      float_param("jump_height", 0.3, synth::kJumpHeightRange,
                  "jump: rise of the root from takeoff to apex, m"),
      float_param("jump_distance", 0.8, synth::kJumpDistanceRange,
                  "jump: forward travel of the feet, m (0: a vertical jump)"),
      float_param("gravity", 9.81, synth::kGravityRange, "jump: gravitational acceleration, m/s^2"),
  };
  return {spec, [](const Params& p) { return std::make_unique<SynthesizeNode>(p); }};
}

}  // namespace

std::vector<graph::NodeType> synth_node_types() {
  return {synthesize_type()};
}

}  // namespace kg
