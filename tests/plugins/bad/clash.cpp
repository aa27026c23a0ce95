// Registers clash.unique and test.constant; the latter clashes with kg_test_nodes (or whatever
// registered it first), so neither may be added.
#include <memory>

#include "kg/graph/plugin_abi.hpp"

namespace {

class Nothing final : public kg::graph::Node {
 public:
  void run(kg::graph::RunContext&) const override {}
};

kg::graph::NodeType nothing(const char* name) {
  return {{name, 1, "Does nothing.", {}, {}, {}},
          [](const kg::graph::Params&) { return std::make_unique<Nothing>(); }};
}

kg::graph::PluginRecord make_record() {
  kg::graph::PluginRecord r{"kg.test_clash", "1.0.0"};
  r.nodes.push_back(nothing("clash.unique"));
  r.nodes.push_back(nothing("test.constant"));
  return r;
}

}  // namespace

KG_PLUGIN(make_record)
