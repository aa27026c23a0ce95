#include <algorithm>
#include "kg/base/json.hpp"

#include <cmath>

#include "kg/base/text.hpp"

namespace kg {

std::string json_quote(std::string_view text) {
  static const char* hex = "0123456789abcdef";
  std::string out;
  out.reserve(text.size() + 2);
  out += '"';
  for (char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\b':
        out += "\\b";
        break;
      case '\f':
        out += "\\f";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (c < 0x20 || c == 0x7f) {
          out += "\\u00";
          out += hex[c >> 4];
          out += hex[c & 0xf];
        } else {
          out += ch;  // UTF-8 passes through unchanged
        }
    }
  }
  out += '"';
  return out;
}

void JsonWriter::newline() {
  if (indent_ <= 0) return;
  os_ << '\n';
  for (std::size_t i = 0; i < first_.size() * static_cast<std::size_t>(indent_); ++i) os_ << ' ';
}

// Separators and indentation before a value, a key or a container's start.
void JsonWriter::before_value() {
  if (after_key_) {
    after_key_ = false;
    return;
  }
  if (first_.empty()) return;
  if (!first_.back()) os_ << ',';
  first_.back() = false;
  newline();
}

void JsonWriter::begin_object() {
  before_value();
  os_ << '{';
  first_.push_back(true);
}

void JsonWriter::end_object() {
  const bool empty = first_.empty() || first_.back();
  if (!first_.empty()) first_.pop_back();
  if (!empty) newline();
  os_ << '}';
  if (first_.empty() && indent_ > 0) os_ << '\n';
}

void JsonWriter::begin_array() {
  before_value();
  os_ << '[';
  first_.push_back(true);
}

void JsonWriter::end_array() {
  const bool empty = first_.empty() || first_.back();
  if (!first_.empty()) first_.pop_back();
  if (!empty) newline();
  os_ << ']';
  if (first_.empty() && indent_ > 0) os_ << '\n';
}

void JsonWriter::key(std::string_view name) {
  before_value();
  os_ << json_quote(name) << (indent_ > 0 ? ": " : ":");
  after_key_ = true;
}

void JsonWriter::value(std::string_view text) {
  before_value();
  os_ << json_quote(text);
}

void JsonWriter::value(double number) {
  before_value();
  if (!std::isfinite(number)) {
    os_ << "null";
    return;
  }
  char buf[64];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, number);
  os_.write(buf, end - buf);
  // A whole double keeps a fraction ("2.0"), so that a reader tells it from an integer.
  if (std::find_if(buf, end, [](char c) { return c == '.' || c == 'e'; }) == end) os_ << ".0";
}

void JsonWriter::value(std::int64_t number) {
  before_value();
  os_ << number;
}

void JsonWriter::value(bool flag) {
  before_value();
  os_ << (flag ? "true" : "false");
}

void JsonWriter::value(const std::vector<double>& numbers) {
  begin_array();
  for (double x : numbers) value(x);
  end_array();
}

void JsonWriter::null() {
  before_value();
  os_ << "null";
}

}  // namespace kg
