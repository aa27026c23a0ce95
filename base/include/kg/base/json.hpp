// A JSON writer for reports, manifests and exported figures, over nlohmann-json: the calls build
// an nlohmann::ordered_json (keys in the order written), and the text goes to the stream when the
// outermost object or array ends (a lone top-level value: at once).
//
//   JsonWriter w(os);
//   w.begin_object(); w.key("ok"); w.value(true); w.field("n", 3); w.end_object();
//
// The text: nlohmann's layout (indent 0: one line, no blanks; otherwise one member or element a
// line, indented by that many spaces per level, "key": value, empty containers as {} and [], and
// a newline after the outermost container), strings escaped by nlohmann (UTF-8 passes through;
// bytes that are not UTF-8 become U+FFFD), integers as themselves, and doubles in the shortest
// text that reads back to the same double (kg::text::format_double: "2.0" for a whole one,
// std::to_chars otherwise), non-finite ones as null. nlohmann's own number text is not used: its
// Grisu2 is not always the shortest, so a report's numbers would change in their last digit.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "kg/base/report.hpp"

namespace kg {

class JsonWriter {
 public:
  // indent 0: one line; otherwise pretty-printed with that many spaces. `os` is not owned and must
  // outlive the writer.
  explicit JsonWriter(std::ostream& os, int indent = 2);
  // Builds the document into `into` (not owned, must outlive the writer) instead of writing
  // text: it is set when the outermost container ends (a lone top-level value: at once).
  explicit JsonWriter(Report& into);
  ~JsonWriter();
  JsonWriter(const JsonWriter&) = delete;
  JsonWriter& operator=(const JsonWriter&) = delete;

  // Inside an object every value (a container too) follows its key(); a key written twice in one
  // object, a value without its key or an end_* that does not match throws std::logic_error.
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
    std::visit([this](const auto& x) { this->value(x); }, v);
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
  struct Document;              // the ordered_json being built and the containers still open
  std::ostream* os_ = nullptr;  // one of os_ and report_
  Report* report_ = nullptr;
  int indent_ = 2;
  std::unique_ptr<Document> doc_;
};

// `text` as a JSON string literal, quotes included (nlohmann's escaping, as JsonWriter writes it).
std::string json_quote(std::string_view text);

}  // namespace kg
