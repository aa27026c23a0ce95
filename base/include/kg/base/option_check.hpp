// Options::validate() in one voice (DESIGN.md 15, Ceres' Options::IsValid): every Options struct
// checks its own fields and throws std::invalid_argument naming the struct, the field, the value
// and the range it accepts:
//
//   void SpacetimeOptions::validate() const {
//     options::require(epsilon > 0 && std::isfinite(epsilon), "SpacetimeOptions", "epsilon", epsilon,
//                      "> 0 and finite");
//   }
//   // throws "SpacetimeOptions.epsilon = -1.0: expected > 0 and finite"
//
// Node constructors call validate() at graph load (a bad setting then fails with the graph file's
// line and the node's id), and the library functions taking the options call it on entry.
#pragma once

#include <cmath>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "kg/base/text.hpp"

namespace kg::options {

// The value as the message shows it: shortest round-trip text for a double, quoted for a string
// (text::excerpt: a long or binary one as a short escaped excerpt), a list of strings in brackets.
template <class T>
std::string value_text(const T& value) {
  if constexpr (std::is_same_v<T, std::vector<std::string>>) {
    std::string s = "[";
    for (const std::string& v : value) s += (s.size() > 1 ? ", '" : "'") + v + "'";
    return s + "]";
  } else if constexpr (std::is_same_v<T, bool>) {
    return value ? "true" : "false";
  } else if constexpr (std::is_floating_point_v<T>) {
    return text::format_double(static_cast<double>(value));
  } else if constexpr (std::is_integral_v<T>) {
    return std::to_string(value);
  } else {
    return text::excerpt(std::string_view(value));
  }
}

// Throws std::invalid_argument "Owner.field = value: expected range".
template <class T>
[[noreturn]] void refuse(std::string_view owner, std::string_view field, const T& value,
                         std::string_view range) {
  throw std::invalid_argument(std::string(owner) + "." + std::string(field) + " = " + value_text(value) +
                              ": expected " + std::string(range));
}

// refuse(...) unless `ok`.
template <class T>
void require(bool ok, std::string_view owner, std::string_view field, const T& value,
             std::string_view range) {
  if (!ok) refuse(owner, field, value, range);
}

// The common ranges of a double (NaN and infinities fail every one of them).
inline bool positive(double v) {
  return v > 0 && std::isfinite(v);
}  // "> 0 and finite"
inline bool non_negative(double v) {
  return v >= 0 && std::isfinite(v);
}  // ">= 0 and finite"

}  // namespace kg::options
