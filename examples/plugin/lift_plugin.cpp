// A node plugin: `example.lift` raises a clip by `height` metres (a walk moved onto a stage).
// A node declares its spec (type, version, doc, typed ports, params with defaults and ranges)
// and a factory; the graph loader checks every graph against the spec before anything runs, and
// run() is const: everything of one run goes through the RunContext.
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include "kg/graph/plugin_abi.hpp"  // the one header a plugin needs: PluginRecord, KG_PLUGIN
#include "kg/motion/nodes.hpp"      // the kg.Motion port type (kg::motion::Motion)

namespace {

using kg::graph::NodeSpec;
using kg::graph::Params;
using kg::graph::ParamType;
using kg::motion::Motion;

NodeSpec lift_spec() {
  return {
      .type = "example.lift",
      .version = 1,
      .doc =
          "Raises a clip by `height` metres along world +Y: adds it to every root joint's "
          "Yposition channel. Fails on a clip whose roots have no Yposition channel.",
      .inputs = {{"motion", "kg.Motion", true, "the clip to raise"}},
      .outputs = {{"motion", "kg.Motion", true, "the raised clip: same skeleton, frames and rate"}},
      .params = {{.name = "height",
                  .type = ParamType::Float,
                  .default_value = 0.2,
                  .doc = "metres, world +Y (negative lowers)",
                  .min = -10.0,
                  .max = 10.0}},
  };
}

class LiftNode final : public kg::graph::Node {
 public:
  explicit LiftNode(const Params& p) : height_(p.get<double>("height")) {}

  void run(kg::graph::RunContext& ctx) const override {
    Motion out = ctx.input<Motion>("motion");  // a copy: inputs are shared and immutable
    std::int64_t roots = 0;
    for (const kg::motion::Joint& joint : out.skeleton->joints()) {
      if (joint.parent != -1) continue;
      bool lifted = false;
      for (std::size_t i = 0; i < joint.channels.size(); ++i) {
        if (joint.channels[i].kind == kg::motion::ChannelKind::Yposition) {
          out.values.col(joint.first_channel + static_cast<int>(i)).array() += height_;
          lifted = true;
        }
      }
      if (!lifted) throw std::invalid_argument("root joint '" + joint.name + "' has no Yposition channel");
      ++roots;
    }
    ctx.report("height", height_);  // figures for `kinegraph run --report`
    ctx.report("roots", roots);
    ctx.output("motion", std::move(out));
  }

 private:
  double height_;
};

kg::graph::PluginRecord make_record() {
  kg::graph::PluginRecord record{"example.lift", "1.0.0"};  // plugin id (unique) and version
  record.nodes.push_back({lift_spec(), [](const Params& p) { return std::make_unique<LiftNode>(p); }});
  return record;
}

}  // namespace

KG_PLUGIN(make_record)  // exports the ABI version (read first) and the entry point
