#include "kg/base/json.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "kg/base/text.hpp"

namespace kg {
namespace {

using Json = nlohmann::ordered_json;

// A string, integer, boolean or null as nlohmann writes it; bytes that are not UTF-8 as U+FFFD.
std::string scalar_text(const Json& j) {
  return j.dump(-1, ' ', false, Json::error_handler_t::replace);
}

std::string number_text(double x) {
  return std::isfinite(x) ? text::format_double(x) : "null";
}

void newline(std::string& out, int indent, int depth) {
  if (indent <= 0) return;
  out += '\n';
  out.append(static_cast<std::size_t>(indent) * static_cast<std::size_t>(depth), ' ');
}

// nlohmann's dump(indent) layout, with number_text for doubles.
void print(std::string& out, const Json& j, int indent, int depth) {
  if (j.is_number_float()) {
    out += number_text(j.get<double>());
    return;
  }
  if (!j.is_structured()) {
    out += scalar_text(j);
    return;
  }
  const bool object = j.is_object();
  if (j.empty()) {
    out += object ? "{}" : "[]";
    return;
  }
  out += object ? '{' : '[';
  bool first = true;
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (!first) out += ',';
    first = false;
    newline(out, indent, depth + 1);
    if (object) {
      out += scalar_text(Json(it.key()));
      out += indent > 0 ? ": " : ":";
    }
    print(out, it.value(), indent, depth + 1);
  }
  newline(out, indent, depth);
  out += object ? '}' : ']';
}

}  // namespace

struct Report::Document {
  Json root;
};

void Report::write(std::ostream& os, int indent) const {
  if (!doc_) return;
  std::string text;
  print(text, doc_->root, indent, 0);
  if (doc_->root.is_structured() && indent > 0) text += '\n';
  os << text;
}

std::vector<std::string> Report::strings(std::string_view key) const {
  std::vector<std::string> out;
  if (!doc_ || !doc_->root.is_object()) return out;
  const auto it = doc_->root.find(std::string(key));
  if (it == doc_->root.end() || !it->is_array()) return out;
  for (const Json& item : *it)
    if (item.is_string()) out.push_back(item.get<std::string>());
  return out;
}

std::string Report::text(int indent) const {
  std::ostringstream os;
  write(os, indent);
  return os.str();
}

struct JsonWriter::Document {
  Json root;
  std::vector<Json*> open;         // containers begun and not yet ended, outermost first
  std::optional<std::string> key;  // given by key(), taken by the next value

  // Places `value` in the innermost open container (or as the root); returns where it went.
  Json& add(Json value) {
    if (open.empty()) {
      root = std::move(value);
      return root;
    }
    Json& parent = *open.back();
    if (parent.is_array()) {
      parent.push_back(std::move(value));
      return parent.back();
    }
    if (!key) throw std::logic_error("JsonWriter: a value inside an object needs its key first");
    auto& members = parent.get_ref<Json::object_t&>();
    auto [it, fresh] = members.emplace(std::move(*key), std::move(value));
    key.reset();
    if (!fresh) throw std::logic_error("JsonWriter: key \"" + it->first + "\" written twice in one object");
    return it->second;
  }

  void begin(Json container) { open.push_back(&add(std::move(container))); }

  void end(bool object, std::ostream* os, Report* report, int indent) {
    if (open.empty() || open.back()->is_object() != object || key)
      throw std::logic_error(object ? "JsonWriter: end_object without its begin_object"
                                    : "JsonWriter: end_array without its begin_array");
    open.pop_back();
    if (open.empty()) finish(os, report, indent);
  }

  void scalar(Json value, std::ostream* os, Report* report, int indent) {
    add(std::move(value));
    if (open.empty()) finish(os, report, indent);
  }

  // The finished document: into the report, or its text to the stream (a container at the top
  // ends its line when pretty-printed).
  void finish(std::ostream* os, Report* report, int indent) {
    if (report) {
      auto doc = std::make_shared<Report::Document>();
      doc->root = std::move(root);
      report->doc_ = std::move(doc);
    } else {
      std::string text;
      print(text, root, indent, 0);
      if (root.is_structured() && indent > 0) text += '\n';
      *os << text;
    }
    root = nullptr;
  }
};

JsonWriter::JsonWriter(std::ostream& os, int indent)
    : os_(&os), indent_(indent), doc_(std::make_unique<Document>()) {}

JsonWriter::JsonWriter(Report& into) : report_(&into), doc_(std::make_unique<Document>()) {}

JsonWriter::~JsonWriter() = default;

void JsonWriter::begin_object() {
  doc_->begin(Json::object());
}

void JsonWriter::end_object() {
  doc_->end(true, os_, report_, indent_);
}

void JsonWriter::begin_array() {
  doc_->begin(Json::array());
}

void JsonWriter::end_array() {
  doc_->end(false, os_, report_, indent_);
}

void JsonWriter::key(std::string_view name) {
  if (doc_->open.empty() || !doc_->open.back()->is_object() || doc_->key)
    throw std::logic_error("JsonWriter: a key outside an object, or two keys in a row");
  doc_->key = std::string(name);
}

void JsonWriter::value(std::string_view text) {
  doc_->scalar(Json(std::string(text)), os_, report_, indent_);
}

void JsonWriter::value(double number) {
  doc_->scalar(Json(number), os_, report_, indent_);
}

void JsonWriter::value(std::int64_t number) {
  doc_->scalar(Json(number), os_, report_, indent_);
}

void JsonWriter::value(bool flag) {
  doc_->scalar(Json(flag), os_, report_, indent_);
}

void JsonWriter::value(const std::vector<double>& numbers) {
  doc_->scalar(Json(numbers), os_, report_, indent_);
}

void JsonWriter::null() {
  doc_->scalar(Json(nullptr), os_, report_, indent_);
}

std::string json_quote(std::string_view text) {
  return scalar_text(Json(std::string(text)));
}

}  // namespace kg
