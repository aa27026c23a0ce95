// Node parameters: the typed values given under `params:` in a graph file, checked against a
// node's ParamSpec before anything runs, defaults filled in.
//
//   double cutoff = params.get<double>("cutoff_hz");
//   const std::string& path = params.get<std::string>("path");
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <variant>
#include <vector>

namespace kg::graph {

// Int params hold std::int64_t, Float double, FloatList std::vector<double>;
// String, Path, InputPath, OutputPath and Enum hold std::string.
using ParamValue = std::variant<bool, std::int64_t, double, std::string, std::vector<double>>;

enum class ParamType {
  Bool,
  Int,
  Float,
  String,
  Enum,        // a string out of ParamSpec::choices
  InputPath,   // a file the node reads; validation refuses a graph writing over one
  OutputPath,  // a file the node writes (atomically); "" means "do not write" where the node says so
  FloatList,   // YAML sequence of numbers, or one number
};

// "bool", "int", "float", "string", "enum", "input_path", "output_path", "float_list".
const char* to_string(ParamType type);

// A value's YAML-like text: true, 3, 0.5, "text", [1, 2, 3].
std::string to_string(const ParamValue& value);

class Params {
 public:
  Params() = default;
  explicit Params(std::map<std::string, ParamValue> values) : values_(std::move(values)) {}

  bool has(const std::string& name) const { return values_.count(name) != 0; }

  // Throws std::out_of_range naming the param when missing, std::bad_variant_access when of
  // another type (validation makes both impossible for params a spec declares).
  template <class T>
  const T& get(const std::string& name) const {
    auto it = values_.find(name);
    if (it == values_.end()) throw_missing(name);
    return std::get<T>(it->second);
  }

  const std::map<std::string, ParamValue>& all() const { return values_; }
  void set(const std::string& name, ParamValue value) { values_[name] = std::move(value); }

 private:
  [[noreturn]] static void throw_missing(const std::string& name);
  std::map<std::string, ParamValue> values_;
};

}  // namespace kg::graph
