// Constraint kinds as registry extensions (kg/retarget/nodes.hpp): the built-in kinds registered
// like plugin kinds, and the lookups of a run or a registry.
#include "kg/retarget/nodes.hpp"

namespace kg::retarget {

ConstraintKindTable kinds_for(const ConstraintSet& set, const graph::RunContext& ctx) {
  return kinds_for(set, [&ctx](const std::string& name) { return ctx.find<ConstraintKind>(name); });
}

ConstraintKindTable kinds_for(const ConstraintSet& set, const graph::Registry& registry) {
  return kinds_for(set, [&registry](const std::string& name) { return registry.find<ConstraintKind>(name); });
}

std::vector<graph::Extension> builtin_constraint_kind_extensions() {
  std::vector<graph::Extension> out;
  const ConstraintKindTable table = ConstraintKindTable::builtin();
  for (const std::string& name : table.names()) {
    std::shared_ptr<const ConstraintKind> k = table.find_shared(name);
    std::string kind_name = k->name(), doc = k->doc();
    out.push_back(graph::Extension::make<ConstraintKind>(std::move(kind_name), std::move(k), std::move(doc)));
  }
  return out;
}

}  // namespace kg::retarget
