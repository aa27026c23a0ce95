#include "kg/graph/params.hpp"

#include <stdexcept>

#include "kg/base/json.hpp"
#include "kg/base/text.hpp"

namespace kg::graph {

const char* to_string(ParamType type) {
  switch (type) {
    case ParamType::Bool:
      return "bool";
    case ParamType::Int:
      return "int";
    case ParamType::Float:
      return "float";
    case ParamType::String:
      return "string";
    case ParamType::Enum:
      return "enum";
    case ParamType::InputPath:
      return "input_path";
    case ParamType::OutputPath:
      return "output_path";
    case ParamType::FloatList:
      return "float_list";
  }
  return "?";
}

std::string to_string(const ParamValue& value) {
  struct Visitor {
    std::string operator()(bool b) const { return b ? "true" : "false"; }
    std::string operator()(std::int64_t i) const { return std::to_string(i); }
    std::string operator()(double d) const { return text::format_double(d); }
    std::string operator()(const std::string& s) const { return json_quote(s); }
    std::string operator()(const std::vector<double>& list) const {
      std::string s = "[";
      for (std::size_t i = 0; i < list.size(); ++i) {
        if (i) s += ", ";
        s += text::format_double(list[i]);
      }
      return s + "]";
    }
  };
  return std::visit(Visitor{}, value);
}

void Params::throw_missing(const std::string& name) {
  throw std::out_of_range("param '" + name + "' is not set");
}

}  // namespace kg::graph
