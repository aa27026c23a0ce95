// A small streaming JSON writer (no DOM): reports, manifests and exported figures.
//
//   JsonWriter w(os);
//   w.begin_object(); w.key("ok"); w.value(true); w.field("n", 3); w.end_object();
#pragma once

#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace kg {

class JsonWriter {
 public:
  // indent 0: one line; otherwise pretty-printed with that many spaces.
  explicit JsonWriter(std::ostream& os, int indent = 2) : os_(os), indent_(indent) {}

  void begin_object();
  void end_object();
  void begin_array();
  void end_array();
  void key(std::string_view name);
  void value(std::string_view text);
  void value(const char* text) { value(std::string_view(text)); }
  void value(const std::string& text) { value(std::string_view(text)); }
  void value(double number);  // shortest exact form, "2.0" for a whole one; non-finite as null
  void value(std::int64_t number);
  void value(int number) { value(static_cast<std::int64_t>(number)); }
  void value(std::size_t number) { value(static_cast<std::int64_t>(number)); }
  void value(bool flag);
  void value(const std::vector<double>& numbers);  // an array of numbers
  // The alternative a variant holds (a ParamValue, a Figure), written as itself.
  template <class... Ts>
  void value(const std::variant<Ts...>& v) {
    std::visit([this](const auto& x) { value(x); }, v);
  }
  // null when empty.
  template <class T>
  void value(const std::optional<T>& v) {
    if (v) {
      value(*v);
    } else {
      null();
    }
  }
  void null();

  // key(name), then value(v).
  template <class T>
  void field(std::string_view name, const T& v) {
    key(name);
    value(v);
  }

 private:
  void before_value();
  void newline();
  std::ostream& os_;
  int indent_;
  std::vector<bool> first_;  // per open container: no element written yet
  bool after_key_ = false;
};

// `text` as a JSON string literal, quotes included.
std::string json_quote(std::string_view text);

}  // namespace kg
