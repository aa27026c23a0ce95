// A real plugin, built as an ordinary shared library that kg_bad_borrowed.so links against.
#include "kg/graph/plugin_abi.hpp"

namespace {
kg::graph::PluginRecord make_record() {
  return {"kg.test_borrowed_base", "1.0.0"};
}
}  // namespace

KG_PLUGIN(make_record)

extern "C" __attribute__((visibility("default"))) int kg_bad_base_marker() {
  return 1;
}
