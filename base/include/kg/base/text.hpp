// Number <-> text in one place, so params, messages, reports and graph
// files print and parse numbers alike (shortest text that reads back to the same double); the
// few significant digits of a message; lists joined for messages; text of any length or bytes
// quoted as a short excerpt; and the file extension files are told apart by.
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

// `text` quoted for a message whatever its length and bytes (a user's pattern, the start of a
// file that is not what it should be): in single quotes like in_quotes, printable ASCII and
// valid UTF-8 characters as they are, every other byte (controls, DEL, C1 controls, bytes of no
// valid UTF-8 character) as \xNN; cut after `max_chars` characters (a UTF-8 character counts
// 1, an escape 4, so the quoted part is at most max_chars columns), the cut marked by
// "... (N bytes)" after the quotes with the whole length:
//   excerpt("lfemur")                    'lfemur'
//   excerpt("a\tb\xff")                  'a\x09b\xff'
//   excerpt(std::string(6144, '('), 8)   '(((((((('... (6144 bytes)
inline std::string excerpt(std::string_view text, std::size_t max_chars = 60) {
  static constexpr char kHex[] = "0123456789abcdef";
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(text[i]); };
  const auto continuation = [&](std::size_t i, unsigned char lo, unsigned char hi) {
    return i < text.size() && byte(i) >= lo && byte(i) <= hi;
  };
  std::string out = "'";
  std::size_t columns = 0, i = 0;
  while (i < text.size()) {
    const unsigned char b = byte(i);
    // Length of the valid, printable UTF-8 character at i (0: escape the byte).
    std::size_t length = 0;
    if (b >= 0x20 && b < 0x7F)
      length = 1;
    else if (b >= 0xC2 && b <= 0xDF && continuation(i + 1, b == 0xC2 ? 0xA0 : 0x80, 0xBF))
      length = 2;  // U+0080..U+009F (C1 controls) escaped
    else if (b >= 0xE0 && b <= 0xEF &&
             continuation(i + 1, b == 0xE0 ? 0xA0 : 0x80, b == 0xED ? 0x9F : 0xBF) &&
             continuation(i + 2, 0x80, 0xBF))
      length = 3;
    else if (b >= 0xF0 && b <= 0xF4 &&
             continuation(i + 1, b == 0xF0 ? 0x90 : 0x80, b == 0xF4 ? 0x8F : 0xBF) &&
             continuation(i + 2, 0x80, 0xBF) && continuation(i + 3, 0x80, 0xBF))
      length = 4;
    const std::size_t width = length > 0 ? 1 : 4;
    if (columns + width > max_chars) break;
    columns += width;
    if (length > 0) {
      out.append(text.substr(i, length));
      i += length;
    } else {
      out += {'\\', 'x', kHex[b >> 4], kHex[b & 0xF]};
      ++i;
    }
  }
  out += "'";
  if (i < text.size()) out += "... (" + std::to_string(text.size()) + " bytes)";
  return out;
}

// 'name': a name or a value quoted in a message; what a file gave may be anything, so it is
// escaped and cut as excerpt does, at 200 characters (a long path stays whole, a 6 KB key does not).
inline std::string in_quotes(std::string_view text) {
  return excerpt(text, 200);
}

// A file's path for a message, where it leads (file:line: ...) or names the file: as it is when
// it is at most 200 bytes of what excerpt keeps unescaped, else quoted and cut as in_quotes does
// (a path is whatever a graph or a command line gave).
inline std::string shown_path(std::string_view path) {
  if (path.size() <= 200) {
    std::string quoted = excerpt(path, 200);
    if (quoted.size() == path.size() + 2) return std::string(path);  // nothing escaped, nothing cut
    return quoted;
  }
  return in_quotes(path);
}

// `path.key`, where a key of a file is, for a message ("segments.thigh", "limits.l.*"): a key
// may be anything, so one that is not a short run of printable ASCII is quoted and cut as
// excerpt does ("bones.'xxxx...'... (4000 bytes)").
inline std::string key_path(std::string_view path, std::string_view key) {
  const bool plain = !key.empty() && key.size() <= 60 &&
                     std::all_of(key.begin(), key.end(), [](char c) { return c > ' ' && c < 0x7f; });
  std::string out(path);
  if (!out.empty()) out += '.';
  out += plain ? std::string(key) : excerpt(key);
  return out;
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
