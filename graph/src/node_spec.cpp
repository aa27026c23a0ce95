#include "kg/graph/node_spec.hpp"

namespace kg::graph {

namespace {

template <class Spec>
const Spec* find_named(const std::vector<Spec>& list, const std::string& name) {
  for (const Spec& s : list)
    if (s.name == name) return &s;
  return nullptr;
}

}  // namespace

const PortSpec* NodeSpec::find_input(const std::string& name) const {
  return find_named(inputs, name);
}
const PortSpec* NodeSpec::find_output(const std::string& name) const {
  return find_named(outputs, name);
}
bool NodeSpec::has_side_effects() const {
  if (side_effects) return true;
  for (const ParamSpec& p : params)
    if (p.type == ParamType::OutputPath) return true;
  return false;
}

const ParamSpec* NodeSpec::find_param(const std::string& name) const {
  return find_named(params, name);
}

}  // namespace kg::graph
