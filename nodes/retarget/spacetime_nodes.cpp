// retarget.spacetime: a thin adapter over solve_spacetime (DESIGN.md 7). The solver's outcome
// (converged or not, violations) is reported as figures and a log line, never thrown (tier 3).
#include <algorithm>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "kg/base/pattern.hpp"
#include "kg/base/text.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/key_spacing.hpp"
#include "kg/retarget/nodes.hpp"
#include "kg/retarget/spacetime.hpp"
#include "kg/retarget/target.hpp"

namespace kg {

namespace {

using graph::Node;
using graph::NodeSpec;
using graph::NodeType;
using graph::Params;
using graph::ParamSpec;
using graph::ParamType;
using graph::RunContext;
using retarget::CharacterProblem;

kg::Pattern compile_freeze(const std::string& name, const std::string& pattern) {
  try {
    return kg::Pattern::compile(pattern);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(name + ": " + e.what());
  }
}

class SpacetimeNode final : public Node {
 public:
  explicit SpacetimeNode(const Params& p)
      : freeze_{compile_freeze("freeze", p.get<std::string>("freeze")),
                compile_freeze("freeze2", p.get<std::string>("freeze2"))},
        keys_(static_cast<int>(p.get<std::int64_t>("keys"))),
        strict_(p.get<bool>("strict")) {
    options_.epsilon = p.get<double>("epsilon");
    options_.equality_tolerance = options_.inequality_tolerance = p.get<double>("tolerance_mm") / 1000;
    options_.max_iterations = static_cast<int>(p.get<std::int64_t>("max_iterations"));
    options_.densify = p.get<bool>("densify");
    options_.validate();  // a bad setting fails when the graph loads
  }

  void run(RunContext& ctx) const override {
    const retarget::ConstraintSet& set = ctx.input<retarget::ConstraintSet>("constraints");
    retarget::SpacetimeProblem problem;
    problem.characters.push_back(character(ctx, 0, "motion", "keys", "target"));
    if (ctx.has_input("motion2")) {
      problem.characters.push_back(character(ctx, 1, "motion2", "keys2", "target2"));
    } else {
      for (const char* port : {"keys2", "target2"})
        if (ctx.has_input(port))
          throw std::invalid_argument(std::string("input '") + port + "' is connected but 'motion2' is not");
      if (set.character_count() > 1)
        throw std::invalid_argument(
            "the constraints refer to a second character but 'motion2' is not connected");
    }
    const retarget::ConstraintKindTable kinds = retarget::kinds_for(set, ctx);
    problem.constraints = &set;
    problem.kinds = [&kinds](const std::string& name) { return kinds.find(name); };
    problem.options = options_;

    retarget::SpacetimeResult result = retarget::solve_spacetime(problem);

    ctx.report("converged", result.converged());
    ctx.report("iterations", static_cast<std::int64_t>(result.iterations));
    ctx.report("passes", static_cast<std::int64_t>(result.passes));
    ctx.report("seconds", result.seconds);
    ctx.report("unknowns", static_cast<std::int64_t>(result.unknowns));
    ctx.report("active_rows", static_cast<std::int64_t>(result.active_rows));
    ctx.report("total_rows", static_cast<std::int64_t>(result.total_rows));
    ctx.report("worst_violation_mm", result.worst_violation() * 1000);
    for (const retarget::KindReport& k : result.kinds) ctx.report("worst_mm." + k.kind, k.worst() * 1000);
    ctx.report("message", result.message);
    ctx.log(result.message);
    // Strict: a solve that missed its constraints fails the node (and the run's exit code), for
    // batch runs that must not pass a bad result on; otherwise the best effort goes on, flagged.
    if (strict_ && !result.converged()) throw std::runtime_error(result.message);
    for (std::size_t k = 0; k < result.frames_per_key.size(); ++k) {
      int finest = 1 << 30;
      for (int f : result.frames_per_key[k]) finest = std::min(finest, f);
      if (!result.frames_per_key[k].empty())
        ctx.report(k == 0 ? "finest_keys" : "finest_keys2", static_cast<std::int64_t>(finest));
    }
    if (result.motions.size() > 1) ctx.output("motion2", std::move(result.motions[1]));
    ctx.output("motion", std::move(result.motions[0]));
    ctx.output("seconds", result.seconds);
  }

 private:
  CharacterProblem character(const RunContext& ctx, int index, const char* motion_port, const char* keys_port,
                             const char* target_port) const {
    CharacterProblem cp;
    cp.initial = ctx.input<motion::Motion>(motion_port);
    const std::string who = std::string("input '") + motion_port + "'";
    if (!cp.initial.skeleton) throw std::invalid_argument(who + ": motion has no skeleton");
    const motion::Skeleton& sk = *cp.initial.skeleton;
    const int channels = sk.channel_count();
    if (ctx.has_input(keys_port)) {
      const retarget::KeySpacing& keys = ctx.input<retarget::KeySpacing>(keys_port);
      if (static_cast<int>(keys.frames_per_key.size()) != channels)
        throw std::invalid_argument(std::string("input '") + keys_port + "' has " +
                                    std::to_string(keys.frames_per_key.size()) + " key spacings, " + who +
                                    " has " + std::to_string(channels) + " channels");
      cp.frames_per_key = keys.frames_per_key;
    } else {
      cp.frames_per_key.assign(static_cast<std::size_t>(channels), keys_);
    }
    if (ctx.has_input(target_port)) {
      const retarget::Target& target = ctx.input<retarget::Target>(target_port);
      if (!target.skeleton || target.skeleton->joint_count() != sk.joint_count() ||
          target.skeleton->channel_count() != channels)
        throw std::invalid_argument(
            std::string("input '") + target_port + "': the target's skeleton (" +
            (target.skeleton ? std::to_string(target.skeleton->joint_count()) : "no") +
            " joints) has another structure than " + who + "'s (" + std::to_string(sk.joint_count()) +
            " joints)");
      if (target.morphing())
        for (int f = 0; f < cp.initial.frame_count(); ++f)
          cp.skeleton_per_frame.push_back(target.skeleton_at(f / cp.initial.fps));
    }
    const std::string& pattern = freeze_[static_cast<std::size_t>(index)].text();
    if (!pattern.empty()) {
      cp.frozen.assign(static_cast<std::size_t>(channels), false);
      int matched = 0;
      for (const motion::Joint& jt : sk.joints()) {
        if (!freeze_[static_cast<std::size_t>(index)].full_match(jt.name)) continue;
        ++matched;
        for (std::size_t c = 0; c < jt.channels.size(); ++c)
          cp.frozen[static_cast<std::size_t>(jt.first_channel) + c] = true;
      }
      if (matched == 0)
        throw std::invalid_argument(std::string(index == 0 ? "freeze" : "freeze2") + ": " +
                                    text::excerpt(pattern) + " matches no joint of " + who + "'s skeleton");
    }
    return cp;
  }

  kg::Pattern freeze_[2];  // compiled once, when the graph loads; "" freezes nothing
  int keys_;
  bool strict_;
  retarget::SpacetimeOptions options_;
};

NodeType spacetime_type() {
  NodeSpec spec;
  spec.type = "retarget.spacetime";
  spec.version = 1;
  spec.doc =
      "Spacetime retargeting (Gleicher 1998 §6): finds cubic B-spline displacement maps (keys every `keys` "
      "frames per channel) that, added to the initial estimate, make the constraints hold while changing the "
      "motion least (damped least squares, eq. 4; inequality rows through an active set; analytic Jacobians; "
      "banded Cholesky). Where constraints stay violated past tolerance it solves again with halved key "
      "spacing (§4 step 5) when `densify` is set. A second character (motion2) joins the same solve; "
      "constraints refer to it as character 1. Not converging is reported (converged = false, message) and, "
      "with `strict`, fails the node.";
  spec.inputs = {
      {"motion", "kg.Motion", true, "the initial estimate m1 on the target skeleton (metres, radians)"},
      {"constraints", "kg.Constraints", true, "what must hold (characters 0 and, with motion2, 1)"},
      {"keys", "kg.KeySpacing", false, "frames between keys per channel; default `keys` frames for all"},
      {"target", "kg.Target", false, "the target character; a morphing one gives each frame its skeleton"},
      {"motion2", "kg.Motion", false, "the second character's initial estimate (same frames and rate)"},
      {"keys2", "kg.KeySpacing", false, "key spacing of the second character"},
      {"target2", "kg.Target", false, "the second target character (for morphing)"}};
  spec.outputs = {{"motion", "kg.Motion", true, "m1 + d on the initial motion's skeleton"},
                  {"motion2", "kg.Motion", false, "the second character's result, when motion2 is connected"},
                  {"seconds", "kg.Scalar", true, "wall time of the solve, s (for retarget.metrics)"}};
  spec.params = {
      ParamSpec{.name = "epsilon",
                .type = ParamType::Float,
                .default_value = 1e-4,
                .doc = "damping weight of the change (x^T M x, M = squared reach of each channel's joint, 1 "
                       "for translation)",
                .min = 1e-12,
                .max = 1.0},
      ParamSpec{.name = "tolerance_mm",
                .type = ParamType::Float,
                .default_value = 1.0,
                .doc = "converged when every equality row is within this and no inequality row is violated "
                       "by more (mm; "
                       "for parameter rows the same number in milliradians)",
                .min = 1e-6,
                .max = 1000.0},
      ParamSpec{.name = "max_iterations",
                .type = ParamType::Int,
                .default_value = std::int64_t{40},
                .doc = "Gauss-Newton iterations per pass",
                .min = 0,
                .max = 10000},
      ParamSpec{.name = "densify",
                .type = ParamType::Bool,
                .default_value = true,
                .doc = "retry with halved key spacing (down to 1) while violated"},
      ParamSpec{.name = "keys",
                .type = ParamType::Int,
                .default_value = std::int64_t{4},
                .doc = "frames between keys when no `keys` input is connected",
                .min = 1,
                .max = 1000},
      ParamSpec{.name = "freeze",
                .type = ParamType::String,
                .default_value = std::string(""),
                .doc = "regular expression (RE2, whole joint name) of joints whose channels must not change; "
                       "\"\": none"},
      ParamSpec{.name = "freeze2",
                .type = ParamType::String,
                .default_value = std::string(""),
                .doc = "the same for the second character"},
      ParamSpec{.name = "strict",
                .type = ParamType::Bool,
                .default_value = false,
                .doc = "fail (a non-zero exit) when the constraints are not met; otherwise the best effort "
                       "is output and "
                       "the failure reported (converged = false, message)"},
  };
  return {spec, [](const Params& p) { return std::make_unique<SpacetimeNode>(p); }};
}

}  // namespace

std::vector<graph::NodeType> retarget_spacetime_node_types() {
  return {spacetime_type(), retarget::at_rate_node_type()};
}

}  // namespace kg
