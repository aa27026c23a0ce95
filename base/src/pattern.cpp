// kg::Pattern over RE2 (see pattern.hpp for the limits and why).
#include "kg/base/pattern.hpp"

#include <stdexcept>

#include <re2/re2.h>

#include "kg/base/text.hpp"

namespace kg {

namespace {

constexpr std::size_t kExcerpt = 60;     // characters of the pattern a message quotes
constexpr std::size_t kArgExcerpt = 24;  // ... and of the part RE2 complains about

bool is_digit(char c) {
  return c >= '0' && c <= '9';
}

// A count of {n,m} RE2 does not read as one: a leading zero, or above kMaxRepeat (RE2 refuses
// 1001 to 99999999 itself, but takes longer counts and leading zeros as literal text).
bool unreadable_count(std::string_view digits) {
  if (digits.size() > 1 && digits.front() == '0') return true;
  if (digits.size() > 4) return true;
  int n = 0;
  for (char c : digits) n = n * 10 + (c - '0');
  return n > Pattern::kMaxRepeat;
}

// The first counted repetition ("{n}", "{n,}", "{n,m}" outside classes and escapes) with an
// unreadable count, or "" when there is none.
std::string_view unreadable_repeat(std::string_view p) {
  const std::size_t n = p.size();
  bool in_class = false, class_start = false;
  for (std::size_t i = 0; i < n; ++i) {
    const char c = p[i];
    if (c == '\\') {  // an escape: \Q...\E, \x{...}, \p{...}, \P{...} or one character
      class_start = false;
      if (i + 1 >= n) break;
      const char e = p[i + 1];
      if (e == 'Q') {
        const std::size_t end = p.find("\\E", i + 2);
        if (end == std::string_view::npos) break;
        i = end + 1;
      } else if ((e == 'x' || e == 'p' || e == 'P') && i + 2 < n && p[i + 2] == '{') {
        const std::size_t end = p.find('}', i + 3);
        if (end == std::string_view::npos) break;
        i = end;
      } else {
        ++i;
      }
      continue;
    }
    if (in_class) {  // [...]: a ']' first is a literal; [:alpha:] inside
      if (c == '[' && i + 1 < n && p[i + 1] == ':') {
        const std::size_t end = p.find(":]", i + 2);
        if (end != std::string_view::npos) i = end + 1;
      } else if (c == ']' && !class_start) {
        in_class = false;
      }
      class_start = false;
      continue;
    }
    if (c == '[') {
      in_class = class_start = true;
      if (i + 1 < n && p[i + 1] == '^') ++i;
      continue;
    }
    if (c != '{') continue;
    std::size_t j = i + 1;
    while (j < n && is_digit(p[j])) ++j;
    const std::string_view lo = p.substr(i + 1, j - i - 1);
    if (lo.empty()) continue;
    std::string_view hi;
    if (j < n && p[j] == ',') {
      const std::size_t from = ++j;
      while (j < n && is_digit(p[j])) ++j;
      hi = p.substr(from, j - from);
    }
    if (j < n && p[j] == '}' && (unreadable_count(lo) || (!hi.empty() && unreadable_count(hi))))
      return p.substr(i, j - i + 1);
  }
  return {};
}

// What RE2's error code means, in the words of a message.
std::string reason(const re2::RE2& re) {
  const std::string& arg = re.error_arg();
  switch (re.error_code()) {
    case re2::RE2::ErrorBadEscape:
      if (arg.size() == 2 && is_digit(arg[1])) return "backreference " + arg + " (RE2 has none)";
      return "bad escape " + text::excerpt(arg, kArgExcerpt);
    case re2::RE2::ErrorBadCharClass:
      return "bad character class " + text::excerpt(arg, kArgExcerpt);
    case re2::RE2::ErrorBadCharRange:
      return "bad range in a character class " + text::excerpt(arg, kArgExcerpt);
    case re2::RE2::ErrorMissingBracket:
      return "missing ] of the class " + text::excerpt(arg, kArgExcerpt);
    case re2::RE2::ErrorMissingParen:
      return "missing ) of the group " + text::excerpt(arg, kArgExcerpt);
    case re2::RE2::ErrorUnexpectedParen:
      return "unexpected ) in " + text::excerpt(arg, kArgExcerpt);
    case re2::RE2::ErrorTrailingBackslash:
      return "a \\ at the end";
    case re2::RE2::ErrorRepeatArgument:
      return "nothing to repeat before " + text::excerpt(arg, kArgExcerpt);
    case re2::RE2::ErrorRepeatSize:
      return "repetition " + text::excerpt(arg, kArgExcerpt) + ": expected counts up to " +
             std::to_string(Pattern::kMaxRepeat) + ", nested counts multiplied";
    case re2::RE2::ErrorRepeatOp:
      return "bad repetition operator " + text::excerpt(arg, kArgExcerpt);
    case re2::RE2::ErrorBadPerlOp:
      return "unsupported group " + text::excerpt(arg, kArgExcerpt) + " (RE2 has no lookahead or lookbehind)";
    case re2::RE2::ErrorBadUTF8:
      return "invalid UTF-8";
    case re2::RE2::ErrorBadNamedCapture:
      return "bad named group " + text::excerpt(arg, kArgExcerpt);
    case re2::RE2::ErrorPatternTooLarge:
      return "too large once compiled (more than " + std::to_string(Pattern::kMaxMemory >> 20) + " MiB)";
    default:
      return re.error().size() > kExcerpt ? text::excerpt(re.error(), kExcerpt) : re.error();
  }
}

[[noreturn]] void refuse(std::string_view pattern, const std::string& why) {
  throw std::invalid_argument("bad regular expression " + text::excerpt(pattern, kExcerpt) + ": " + why);
}

}  // namespace

Pattern Pattern::compile(std::string_view text) {
  if (text.size() > kMaxLength)
    refuse(text, "longer than the " + std::to_string(kMaxLength) + " bytes allowed");
  if (const std::string_view repeat = unreadable_repeat(text); !repeat.empty())
    refuse(text, "repetition " + text::excerpt(repeat, kArgExcerpt) + ": expected counts up to " +
                     std::to_string(kMaxRepeat) + " without leading zeros");
  re2::RE2::Options options;
  options.set_encoding(re2::RE2::Options::EncodingLatin1);
  options.set_log_errors(false);
  options.set_max_mem(kMaxMemory);
  options.set_never_capture(true);  // only whether it matches is asked
  auto re = std::make_shared<const re2::RE2>(re2::StringPiece(text.data(), text.size()), options);
  if (!re->ok()) refuse(text, reason(*re) + " (RE2 syntax: https://github.com/google/re2/wiki/Syntax)");
  return Pattern(std::move(re));
}

const std::string& Pattern::text() const {
  return re_->pattern();
}

bool Pattern::full_match(std::string_view s) const {
  return re2::RE2::FullMatch(re2::StringPiece(s.data(), s.size()), *re_);
}

bool Pattern::partial_match(std::string_view s) const {
  return re2::RE2::PartialMatch(re2::StringPiece(s.data(), s.size()), *re_);
}

}  // namespace kg
