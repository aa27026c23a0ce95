// Number <-> text in one place, so params, messages, reports and graph
// files print and parse numbers alike (shortest text that reads back to the same double); the
// few significant digits of a message; lists joined for messages; and the file extension files
// are told apart by.
#pragma once

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace kg::text {

// Shortest round-trip text; integral values keep a ".0" so they read back as floats.
inline std::string format_double(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[64];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, x);
  std::string s(buf, end);
  if (s.find_first_of(".en") == std::string::npos) s += ".0";
  return s;
}

// `x` to `digits` significant digits (printf's %.*g, what an ostream prints at that precision):
// for messages and logs, where 0.1234 reads better than 0.12340000000000001; never for data.
inline std::string significant(double x, int digits = 6) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, x);
  return buf;
}

// At most about `max_bytes` of `text` as a message shows what a file holds: control bytes, DEL
// and bytes that are not UTF-8 as \xNN (so a UTF-16 file or a binary one prints as escapes, never
// as raw bytes); cut at a character boundary, with "... (N bytes)" telling the whole size.
inline std::string excerpt(std::string_view text, std::size_t max_bytes = 60) {
  auto utf8_length = [&](std::size_t i) -> std::size_t {  // 0: not a UTF-8 sequence at i
    const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
    const unsigned char c = byte(i);
    const std::size_t n = c >= 0xC2 && c <= 0xDF   ? 2
                          : c >= 0xE0 && c <= 0xEF ? 3
                          : c >= 0xF0 && c <= 0xF4 ? 4
                                                   : 0;
    if (n == 0 || i + n > text.size()) return 0;
    for (std::size_t k = 1; k < n; ++k)
      if ((byte(i + k) & 0xC0) != 0x80) return 0;
    return n;
  };
  std::string out;
  std::size_t i = 0;
  while (i < text.size() && out.size() < max_bytes) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    const std::size_t n = c >= 0x80 ? utf8_length(i) : 1;
    if (c < 0x20 || c == 0x7f || n == 0) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
      ++i;
    } else {
      out.append(text.substr(i, n));
      i += n;
    }
  }
  if (i < text.size()) out += "... (" + std::to_string(text.size()) + " bytes)";
  return out;
}

// 'name': a name or a value quoted in a message; what a file gave may be anything, so it is
// escaped and cut as excerpt does (at 200 bytes: a long path stays whole, a 6 KB key does not).
inline std::string in_quotes(std::string_view text) {
  return "'" + excerpt(text, 200) + "'";
}

// `items` with `separator` between them ("a, b, c"; "" for none).
inline std::string join(const std::vector<std::string>& items, std::string_view separator = ", ") {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i) out += separator;
    out += items[i];
  }
  return out;
}

inline std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\n' || s.front() == '\r'))
    s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\n' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

// The whole of `text` (surrounding blanks allowed, a leading '+' too) as an integer.
inline std::optional<std::int64_t> parse_int(std::string_view text) {
  text = trim(text);
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  if (text.empty()) return std::nullopt;
  std::int64_t v = 0;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return v;
}

// The whole of `text` as a number; also YAML's .inf/-.inf. NaN is refused.
inline std::optional<double> parse_double(std::string_view text) {
  text = trim(text);
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  if (text == ".inf" || text == ".Inf" || text == ".INF") return HUGE_VAL;
  if (text == "-.inf" || text == "-.Inf" || text == "-.INF") return -HUGE_VAL;
  if (text.empty()) return std::nullopt;
  double v = 0;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || std::isnan(v)) return std::nullopt;
  return v;
}

// `s` with ASCII letters lower-cased (other bytes as they are).
inline std::string ascii_lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// The extension of the file `path` names, with its dot, lower-cased ("walk.BVH" -> ".bvh"; ""
// for "walk" or "dir/.hidden"), so that dispatch on file types ignores case.
inline std::string lower_extension(const std::filesystem::path& path) {
  return ascii_lower(path.extension().string());
}

}  // namespace kg::text
