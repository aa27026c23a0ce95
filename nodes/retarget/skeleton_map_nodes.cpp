// retarget.propose_map and retarget.write_map: thin adapters over propose_map and
// write_skeleton_map (skeleton_map.hpp); `kinegraph map` runs the two.
#include <memory>
#include <stdexcept>
#include <string>

#include "kg/base/json.hpp"
#include "kg/base/report.hpp"
#include "kg/base/text.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/graph/sink.hpp"
#include "kg/retarget/nodes.hpp"
#include "kg/retarget/skeleton_map.hpp"

namespace kg::retarget {
namespace {

using graph::ParamType;

class ProposeMapNode final : public graph::Node {
 public:
  explicit ProposeMapNode(const graph::Params& p)
      : source_file_(p.get<std::string>("source_file")), target_file_(p.get<std::string>("target_file")) {}

  void run(graph::RunContext& ctx) const override {
    const auto& source = ctx.input<motion::Motion>("source");
    const auto& target = ctx.input<motion::Motion>("target");
    ProposedMap p = propose_map(*source.skeleton, *target.skeleton, source_file_, target_file_);
    for (const std::string& n : p.notes) ctx.log(n);
    ctx.report("matched", static_cast<std::int64_t>(p.matched.size()));
    ctx.report("unmatched", static_cast<std::int64_t>(p.unmatched.size()));
    const std::size_t pairs = feature_pairs(p.map).size();
    ctx.report("pairs", static_cast<std::int64_t>(pairs));
    Report report;
    {
      JsonWriter w(report);
      w.begin_object();
      auto list = [&](const char* key, const std::vector<std::string>& lines) {
        w.key(key);
        w.begin_array();
        for (const std::string& l : lines) w.value(l);
        w.end_array();
      };
      std::vector<std::string> summary;
      for (const std::string& m : p.matched) summary.push_back("matched " + m);
      for (const std::string& m : p.unmatched) summary.push_back("not matched: " + m);
      summary.push_back(std::to_string(pairs) + " feature pairs from " + std::to_string(p.matched.size()) +
                        " chains");
      if (pairs == 0) {
        summary.push_back(
            "warning: no chain is on both skeletons, so the map pairs nothing; name the chains or write "
            "pairs "
            "of your own in the map file");
      }
      list("summary", summary);
      list("matched", p.matched);
      list("unmatched", p.unmatched);
      list("notes", p.notes);
      w.end_object();
    }
    ctx.output("report", std::move(report));
    ctx.output("map", SkeletonMapValue{std::move(p.map), source.skeleton, target.skeleton});
  }

 private:
  std::string source_file_, target_file_;
};

class WriteMapNode final : public graph::Node {
 public:
  explicit WriteMapNode(const graph::Params& p) : path_(p.get<std::string>("path")) {
    const std::string ext = text::lower_extension(path_);
    if (!path_.empty() && ext != ".yaml" && ext != ".yml")
      throw std::invalid_argument(
          path_ + ": a skeleton map is written as YAML; expected a .yaml or .yml path, got '" + ext + "'");
  }
  void run(graph::RunContext& ctx) const override {
    const auto& m = ctx.input<SkeletonMapValue>("map");
    graph::write_sink_file(ctx, path_,
                           [&](std::ostream& os) { write_skeleton_map(os, m.map, *m.source, *m.target); });
  }

 private:
  std::string path_;
};

graph::NodeType propose_map_type() {
  graph::NodeSpec spec{
      .type = "retarget.propose_map",
      .version = 1,
      .doc =
          "Proposes a skeleton map (Gleicher 1998 §8) between the source's skeleton and a target of any "
          "structure: each skeleton's chains (pelvis, spine, neck, legs, arms) found from its tree (the legs "
          "and arms as the two longest mirrored pairs of limbs), its names (knee, elbow, ... with the side "
          "marker removed) and its rest pose (left and right when the names do not say), then paired by "
          "chain. Logs every decision with its evidence; reports what matched and what did not.",
      .inputs = {{"source", "kg.Motion", true, "a clip on the source skeleton (its skeleton is used)"},
                 {"target", "kg.Motion", true, "a clip, a skeleton's rest pose or a URDF robot's tree"}},
      .outputs = {{"map", "kg.SkeletonMap", true, "the proposed map"},
                  {"report", "kg.Report", true, "summary, matched, unmatched and notes (lists of lines)"}},
      .params = {{.name = "source_file",
                  .type = ParamType::String,
                  .default_value = std::string{},
                  .doc = "the source's file, recorded in the map (informative)"},
                 {.name = "target_file",
                  .type = ParamType::String,
                  .default_value = std::string{},
                  .doc = "the target's file, recorded in the map (informative)"}}};
  return {std::move(spec), [](const graph::Params& p) { return std::make_unique<ProposeMapNode>(p); }};
}

graph::NodeType write_map_type() {
  graph::NodeSpec spec{
      .type = "retarget.write_map",
      .version = 1,
      .doc =
          "Writes a skeleton map as the YAML file read_skeleton_map reads (kg/retarget/skeleton_map.hpp), "
          "atomically, for the user to edit.",
      .inputs = {{"map", "kg.SkeletonMap", true, "the map"}},
      .params = {graph::sink_path_param("the .yaml file; \"\" writes none (logged)")},
      .side_effects = true};
  return {std::move(spec), [](const graph::Params& p) { return std::make_unique<WriteMapNode>(p); }};
}

}  // namespace
}  // namespace kg::retarget

namespace kg {
std::vector<graph::NodeType> retarget_map_node_types() {
  return {retarget::propose_map_type(), retarget::write_map_type()};
}
}  // namespace kg
