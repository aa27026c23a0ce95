// ASF and AMC parsers (see kg/io/asf_amc.hpp for the mapping onto skeleton.hpp).
#include "kg/io/asf_amc.hpp"
#include "kg/base/text.hpp"

#include "kg/base/atomic_file.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <sstream>
#include <unordered_map>

#include "kg/base/error.hpp"

namespace kg::io {

using motion::Channel;
using motion::ChannelKind;
using motion::Joint;
using motion::Skeleton;

const char* to_string(AsfDof dof) {
  static constexpr std::array<const char*, 6> kNames{"tx", "ty", "tz", "rx", "ry", "rz"};
  return kNames[static_cast<std::size_t>(dof)];
}

std::optional<double> AsfSkeleton::declared_metres_per_unit() const {
  if (!length_unit) return std::nullopt;
  return 0.0254 / *length_unit;
}

const AsfBone* AsfSkeleton::find_bone(std::string_view bone_name) const {
  for (const AsfBone& b : bones)
    if (b.name == bone_name) return &b;
  return nullptr;
}

namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i])))
      return false;
  return true;
}

struct Token {
  std::string_view text;
  int column = 0;  // 1-based
};

// "'text'" for messages; long tokens are cut.
std::string show(std::string_view text) {
  constexpr std::size_t kMax = 40;
  if (text.size() > kMax) return "'" + std::string(text.substr(0, kMax)) + "...'";
  return "'" + std::string(text) + "'";
}

// Lines of a text file split into whitespace-separated tokens. Blank lines and lines whose first
// non-blank character is '#' are skipped. Handles LF and CRLF; tabs are blanks.
class Lines {
 public:
  Lines(std::string_view text, const std::string& path) : text_(text), path_(path) {}

  // Moves to the next line with tokens; false at end of file.
  bool next() {
    if (at_end_) return false;
    while (pos_ < text_.size()) {
      std::size_t end = text_.find('\n', pos_);
      if (end == std::string_view::npos) end = text_.size();
      line_text_ = text_.substr(pos_, end - pos_);
      if (!line_text_.empty() && line_text_.back() == '\r') line_text_.remove_suffix(1);
      pos_ = end + 1;
      ++line_;
      tokenize();
      if (!tokens_.empty() && tokens_[0].text[0] != '#') return true;
    }
    at_end_ = true;
    tokens_.clear();
    line_text_ = {};
    ++line_;  // errors "at end of file" point just past the last line
    return false;
  }

  bool at_end() const { return at_end_; }
  int line() const { return line_; }
  const std::vector<Token>& tokens() const { return tokens_; }
  std::size_t size() const { return tokens_.size(); }
  const Token& operator[](std::size_t i) const { return tokens_[i]; }
  // True when the current line opens a section (":bonedata").
  bool is_section() const { return !at_end_ && tokens_[0].text[0] == ':'; }
  // The text of the current line from token i on, trailing blanks removed.
  std::string_view rest_from(std::size_t i) const {
    std::string_view r = line_text_.substr(static_cast<std::size_t>(tokens_[i].column - 1));
    while (!r.empty() && is_space(r.back())) r.remove_suffix(1);
    return r;
  }
  const std::string& path() const { return path_; }

  [[noreturn]] void fail(int line, int column, const std::string& message) const {
    throw kg::Error(message, {path_, line, column});
  }
  // "expected <what>, got <token i | end of line | end of file>".
  [[noreturn]] void expected(const std::string& what, std::size_t i) const {
    if (at_end_) fail(line_, 0, "expected " + what + ", got end of file");
    if (i >= tokens_.size()) {
      fail(line_, static_cast<int>(line_text_.size()) + 1, "expected " + what + ", got end of line");
    }
    fail(line_, tokens_[i].column, "expected " + what + ", got " + show(tokens_[i].text));
  }
  // Fails unless the current line has exactly n tokens.
  void expect_count(std::size_t n, const std::string& what) const {
    if (tokens_.size() < n) expected(what, tokens_.size());
    if (tokens_.size() > n) expected("end of line after " + what, n);
  }

 private:
  void tokenize() {
    tokens_.clear();
    std::size_t i = 0;
    const std::size_t n = line_text_.size();
    while (i < n) {
      while (i < n && is_space(line_text_[i])) ++i;
      if (i == n) break;
      std::size_t start = i;
      while (i < n && !is_space(line_text_[i])) ++i;
      tokens_.push_back({line_text_.substr(start, i - start), static_cast<int>(start) + 1});
    }
  }

  std::string_view text_;
  const std::string& path_;
  std::size_t pos_ = 0;
  int line_ = 0;
  bool at_end_ = false;
  std::string_view line_text_;
  std::vector<Token> tokens_;
};

// Parses the whole of `text` as a number; infinities only when allowed, never NaN.
bool parse_number(std::string_view text, double& out, bool allow_infinite = false) {
  const char* first = text.data();
  const char* last = first + text.size();
  auto [ptr, ec] = std::from_chars(first, last, out);
  if (ec != std::errc() || ptr != last) return false;
  if (std::isnan(out)) return false;
  return allow_infinite || std::isfinite(out);
}

// `what` and `axis` make the message, built only on failure (these run for every bone).
double number_at(const Lines& lines, std::size_t i, std::string_view what, const char* axis = "") {
  double v = 0;
  if (i >= lines.size() || !parse_number(lines[i].text, v)) lines.expected(std::string(what) + axis, i);
  return v;
}

Eigen::Vector3d vector_at(const Lines& lines, std::size_t first, std::string_view what) {
  return {number_at(lines, first, what, " x"), number_at(lines, first + 1, what, " y"),
          number_at(lines, first + 2, what, " z")};
}

// "XYZ" (any permutation, any case) -> axis indices in application order.
bool parse_axis_order(std::string_view text, std::array<int, 3>& order) {
  if (text.size() != 3) return false;
  bool seen[3] = {false, false, false};
  for (std::size_t i = 0; i < 3; ++i) {
    const char c = static_cast<char>(std::toupper(static_cast<unsigned char>(text[i])));
    if (c < 'X' || c > 'Z' || seen[c - 'X']) return false;
    seen[c - 'X'] = true;
    order[i] = c - 'X';
  }
  return true;
}

// Rotation by `angles` (radians about X, Y, Z) applied in `order`: the first applied is the
// rightmost factor.
Eigen::Matrix3d euler_matrix(const Eigen::Vector3d& angles, const std::array<int, 3>& order) {
  Eigen::Matrix3d m = Eigen::Matrix3d::Identity();
  for (int axis : order)
    m = Eigen::AngleAxisd(angles[axis], Eigen::Vector3d::Unit(axis)).toRotationMatrix() * m;
  return m;
}

std::optional<AsfDof> dof_from_string(std::string_view text) {
  static constexpr std::array<std::string_view, 6> kNames{"tx", "ty", "tz", "rx", "ry", "rz"};
  for (std::size_t i = 0; i < kNames.size(); ++i)
    if (iequals(text, kNames[i])) return static_cast<AsfDof>(i);
  return std::nullopt;
}

bool is_rotation(AsfDof d) {
  return d >= AsfDof::Rx;
}
int dof_axis(AsfDof d) {
  return static_cast<int>(d) % 3;
}

// A bone as read, before the hierarchy places it.
struct RawBone {
  std::string name;
  int line = 0;
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();
  double length = 0;
  Eigen::Vector3d axis_angles = Eigen::Vector3d::Zero();  // file angle unit
  std::array<int, 3> axis_order{0, 1, 2};
  std::vector<AsfDof> dofs;
  std::vector<std::pair<double, double>> limits;  // file units, one per dof, empty if none
  int parent = -2;                                // -1 root, >= 0 raw bone index; -2 unplaced
  std::vector<int> children;                      // raw bone indices, hierarchy order
};

struct HierarchyLine {
  int line = 0;
  std::vector<std::pair<std::string, int>> names;  // name, column
};

class AsfParser {
 public:
  AsfParser(std::string_view text, const std::string& path) : lines_(text, path) { result_.path = path; }

  AsfSkeleton parse() {
    lines_.next();
    while (!lines_.at_end()) {
      const Token& t = lines_[0];
      if (!lines_.is_section()) lines_.expected("a section keyword such as ':bonedata'", 0);
      const std::string keyword(t.text);
      static const std::vector<std::string> kSections{":version", ":name",     ":units",    ":documentation",
                                                      ":root",    ":bonedata", ":hierarchy"};
      if (std::find(kSections.begin(), kSections.end(), keyword) == kSections.end()) {
        std::string hint = kg::nearest_name(keyword, kSections);
        lines_.expected(
            "a section keyword (:version, :name, :units, :documentation, :root, :bonedata, :hierarchy)" +
                (hint.empty() ? std::string() : " (did you mean " + text::in_quotes(hint) + "?)"),
            0);
      }
      if (seen_sections_.count(keyword)) {
        lines_.fail(lines_.line(), t.column,
                    "expected each section once, got a second " + show(keyword) + " (first at line " +
                        std::to_string(seen_sections_[keyword]) + ")");
      }
      seen_sections_[keyword] = lines_.line();
      if (keyword == ":version") {
        lines_.expect_count(2, "a version after :version");
        result_.version = std::string(lines_[1].text);
        lines_.next();
      } else if (keyword == ":name") {
        if (lines_.size() < 2) lines_.expected("a name after :name", 1);
        result_.name = std::string(lines_.rest_from(1));
        lines_.next();
      } else if (keyword == ":units") {
        parse_units();
      } else if (keyword == ":documentation") {
        parse_documentation();
      } else if (keyword == ":root") {
        parse_root();
      } else if (keyword == ":bonedata") {
        parse_bonedata();
      } else {
        parse_hierarchy();
      }
    }
    if (!seen_sections_.count(":root")) lines_.expected("a ':root' section", 0);
    if (!seen_sections_.count(":bonedata")) lines_.expected("a ':bonedata' section", 0);
    if (!seen_sections_.count(":hierarchy")) lines_.expected("a ':hierarchy' section", 0);
    place_bones();
    build();
    return std::move(result_);
  }

 private:
  double angle_scale() const { return result_.degrees ? kDegree : 1.0; }

  // Section bodies run until the next line opening a section (or the end of the file).
  void parse_units() {
    lines_.expect_count(1, ":units alone on its line");
    std::map<std::string, int> seen;
    while (lines_.next() && !lines_.is_section()) {
      const std::string key(lines_[0].text);
      if (seen.count(key)) {
        lines_.fail(lines_.line(), lines_[0].column, "expected each unit once, got a second " + show(key));
      }
      seen[key] = lines_.line();
      if (key == "mass") {
        lines_.expect_count(2, "a mass unit");
        result_.mass_unit = positive_at(1, "a positive mass unit");
      } else if (key == "length") {
        lines_.expect_count(2, "a length unit");
        result_.length_unit = positive_at(1, "a positive length unit");
        // Beyond these, converting to metres overflows or underflows for any sane bone length.
        if (result_.length_unit < 1e-6 || result_.length_unit > 1e6)
          lines_.expected("a length unit in 1e-06..1e+06", 1);
      } else if (key == "angle") {
        lines_.expect_count(2, "an angle unit");
        if (iequals(lines_[1].text, "deg")) {
          result_.degrees = true;
        } else if (iequals(lines_[1].text, "rad")) {
          result_.degrees = false;
        } else {
          lines_.expected("angle unit 'deg' or 'rad'", 1);
        }
      } else {
        lines_.expected("'mass', 'length' or 'angle' in :units", 0);
      }
    }
  }

  double positive_at(std::size_t i, std::string_view what) {
    double v = number_at(lines_, i, what);
    if (!(v > 0)) lines_.expected(std::string(what), i);
    return v;
  }

  void parse_documentation() {
    std::string doc;
    if (lines_.size() > 1) doc = std::string(lines_.rest_from(1));
    while (lines_.next() && !lines_.is_section()) {
      if (!doc.empty()) doc += '\n';
      doc += std::string(lines_.rest_from(0));
    }
    result_.documentation = std::move(doc);
  }

  void parse_root() {
    lines_.expect_count(1, ":root alone on its line");
    root_line_ = lines_.line();
    std::map<std::string, int> seen;
    while (lines_.next() && !lines_.is_section()) {
      const std::string key(lines_[0].text);
      if (seen.count(key)) {
        lines_.fail(lines_.line(), lines_[0].column,
                    "expected each root field once, got a second " + show(key));
      }
      seen[key] = lines_.line();
      if (key == "order") {
        if (lines_.size() < 2) lines_.expected("root dofs (TX TY TZ RX RY RZ)", 1);
        for (std::size_t i = 1; i < lines_.size(); ++i) {
          auto d = dof_from_string(lines_[i].text);
          if (!d) lines_.expected("a root dof (TX, TY, TZ, RX, RY or RZ)", i);
          if (std::find(root_dofs_.begin(), root_dofs_.end(), *d) != root_dofs_.end())
            lines_.expected("each root dof once", i);
          root_dofs_.push_back(*d);
        }
      } else if (key == "axis") {
        lines_.expect_count(2, "an axis order such as XYZ");
        if (!parse_axis_order(lines_[1].text, root_axis_order_))
          lines_.expected("an axis order such as XYZ", 1);
      } else if (key == "position") {
        lines_.expect_count(4, "three position values");
        root_position_ = vector_at(lines_, 1, "root position");
      } else if (key == "orientation") {
        lines_.expect_count(4, "three orientation angles");
        root_orientation_ = vector_at(lines_, 1, "root orientation");
      } else {
        lines_.expected("'order', 'axis', 'position' or 'orientation' in :root", 0);
      }
    }
    for (const char* required : {"order", "axis", "position", "orientation"}) {
      if (!seen.count(required)) {
        lines_.fail(root_line_, 1, std::string("expected root field '") + required + "' in :root, got none");
      }
    }
  }

  void parse_bonedata() {
    lines_.expect_count(1, ":bonedata alone on its line");
    while (lines_.next() && !lines_.is_section()) {
      if (lines_[0].text != "begin") lines_.expected("'begin' of a bone", 0);
      lines_.expect_count(1, "'begin' alone on its line");
      parse_bone();
    }
  }

  // The fields of a bone; parse_bone keeps the line of each one seen in an array (no map per bone).
  static constexpr std::array<std::string_view, 9> kBoneFields{"id",  "name",   "direction", "length", "axis",
                                                               "dof", "limits", "bodymass",  "cofmass"};
  static constexpr std::size_t field_index(std::string_view key) {
    std::size_t i = 0;
    while (i < kBoneFields.size() && kBoneFields[i] != key) ++i;
    return i;  // kBoneFields.size() when not a field
  }

  void parse_bone() {
    RawBone bone;
    bone.line = lines_.line();
    const int begin_line = lines_.line();
    std::array<int, kBoneFields.size()> seen{};  // line of each field, 0 until seen
    const auto was_seen = [&](std::string_view field) { return seen[field_index(field)] != 0; };
    for (;;) {
      if (!lines_.next() || lines_.is_section()) {
        lines_.expected("'end' of the bone begun at line " + std::to_string(begin_line), 0);
      }
      const std::string key(lines_[0].text);
      if (key == "end") {
        lines_.expect_count(1, "'end' alone on its line");
        break;
      }
      if (key == "begin") lines_.expected("'end' of the bone begun at line " + std::to_string(begin_line), 0);
      const std::size_t field = field_index(key);
      if (field < seen.size() && seen[field] != 0) {
        lines_.fail(lines_.line(), lines_[0].column,
                    "expected each bone field once, got a second " + show(key) + " (first at line " +
                        std::to_string(seen[field]) + ")");
      }
      if (field < seen.size()) seen[field] = lines_.line();
      if (key == "id") {
        lines_.expect_count(2, "a bone id");
        double id = number_at(lines_, 1, "an integer bone id");
        if (id != std::floor(id)) lines_.expected("an integer bone id", 1);
      } else if (key == "name") {
        lines_.expect_count(2, "a bone name");
        bone.name = std::string(lines_[1].text);
        if (bone.name == "root") lines_.expected("a bone name other than 'root'", 1);
        if (const auto it = bone_index_.find(bone.name); it != bone_index_.end()) {
          lines_.fail(lines_.line(), lines_[1].column,
                      "expected a new bone name, got " + show(bone.name) + " again (first at line " +
                          std::to_string(bones_[static_cast<std::size_t>(it->second)].line) + ")");
        }
      } else if (key == "direction") {
        lines_.expect_count(4, "three direction components");
        bone.direction = vector_at(lines_, 1, "direction");
      } else if (key == "length") {
        lines_.expect_count(2, "a bone length");
        bone.length = number_at(lines_, 1, "a bone length");
        if (bone.length < 0) lines_.expected("a non-negative bone length", 1);
      } else if (key == "axis") {
        lines_.expect_count(5, "three axis angles and an order such as XYZ");
        bone.axis_angles = vector_at(lines_, 1, "axis");
        if (!parse_axis_order(lines_[4].text, bone.axis_order))
          lines_.expected("an axis order such as XYZ", 4);
      } else if (key == "dof") {
        if (lines_.size() < 2) lines_.expected("dofs (rx ry rz tx ty tz)", 1);
        for (std::size_t i = 1; i < lines_.size(); ++i) {
          if (iequals(lines_[i].text, "l")) {
            lines_.fail(lines_.line(), lines_[i].column,
                        "expected a dof out of rx ry rz tx ty tz, got 'l' (bone stretch is not supported)");
          }
          auto d = dof_from_string(lines_[i].text);
          if (!d) lines_.expected("a dof out of rx ry rz tx ty tz", i);
          if (std::find(bone.dofs.begin(), bone.dofs.end(), *d) != bone.dofs.end())
            lines_.expected("each dof once", i);
          bone.dofs.push_back(*d);
        }
      } else if (key == "limits") {
        if (!was_seen("dof")) lines_.expected("'dof' before 'limits'", 0);
        parse_limits(bone);
      } else if (key == "bodymass" || key == "cofmass") {
        lines_.expect_count(2, "a number after " + show(key));
        number_at(lines_, 1, "a number");
      } else {
        static const std::vector<std::string> kKeys{"id",  "name",   "direction", "length",  "axis",
                                                    "dof", "limits", "bodymass",  "cofmass", "end"};
        std::string hint = kg::nearest_name(key, kKeys);
        lines_.expected("a bone field (id, name, direction, length, axis, dof, limits, end)" +
                            (hint.empty() ? std::string() : " (did you mean " + text::in_quotes(hint) + "?)"),
                        0);
      }
    }
    for (const char* required : {"name", "direction", "length", "axis"}) {
      if (!was_seen(required)) {
        lines_.fail(lines_.line(), lines_[0].column,
                    std::string("expected field '") + required + "' in the bone begun at line " +
                        std::to_string(begin_line) + ", got 'end'");
      }
    }
    if (!(bone.direction * bone.length).allFinite()) {
      lines_.fail(seen[field_index("length")], 0,
                  "expected a bone whose direction times length (its offset) is finite, got direction (" +
                      kg::text::significant(bone.direction.x()) + ", " +
                      kg::text::significant(bone.direction.y()) + ", " +
                      kg::text::significant(bone.direction.z()) + ") and length " +
                      kg::text::significant(bone.length));
    }
    bone_index_[bone.name] = static_cast<int>(bones_.size());
    bones_.push_back(std::move(bone));
  }

  // `limits (min max)` once per dof; pairs may continue on the following lines.
  void parse_limits(RawBone& bone) {
    const std::size_t wanted = bone.dofs.size();
    // Tokens split further at parentheses: "(-160.0" -> "(", "-160.0".
    std::vector<Token> parts;
    std::size_t next_part = 0;
    auto refill = [&](std::size_t first_token) {
      parts.clear();
      next_part = 0;
      for (std::size_t i = first_token; i < lines_.size(); ++i) {
        std::string_view t = lines_[i].text;
        int col = lines_[i].column;
        while (!t.empty()) {
          std::size_t cut = t.find_first_of("()");
          if (cut == 0) cut = 1;
          if (cut == std::string_view::npos) cut = t.size();
          parts.push_back({t.substr(0, cut), col});
          col += static_cast<int>(cut);
          t.remove_prefix(cut);
        }
      }
    };
    refill(1);
    auto expect_part = [&](const auto& what) -> const Token& {
      while (next_part == parts.size()) {
        // Only whole pairs continue on the next line.
        if (!lines_.next() || lines_.is_section() || lines_[0].text[0] != '(') lines_.expected(what(), 0);
        refill(0);
      }
      return parts[next_part++];
    };
    auto fail_part = [&](const Token& t, const std::string& what) {
      lines_.fail(lines_.line(), t.column, "expected " + what + ", got " + show(t.text));
    };
    for (std::size_t k = 0; k < wanted; ++k) {
      // Messages built only on failure.
      const auto which = [&] { return "limits of dof " + std::string(to_string(bone.dofs[k])); };
      const auto open = [&] { return "'(' opening the " + which(); };
      const Token& a = expect_part(open);
      if (a.text != "(") fail_part(a, open());
      double lo = 0, hi = 0;
      if (next_part == parts.size()) lines_.expected("the minimum of the " + which(), lines_.size());
      const Token& b = parts[next_part++];
      if (!parse_number(b.text, lo, true)) fail_part(b, "the minimum of the " + which());
      if (next_part == parts.size()) lines_.expected("the maximum of the " + which(), lines_.size());
      const Token& c = parts[next_part++];
      if (!parse_number(c.text, hi, true)) fail_part(c, "the maximum of the " + which());
      if (next_part == parts.size()) lines_.expected("')' closing the " + which(), lines_.size());
      const Token& d = parts[next_part++];
      if (d.text != ")") fail_part(d, "')' closing the " + which());
      if (lo > hi) fail_part(b, "a minimum not above the maximum in the " + which());
      bone.limits.emplace_back(lo, hi);
    }
    if (next_part != parts.size()) {
      fail_part(parts[next_part], "end of line after " + std::to_string(wanted) + " limit pair" +
                                      (wanted == 1 ? "" : "s") + " (one per dof)");
    }
  }

  void parse_hierarchy() {
    lines_.expect_count(1, ":hierarchy alone on its line");
    if (!lines_.next() || lines_.is_section()) lines_.expected("'begin' of the hierarchy", 0);
    if (lines_[0].text != "begin") lines_.expected("'begin' of the hierarchy", 0);
    lines_.expect_count(1, "'begin' alone on its line");
    const int begin_line = lines_.line();
    for (;;) {
      if (!lines_.next() || lines_.is_section()) {
        lines_.expected("'end' of the hierarchy begun at line " + std::to_string(begin_line), 0);
      }
      if (lines_[0].text == "end") {
        lines_.expect_count(1, "'end' alone on its line");
        lines_.next();
        return;
      }
      if (lines_.size() < 2) lines_.expected("a parent followed by its children", 1);
      HierarchyLine h{lines_.line(), {}};
      for (const Token& t : lines_.tokens()) h.names.emplace_back(std::string(t.text), t.column);
      hierarchy_.push_back(std::move(h));
    }
  }

  [[noreturn]] void fail_unknown_bone(const std::string& name, int line, int column) {
    std::vector<std::string> names{"root"};
    for (const RawBone& b : bones_) names.push_back(b.name);
    std::string hint = kg::nearest_name(name, names);
    lines_.fail(line, column,
                "expected a bone of :bonedata, got " + show(name) +
                    (hint.empty() ? std::string() : " (did you mean " + text::in_quotes(hint) + "?)"));
  }

  int index_of(const std::string& name, int line, int column) {
    if (name == "root") return -1;
    auto it = bone_index_.find(name);
    if (it == bone_index_.end()) fail_unknown_bone(name, line, column);
    return it->second;
  }

  void place_bones() {
    for (const HierarchyLine& h : hierarchy_) {
      const int parent = index_of(h.names[0].first, h.line, h.names[0].second);
      for (std::size_t i = 1; i < h.names.size(); ++i) {
        const auto& [name, column] = h.names[i];
        const int child = index_of(name, h.line, column);
        if (child == -1) lines_.fail(h.line, column, "expected a child bone, got 'root'");
        if (child == parent)
          lines_.fail(h.line, column, "expected a child other than its parent, got " + show(name));
        RawBone& c = bones_[static_cast<std::size_t>(child)];
        if (c.parent != -2) {
          lines_.fail(h.line, column, "expected each bone to have one parent, got " + show(name) + " again");
        }
        c.parent = parent;
        if (parent == -1) {
          root_children_.push_back(child);
        } else {
          bones_[static_cast<std::size_t>(parent)].children.push_back(child);
        }
      }
    }
  }

  void build() {
    auto skeleton = std::make_shared<Skeleton>();
    skeleton->reserve(static_cast<int>(bones_.size()) + 1);
    result_.bones.reserve(bones_.size() + 1);
    const double a = angle_scale();

    // Root.
    Joint root;
    root.name = "root";
    root.offset = root_position_;
    root.axis = euler_matrix(root_orientation_ * a, root_axis_order_);
    AsfBone root_bone;
    root_bone.name = "root";
    root_bone.joint = 0;
    root_bone.line = root_line_;
    root_bone.dofs = root_dofs_;
    for (AsfDof d : root_dofs_)
      if (!is_rotation(d)) root.channels.push_back({static_cast<ChannelKind>(dof_axis(d))});
    for (auto it = root_dofs_.rbegin(); it != root_dofs_.rend(); ++it)
      if (is_rotation(*it)) root.channels.push_back({static_cast<ChannelKind>(3 + dof_axis(*it))});
    skeleton->add_joint(std::move(root));
    result_.bones.push_back(std::move(root_bone));

    // Bones depth first in hierarchy order, so that every parent precedes its children.
    std::vector<int> raw_to_joint(bones_.size(), -1);
    std::vector<std::pair<int, int>> stack;  // raw bone, parent joint
    for (auto it = root_children_.rbegin(); it != root_children_.rend(); ++it) stack.emplace_back(*it, 0);
    while (!stack.empty()) {
      auto [raw, parent_joint] = stack.back();
      stack.pop_back();
      const RawBone& b = bones_[static_cast<std::size_t>(raw)];
      raw_to_joint[static_cast<std::size_t>(raw)] = skeleton->joint_count();
      add_bone(*skeleton, b, parent_joint);
      const int self = skeleton->joint_count() - 1;
      for (auto c = b.children.rbegin(); c != b.children.rend(); ++c) stack.emplace_back(*c, self);
    }
    for (std::size_t i = 0; i < bones_.size(); ++i) {
      if (raw_to_joint[i] < 0) {
        lines_.fail(bones_[i].line, 0,
                    "expected bone " + show(bones_[i].name) +
                        " to hang from 'root' through :hierarchy, got " +
                        (bones_[i].parent == -2 ? std::string("no parent")
                                                : std::string("parents that never reach it (a cycle)")));
      }
    }

    // Frame-channel targets of every dof, now that first_channel is known.
    for (AsfBone& bone : result_.bones) {
      const Joint& j = skeleton->joint(bone.joint);
      bone.targets.clear();
      for (AsfDof d : bone.dofs) {
        if (!is_rotation(d) && bone.joint != 0) {
          bone.targets.push_back(dof_axis(d));
          continue;
        }
        const auto kind = static_cast<ChannelKind>(is_rotation(d) ? 3 + dof_axis(d) : dof_axis(d));
        int found = -1;
        for (std::size_t c = 0; c < j.channels.size(); ++c)
          if (j.channels[c].kind == kind) found = j.first_channel + static_cast<int>(c);
        bone.targets.push_back(found);
      }
    }
    result_.skeleton = std::move(skeleton);
  }

  void add_bone(Skeleton& skeleton, const RawBone& b, int parent_joint) {
    const double a = angle_scale();
    Joint j;
    j.name = b.name;
    j.parent = parent_joint;
    if (b.parent >= 0) {
      const RawBone& p = bones_[static_cast<std::size_t>(b.parent)];
      j.offset = p.direction * p.length;
    }
    j.axis = euler_matrix(b.axis_angles * a, b.axis_order);
    const bool translates =
        std::any_of(b.dofs.begin(), b.dofs.end(), [](AsfDof d) { return !is_rotation(d); });
    const bool axis_identity = j.axis.isIdentity(1e-12);
    if (translates) {
      // Position channels hold offset + C t: all three, since C may mix the components.
      for (int k = 0; k < 3; ++k) {
        Channel c{static_cast<ChannelKind>(k)};
        if (axis_identity) {
          c.min = c.max = j.offset[k];  // no dof along this axis: fixed at the offset
          for (std::size_t i = 0; i < b.dofs.size(); ++i) {
            if (b.dofs[i] == static_cast<AsfDof>(k)) {
              c.min = b.limits.empty() ? -std::numeric_limits<double>::infinity()
                                       : j.offset[k] + b.limits[i].first;
              c.max = b.limits.empty() ? std::numeric_limits<double>::infinity()
                                       : j.offset[k] + b.limits[i].second;
            }
          }
        }
        j.channels.push_back(c);
      }
      if (!axis_identity && !b.limits.empty()) {
        result_.notes.push_back(
            result_.path + ":" + std::to_string(b.line) + ": bone '" + b.name +
            "': translation limits along a rotated axis cannot be expressed as channel limits; "
            "left unlimited");
      }
    }
    for (std::size_t i = b.dofs.size(); i-- > 0;) {
      if (!is_rotation(b.dofs[i])) continue;
      Channel c{static_cast<ChannelKind>(3 + dof_axis(b.dofs[i]))};
      if (!b.limits.empty()) {
        c.min = b.limits[i].first * a;
        c.max = b.limits[i].second * a;
      }
      j.channels.push_back(c);
    }
    if (b.children.empty() && b.length > 0) j.end_sites.push_back(b.direction * b.length);
    const int joint = skeleton.add_joint(std::move(j));
    AsfBone bone;
    bone.name = b.name;
    bone.joint = joint;
    bone.line = b.line;
    bone.dofs = b.dofs;
    result_.bones.push_back(std::move(bone));
  }

  Lines lines_;
  AsfSkeleton result_;
  std::map<std::string, int> seen_sections_;
  int root_line_ = 0;
  std::vector<AsfDof> root_dofs_;
  std::array<int, 3> root_axis_order_{0, 1, 2};
  Eigen::Vector3d root_position_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d root_orientation_ = Eigen::Vector3d::Zero();
  std::vector<RawBone> bones_;
  std::unordered_map<std::string, int> bone_index_;
  std::vector<int> root_children_;
  std::vector<HierarchyLine> hierarchy_;
};

std::string read_text(const std::string& path, const char* what) {
  return kg::read_input_file(path, std::string(what) + " file");
}

bool is_integer(std::string_view t) {
  if (t.empty()) return false;
  return std::all_of(t.begin(), t.end(), [](char c) { return c >= '0' && c <= '9'; });
}

struct NameHash {
  using is_transparent = void;
  std::size_t operator()(std::string_view s) const { return std::hash<std::string_view>{}(s); }
};

}  // namespace

AsfSkeleton parse_asf(std::string_view text, const std::string& path) {
  return AsfParser(text, path).parse();
}

AsfSkeleton read_asf(const std::string& path) {
  return parse_asf(read_text(path, "ASF"), path);
}

motion::Motion parse_amc(std::string_view text, const std::string& path, const AsfSkeleton& asf) {
  if (!asf.skeleton) throw std::invalid_argument("parse_amc: the AsfSkeleton has no skeleton");
  const Skeleton& skeleton = *asf.skeleton;
  const std::size_t channels = static_cast<std::size_t>(skeleton.channel_count());
  Lines lines(text, path);

  // Header.
  bool degrees = asf.degrees;
  bool seen_angle_unit = false;
  while (lines.next() && lines.is_section()) {
    lines.expect_count(1, "a header keyword alone on its line");
    const std::string_view k = lines[0].text;
    if (k == ":FULLY-SPECIFIED") continue;
    if (k == ":DEGREES" || k == ":RADIANS") {
      if (seen_angle_unit) lines.expected("one of :DEGREES and :RADIANS", 0);
      seen_angle_unit = true;
      degrees = k == ":DEGREES";
      continue;
    }
    lines.expected("':FULLY-SPECIFIED', ':DEGREES' or ':RADIANS'", 0);
  }
  const double angle = degrees ? kDegree : 1.0;

  // Bones with dofs, looked up by name on every line.
  std::unordered_map<std::string, int, NameHash, std::equal_to<>> index;
  std::vector<int> moving;  // indices into asf.bones of bones with dofs
  index.reserve(asf.bones.size());
  for (std::size_t b = 0; b < asf.bones.size(); ++b) {
    index.emplace(asf.bones[b].name, static_cast<int>(b));
    if (!asf.bones[b].dofs.empty()) moving.push_back(static_cast<int>(b));
  }
  // Per bone: rest offset and axis for bones whose translation dofs move them by C t.
  std::vector<char> translates(asf.bones.size(), 0);
  for (std::size_t b = 1; b < asf.bones.size(); ++b)
    for (AsfDof d : asf.bones[b].dofs)
      if (!is_rotation(d)) translates[b] = 1;

  std::vector<double> values;
  values.reserve(channels * (text.size() / 800 + 1));
  std::vector<int> seen_in_frame(asf.bones.size(), -1);
  std::vector<int> frame_line(asf.bones.size(), 0);
  int frames = 0;
  long long expected_number = 0;

  if (lines.at_end()) lines.expected("a frame number", 0);
  while (!lines.at_end()) {
    // Frame number line.
    if (lines.size() != 1 || !is_integer(lines[0].text)) lines.expected("a frame number", 0);
    long long number = 0;
    {
      auto t = lines[0].text;
      auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), number);
      if (ec != std::errc() || ptr != t.data() + t.size()) lines.expected("a frame number", 0);
      // Bounded so that number + 1 cannot overflow and a frame count fits in int.
      if (number < 0 || number > std::numeric_limits<int>::max())
        lines.expected("a frame number 0.." + std::to_string(std::numeric_limits<int>::max()), 0);
    }
    if (frames > 0 && number != expected_number) {
      lines.expected("frame number " + std::to_string(expected_number), 0);
    }
    const int number_line = lines.line();
    expected_number = number + 1;
    values.resize(values.size() + channels, 0.0);
    double* row = values.data() + values.size() - channels;

    int lines_in_frame = 0;
    while (lines.next() && !(lines.size() == 1 && is_integer(lines[0].text))) {
      const Token& name = lines[0];
      auto it = index.find(name.text);
      if (it == index.end()) {
        std::vector<std::string> names;
        for (const AsfBone& b : asf.bones) names.push_back(b.name);
        std::string hint = kg::nearest_name(std::string(name.text), names);
        lines.expected("a bone of " + asf.path + " or a frame number" +
                           (hint.empty() ? std::string() : " (did you mean " + text::in_quotes(hint) + "?)"),
                       0);
      }
      const int b = it->second;
      const AsfBone& bone = asf.bones[static_cast<std::size_t>(b)];
      if (seen_in_frame[static_cast<std::size_t>(b)] == frames) {
        lines.fail(lines.line(), name.column,
                   "expected each bone once per frame, got " + show(name.text) + " again (first at line " +
                       std::to_string(frame_line[static_cast<std::size_t>(b)]) + ")");
      }
      seen_in_frame[static_cast<std::size_t>(b)] = frames;
      frame_line[static_cast<std::size_t>(b)] = lines.line();
      const std::size_t n = bone.dofs.size();
      if (lines.size() != n + 1) {
        std::string dofs;
        for (AsfDof d : bone.dofs) dofs += std::string(dofs.empty() ? "" : " ") + to_string(d);
        const std::string what = std::to_string(n) + " value" + (n == 1 ? "" : "s") + " for bone '" +
                                 bone.name + "'" + (n ? " (" + dofs + ")" : "");
        if (lines.size() < n + 1) lines.expected(what, lines.size());
        lines.expected("end of line after " + what, n + 1);
      }
      Eigen::Vector3d t = Eigen::Vector3d::Zero();
      for (std::size_t i = 0; i < n; ++i) {
        double v = 0;
        if (!parse_number(lines[i + 1].text, v)) {
          lines.expected("a number for " + bone.name + "." + to_string(bone.dofs[i]), i + 1);
        }
        const AsfDof d = bone.dofs[i];
        const int target = bone.targets[i];
        if (is_rotation(d)) {
          row[target] = v * angle;
        } else if (b == 0) {
          row[target] = v;  // the root's translation replaces its offset
        } else {
          t[target] = v;
        }
      }
      if (translates[static_cast<std::size_t>(b)]) {
        const Joint& j = skeleton.joint(bone.joint);
        const Eigen::Vector3d p = j.offset + j.axis * t;
        if (!p.allFinite())
          lines.fail(
              lines.line(), name.column,
              "expected translations of bone '" + bone.name + "' whose position is finite, got an overflow");
        for (int k = 0; k < 3; ++k) row[j.first_channel + k] = p[k];
      }
      ++lines_in_frame;
    }
    for (int b : moving) {
      if (seen_in_frame[static_cast<std::size_t>(b)] != frames) {
        const std::string got = lines.at_end() ? "end of file" : "frame number " + std::string(lines[0].text);
        lines.fail(lines.line(), lines.at_end() ? 0 : lines[0].column,
                   "expected a line for bone '" + asf.bones[static_cast<std::size_t>(b)].name +
                       "' in frame " + std::to_string(number) + " (begun at line " +
                       std::to_string(number_line) + "), got " + got);
      }
    }
    ++frames;
  }

  motion::Motion m;
  m.skeleton = asf.skeleton;
  m.values =
      Eigen::Map<const motion::FrameMatrix>(values.data(), frames, static_cast<Eigen::Index>(channels));
  m.fps = kAmcDefaultFps;
  m.name = std::filesystem::path(path).stem().string();
  return m;
}

motion::Motion read_amc(const std::string& path, const AsfSkeleton& asf) {
  return parse_amc(read_text(path, "AMC"), path, asf);
}

}  // namespace kg::io
