// Target files: the YAML of per-bone factors, lengths or morph keys, and skeleton files.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <yaml-cpp/yaml.h>

#include "kg/base/atomic_file.hpp"
#include "kg/base/error.hpp"
#include "kg/base/text.hpp"
#include "kg/base/yaml_reader.hpp"
#include "kg/io/import_options.hpp"
#include "kg/io/motion_format.hpp"
#include "kg/retarget/target.hpp"

namespace kg::retarget {

namespace {

using kg::Error;
using kg::SourceLocation;
using motion::Skeleton;

class Reader : public kg::YamlReader {
 public:
  Reader(const Skeleton& source, std::string path) : YamlReader(std::move(path)), source_(source) {}

  // Per-joint factors from a `bones:` or `lengths:` map, with `fallback` for unmatched joints.
  Eigen::VectorXd factors(const YAML::Node& map, bool lengths, double fallback, const std::string& what,
                          std::vector<std::string>& notes) const {
    const int n = source_.joint_count();
    Eigen::VectorXd f = Eigen::VectorXd::Constant(n, fallback);
    std::vector<int> owner(static_cast<std::size_t>(n), -1);  // which pattern set the joint
    const std::vector<Entry> es = entries(map, what);
    if (es.empty())
      fail(what + " is empty (expected joint-name patterns: " + (lengths ? "length" : "factor") + ")", map);
    for (std::size_t p = 0; p < es.size(); ++p) {
      const Entry& e = es[p];
      const kg::Pattern re = pattern(e.key_node, what);
      const double v = positive(e.value, text::key_path(what, e.key));
      std::vector<std::string> matched, shadowed;
      for (int j = 0; j < n; ++j) {
        const std::string& name = source_.joint(j).name;
        if (!re.full_match(name)) continue;
        if (owner[static_cast<std::size_t>(j)] >= 0) {
          shadowed.push_back(name);
          continue;
        }
        if (lengths) {
          const double len = source_.joint(j).offset.norm();
          if (!(len > 0))
            fail(text::key_path(what, e.key) + ": joint " + text::in_quotes(name) +
                     " has a zero offset from its parent in the source, so no length can be set for it",
                 e.key_node);
          f[j] = v / len;
        } else {
          f[j] = v;
        }
        owner[static_cast<std::size_t>(j)] = static_cast<int>(p);
        matched.push_back(name);
      }
      if (matched.empty() && shadowed.empty())
        fail("pattern " + text::excerpt(e.key) + " in " + what +
                 " matches no joint (the whole name must match)",
             e.key_node);
      std::string note = what + " " + text::in_quotes(e.key) + " = " + text::significant(v) + ": " +
                         (matched.empty() ? std::string("no joint left") : text::join(matched));
      if (!shadowed.empty()) note += " (already matched earlier: " + text::join(shadowed) + ")";
      notes.push_back(note);
    }
    return f;
  }

  LoadedTarget read(std::string_view text, std::shared_ptr<const Skeleton> source_ptr) const {
    const YAML::Node root =
        load(text, "empty target file (expected version: 1 and one of bones, lengths, morph)");
    const std::vector<Entry> top = entries(root, "the target file");
    check_keys(top, "the target file", {"version", "default", "bones", "lengths", "morph"});
    check_version(top);
    auto find = [&](const std::string& key) { return YamlReader::find(top, key); };
    const Entry* def = find("default");
    const double fallback = def != nullptr ? positive(def->value, "default") : 1.0;
    const Entry* bones = find("bones");
    const Entry* lengths = find("lengths");
    const Entry* morph = find("morph");
    const int given = (bones != nullptr) + (lengths != nullptr) + (morph != nullptr);
    if (given != 1) {
      const YAML::Node& where =
          given == 0 ? find("version")->key_node : (morph != nullptr ? morph->key_node : lengths->key_node);
      fail(given == 0 ? "expected one of 'bones', 'lengths' or 'morph'"
                      : "give only one of 'bones', 'lengths' and 'morph'",
           where);
    }
    LoadedTarget out;
    if (bones != nullptr || lengths != nullptr) {
      const bool is_lengths = lengths != nullptr;
      const Entry& e = is_lengths ? *lengths : *bones;
      out.kind = e.key;
      Eigen::VectorXd f = factors(e.value, is_lengths, fallback, e.key, out.notes);
      out.target = factor_target(std::move(source_ptr), f);
      return out;
    }
    out.kind = "morph";
    if (!morph->value.IsSequence() || morph->value.size() == 0)
      fail("morph must be a list of keys ({time: seconds, scale: factor} or time with bones/lengths)",
           morph->value);
    std::vector<double> times;
    std::vector<Eigen::VectorXd> keys;
    for (std::size_t k = 0; k < morph->value.size(); ++k) {
      const YAML::Node key = morph->value[k];
      const std::string what = "morph[" + std::to_string(k) + "]";
      const std::vector<Entry> es = entries(key, what);
      check_keys(es, what, {"time", "scale", "bones", "lengths", "default"});
      const Entry *time = nullptr, *scale = nullptr, *kb = nullptr, *kl = nullptr, *kd = nullptr;
      for (const Entry& e : es) {
        if (e.key == "time") time = &e;
        if (e.key == "scale") scale = &e;
        if (e.key == "bones") kb = &e;
        if (e.key == "lengths") kl = &e;
        if (e.key == "default") kd = &e;
      }
      if (time == nullptr) fail(what + ": missing 'time' (seconds)", key);
      const double t = number(time->value, what + ".time");
      if (t < 0) fail(what + ".time: expected seconds >= 0, got " + text::significant(t), time->value);
      if (!times.empty() && !(t > times.back()))
        fail(what + ".time: key times must increase strictly, " + text::significant(t) + " s follows " +
                 text::significant(times.back()) + " s",
             time->value);
      const int forms = (scale != nullptr) + (kb != nullptr) + (kl != nullptr);
      if (forms != 1) fail(what + ": expected exactly one of 'scale', 'bones' or 'lengths'", key);
      if (kd != nullptr && scale != nullptr)
        fail(what + ": 'default' goes with bones or lengths, not scale", kd->key_node);
      Eigen::VectorXd f;
      if (scale != nullptr) {
        f = Eigen::VectorXd::Constant(source_.joint_count(), positive(scale->value, what + ".scale"));
      } else {
        const double key_default = kd != nullptr ? positive(kd->value, what + ".default") : fallback;
        const Entry& e = kb != nullptr ? *kb : *kl;
        f = factors(e.value, kl != nullptr, key_default, text::key_path(what, e.key), out.notes);
      }
      times.push_back(t);
      keys.push_back(std::move(f));
    }
    out.target = morph_target(std::move(source_ptr), std::move(times), std::move(keys));
    return out;
  }

 private:
  const Skeleton& source_;
};

}  // namespace

LoadedTarget parse_target_yaml(std::shared_ptr<const Skeleton> source, std::string_view text,
                               const std::string& path) {
  if (!source) throw std::invalid_argument("parse_target_yaml: no source skeleton");
  const Reader reader(*source, path);
  return reader.read(text, source);
}

LoadedTarget load_target(std::shared_ptr<const Skeleton> source, const std::string& path) {
  if (!source) throw std::invalid_argument("load_target: no source skeleton");
  const std::string ext = kg::text::lower_extension(path);
  if (ext == ".yaml" || ext == ".yml") {
    return parse_target_yaml(std::move(source), kg::read_input_file(path, "target file"), path);
  }
  LoadedTarget out;
  out.kind = "skeleton";
  const std::string what = "target skeleton " + path;
  if (ext == ".bvh" || ext == ".asf") {
    io::ImportedMotion in = io::import_motion(path, "", io::ImportOptions{});
    out.notes = in.notes;
    out.target = skeleton_target(std::move(source), *in.motion.skeleton, what, &out.notes);
    return out;
  }
  throw std::invalid_argument(
      "target file " + path + ": unknown extension '" + ext +
      "' (expected .yaml or .yml for factors, lengths or a morph, .bvh or .asf for a skeleton)");
}

}  // namespace kg::retarget
