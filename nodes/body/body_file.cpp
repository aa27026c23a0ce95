// Body files: the YAML of body_build.hpp (table, mass, classes, overrides, torque limits,
// friction, gravity), every error located at file:line:column.
#include <algorithm>
#include <cmath>
#include <limits>

#include <yaml-cpp/yaml.h>

#include "kg/base/atomic_file.hpp"
#include "kg/base/error.hpp"
#include "kg/base/text.hpp"
#include "kg/base/yaml_reader.hpp"
#include "kg/body/body_build.hpp"

namespace kg::body {

namespace {

using kg::Error;
using kg::SourceLocation;

class Reader : public kg::YamlReader {
 public:
  explicit Reader(std::string path) : YamlReader(std::move(path)) {}

  std::vector<double> numbers(const YAML::Node& n, const std::string& what, bool allow_inf = false) const {
    if (!n.IsSequence()) fail(what + ": expected a list of numbers", n);
    std::vector<double> out;
    for (std::size_t i = 0; i < n.size(); ++i)
      out.push_back(number(n[i], what + "[" + std::to_string(i) + "]", allow_inf));
    return out;
  }
  Eigen::Vector3d vector3(const YAML::Node& n, const std::string& what) const {
    const std::vector<double> v = numbers(n, what);
    if (v.size() != 3) fail(what + ": expected 3 numbers [x, y, z], got " + std::to_string(v.size()), n);
    return {v[0], v[1], v[2]};
  }
  // A bad pattern fails here, at its key; build_body_model compiles it again (BodySpec keeps text).
  void check_pattern(const Entry& e, const std::string& what) const { pattern(e.key_node, what); }

  // [Ixx, Iyy, Izz], [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] or three rows of three.
  Eigen::Matrix3d inertia(const YAML::Node& n, const std::string& what) const {
    if (!n.IsSequence())
      fail(what + ": expected [Ixx, Iyy, Izz], [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] or 3 rows of 3", n);
    Eigen::Matrix3d I = Eigen::Matrix3d::Zero();
    if (n.size() == 3 && n[0].IsSequence()) {
      for (int r = 0; r < 3; ++r) {
        const Eigen::Vector3d row =
            vector3(n[static_cast<std::size_t>(r)], what + "[" + std::to_string(r) + "]");
        I.row(r) = row.transpose();
      }
    } else {
      const std::vector<double> v = numbers(n, what);
      if (v.size() != 3 && v.size() != 6)
        fail(what + ": expected 3 numbers (principal moments) or 6 (Ixx, Iyy, Izz, Ixy, Ixz, Iyz), got " +
                 std::to_string(v.size()),
             n);
      I.diagonal() << v[0], v[1], v[2];
      if (v.size() == 6) {
        I(0, 1) = I(1, 0) = v[3];
        I(0, 2) = I(2, 0) = v[4];
        I(1, 2) = I(2, 1) = v[5];
      }
    }
    try {
      check_segment_inertia(I, what);  // the builder's own check, located here
    } catch (const std::invalid_argument& e) {
      fail(e.what(), n);
    }
    return I;
  }

  LoadedBodySpec read(std::string_view text, const BodySpec& base) const {
    const YAML::Node root = load(text, "empty body file (expected at least version: 1)");
    const std::vector<Entry> top = entries(root, "the body file");
    check_keys(
        top, "the body file",
        {"version", "table", "mass", "radii", "classes", "segments", "torque_limits", "friction", "gravity"});
    check_version(top);

    LoadedBodySpec out{base, {}};
    BodySpec& spec = out.spec;
    const Entry* mass = nullptr;
    for (const Entry& e : top) {
      if (e.key == "version") continue;
      out.given.push_back(e.key);
      if (e.key == "table") {
        spec.table = table(e.value);
      } else if (e.key == "mass") {
        spec.mass = non_negative(e.value, "mass");
        mass = &e;
      } else if (e.key == "radii") {
        read_radii(e.value, spec.radii);
      } else if (e.key == "classes") {
        spec.classes = classes(e.value);
      } else if (e.key == "segments") {
        spec.segments = segments(e.value);
      } else if (e.key == "torque_limits") {
        spec.torque_limits = torque_limits(e.value);
      } else if (e.key == "friction") {
        spec.friction = non_negative(e.value, "friction");
      } else if (e.key == "gravity") {
        spec.gravity = gravity(e.value);
      }
    }
    check_mass(spec, mass);
    return out;
  }

 private:
  BodyTable table(const YAML::Node& n) const {
    if (!n.IsScalar()) fail("table: expected one of " + text::join(body_table_names()), n);
    const auto t = body_table_from_string(n.Scalar());
    if (!t) {
      const std::string near = kg::nearest_name(n.Scalar(), body_table_names());
      fail("table: unknown table " + text::in_quotes(n.Scalar()) +
               (near.empty() ? "" : " (did you mean " + text::in_quotes(near) + "?)") + "; expected one of " +
               text::join(body_table_names()),
           n);
    }
    return *t;
  }

  // The radii given replace those of `radii`, the others stay.
  void read_radii(const YAML::Node& n, std::array<double, kSegmentClassCount>& radii) const {
    for (const Entry& r : entries(n, "radii")) {
      const auto c = segment_class_from_string(r.key);
      if (!c || *c == SegmentClass::Massless) {
        std::vector<std::string> names = segment_class_names();
        names.pop_back();  // massless has no radius
        const std::string near = kg::nearest_name(r.key, names);
        fail("unknown class " + text::in_quotes(r.key) + " in radii" +
                 (near.empty() ? "" : " (did you mean " + text::in_quotes(near) + "?)") +
                 "; allowed: " + text::join(names),
             r.key_node);
      }
      radii[static_cast<std::size_t>(index_of(*c))] = positive(r.value, text::key_path("radii", r.key));
    }
  }

  std::vector<ClassPattern> classes(const YAML::Node& n) const {
    std::vector<ClassPattern> out;
    for (const Entry& c : entries(n, "classes")) {
      check_pattern(c, "classes");
      if (!c.value.IsScalar() || !segment_class_from_string(c.value.Scalar())) {
        const std::string got = c.value.IsScalar() ? c.value.Scalar() : "?";
        const std::string near = kg::nearest_name(got, segment_class_names());
        fail(text::key_path("classes", c.key) + ": unknown class " + text::in_quotes(got) +
                 (near.empty() ? "" : " (did you mean " + text::in_quotes(near) + "?)") +
                 "; expected one of " + text::join(segment_class_names()),
             c.value);
      }
      out.push_back({c.key, *segment_class_from_string(c.value.Scalar()), at(c.key_node)});
    }
    return out;
  }

  SegmentOverride segment_override(const Entry& s) const {
    check_pattern(s, "segments");
    const std::string what = text::key_path("segments", s.key);
    const std::vector<Entry> fields = entries(s.value, what);
    check_keys(fields, what, {"mass", "mass_scale", "com", "inertia", "radius"});
    if (fields.empty())
      fail(what + ": expected at least one of mass, mass_scale, com, inertia, radius", s.value);
    SegmentOverride o{.pattern = s.key, .where = at(s.key_node)};
    for (const Entry& f : fields) {
      const std::string fw = text::key_path(what, f.key);
      if (f.key == "mass") o.mass = positive(f.value, fw);
      if (f.key == "mass_scale") o.mass_scale = positive(f.value, fw);
      if (f.key == "radius") o.radius = positive(f.value, fw);
      if (f.key == "com") o.com = vector3(f.value, fw);
      if (f.key == "inertia") o.inertia = inertia(f.value, fw);
      if (o.mass && o.mass_scale) fail(what + ": give mass or mass_scale, not both", f.key_node);
    }
    return o;
  }

  std::vector<SegmentOverride> segments(const YAML::Node& n) const {
    std::vector<SegmentOverride> out;
    for (const Entry& s : entries(n, "segments")) out.push_back(segment_override(s));
    return out;
  }

  TorqueLimit torque_limit(const Entry& t) const {
    check_pattern(t, "torque_limits");
    const std::string what = text::key_path("torque_limits", t.key);
    TorqueLimit limit{.pattern = t.key, .values = {}, .where = at(t.key_node)};
    if (t.value.IsSequence()) {
      limit.values = numbers(t.value, what, true);
      if (limit.values.empty()) fail(what + ": expected one bound per channel, got an empty list", t.value);
      for (std::size_t i = 0; i < limit.values.size(); ++i)
        if (!(limit.values[i] > 0))
          fail(what + "[" + std::to_string(i) + "]: expected N m > 0 (or .inf), got " +
                   text::significant(limit.values[i]),
               t.value[i]);
    } else {
      const double v = number(t.value, what, true);
      if (!(v > 0)) fail(what + ": expected N m > 0 (or .inf), got " + text::significant(v), t.value);
      limit.values = {v};
    }
    return limit;
  }

  std::vector<TorqueLimit> torque_limits(const YAML::Node& n) const {
    std::vector<TorqueLimit> out;
    for (const Entry& t : entries(n, "torque_limits")) out.push_back(torque_limit(t));
    return out;
  }

  Eigen::Vector3d gravity(const YAML::Node& n) const {
    if (n.IsSequence()) return vector3(n, "gravity");
    if (!n.IsScalar()) fail("gravity: expected m/s² (straight down) or a vector [x, y, z]", n);
    const double g = number(n, "gravity");
    if (g < 0)
      fail("gravity: expected a magnitude >= 0 (m/s², straight down) or a vector [x, y, z], got " +
               text::significant(g),
           n);
    return Eigen::Vector3d(0, -g, 0);
  }

  // A table needs a mass > 0, located at the file's `mass` when it gave one.
  void check_mass(const BodySpec& spec, const Entry* mass) const {
    if (spec.table == BodyTable::Cylinders || spec.mass > 0) return;
    const std::string msg = "mass " + text::significant(spec.mass) + " kg with table " +
                            to_string(spec.table) +
                            ": expected > 0 (0 means 'from the volumes' only with cylinders)";
    if (mass != nullptr) fail(msg, mass->value);
    throw Error(msg, {path(), 1, 1});
  }
};

}  // namespace

LoadedBodySpec parse_body_yaml(std::string_view text, const std::string& path, const BodySpec& base) {
  return Reader(path).read(text, base);
}

LoadedBodySpec load_body_yaml(const std::string& path, const BodySpec& base) {
  return parse_body_yaml(kg::read_input_file(path, "body file"), path, base);
}

}  // namespace kg::body
