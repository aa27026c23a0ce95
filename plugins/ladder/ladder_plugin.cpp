// The ladder plugin: constraint kinds ladder.rung and ladder.rail (ladder_kinds.hpp) as
// `kg.ConstraintKind` extensions. Built as lib/kinegraph/plugins/kg_ladder.so, loaded at run time
// (graph file: `plugins: [kg_ladder]`); constraint files then name the kinds like built-in ones.
#include <memory>

#include "kg/graph/plugin_abi.hpp"
#include "ladder_kinds.hpp"

namespace {

kg::graph::Extension as_extension(std::shared_ptr<const kg::retarget::ConstraintKind> kind) {
  kg::graph::Extension e;
  e.interface = kg::retarget::kConstraintKindInterface;
  e.name = kind->name();
  e.doc = kind->doc();
  // Converted from shared_ptr<const ConstraintKind> so the host's static_pointer_cast back is exact.
  e.factory = std::shared_ptr<const void>(std::move(kind));
  return e;
}

kg::graph::PluginRecord make_record() {
  kg::graph::PluginRecord r{"kg.ladder", "1.0.0"};
  r.extensions.push_back(as_extension(kg::ladder::make_rung_kind()));
  r.extensions.push_back(as_extension(kg::ladder::make_rail_kind()));
  return r;
}

}  // namespace

KG_PLUGIN(make_record)
