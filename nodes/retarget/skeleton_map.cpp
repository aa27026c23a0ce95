// Skeleton map files and the pairs their chains give (skeleton_map.hpp).
#include "kg/retarget/skeleton_map.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <ostream>
#include <set>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "kg/base/atomic_file.hpp"
#include "kg/base/error.hpp"
#include "kg/base/text.hpp"
#include "kg/base/yaml_reader.hpp"

namespace kg::retarget {

using motion::PointRef;
using motion::Skeleton;

const char* to_string(FeatureKind kind) {
  switch (kind) {
    case FeatureKind::Position:
      return "position";
    case FeatureKind::Direction:
      return "direction";
    case FeatureKind::Orientation:
      return "orientation";
  }
  return "?";
}

namespace {

constexpr const char* kChainNames[] = {"pelvis",    "spine",    "neck",     "left_leg",
                                       "right_leg", "left_arm", "right_arm"};

FeatureSide point(int joint) {
  return {PointRef{0, joint, Eigen::Vector3d::Zero()}, PointRef{}};
}
FeatureSide direction(int from, int to) {
  return {PointRef{0, from, Eigen::Vector3d::Zero()}, PointRef{0, to, Eigen::Vector3d::Zero()}};
}

// The chains' pairs (the table in the header), for chains both sides have.
std::vector<FeaturePair> chain_pairs(const SkeletonChains& s, const SkeletonChains& t) {
  std::vector<FeaturePair> out;
  auto add = [&](std::string name, FeatureKind kind, FeatureSide a, FeatureSide b, double w) {
    out.push_back({std::move(name), kind, a, b, w, false});
  };
  // A position pair named CHAIN.ROLE at a role both limbs have.
  auto at_role = [&](const std::string& chain, const Limb& a, const Limb& b, const LimbRole& r, double w) {
    if (a.*r.joint >= 0 && b.*r.joint >= 0)
      add(chain + r.name, FeatureKind::Position, point(a.*r.joint), point(b.*r.joint), w);
  };
  if (s.pelvis >= 0 && t.pelvis >= 0) {
    add("pelvis.position", FeatureKind::Position, point(s.pelvis), point(t.pelvis), 1);
    add("pelvis.orientation", FeatureKind::Orientation, point(s.pelvis), point(t.pelvis), 1);
  }
  if (!s.spine.empty() && !t.spine.empty()) {
    add("spine.chest", FeatureKind::Orientation, point(s.spine.back()), point(t.spine.back()), 0.5);
    if (s.pelvis >= 0 && t.pelvis >= 0)
      add("spine.direction", FeatureKind::Direction, direction(s.pelvis, s.spine.back()),
          direction(t.pelvis, t.spine.back()), 1);
  }
  if (!s.neck.empty() && !t.neck.empty()) {
    add("neck.head", FeatureKind::Position, point(s.neck.back()), point(t.neck.back()), 1);
    add("neck.orientation", FeatureKind::Orientation, point(s.neck.back()), point(t.neck.back()), 0.5);
  }
  const char* sides[] = {"left", "right"};
  for (int k = 0; k < 2; ++k) {
    const Limb &a = s.legs[k], &b = t.legs[k];
    const std::string c = std::string(sides[k]) + "_leg.";
    at_role(c, a, b, kLegRoles[1], 1);  // knee
    at_role(c, a, b, kLegRoles[2], 4);  // ankle
    at_role(c, a, b, kLegRoles[3], 2);  // toe
    if (a.foot >= 0 && b.foot >= 0)
      add(c + "foot", FeatureKind::Orientation, point(a.foot), point(b.foot), 1);
    if (a.upper >= 0 && b.upper >= 0 && a.middle >= 0 && b.middle >= 0)
      add(c + "thigh", FeatureKind::Direction, direction(a.upper, a.middle), direction(b.upper, b.middle), 1);
    if (a.middle >= 0 && b.middle >= 0 && a.lower >= 0 && b.lower >= 0)
      add(c + "shin", FeatureKind::Direction, direction(a.middle, a.lower), direction(b.middle, b.lower), 1);
  }
  for (int k = 0; k < 2; ++k) {
    const Limb &a = s.arms[k], &b = t.arms[k];
    const std::string c = std::string(sides[k]) + "_arm.";
    at_role(c, a, b, kArmRoles[2], 1);  // elbow
    at_role(c, a, b, kArmRoles[3], 2);  // wrist
    if (a.upper >= 0 && b.upper >= 0 && a.middle >= 0 && b.middle >= 0)
      add(c + "upper_arm", FeatureKind::Direction, direction(a.upper, a.middle), direction(b.upper, b.middle),
          1);
    if (a.middle >= 0 && b.middle >= 0 && a.lower >= 0 && b.lower >= 0)
      add(c + "forearm", FeatureKind::Direction, direction(a.middle, a.lower), direction(b.middle, b.lower),
          1);
  }
  return out;
}

class MapReader : public kg::YamlReader {
 public:
  MapReader(std::string path, const Skeleton* source, const Skeleton* target)
      : YamlReader(std::move(path)), source_(source), target_(target) {}

  int joint(const YAML::Node& n, const Skeleton& sk, const std::string& side, const std::string& what) const {
    const std::string name = text(n, what);
    const int j = sk.find_joint(name);
    if (j < 0) {
      const std::string near = motion::nearest_joint_name(sk, name);
      fail(what + ": the " + side + " skeleton has no joint " + kg::text::in_quotes(name) +
               (near.empty() ? std::string(" (none is close)")
                             : " (nearest: " + kg::text::in_quotes(near) + ")"),
           n);
    }
    return j;
  }

  std::vector<int> joint_list(const YAML::Node& n, const Skeleton& sk, const std::string& side,
                              const std::string& what) const {
    if (n.IsScalar()) return {joint(n, sk, side, what)};
    if (!n.IsSequence()) fail(what + " must be a joint name or a list of joint names", n);
    std::vector<int> out;
    for (std::size_t i = 0; i < n.size(); ++i)
      out.push_back(joint(n[i], sk, side, what + "[" + std::to_string(i) + "]"));
    return out;
  }

  Limb limb(const YAML::Node& n, const Skeleton& sk, const std::string& side, const std::string& what,
            bool leg) const {
    if (!n.IsMap()) fail(what + " must be a map of roles to joints (" + roles_text(leg) + ")", n);
    Limb l;
    const auto es = entries(n, what);
    const auto& roles = limb_role_table(leg);
    std::vector<std::string> allowed;
    for (const LimbRole& r : roles) allowed.push_back(r.name);
    check_keys(es, what, allowed);
    for (const Entry& e : es)
      for (const LimbRole& r : roles)
        if (e.key == r.name) l.*r.joint = joint(e.value, sk, side, kg::text::key_path(what, e.key));
    for (const LimbRole& r : roles)
      if (r.required && l.*r.joint < 0)
        fail(what + ": missing '" + r.name + "' (a " + (leg ? "leg" : "arm") + " needs " + roles_text(leg) +
                 "; the " + (leg ? "toe" : "clavicle") + " is optional)",
             n);
    for (int j : {l.root, l.upper, l.middle, l.lower, l.end})
      if (j >= 0) l.path.push_back(j);
    if (leg) l.foot = l.end >= 0 ? sk.joint(l.end).parent : l.lower;
    return l;
  }

  static std::string roles_text(bool leg) {
    std::vector<std::string> names;
    for (const LimbRole& r : limb_role_table(leg)) names.push_back(r.name);
    return kg::text::join(names, ", ");
  }

  SkeletonChains chains(const YAML::Node& n, const Skeleton& sk, const std::string& side,
                        const std::string& what) const {
    SkeletonChains c;
    if (!n || n.IsNull()) return c;
    if (!n.IsMap())
      fail(what + " must be a map of chains (" +
               kg::text::join({std::begin(kChainNames), std::end(kChainNames)}) + ")",
           n);
    const auto es = entries(n, what);
    check_keys(es, what, {std::begin(kChainNames), std::end(kChainNames)});
    for (const Entry& e : es) {
      const std::string w = kg::text::key_path(what, e.key);
      if (e.key == "pelvis") {
        c.pelvis = joint(e.value, sk, side, w);
      } else if (e.key == "spine") {
        c.spine = joint_list(e.value, sk, side, w);
      } else if (e.key == "neck") {
        c.neck = joint_list(e.value, sk, side, w);
      } else {
        const bool leg = e.key.find("leg") != std::string::npos;
        const int s = e.key.rfind("left", 0) == 0 ? kLeft : kRight;
        (leg ? c.legs : c.arms)[s] = limb(e.value, sk, side, w, leg);
      }
    }
    return c;
  }

  PointRef point_ref(const YAML::Node& n, const Skeleton& sk, const std::string& side,
                     const std::string& what) const {
    PointRef p;
    if (n.IsScalar()) {
      p.joint = joint(n, sk, side, what);
      return p;
    }
    if (!n.IsMap()) fail(what + " must be a joint name or {joint: NAME, offset: [x, y, z]}", n);
    const auto es = entries(n, what);
    check_keys(es, what, {"joint", "offset"});
    const Entry* j = find(es, "joint");
    if (!j) fail(what + ": missing 'joint'", n);
    p.joint = joint(j->value, sk, side, what + ".joint");
    if (const Entry* o = find(es, "offset")) {
      if (!o->value.IsSequence() || o->value.size() != 3)
        fail(what + ".offset must be [x, y, z] (metres, in the joint's frame)", o->value);
      for (int k = 0; k < 3; ++k) p.local[k] = number(o->value[k], what + ".offset");
    }
    return p;
  }

  FeatureSide feature_side(const YAML::Node& n, FeatureKind kind, const Skeleton& sk, const std::string& side,
                           const std::string& what) const {
    FeatureSide f;
    if (kind != FeatureKind::Direction) {
      f.point = point_ref(n, sk, side, what);
      return f;
    }
    if (!n.IsMap()) fail(what + " of a direction must be {from: POINT, to: POINT}", n);
    const auto es = entries(n, what);
    check_keys(es, what, {"from", "to"});
    const Entry* a = find(es, "from");
    const Entry* b = find(es, "to");
    if (!a || !b) fail(what + " of a direction needs both 'from' and 'to'", n);
    f.point = point_ref(a->value, sk, side, what + ".from");
    f.to = point_ref(b->value, sk, side, what + ".to");
    return f;
  }

  void pairs(const YAML::Node& n, SkeletonMap& m) const {
    if (!n || n.IsNull()) return;
    if (!n.IsSequence()) fail("'pairs' must be a list", n);
    const std::vector<FeaturePair> from_chains = chain_pairs(m.source.chains, m.target.chains);
    std::set<std::string> names;
    for (const FeaturePair& p : from_chains) names.insert(p.name);
    std::set<std::string> changed;
    for (std::size_t i = 0; i < n.size(); ++i) {
      const YAML::Node& e = n[i];
      const std::string what = "pairs[" + std::to_string(i) + "]";
      if (!e.IsMap()) fail(what + " must be a map (kind, source, target, weight or hard)", e);
      const auto es = entries(e, what);
      check_keys(es, what, {"name", "kind", "source", "target", "weight", "hard"});
      const Entry* name = find(es, "name");
      const Entry* weight = find(es, "weight");
      const Entry* hard = find(es, "hard");
      double w = 1;
      if (weight) w = positive(weight->value, what + ".weight");
      int h = -1;
      if (hard) {
        bool b = false;
        if (!YAML::convert<bool>::decode(hard->value, b))
          fail(what + ".hard must be true or false", hard->value);
        h = b ? 1 : 0;
      }
      if (hard && weight && h == 1)
        fail(what + ": a hard pair holds exactly and takes no weight", weight->key_node);
      if (!find(es, "kind") && !find(es, "source") && !find(es, "target")) {
        if (!name)
          fail(what + ": a pair needs kind, source and target (or a chain pair's name to change it)", e);
        const std::string nm = text(name->value, what + ".name");
        if (std::find_if(from_chains.begin(), from_chains.end(),
                         [&](const FeaturePair& p) { return p.name == nm; }) == from_chains.end()) {
          std::vector<std::string> all(names.begin(), names.end());
          const std::string near = kg::nearest_name(nm, all);
          fail(what + ": no chain pair is named " + kg::text::in_quotes(nm) +
                   (near.empty() ? "" : " (did you mean " + kg::text::in_quotes(near) + "?)") +
                   "; a pair of your own needs kind, source and target",
               name->value);
        }
        if (!changed.insert(nm).second)
          fail(what + ": " + kg::text::in_quotes(nm) + " is changed twice", name->value);
        m.changes.push_back({nm, weight ? w : 0.0, h});
        continue;
      }
      FeaturePair p;
      const Entry* kind = find(es, "kind");
      if (!kind) fail(what + ": missing 'kind' (position, direction or orientation)", e);
      const std::string k = text(kind->value, what + ".kind");
      if (k == "position") {
        p.kind = FeatureKind::Position;
      } else if (k == "direction") {
        p.kind = FeatureKind::Direction;
      } else if (k == "orientation") {
        p.kind = FeatureKind::Orientation;
      } else {
        fail(what + ".kind: unknown kind " + kg::text::in_quotes(k) +
                 " (expected position, direction or orientation)",
             kind->value);
      }
      const Entry* s = find(es, "source");
      const Entry* t = find(es, "target");
      if (!s || !t) fail(what + ": needs both 'source' and 'target'", e);
      p.source = feature_side(s->value, p.kind, *source_, "source", what + ".source");
      p.target = feature_side(t->value, p.kind, *target_, "target", what + ".target");
      p.weight = w;
      p.hard = h == 1;
      if (name) {
        p.name = text(name->value, what + ".name");
      } else {
        p.name = std::string(to_string(p.kind)) + " " + source_->joint(p.source.point.joint).name + " -> " +
                 target_->joint(p.target.point.joint).name;
      }
      if (!names.insert(p.name).second)
        fail(
            what + ": a pair named " + kg::text::in_quotes(p.name) + " already exists (names must be unique)",
            name ? name->value : e);
      m.pairs.push_back(std::move(p));
    }
  }

  SkeletonMap read(std::string_view text_in) const {
    const YAML::Node root = load(text_in, "empty skeleton map (expected version: 1, source, target)");
    const auto top = entries(root, "the skeleton map");
    check_keys(top, "the skeleton map", {"version", "doc", "source", "target", "pairs"});
    check_version(top);
    SkeletonMap m;
    m.path = path();
    for (const char* side : {"source", "target"}) {
      const Entry* e = find(top, side);
      if (!e) throw kg::Error(std::string("missing '") + side + "' (its file and chains)", {path(), 1, 1});
      SkeletonMapSide& out = side == std::string("source") ? m.source : m.target;
      const Skeleton& sk = side == std::string("source") ? *source_ : *target_;
      if (!e->value.IsMap()) fail(std::string(side) + " must be a map (file, chains)", e->value);
      const auto es = entries(e->value, side);
      check_keys(es, side, {"file", "chains"});
      if (const Entry* f = find(es, "file")) out.file = text(f->value, std::string(side) + ".file");
      if (const Entry* c = find(es, "chains"))
        out.chains = chains(c->value, sk, side, std::string(side) + ".chains");
    }
    if (const Entry* p = find(top, "pairs")) pairs(p->value, m);
    return m;
  }

  SkeletonChains preset(std::string_view text_in, const Skeleton& sk) const {
    const YAML::Node root = load(text_in, "empty chains preset (expected version: 1 and chains)");
    const auto top = entries(root, "the chains preset");
    check_keys(top, "the chains preset", {"version", "doc", "chains"});
    check_version(top);
    const Entry* c = find(top, "chains");
    if (!c) throw kg::Error("missing 'chains'", {path(), 1, 1});
    return chains(c->value, sk, "preset's", "chains");
  }

 private:
  const Skeleton* source_;
  const Skeleton* target_;
};

// A joint name as a YAML scalar: plain when that reads back as the same string.
std::string yaml_name(const std::string& s) {
  YAML::Emitter e;
  e << s;
  return e.c_str();
}

void write_chains(std::ostream& os, const SkeletonChains& c, const Skeleton& sk, const std::string& indent) {
  auto list = [&](const std::vector<int>& js) {
    std::vector<std::string> names;
    for (int j : js) names.push_back(yaml_name(sk.joint(j).name));
    return "[" + kg::text::join(names, ", ") + "]";
  };
  bool any = false;
  auto line = [&](const std::string& s) {
    os << indent << s << '\n';
    any = true;
  };
  if (c.pelvis >= 0) line("pelvis: " + yaml_name(sk.joint(c.pelvis).name));
  if (!c.spine.empty()) line("spine: " + list(c.spine));
  if (!c.neck.empty()) line("neck: " + list(c.neck));
  const char* sides[] = {"left", "right"};
  for (int leg = 1; leg >= 0; --leg)
    for (int k = 0; k < 2; ++k) {
      const Limb& l = leg ? c.legs[k] : c.arms[k];
      if (!l.found()) continue;
      std::vector<std::string> roles;
      for (const LimbRole& r : limb_role_table(leg != 0))
        if (l.*r.joint >= 0)
          roles.push_back(std::string(r.name) + ": " + yaml_name(sk.joint(l.*r.joint).name));
      line(std::string(sides[k]) + (leg ? "_leg" : "_arm") + ": {" + kg::text::join(roles, ", ") + "}");
    }
  if (!any) os << indent << "{}\n";
}

std::string point_text(const PointRef& p, const Skeleton& sk) {
  if (p.local.isZero(0)) return yaml_name(sk.joint(p.joint).name);
  return "{joint: " + yaml_name(sk.joint(p.joint).name) + ", offset: [" +
         kg::text::format_double(p.local.x()) + ", " + kg::text::format_double(p.local.y()) + ", " +
         kg::text::format_double(p.local.z()) + "]}";
}

std::string side_text(const FeaturePair& p, const FeatureSide& f, const Skeleton& sk) {
  if (p.kind != FeatureKind::Direction) return point_text(f.point, sk);
  return "{from: " + point_text(f.point, sk) + ", to: " + point_text(f.to, sk) + "}";
}

}  // namespace

std::vector<FeaturePair> feature_pairs(const SkeletonMap& map) {
  std::vector<FeaturePair> out = chain_pairs(map.source.chains, map.target.chains);
  for (const SkeletonMap::Change& c : map.changes) {
    auto it = std::find_if(out.begin(), out.end(), [&](const FeaturePair& p) { return p.name == c.name; });
    if (it == out.end()) throw std::invalid_argument("skeleton map: no chain pair is named '" + c.name + "'");
    if (c.weight > 0) it->weight = c.weight;
    if (c.hard >= 0) it->hard = c.hard == 1;
  }
  out.insert(out.end(), map.pairs.begin(), map.pairs.end());
  return out;
}

SkeletonMap parse_skeleton_map(std::string_view text, const std::string& path, const Skeleton& source,
                               const Skeleton& target) {
  return MapReader(path, &source, &target).read(text);
}

SkeletonMap read_skeleton_map(const std::string& path, const Skeleton& source, const Skeleton& target) {
  return parse_skeleton_map(kg::read_input_file(path, "skeleton map"), path, source, target);
}

SkeletonChains parse_chains_preset(std::string_view text, const std::string& path, const Skeleton& skeleton) {
  return MapReader(path, &skeleton, &skeleton).preset(text, skeleton);
}

void write_skeleton_map(std::ostream& os, const SkeletonMap& map, const Skeleton& source,
                        const Skeleton& target) {
  os << "# A skeleton map (kg/retarget/skeleton_map.hpp): the chains of each skeleton, paired by name;\n"
        "# each chain both sides have gives its feature pairs (pelvis.position, left_leg.ankle, ...).\n"
        "# Edit the joints, add pairs of your own, or change a chain pair's weight:\n"
        "#   pairs:\n"
        "#     - {name: left_leg.ankle, weight: 10}\n"
        "#     - {kind: position, source: {joint: J, offset: [0, 0, 0.1]}, target: J2, hard: true}\n"
        "version: 1\n";
  for (int k = 0; k < 2; ++k) {
    const SkeletonMapSide& s = k == 0 ? map.source : map.target;
    const Skeleton& sk = k == 0 ? source : target;
    os << (k == 0 ? "source:\n" : "target:\n");
    if (!s.file.empty()) os << "  file: " << yaml_name(s.file) << '\n';
    os << "  chains:\n";
    write_chains(os, s.chains, sk, "    ");
  }
  if (map.pairs.empty() && map.changes.empty()) {
    os << "pairs: []\n";
    return;
  }
  os << "pairs:\n";
  for (const SkeletonMap::Change& c : map.changes) {
    os << "  - {name: " << yaml_name(c.name);
    if (c.weight > 0 && c.hard != 1)
      os << ", weight: " << kg::text::format_double(c.weight);  // hard takes none
    if (c.hard >= 0) os << ", hard: " << (c.hard ? "true" : "false");
    os << "}\n";
  }
  for (const FeaturePair& p : map.pairs) {
    os << "  - {name: " << yaml_name(p.name) << ", kind: " << to_string(p.kind)
       << ", source: " << side_text(p, p.source, source) << ", target: " << side_text(p, p.target, target);
    if (p.hard) {
      os << ", hard: true}\n";
    } else {
      os << ", weight: " << kg::text::format_double(p.weight) << "}\n";
    }
  }
}

Eigen::Matrix3d body_frame(const SkeletonChains& chains, const Skeleton& skeleton, const std::string& side) {
  const std::vector<Eigen::Vector3d> p = skeleton.rest_world_origins();
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  for (const auto* limbs : {&chains.legs, &chains.arms}) {
    const Limb &l = (*limbs)[kLeft], &r = (*limbs)[kRight];
    if (l.upper < 0 || r.upper < 0 || l.upper >= skeleton.joint_count() || r.upper >= skeleton.joint_count())
      continue;
    Eigen::Vector3d d = p[l.upper] - p[r.upper];
    d -= d.dot(up) * up;
    if (d.norm() > 1e-9) {
      Eigen::Matrix3d f;
      f.col(0) = d.normalized();
      f.col(1) = up;
      f.col(2) = f.col(0).cross(up);
      return f;
    }
  }
  throw std::invalid_argument(
      "skeleton map: the " + side +
      " chains give no left (neither legs nor arms on both sides), which an orientation "
      "pair and the adapted figure need");
}

std::vector<Eigen::Matrix3d> rest_offsets(const SkeletonMap& map, const std::vector<FeaturePair>& pairs,
                                          const Skeleton& source, const Skeleton& target) {
  std::vector<Eigen::Matrix3d> out(pairs.size(), Eigen::Matrix3d::Identity());
  const std::vector<Eigen::Vector3d> ps = source.rest_world_origins(), pt = target.rest_world_origins();
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  // The joint's own axis: world up on the body's trunk, else toward its child reaching furthest.
  auto own_axis = [&](const SkeletonChains& c, const Skeleton& sk, const std::vector<Eigen::Vector3d>& p,
                      int j) {
    const bool trunk = j == c.pelvis || std::count(c.spine.begin(), c.spine.end(), j) > 0 ||
                       std::count(c.neck.begin(), c.neck.end(), j) > 0;
    if (!trunk) {
      // A child at the joint's own origin (a twist or helper joint) gives no axis: look past it.
      int best = furthest_child(sk, j);
      while (best >= 0 && (p[best] - p[j]).norm() <= 1e-9) best = furthest_child(sk, best);
      if (best >= 0) return Eigen::Vector3d((p[best] - p[j]).normalized());
      for (const Eigen::Vector3d& e : sk.joint(j).end_sites)
        if (e.norm() > 1e-9) return Eigen::Vector3d((sk.file_to_world * e).normalized());
    }
    return up;
  };
  auto frame = [&](const Eigen::Vector3d& left, const Eigen::Vector3d& axis) {
    // Columns: left (made orthogonal to the axis), the axis, across.
    Eigen::Vector3d y = axis.normalized();
    Eigen::Vector3d x = left - left.dot(y) * y;
    if (x.norm() < 1e-6) x = y.unitOrthogonal();
    x.normalize();
    Eigen::Matrix3d f;
    f.col(0) = x;
    f.col(1) = y;
    f.col(2) = x.cross(y);
    return f;
  };
  bool need = false;
  for (const FeaturePair& p : pairs) need = need || p.kind == FeatureKind::Orientation;
  if (!need) return out;
  const Eigen::Vector3d ls = body_frame(map.source.chains, source, "source").col(0),
                        lt = body_frame(map.target.chains, target, "target").col(0);
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const FeaturePair& p = pairs[i];
    if (p.kind != FeatureKind::Orientation) continue;
    const int js = p.source.point.joint, jt = p.target.point.joint;
    // Rest world rotations are file_to_world (every rotation channel zero).
    const Eigen::Matrix3d as =
        source.file_to_world.transpose() * frame(ls, own_axis(map.source.chains, source, ps, js));
    const Eigen::Matrix3d at =
        target.file_to_world.transpose() * frame(lt, own_axis(map.target.chains, target, pt, jt));
    out[i] = as * at.transpose();
  }
  return out;
}

}  // namespace kg::retarget
