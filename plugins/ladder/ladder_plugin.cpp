// The ladder plugin: constraint kinds ladder.rung and ladder.rail (ladder_kinds.hpp) as
// `kg.ConstraintKind` extensions. Built as lib/kinegraph/plugins/kg_ladder.so, loaded at run time
// (graph file: `plugins: [kg_ladder]`); constraint files then name the kinds like built-in ones.
#include <memory>

#include "kg/graph/plugin_abi.hpp"
#include "kg/retarget/nodes.hpp"  // KG_DECLARE_INTERFACE of kg::retarget::ConstraintKind
#include "ladder_kinds.hpp"

namespace {

using kg::retarget::ConstraintKind;

void add_kind(kg::graph::PluginRecord& record, std::shared_ptr<const ConstraintKind> kind) {
  record.add_extension<ConstraintKind>(kind->name(), kind, kind->doc());
}

kg::graph::PluginRecord make_record() {
  kg::graph::PluginRecord r{"kg.ladder", "1.0.0"};
  add_kind(r, kg::ladder::make_rung_kind());
  add_kind(r, kg::ladder::make_rail_kind());
  return r;
}

}  // namespace

KG_PLUGIN(make_record)
