// The BVH reader: one pass over the text in memory, numbers by std::from_chars, no stream per
// token. The hierarchy is a small recursive-descent parser; the MOTION section, which is nearly
// all of a file, is a tight loop writing straight into the frames matrix.
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <new>
#include <numbers>
#include <stdexcept>

#include "kg/base/error.hpp"
#include "kg/base/text.hpp"
#include "kg/io/bvh.hpp"
#include "kg/motion/frame_time.hpp"

#include "kg/base/atomic_file.hpp"

namespace kg::io {
namespace {

using kg::Error;
using kg::SourceLocation;
using motion::ChannelKind;

// Deeper nesting than any figure has; the limit keeps a hostile file from exhausting the stack.
constexpr int kMaxDepth = 1000;

bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}
bool is_space(char c) {
  return is_blank(c) || c == '\n';
}

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    char x = a[i], y = b[i];
    if (x >= 'A' && x <= 'Z') x = static_cast<char>(x - 'A' + 'a');
    if (y >= 'A' && y <= 'Z') y = static_cast<char>(y - 'A' + 'a');
    if (x != y) return false;
  }
  return true;
}

// A token as a message shows it: quoted, control characters escaped, long ones cut.
std::string shown(std::string_view token) {
  std::string s = "'";
  const std::size_t n = std::min<std::size_t>(token.size(), 40);
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned char c = static_cast<unsigned char>(token[i]);
    if (c < 0x20 || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      s += buf;
    } else {
      s += static_cast<char>(c);
    }
  }
  if (token.size() > n) s += "...";
  return s + "'";
}

std::optional<ChannelKind> channel_from_name(std::string_view name) {
  static constexpr std::pair<const char*, ChannelKind> kNames[] = {
      {"Xposition", ChannelKind::Xposition}, {"Yposition", ChannelKind::Yposition},
      {"Zposition", ChannelKind::Zposition}, {"Xrotation", ChannelKind::Xrotation},
      {"Yrotation", ChannelKind::Yrotation}, {"Zrotation", ChannelKind::Zrotation},
  };
  for (const auto& [text, kind] : kNames)
    if (iequals(name, text)) return kind;
  return std::nullopt;
}

// The value of a number from_chars found out of range: +-HUGE_VAL on overflow, 0 or a
// denormal on underflow (a legitimate tiny value), as strtod says.
double out_of_range_value(const char* begin, const char* end) {
  const std::string copy(begin, end);
  return std::strtod(copy.c_str(), nullptr);
}

// Clinger's fast path for the plain decimals BVH files are made of ("-12.3456"): with at most
// 2^53 as the digits' integer m and at most 22 decimals k, m and 10^k are exact doubles and one
// division rounds correctly, so the result is bit-identical to from_chars, at a third of its
// cost. Returns the end of the number, or nullptr to leave the text to from_chars (exponents,
// long mantissas, anything odd).
const char* parse_plain_decimal(const char* p, const char* end, double& out) {
  static constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                      1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  const bool negative = p < end && *p == '-';
  if (negative) ++p;
  std::uint64_t m = 0;
  int digits = 0, decimals = 0;
  for (; p < end && static_cast<unsigned>(*p - '0') < 10; ++p, ++digits)
    m = m * 10 + static_cast<unsigned>(*p - '0');
  if (p < end && *p == '.')
    for (++p; p < end && static_cast<unsigned>(*p - '0') < 10; ++p, ++digits, ++decimals)
      m = m * 10 + static_cast<unsigned>(*p - '0');
  if (digits == 0 || digits > 19 || decimals > 22 || m > (std::uint64_t{1} << 53)) return nullptr;
  if (p < end && !is_space(*p)) return nullptr;
  const double v = static_cast<double>(m) / kPow10[decimals];
  out = negative ? -v : v;
  return p;
}

// A word of the text and where it starts.
struct Token {
  std::string_view text;  // empty at the end of the text
  int line = 0;
  int column = 0;
};

class Parser {
 public:
  Parser(std::string_view text, const std::string& file)
      : p_(text.data()), end_(text.data() + text.size()), line_start_(p_), file_(file) {
    if (end_ - p_ >= 3 && std::memcmp(p_, "\xEF\xBB\xBF", 3) == 0) p_ += 3, line_start_ = p_;
  }

  BvhClip parse();

 private:
  // --- lexing ---
  void skip_space() {
    while (p_ < end_ && is_space(*p_)) {
      if (*p_ == '\n') ++line_, line_start_ = p_ + 1;
      ++p_;
    }
  }
  void skip_blanks() {
    while (p_ < end_ && is_blank(*p_)) ++p_;
  }
  bool at_line_end() {
    skip_blanks();
    return p_ == end_ || *p_ == '\n';
  }
  int column(const char* at) const { return static_cast<int>(at - line_start_) + 1; }
  Token here() const { return {{}, line_, column(p_)}; }

  Token next() {
    skip_space();
    Token t = here();
    const char* start = p_;
    while (p_ < end_ && !is_space(*p_)) ++p_;
    t.text = std::string_view(start, static_cast<std::size_t>(p_ - start));
    return t;
  }
  // The next word on the current line; empty text when the line ends first.
  Token next_on_line() {
    skip_blanks();
    if (p_ == end_ || *p_ == '\n') return here();
    return next();
  }

  [[noreturn]] void fail(const Token& at, const std::string& expected, const std::string& got) const {
    throw Error("expected " + expected + ", got " + got, SourceLocation{file_, at.line, at.column});
  }
  [[noreturn]] void fail(const Token& at, const std::string& expected) const {
    fail(at, expected, at.text.empty() ? (p_ == end_ ? "end of file" : "end of line") : shown(at.text));
  }

  Token expect_keyword(const char* keyword, const std::string& what) {
    Token t = next();
    if (!iequals(t.text, keyword)) fail(t, what);
    return t;
  }

  // `what()` builds the description of the number for a message, only when one is needed.
  template <class What>
  double number_token(const Token& t, const What& what) {
    double v = 0;
    if (!parse_number(t.text, v)) fail(t, what());
    if (!std::isfinite(v)) fail(t, "a finite number for " + what());
    return v;
  }

  // Whole token as a double; a leading '+' allowed.
  static bool parse_number(std::string_view s, double& v) {
    const char* b = s.data();
    const char* e = b + s.size();
    if (b < e && *b == '+') {
      ++b;
      if (b < e && (*b == '+' || *b == '-')) return false;
    }
    if (b == e) return false;
    if (*b != '+' && parse_plain_decimal(b, e, v) == e) return true;  // as from_chars would
    auto [ptr, ec] = std::from_chars(b, e, v);
    if (ptr != e) return false;
    if (ec == std::errc::result_out_of_range)
      v = out_of_range_value(b, e);
    else if (ec != std::errc())
      return false;
    return true;
  }

  // --- grammar ---
  void parse_joint(int parent, const Token& keyword, int depth);
  // `owner` + `name` ("joint " + "Hips") names the OFFSET's owner in messages.
  Eigen::Vector3d parse_offset(const char* owner, std::string_view name);
  void parse_motion(BvhClip& clip);

  const char* p_;
  const char* end_;
  const char* line_start_;
  int line_ = 1;
  const std::string& file_;
  motion::Skeleton skeleton_;
};

Eigen::Vector3d Parser::parse_offset(const char* owner_prefix, std::string_view name) {
  const auto owner = [&] { return owner_prefix + std::string(name); };
  const Token keyword = next();
  if (!iequals(keyword.text, "OFFSET")) fail(keyword, "OFFSET of " + owner());
  Eigen::Vector3d o;
  for (int i = 0; i < 3; ++i) {
    Token t = next_on_line();
    o[i] =
        number_token(t, [&] { return std::string("OFFSET ") + "xyz"[i] + " of " + owner() + " (a number)"; });
  }
  Token extra = next_on_line();
  if (!extra.text.empty()) fail(extra, "end of line after the 3 OFFSET values of " + owner());
  return o;
}

void Parser::parse_joint(int parent, const Token& keyword, int depth) {
  if (depth > kMaxDepth) fail(keyword, "at most " + std::to_string(kMaxDepth) + " nested joints");
  // The name is the rest of the line (names with blanks exist); a '{' may end it. It is read
  // straight into the joint: the messages below name it from there.
  motion::Joint joint;
  std::string& name = joint.name;
  bool brace = false;
  const Token name_start = next_on_line();
  for (Token t = name_start; !t.text.empty(); t = next_on_line()) {
    if (t.text == "{") {
      brace = true;
      Token after = next_on_line();
      if (!after.text.empty()) fail(after, "end of line after '{'");
      break;
    }
    if (!name.empty()) name += ' ';
    name += t.text;
  }
  if (name.empty()) fail(name_start, "a joint name after " + std::string(keyword.text));
  if (!brace) {
    Token t = next();
    if (t.text != "{") fail(t, "'{' opening joint " + name);
  }

  joint.parent = parent;
  joint.offset = parse_offset("joint ", name);

  // CHANNELS n name... (all on one line); absent means none.
  const char* save_p = p_;
  const char* save_line_start = line_start_;
  const int save_line = line_;
  Token t = next();
  if (iequals(t.text, "CHANNELS")) {
    Token count_token = next_on_line();
    int n = -1;
    {
      const char* b = count_token.text.data();
      const char* e = b + count_token.text.size();
      auto [ptr, ec] = std::from_chars(b, e, n);
      if (count_token.text.empty() || ec != std::errc() || ptr != e || n < 0 || n > 6)
        fail(count_token, "a channel count 0..6 after CHANNELS of joint " + name);
    }
    joint.channels.reserve(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      Token c = next_on_line();
      const auto which = [&] {
        return "channel name " + std::to_string(i + 1) + " of " + std::to_string(n) + " of joint " + name +
               " (Xposition, Yposition, Zposition, Xrotation, "
               "Yrotation or Zrotation)";
      };
      if (c.text.empty()) fail(c, which());
      std::optional<ChannelKind> kind = channel_from_name(c.text);
      if (!kind) fail(c, which());
      for (const motion::Channel& seen : joint.channels)
        if (seen.kind == *kind) fail(c, which() + " not given twice");
      joint.channels.push_back(motion::Channel{*kind});
    }
    Token extra = next_on_line();
    if (!extra.text.empty())
      fail(extra, "end of line after the " + std::to_string(n) + " channel names of CHANNELS " +
                      std::to_string(n) + " of joint " + name);
  } else {
    p_ = save_p, line_start_ = save_line_start, line_ = save_line;  // not a CHANNELS line: unread
  }

  if (skeleton_.find_joint(name) >= 0) fail(name_start, "a joint name not used before", shown(name));
  int index = 0;
  // From here on the name is the added joint's (`name` refers to the moved-from one).
  try {
    index = skeleton_.add_joint(std::move(joint));
  } catch (const std::invalid_argument& e) {  // the reader checks all add_joint does; kept for safety
    throw Error(e.what(), SourceLocation{file_, name_start.line, name_start.column});
  }

  for (;;) {
    Token k = next();
    if (iequals(k.text, "JOINT")) {
      parse_joint(index, k, depth + 1);
    } else if (iequals(k.text, "End")) {
      Token site = next_on_line();
      if (!iequals(site.text, "Site"))
        fail(site, "'Site' after 'End' in joint " + skeleton_.joint(index).name);
      // Some exporters name the End Site; the name is not kept.
      bool site_brace = false;
      for (Token w = next_on_line(); !w.text.empty(); w = next_on_line()) {
        if (w.text == "{") {
          site_brace = true;
          break;
        }
      }
      if (!site_brace) {
        Token b = next();
        if (b.text != "{") fail(b, "'{' opening the End Site of joint " + skeleton_.joint(index).name);
      }
      Eigen::Vector3d tip = parse_offset("the End Site of joint ", skeleton_.joint(index).name);
      Token close = next();
      if (close.text != "}") fail(close, "'}' closing the End Site of joint " + skeleton_.joint(index).name);
      skeleton_.joint_mut(index).end_sites.push_back(tip);
    } else if (k.text == "}") {
      return;
    } else {
      fail(k, "JOINT, End Site or '}' closing joint " + skeleton_.joint(index).name);
    }
  }
}

void Parser::parse_motion(BvhClip& clip) {
  const Token frames_kw = next();
  if (!iequals(frames_kw.text, "Frames:")) fail(frames_kw, "'Frames:' after MOTION");
  const Token frames_token = next_on_line();
  long long frames = -1;
  {
    const char* b = frames_token.text.data();
    const char* e = b + frames_token.text.size();
    auto [ptr, ec] = std::from_chars(b, e, frames);
    if (frames_token.text.empty() || ec != std::errc() || ptr != e || frames < 0 || frames > (1LL << 31) - 1)
      fail(frames_token, "a frame count (an integer >= 0) after 'Frames:'");
  }
  expect_keyword("Frame", "'Frame Time:' after the frame count");
  const Token time_kw = next_on_line();
  if (!iequals(time_kw.text, "Time:")) fail(time_kw, "'Time:' after 'Frame'");
  const Token time_token = next_on_line();
  clip.frame_time =
      number_token(time_token, [] { return std::string("a frame time in seconds after 'Frame Time:'"); });
  if (!(clip.frame_time >= kBvhMinFrameTime && clip.frame_time <= kBvhMaxFrameTime))
    fail(time_token, "a frame time of 1e-06..3600 seconds (1e6 to 1/3600 frames per second)",
         shown(time_token.text));
  clip.motion.fps = motion::rate_of_printed_frame_time(time_token.text, clip.frame_time);
  Token extra = next_on_line();
  if (!extra.text.empty()) fail(extra, "end of line after the frame time");

  const int channels = skeleton_.channel_count();
  if (channels == 0 && frames > 0)
    fail(frames_kw, "a hierarchy with channels for " + std::to_string(frames) + " frames", "none");

  // Each frame line holds at least one character and one separator per value, so a file too
  // short for its Frames: is caught without allocating for the count it claims.
  const long long remaining = static_cast<long long>(end_ - p_);
  const long long fit = channels > 0 ? (remaining + 1) / (2LL * channels) : 0;
  const long long rows = std::min(frames, fit);
  motion::FrameMatrix values(rows, channels);
  std::vector<double> scratch(static_cast<std::size_t>(channels));

  // Rotations become radians on the way in.
  std::vector<double> scale(static_cast<std::size_t>(channels), 1.0);
  for (const motion::Joint& j : skeleton_.joints())
    for (std::size_t c = 0; c < j.channels.size(); ++c)
      if (motion::is_rotation(j.channels[c].kind)) scale[j.first_channel + c] = std::numbers::pi / 180.0;

  const std::string frames_note =
      " (Frames: " + std::to_string(frames) + " on line " + std::to_string(frames_token.line) + ")";
  for (long long f = 0; f < frames; ++f) {
    skip_space();  // blank lines between frames are harmless
    if (p_ == end_)
      fail(here(), "frame line " + std::to_string(f + 1) + " of " + std::to_string(frames) + frames_note,
           "end of file");
    // Past `rows` the text cannot hold a whole line any more: parse into scratch to report the
    // precise error.
    double* row = f < rows ? values.data() + f * channels : scratch.data();
    for (int c = 0; c < channels; ++c) {
      while (p_ < end_ && is_blank(*p_)) ++p_;
      if (p_ == end_ || *p_ == '\n')
        fail(here(), std::to_string(channels) + " values on frame " + std::to_string(f + 1),
             (p_ == end_ ? "end of file" : "end of line") + std::string(" after ") + std::to_string(c));
      const char* start = p_;
      const char* b = start;
      bool bad_sign = false;
      if (*b == '+') {
        ++b;
        bad_sign = b < end_ && (*b == '+' || *b == '-');
      }
      double v = 0;
      if (!bad_sign) {
        if (const char* fast_end = parse_plain_decimal(b, end_, v)) {
          row[c] = v * scale[static_cast<std::size_t>(c)];
          p_ = fast_end;
          continue;
        }
      }
      auto [ptr, ec] = std::from_chars(b, end_, v);
      const bool delimited = ptr == end_ || is_space(*ptr);
      if ((ec != std::errc() && ec != std::errc::result_out_of_range) || !delimited || ptr == b || bad_sign) {
        const char* tok_end = start;
        while (tok_end < end_ && !is_space(*tok_end)) ++tok_end;
        fail(Token{{}, line_, column(start)},
             "a number (value " + std::to_string(c + 1) + " of " + std::to_string(channels) + " of frame " +
                 std::to_string(f + 1) + ", channel " + skeleton_.channel_name(c) + ")",
             shown(std::string_view(start, static_cast<std::size_t>(tok_end - start))));
      }
      if (ec == std::errc::result_out_of_range) v = out_of_range_value(b, ptr);
      if (!std::isfinite(v))
        fail(Token{{}, line_, column(start)},
             "a finite number (value " + std::to_string(c + 1) + " of frame " + std::to_string(f + 1) + ")",
             shown(std::string_view(start, static_cast<std::size_t>(ptr - start))));
      row[c] = v * scale[static_cast<std::size_t>(c)];
      p_ = ptr;
    }
    while (p_ < end_ && is_blank(*p_)) ++p_;
    if (p_ < end_ && *p_ != '\n') {
      const char* tok_end = p_;
      while (tok_end < end_ && !is_space(*tok_end)) ++tok_end;
      fail(here(),
           "end of line after the " + std::to_string(channels) + " values of frame " + std::to_string(f + 1),
           shown(std::string_view(p_, static_cast<std::size_t>(tok_end - p_))));
    }
  }
  if (rows < frames) throw std::logic_error("BVH reader: frame bound violated");  // cannot happen
  skip_space();
  if (p_ != end_) {
    Token t = next();
    fail(t, "end of file after the " + std::to_string(frames) + " frames" + frames_note);
  }
  clip.motion.values = std::move(values);
}

BvhClip Parser::parse() {
  expect_keyword("HIERARCHY", "HIERARCHY at the start of a BVH file");
  // Every joint opens a '{', so the braces bound the joints (End Sites open one too): the
  // skeleton is sized once instead of regrown joint by joint. A joint takes at least
  // kMinJointText characters ("JOINT a { OFFSET 0 0 0 }"), which caps what a file of braces
  // can reserve. Only a hint: a failure to reserve is not an error.
  constexpr long long kMinJointText = 24;
  const long long braces = std::count(p_, end_, '{');
  try {
    skeleton_.reserve(static_cast<int>(
        std::min<long long>({braces, (end_ - p_) / kMinJointText + 1, std::numeric_limits<int>::max()})));
  } catch (const std::bad_alloc&) {
  }
  Token t = next();
  if (!iequals(t.text, "ROOT")) fail(t, "ROOT after HIERARCHY");
  for (;;) {
    parse_joint(-1, t, 0);
    t = next();
    if (iequals(t.text, "ROOT")) continue;
    if (iequals(t.text, "MOTION")) break;
    fail(t, "ROOT or MOTION after the hierarchy");
  }
  BvhClip clip;
  parse_motion(clip);
  clip.motion.name = std::filesystem::path(file_).stem().string();
  clip.motion.skeleton = std::make_shared<const motion::Skeleton>(std::move(skeleton_));
  return clip;
}

}  // namespace

BvhClip parse_bvh(std::string_view text, const std::string& file_name) {
  return Parser(text, file_name).parse();
}

BvhClip read_bvh(const std::filesystem::path& path) {
  const kg::InputText input = kg::map_input_file(path, "BVH file");
  return parse_bvh(input.text(), path.string());
}

ImportedMotion import_bvh(const std::filesystem::path& path, const ImportOptions& options) {
  BvhClip clip = read_bvh(path);
  ImportedMotion out;
  out.file_frame_time = clip.frame_time;
  const double file_fps = clip.motion.fps;
  out.notes = apply_import_options(clip.motion, options, file_fps, path.string());
  if (options.fps == 0 && file_fps != 1.0 / clip.frame_time)
    out.notes.insert(out.notes.begin(),
                     path.string() + ": fps " + text::significant(file_fps, 12) + ": Frame Time " +
                         text::significant(clip.frame_time, 12) + " s is 1/" +
                         text::significant(file_fps, 12) + " s to its printed digits (1/Frame Time = " +
                         text::significant(1.0 / clip.frame_time, 9) + "); set fps to override");
  out.motion = std::move(clip.motion);
  return out;
}

}  // namespace kg::io
