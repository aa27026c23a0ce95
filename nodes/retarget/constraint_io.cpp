// Constraint files (constraint_io.hpp): YAML -> ConstraintSet with joint names resolved, every
// error at file:line:column.
#include "kg/retarget/constraint_io.hpp"

#include "kg/base/atomic_file.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "kg/base/error.hpp"
#include "kg/base/text.hpp"
#include "kg/base/yaml_reader.hpp"
#include "kg/motion/frame_time.hpp"

namespace kg::retarget {

namespace {

using kg::Error;
using kg::SourceLocation;

class Reader : public kg::YamlReader {
 public:
  Reader(std::string file, std::span<const motion::Motion> characters)
      : YamlReader(std::move(file)), chars_(characters) {}

  ConstraintSet read(const std::string& source) {
    const YAML::Node root = load(source, "empty constraint file (expected 'version: 1')");
    if (!root.IsMap()) fail("a constraint file must be a map (version, constraints, limits)", root.Mark());
    check_keys(root, "", {"version", "doc", "constraints", "limits", "limits_character"});
    if (!root["version"]) throw Error("missing 'version: 1'", {path(), 1, 1});
    const int version = integer(root["version"], "version");
    if (version != kConstraintFormatVersion)
      fail("unsupported version " + std::to_string(version) + " (this reads version 1)",
           root["version"].Mark());
    if (chars_.empty()) throw Error("no character motion to resolve joint names against", {path(), 1, 1});
    ConstraintSet set;
    if (const YAML::Node cs = root["constraints"]) {
      if (!cs.IsSequence() && !cs.IsNull()) fail("'constraints' must be a list", cs.Mark());
      int index = 0;
      for (const YAML::Node& c : cs) set.constraints.push_back(constraint(c, index++));
    }
    if (const YAML::Node limits = root["limits"]) {
      int character = 0;
      if (const YAML::Node lc = root["limits_character"]) character = character_index(lc, "limits_character");
      read_limits(limits, character, set);
    }
    return set;
  }

 private:
  double as_double(const YAML::Node& n, const std::string& what) const { return number(n, what, true); }

  bool as_bool(const YAML::Node& n, const std::string& what) const {
    if (!n.IsScalar()) fail(what + ": expected true or false", n.Mark());
    try {
      return n.as<bool>();
    } catch (const YAML::Exception&) {
      fail(what + ": expected true or false, got '" + n.Scalar() + "'", n.Mark());
    }
  }

  std::vector<double> numbers(const YAML::Node& n, const std::string& what) const {
    if (!n.IsSequence()) fail(what + ": expected a list of numbers", n.Mark());
    std::vector<double> out;
    for (const YAML::Node& x : n) out.push_back(as_double(x, what));
    return out;
  }

  int character_index(const YAML::Node& n, const std::string& what) const {
    const int c = integer(n, what);
    if (c < 0 || c >= static_cast<int>(chars_.size()))
      fail(what + ": character " + std::to_string(c) + " does not exist (" + std::to_string(chars_.size()) +
               " given)",
           n.Mark());
    return c;
  }

  const motion::Skeleton& skeleton(int character) const {
    return *chars_[static_cast<std::size_t>(character)].skeleton;
  }

  int joint(const YAML::Node& n, int character) const {
    const std::string name = text(n, "joint");
    const motion::Skeleton& sk = skeleton(character);
    const int j = sk.find_joint(name);
    if (j >= 0) return j;
    std::string msg = "unknown joint " + text::in_quotes(name);
    const std::string near = motion::nearest_joint_name(sk, name);
    if (!near.empty()) msg += " (nearest: " + text::in_quotes(near) + ")";
    if (chars_.size() > 1) msg += " in character " + std::to_string(character);
    fail(msg, n.Mark());
  }

  PointRef point(const YAML::Node& n, const std::string& path, int& frame_offset) const {
    if (!n.IsMap())
      fail(path + ": expected a map {joint, offset, end_site, character, frame_offset}", n.Mark());
    check_keys(n, path, {"joint", "offset", "end_site", "character", "frame_offset"});
    PointRef p;
    if (n["character"]) p.character = character_index(n["character"], path + ".character");
    if (!n["joint"]) fail(path + ": missing 'joint'", n.Mark());
    p.joint = joint(n["joint"], p.character);
    const bool end = n["end_site"] && as_bool(n["end_site"], path + ".end_site");
    if (end) {
      if (n["offset"]) fail(path + ": give either 'offset' or 'end_site', not both", n["offset"].Mark());
      const motion::Joint& jt = skeleton(p.character).joint(p.joint);
      if (jt.end_sites.empty()) fail(path + ": joint '" + jt.name + "' has no End Site", n["joint"].Mark());
      p.local = jt.end_sites.front();
    }
    if (const YAML::Node off = n["offset"]) {
      const std::vector<double> v = numbers(off, path + ".offset");
      if (v.size() != 3)
        fail(path + ".offset: expected [x, y, z] (metres), got " + std::to_string(v.size()) + " numbers",
             off.Mark());
      p.local = Eigen::Vector3d(v[0], v[1], v[2]);
      if (!p.local.allFinite()) fail(path + ".offset: not finite", off.Mark());
    }
    frame_offset =
        n["frame_offset"] ? offset_frames(n["frame_offset"], path + ".frame_offset", p.character) : 0;
    return p;
  }

  ChannelRef channel(const YAML::Node& n, const std::string& path, int& frame_offset) const {
    ChannelRef ch;
    frame_offset = 0;
    std::string joint_name, channel_name;
    if (n.IsScalar()) {
      const std::string text = n.Scalar();
      const auto dot = text.rfind('.');
      if (dot == std::string::npos)
        fail(path + ": expected 'Joint.Channel' (e.g. LeftLeg.Xrotation), got " + text::in_quotes(text),
             n.Mark());
      joint_name = text.substr(0, dot);
      channel_name = text.substr(dot + 1);
    } else if (n.IsMap()) {
      check_keys(n, path, {"joint", "channel", "character", "frame_offset"});
      if (n["character"]) ch.character = character_index(n["character"], path + ".character");
      if (!n["joint"] || !n["channel"]) fail(path + ": needs 'joint' and 'channel'", n.Mark());
      joint_name = text(n["joint"], path + ".joint");
      channel_name = text(n["channel"], path + ".channel");
      if (n["frame_offset"])
        frame_offset = offset_frames(n["frame_offset"], path + ".frame_offset", ch.character);
    } else {
      fail(path + ": expected 'Joint.Channel' or {joint, channel}", n.Mark());
    }
    const motion::Skeleton& sk = skeleton(ch.character);
    const int j = sk.find_joint(joint_name);
    if (j < 0) {
      std::string msg = "unknown joint " + text::in_quotes(joint_name);
      const std::string near = motion::nearest_joint_name(sk, joint_name);
      if (!near.empty()) msg += " (nearest: " + text::in_quotes(near) + ")";
      fail(msg, n.Mark());
    }
    const auto kind = motion::channel_kind_from_string(channel_name);
    const motion::Joint& jt = sk.joint(j);
    std::vector<std::string> has;
    for (std::size_t i = 0; i < jt.channels.size(); ++i) {
      has.push_back(motion::to_string(jt.channels[i].kind));
      if (kind && jt.channels[i].kind == *kind) {
        ch.channel = jt.first_channel + static_cast<int>(i);
        return ch;
      }
    }
    fail("joint " + text::in_quotes(joint_name) + " has no channel " + text::in_quotes(channel_name) +
             " (it has: " + text::join(has) + ")",
         n.Mark());
  }

  int frame_count(int character) const { return chars_[static_cast<std::size_t>(character)].frame_count(); }

  int max_frame_count() const {
    int n = 0;
    for (const motion::Motion& m : chars_) n = std::max(n, m.frame_count());
    return n;
  }

  // A frame_offset: within -(n-1)..n-1 for a clip of n frames, as a larger one moves every frame
  // outside the clip (and could overflow int when added to a frame).
  int offset_frames(const YAML::Node& n, const std::string& what, int character) const {
    const int off = integer(n, what);
    const long long most = std::max(frame_count(character) - 1, 0);
    if (off < -most || off > most)
      fail(what + ": " + std::to_string(off) + " is outside -" + std::to_string(most) + ".." +
               std::to_string(most) + " (the clip has frames 0.." +
               std::to_string(frame_count(character) - 1) + ")",
           n.Mark());
    return off;
  }

  int time_to_frame(const YAML::Node& n, const std::string& what) const {
    const double t = as_double(n, what);
    if (!std::isfinite(t) || t < 0) fail(what + ": a time must be finite and >= 0 s", n.Mark());
    // Against the longest clip: a frame_offset may move the frame into another character's clip,
    // and the frames are checked against each character's own clip once the offsets are added.
    try {
      return motion::seconds_to_frame(t, chars_.front().fps, max_frame_count());
    } catch (const std::out_of_range& e) {
      fail(what + ": " + e.what(), n.Mark());
    }
  }

  // The sample base frames of an entry: exactly one of frames / at_frames / times / at_times.
  std::vector<int> base_frames(const YAML::Node& c, const std::string& path) const {
    const char* keys[] = {"frames", "at_frames", "times", "at_times"};
    const char* given = nullptr;
    for (const char* k : keys)
      if (c[k]) {
        if (given) fail(path + ": give only one of frames, at_frames, times, at_times", c[k].Mark());
        given = k;
      }
    if (!given)
      fail(path + ": missing frames (frames: [first, last], at_frames, times or at_times)", c.Mark());
    const YAML::Node n = c[given];
    const std::string what = path + "." + given;
    if (!n.IsSequence()) fail(what + ": expected a list", n.Mark());
    const bool seconds = given[0] == 't' || std::string(given) == "at_times";
    std::vector<int> frames;
    for (const YAML::Node& x : n) frames.push_back(seconds ? time_to_frame(x, what) : integer(x, what));
    const bool range = std::string(given) == "frames" || std::string(given) == "times";
    if (range) {
      if (frames.size() != 2)
        fail(what + ": expected [first, last], got " + std::to_string(frames.size()) + " entries", n.Mark());
      if (frames[0] > frames[1])
        fail(what + ": the range [" + std::to_string(frames[0]) + ", " + std::to_string(frames[1]) +
                 "] is reversed",
             n.Mark());
      const int a = frames[0], b = frames[1];
      if (static_cast<long long>(b) - a >= max_frame_count())
        fail(what + ": the range [" + std::to_string(a) + ", " + std::to_string(b) +
                 "] is outside the clip (frames 0.." + std::to_string(max_frame_count() - 1) +
                 "): longer than its " + std::to_string(max_frame_count()) + " frames",
             n.Mark());
      frames.clear();
      for (int f = a; f <= b; ++f) frames.push_back(f);
    } else if (frames.empty()) {
      fail(what + ": the list is empty", n.Mark());
    }
    return frames;
  }

  Constraint constraint(const YAML::Node& n, int index) {
    const std::string path = "constraints[" + std::to_string(index) + "]";
    if (!n.IsMap()) fail(path + ": expected a map {kind, points, params, frames, ...}", n.Mark());
    check_keys(n, path,
               {"kind", "label", "relation", "points", "channels", "params", "frames", "at_frames", "times",
                "at_times", "weight"});
    Constraint c;
    if (!n["kind"]) fail(path + ": missing 'kind'", n.Mark());
    c.kind = text(n["kind"], path + ".kind");
    c.label = n["label"] ? text(n["label"], path + ".label") : c.kind + " " + std::to_string(index);
    if (const YAML::Node r = n["relation"]) {
      try {
        c.relation = relation_from_string(text(r, path + ".relation"));
      } catch (const std::invalid_argument& e) {
        fail(path + ".relation: " + e.what(), r.Mark());
      }
    }
    if (n["weight"]) c.weight = as_double(n["weight"], path + ".weight");
    if (n["params"]) c.params = numbers(n["params"], path + ".params");
    std::vector<int> offsets;
    if (const YAML::Node ps = n["points"]) {
      if (!ps.IsSequence()) fail(path + ".points: expected a list", ps.Mark());
      int i = 0;
      for (const YAML::Node& p : ps) {
        int off = 0;
        c.points.push_back(point(p, path + ".points[" + std::to_string(i++) + "]", off));
        offsets.push_back(off);
      }
    }
    if (const YAML::Node cs = n["channels"]) {
      if (!cs.IsSequence()) fail(path + ".channels: expected a list", cs.Mark());
      int i = 0;
      for (const YAML::Node& ch : cs) {
        int off = 0;
        c.channels.push_back(channel(ch, path + ".channels[" + std::to_string(i++) + "]", off));
        offsets.push_back(off);
      }
    }
    const std::vector<int> frames = base_frames(n, path);
    const YAML::Mark frames_mark = (n["frames"]      ? n["frames"]
                                    : n["at_frames"] ? n["at_frames"]
                                    : n["times"]     ? n["times"]
                                                     : n["at_times"])
                                       .Mark();
    // Every read frame inside its character's clip: base frame + offset summed in long long and
    // checked before it is narrowed to int.
    const std::size_t np = c.points.size();
    auto frame_at = [&](int base, std::size_t entry) {
      const long long f = static_cast<long long>(base) + offsets[entry];
      const int character = entry < np ? c.points[entry].character : c.channels[entry - np].character;
      if (f < 0 || f >= frame_count(character))
        fail(path + ": frame " + std::to_string(f) + " is outside the clip (frames 0.." +
                 std::to_string(frame_count(character) - 1) +
                 (chars_.size() > 1 ? " of character " + std::to_string(character) : "") + ")",
             frames_mark);
      return static_cast<int>(f);
    };
    // same_place with one point: the point at consecutive sample frames (non-skid).
    if (c.kind == "same_place" && c.points.size() == 1 && c.channels.empty()) {
      if (frames.size() < 2)
        fail(path + ": same_place with one point needs at least two frames", frames_mark);
      for (std::size_t i = 0; i + 1 < frames.size(); ++i)
        c.samples.push_back({.frames = {frame_at(frames[i], 0), frame_at(frames[i + 1], 0)}});
      c.points.push_back(c.points.front());
    } else {
      for (int f : frames) {
        Sample s;
        for (std::size_t e = 0; e < offsets.size(); ++e) s.frames.push_back(frame_at(f, e));
        c.samples.push_back(std::move(s));
      }
    }
    if (const ConstraintKind* kind = builtin_.find(c.kind)) {
      try {
        kind->check(c);
      } catch (const std::invalid_argument& e) {
        fail(path + ": " + e.what(), n.Mark());
      }
    }
    return c;
  }

  void read_limits(const YAML::Node& limits, int character, ConstraintSet& set) const {
    if (!limits.IsMap()) fail("'limits' must be a map {joint regex: {channel: [min, max]}}", limits.Mark());
    const motion::Skeleton& sk = skeleton(character);
    std::vector<std::string> names;
    for (const motion::Joint& jt : sk.joints()) names.push_back(jt.name);
    const int frames = frame_count(character);
    for (auto it = limits.begin(); it != limits.end(); ++it) {
      const std::string pattern = it->first.Scalar();
      const kg::Pattern re = YamlReader::pattern(it->first, "limits");
      std::vector<int> joints;
      for (int j = 0; j < sk.joint_count(); ++j)
        if (re.full_match(sk.joint(j).name)) joints.push_back(j);
      if (joints.empty()) {
        std::string msg = "limits: " + text::excerpt(pattern) + " matches no joint";
        const std::string near = kg::nearest_name(pattern, names);
        if (!near.empty()) msg += " (nearest: " + text::in_quotes(near) + ")";
        fail(msg, it->first.Mark());
      }
      const std::string where = text::key_path("limits", pattern);
      const YAML::Node chans = it->second;
      if (!chans.IsMap()) fail(where + ": expected {channel: [min, max]}", chans.Mark());
      for (auto ct = chans.begin(); ct != chans.end(); ++ct) {
        const std::string cname = ct->first.Scalar();
        const auto kind = motion::channel_kind_from_string(cname);
        if (!kind)
          fail(where + ": unknown channel " + text::in_quotes(cname) + " (Xposition..Zrotation)",
               ct->first.Mark());
        const std::vector<double> range = numbers(ct->second, text::key_path(where, cname));
        if (range.size() != 2 || std::isnan(range[0]) || std::isnan(range[1]) || range[0] > range[1])
          fail(text::key_path(where, cname) + ": expected [min, max] with min <= max", ct->second.Mark());
        const double scale = motion::is_rotation(*kind) ? std::numbers::pi / 180.0 : 1.0;
        int made = 0;
        for (int j : joints) {
          const motion::Joint& jt = sk.joint(j);
          for (std::size_t i = 0; i < jt.channels.size(); ++i) {
            if (jt.channels[i].kind != *kind) continue;
            const int ch = jt.first_channel + static_cast<int>(i);
            Constraint c;
            c.kind = "parameter_range";
            c.label = "limit " + sk.channel_name(ch);
            c.channels = {{character, ch}};
            c.params = {range[0] * scale, range[1] * scale};
            for (int f = 0; f < frames; ++f) c.samples.push_back({.frames = {f}});
            set.constraints.push_back(std::move(c));
            ++made;
          }
        }
        if (made == 0) fail(where + ": no joint it matches has a " + cname + " channel", ct->first.Mark());
      }
    }
  }

  std::span<const motion::Motion> chars_;
  ConstraintKindTable builtin_ = ConstraintKindTable::builtin();
};

}  // namespace

ConstraintSet read_constraints_string(const std::string& text, const std::string& file_name,
                                      std::span<const motion::Motion> characters) {
  for (const motion::Motion& m : characters)
    if (!m.skeleton) throw Error("a character motion has no skeleton", {file_name, 0, 0});
  return Reader(file_name, characters).read(text);
}

ConstraintSet read_constraints_file(const std::string& path, std::span<const motion::Motion> characters) {
  return read_constraints_string(kg::read_input_file(path, "constraint file"), path, characters);
}

ConstraintSet joint_limit_constraints(const motion::Skeleton& sk, int character, int frames) {
  ConstraintSet set;
  for (int ch = 0; ch < sk.channel_count(); ++ch) {
    const auto [j, i] = sk.channel_owner(ch);
    const motion::Channel& c = sk.joint(j).channels[static_cast<std::size_t>(i)];
    if (!std::isfinite(c.min) && !std::isfinite(c.max)) continue;
    Constraint k;
    k.kind = "parameter_range";
    k.label = "limit " + sk.channel_name(ch);
    k.channels = {{character, ch}};
    k.params = {c.min, c.max};
    for (int f = 0; f < frames; ++f) k.samples.push_back({.frames = {f}});
    set.constraints.push_back(std::move(k));
  }
  return set;
}

void merge_constraints(ConstraintSet& into, const ConstraintSet& more) {
  into.constraints.insert(into.constraints.end(), more.constraints.begin(), more.constraints.end());
}

}  // namespace kg::retarget
