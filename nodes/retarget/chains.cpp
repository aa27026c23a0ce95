// find_chains and propose_map (skeleton_map.hpp): a humanoid's chains from its tree, names and
// rest pose, every decision said with its evidence.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <functional>
#include <initializer_list>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "kg/base/text.hpp"
#include "kg/retarget/skeleton_map.hpp"

namespace kg::retarget {

namespace {

using motion::Skeleton;

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::string metres(double x) {
  return kg::text::significant(x, 3) + " m";
}

struct Tree {
  const Skeleton& sk;
  std::vector<std::vector<int>> children;
  std::vector<double> reach;          // longest path below a joint's origin (offsets and End Sites), m
  std::vector<int> count;             // joints in the subtree, itself included
  std::vector<Eigen::Vector3d> rest;  // world rest positions
  double tiny = 0;                    // joints closer than this are at one point: 1e-5 of the figure's size

  explicit Tree(const Skeleton& s)
      : sk(s),
        children(s.joint_count()),
        reach(s.joint_count(), 0.0),
        count(s.joint_count(), 1),
        rest(s.rest_world_origins()) {
    for (int j = 0; j < s.joint_count(); ++j)
      if (s.joint(j).parent >= 0) children[s.joint(j).parent].push_back(j);
    for (int j = s.joint_count() - 1; j >= 0; --j) {
      for (const Eigen::Vector3d& e : s.joint(j).end_sites) reach[j] = std::max(reach[j], e.norm());
      for (int c : children[j]) {
        reach[j] = std::max(reach[j], limb_length(c));
        count[j] += count[c];
      }
    }
    for (int j = 0; j < s.joint_count(); ++j)
      if (s.joint(j).parent < 0) tiny = std::max(tiny, 1e-5 * reach[j]);
  }
  // From the parent's origin to the furthest point below c.
  double limb_length(int c) const { return sk.joint(c).offset.norm() + reach[c]; }
  bool in_subtree(int j, int top) const {
    for (; j >= 0; j = sk.joint(j).parent)
      if (j == top) return true;
    return false;
  }
  int furthest_child(int j) const {
    if (children[j].empty()) return -1;
    int best = children[j].front();
    for (int c : children[j])
      if (limb_length(c) > limb_length(best) + 1e-12) best = c;
    return best;
  }
  // From `first` down through the child reaching furthest, to a leaf.
  std::vector<int> path_from(int first) const {
    std::vector<int> path{first};
    for (int j = furthest_child(first); j >= 0; j = furthest_child(j)) path.push_back(j);
    return path;
  }
  const std::string& name(int j) const { return sk.joint(j).name; }
};

// Which of two mirrored names is the left one: 0 (a), 1 (b), or nullopt when they do not differ
// by a side marker. A marker is "left"/"right" or "l"/"r" in any case at the one place they
// differ: "lfemur"/"rfemur", "UpperLeg_L"/"UpperLeg_R", "left_hip_pitch_joint"/"right_...".
std::optional<int> left_by_name(const std::string& a, const std::string& b) {
  const std::string la = lower(a), lb = lower(b);
  for (const auto& [l, r] : {std::pair<std::string, std::string>{"left", "right"}, {"l", "r"}}) {
    for (int swap = 0; swap < 2; ++swap) {
      const std::string& x = swap ? lb : la;
      const std::string& y = swap ? la : lb;
      for (std::size_t i = x.find(l); i != std::string::npos; i = x.find(l, i + 1))
        if (x.substr(0, i) + r + x.substr(i + l.size()) == y) return swap;
    }
  }
  return std::nullopt;
}

bool has_any(const std::string& lowered, std::initializer_list<const char*> words) {
  for (const char* w : words)
    if (lowered.find(w) != std::string::npos) return true;
  return false;
}

// The name without side markers and separators, lowercased: "LeftUpLeg" -> "upleg", "lfemur" ->
// "femur" (given its mirror "rfemur").
std::string core_name(const std::string& name, const std::string& mirror) {
  std::string n = lower(name);
  if (!mirror.empty()) {
    const std::string m = lower(mirror);
    std::size_t pre = 0;
    while (pre < n.size() && pre < m.size() && n[pre] == m[pre]) ++pre;
    std::size_t suf = 0;
    while (suf < n.size() - pre && suf < m.size() - pre && n[n.size() - 1 - suf] == m[m.size() - 1 - suf])
      ++suf;
    n = n.substr(0, pre) + n.substr(n.size() - suf);
    for (const char* marker : {"left", "right"})
      if (const std::size_t i = n.find(marker); i != std::string::npos)
        n.erase(i, std::string(marker).size());
  }
  std::string out;
  for (char c : n)
    if (std::isalpha(static_cast<unsigned char>(c))) out += c;
  return out;
}

struct LimbWords {
  const char* kind;  // "leg" | "arm"
  std::initializer_list<const char*> middle, upper_first, upper_second, lower, end, root;
  const char* middle_exact;  // a core name that is the middle joint by itself ("leg": Mixamo's knee)
  const char* upper_exact;   // ("arm": Mixamo's shoulder)
};

const LimbWords kLegWords{"leg",
                          {"knee", "shin", "calf", "tibia", "lowerleg"},
                          {"thigh", "femur", "upleg", "upperleg"},
                          {"hip"},
                          {"ankle", "foot"},
                          {"toe", "ball"},
                          {},
                          "leg",
                          ""};
const LimbWords kArmWords{"arm",
                          {"elbow", "forearm", "radius", "lowerarm"},
                          {"upperarm", "humerus", "shldr"},
                          {"shoulder"},
                          {"wrist", "hand"},
                          {},
                          {"clavicle", "collar", "shoulder"},
                          "",
                          "arm"};

// Roles along one limb's path. `mirror` is the other limb's path (for side-free names; may be
// shorter or empty). Notes say how each role was decided.
Limb limb_roles(const Tree& t, const std::vector<int>& path, const std::vector<int>& mirror,
                const LimbWords& w, const std::string& label, std::vector<std::string>& notes) {
  Limb limb;
  limb.path = path;
  const int n = static_cast<int>(path.size());
  std::vector<std::string> core(n);
  for (int i = 0; i < n; ++i)
    core[i] = core_name(t.name(path[i]), i < static_cast<int>(mirror.size()) ? t.name(mirror[i]) : "");
  auto seg = [&](int i) { return t.sk.joint(path[i]).offset.norm(); };
  const double tiny = t.tiny;
  auto movable = [&](int i) { return !t.sk.joint(path[i]).channels.empty() && seg(i) > tiny; };

  int mid = -1;
  for (int i = 1; i < n && mid < 0; ++i)
    if (has_any(core[i], w.middle) || (*w.middle_exact && core[i] == w.middle_exact)) mid = i;
  std::string how;
  if (mid >= 0) {
    how = "named";
  } else {
    // The two adjacent non-zero segments whose shorter one is longest: thigh and shin.
    std::vector<int> nonzero;
    for (int i = 0; i < n; ++i)
      if (seg(i) > tiny) nonzero.push_back(i);
    double best = 0;
    for (std::size_t k = 0; k + 1 < nonzero.size(); ++k) {
      const double m = std::min(seg(nonzero[k]), seg(nonzero[k + 1]));
      if (m > best && nonzero[k] > 0) {
        best = m;
        mid = nonzero[k];
      }
    }
    how = "by segment lengths (names did not tell): " + metres(seg(mid < 0 ? 0 : mid)) + " into it";
  }
  if (mid < 0) {
    notes.push_back(label + ": no " + (w.kind == std::string("leg") ? "knee" : "elbow") + " found on " +
                    t.name(path.front()) + "'s path");
    return limb;
  }
  limb.middle = path[mid];

  int up = -1;
  for (const auto* words : {&w.upper_first, &w.upper_second}) {
    for (int i = 0; i < mid && up < 0; ++i)
      if (movable(i) && (has_any(core[i], *words) || (*w.upper_exact && core[i] == w.upper_exact))) up = i;
    if (up >= 0) break;
  }
  if (up < 0) {  // the joint starting the last non-zero segment into the middle one
    int k = mid;
    while (k > 0 && seg(k) <= tiny) --k;
    if (k > 0) up = k - 1;
  }
  if (up >= 0) limb.upper = path[up];

  int low = -1;
  for (int i = mid + 1; i < n && low < 0; ++i)
    if (has_any(core[i], w.lower)) low = i;
  if (low < 0)
    for (int i = mid + 1; i < n && low < 0; ++i)
      if (seg(i) > tiny) low = i;
  if (low < 0 && !t.sk.joint(path[mid]).end_sites.empty()) low = mid;  // a chain ending at its middle
  if (low >= 0 && low != mid) limb.lower = path[low];

  if (w.end.size() > 0 && low >= 0 && low != mid) {
    int e = -1;
    for (int i = low + 1; i < n && e < 0; ++i)
      if (has_any(core[i], w.end)) e = i;
    if (e < 0 && low + 1 < n && seg(low + 1) > tiny) e = low + 1;
    if (e >= 0) limb.end = path[e];
  }
  if (w.root.size() > 0 && up > 0) {
    for (int i = 0; i < up && limb.root < 0; ++i)
      if (has_any(core[i], w.root)) limb.root = path[i];
    if (limb.root < 0)
      for (int i = 0; i < up && limb.root < 0; ++i)
        if (movable(i)) limb.root = path[i];
  }
  std::string line = label + ":";
  for (const LimbRole& r : limb_role_table(w.kind == std::string("leg")))
    if (limb.*r.joint >= 0) line += std::string(" ") + r.name + " " + t.name(limb.*r.joint);
  notes.push_back(line + " (" + (w.kind == std::string("leg") ? "knee " : "elbow ") + how + ")");
  if (w.kind == std::string("leg")) limb.foot = limb.end >= 0 ? t.sk.joint(limb.end).parent : limb.lower;
  return limb;
}

struct MirrorPair {
  int parent = -1, a = -1, b = -1;
  double length = 0;  // the shorter limb's length, m
};

// Sibling subtrees of equal joint count and length (5%), longest first.
std::vector<MirrorPair> mirror_pairs(const Tree& t) {
  std::vector<MirrorPair> out;
  for (int p = 0; p < t.sk.joint_count(); ++p) {
    const std::vector<int>& c = t.children[p];
    for (std::size_t i = 0; i < c.size(); ++i)
      for (std::size_t k = i + 1; k < c.size(); ++k) {
        const double la = t.limb_length(c[i]), lb = t.limb_length(c[k]);
        if (t.count[c[i]] != t.count[c[k]] || std::max(la, lb) <= 0) continue;
        if (std::abs(la - lb) > 0.05 * std::max(la, lb)) continue;
        out.push_back({p, c[i], c[k], std::min(la, lb)});
      }
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const MirrorPair& x, const MirrorPair& y) { return x.length > y.length; });
  return out;
}

}  // namespace

SkeletonChains find_chains(const Skeleton& sk) {
  SkeletonChains out;
  if (sk.joint_count() == 0) {
    out.missing.push_back("the skeleton has no joints");
    return out;
  }
  const Tree t(sk);
  const std::vector<MirrorPair> pairs = mirror_pairs(t);
  if (pairs.empty()) {
    out.missing.push_back(
        "no pair of mirrored limbs (sibling subtrees of equal length and joint count): not a humanoid?");
    return out;
  }
  const MirrorPair legs = pairs.front();
  std::optional<MirrorPair> arms;
  for (const MirrorPair& p : pairs) {
    if (p.parent == legs.parent && p.a == legs.a) continue;
    if (t.in_subtree(p.parent, legs.a) || t.in_subtree(p.parent, legs.b)) continue;
    if (t.in_subtree(legs.parent, p.a) || t.in_subtree(legs.parent, p.b)) continue;
    arms = p;
    break;
  }
  out.pelvis = legs.parent;
  out.notes.push_back("pelvis " + t.name(legs.parent) + ": the legs " + t.name(legs.a) + " and " +
                      t.name(legs.b) + " branch from it (the longest mirrored pair, " + metres(legs.length) +
                      ")");

  // Sides: names, else the rest pose (toes point forward; left = up x forward).
  const std::vector<int> leg_a = t.path_from(legs.a), leg_b = t.path_from(legs.b);
  Limb la = limb_roles(t, leg_a, leg_b, kLegWords, "leg " + t.name(legs.a), out.notes);
  Limb lb = limb_roles(t, leg_b, leg_a, kLegWords, "leg " + t.name(legs.b), out.notes);
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  Eigen::Vector3d forward = Eigen::Vector3d::Zero();
  for (const Limb* l : {&la, &lb}) {
    if (l->lower < 0) continue;
    const int last = l->path.back();
    Eigen::Vector3d tip = t.rest[last];
    for (const Eigen::Vector3d& e : sk.joint(last).end_sites) tip = t.rest[last] + sk.file_to_world * e;
    Eigen::Vector3d d = tip - t.rest[l->lower];
    d -= d.dot(up) * up;
    forward += d;
  }
  auto side_of = [&](int a, int b, const std::string& what) -> int {
    if (const std::optional<int> by_name = left_by_name(t.name(a), t.name(b))) {
      out.notes.push_back(what + ": left is " + t.name(*by_name == 0 ? a : b) + " (by name)");
      return *by_name;
    }
    const Eigen::Vector3d left_dir = up.cross(forward);
    const double s = (t.rest[a] - t.rest[b]).dot(left_dir);
    if (forward.norm() > t.tiny && std::abs(s) > t.tiny * forward.norm()) {
      out.notes.push_back(what + ": left is " + t.name(s > 0 ? a : b) +
                          " (by the rest pose: the toes point forward, left = up x forward)");
      return s > 0 ? 0 : 1;
    }
    out.notes.push_back(what +
                        ": cannot tell left from right (no side in the names, no forward toes); took " +
                        t.name(a) + " as left: swap the sides in the map if wrong");
    return 0;
  };
  const int leg_left = side_of(legs.a, legs.b, "legs");
  out.legs[kLeft] = leg_left == 0 ? la : lb;
  out.legs[kRight] = leg_left == 0 ? lb : la;
  for (int s = 0; s < 2; ++s)
    if (!out.legs[s].found())
      out.missing.push_back(std::string(s == kLeft ? "left" : "right") + "_leg: roles not found");

  if (!arms) {
    out.missing.push_back("arms: no second mirrored pair outside the legs");
    return out;
  }
  const int chest = arms->parent;
  out.notes.push_back("chest " + t.name(chest) + ": the arms " + t.name(arms->a) + " and " + t.name(arms->b) +
                      " branch from it (" + metres(arms->length) + ")");
  const std::vector<int> arm_a = t.path_from(arms->a), arm_b = t.path_from(arms->b);
  Limb aa = limb_roles(t, arm_a, arm_b, kArmWords, "arm " + t.name(arms->a), out.notes);
  Limb ab = limb_roles(t, arm_b, arm_a, kArmWords, "arm " + t.name(arms->b), out.notes);
  const int arm_left = side_of(arms->a, arms->b, "arms");
  out.arms[kLeft] = arm_left == 0 ? aa : ab;
  out.arms[kRight] = arm_left == 0 ? ab : aa;
  for (int s = 0; s < 2; ++s)
    if (!out.arms[s].found())
      out.missing.push_back(std::string(s == kLeft ? "left" : "right") + "_arm: roles not found");

  // The pelvis carries legs and spine: when the spine does not start below the legs' parent
  // (iClone's CC_Base_Pelvis holds only the legs, its parent CC_Base_Hip the waist too), it is
  // the lowest joint above both.
  if (!t.in_subtree(chest, out.pelvis)) {
    int common = out.pelvis;
    while (common >= 0 && !t.in_subtree(chest, common)) common = sk.joint(common).parent;
    if (common >= 0) {
      out.notes.push_back("pelvis " + t.name(common) + " instead: the legs' parent " + t.name(out.pelvis) +
                          " does not carry the chest " + t.name(chest) + "; " + t.name(common) +
                          " carries both");
      out.pelvis = common;
    }
  }
  // Spine: the tree path from the pelvis up to the chest.
  if (t.in_subtree(chest, out.pelvis)) {
    for (int j = chest; j != out.pelvis; j = sk.joint(j).parent) out.spine.push_back(j);
    std::reverse(out.spine.begin(), out.spine.end());
    if (out.spine.empty())
      out.notes.push_back("spine: the arms branch from the pelvis itself (no spine joints)");
  } else {
    out.missing.push_back("spine: the chest " + t.name(chest) + " is not below the pelvis " +
                          t.name(out.pelvis));
  }

  // Neck: the chest's other child reaching furthest, down to the head.
  int neck = -1;
  for (int c : t.children[chest]) {
    if (c == arms->a || c == arms->b || t.in_subtree(out.pelvis, c) || c == legs.a || c == legs.b) continue;
    if (neck < 0 || t.limb_length(c) > t.limb_length(neck)) neck = c;
  }
  if (neck < 0) {
    out.missing.push_back("neck: the chest " + t.name(chest) + " has no child besides the arms");
    return out;
  }
  const std::vector<int> path = t.path_from(neck);
  int head = -1;
  for (std::size_t i = 0; i < path.size() && head < 0; ++i)
    if (lower(t.name(path[i])).find("head") != std::string::npos) head = static_cast<int>(i);
  std::string how = "named";
  if (head < 0) {
    how = "the path's end before it branches";
    head = static_cast<int>(path.size()) - 1;
    for (std::size_t i = 0; i < path.size(); ++i)
      if (t.children[path[i]].size() >= 2) {
        head = static_cast<int>(i);
        break;
      }
  }
  out.neck.assign(path.begin(), path.begin() + head + 1);
  out.notes.push_back("neck " + t.name(neck) + " to head " + t.name(path[head]) + " (" + how + ")");
  return out;
}

namespace {

std::string chain_text(const Skeleton& s, const std::vector<int>& joints) {
  std::vector<std::string> names;
  for (int j : joints)
    if (j >= 0) names.push_back(s.joint(j).name);
  return kg::text::join(names, ", ");
}

std::vector<const char*> role_names(bool leg) {
  std::vector<const char*> out;
  for (const LimbRole& r : limb_role_table(leg)) out.push_back(r.name);
  return out;
}

std::vector<int> limb_joints(const Limb& l, bool leg) {
  std::vector<int> out;
  for (const LimbRole& r : limb_role_table(leg)) out.push_back(l.*r.joint);
  return out;
}

}  // namespace

int furthest_child(const Skeleton& sk, int joint) {
  if (joint < 0 || joint >= sk.joint_count())
    throw std::out_of_range("furthest_child: joint " + std::to_string(joint) + " out of range");
  return Tree(sk).furthest_child(joint);
}

ProposedMap propose_map(const Skeleton& source, const Skeleton& target, const std::string& source_file,
                        const std::string& target_file) {
  ProposedMap out;
  out.map.source = {source_file, find_chains(source)};
  out.map.target = {target_file, find_chains(target)};
  const SkeletonChains& s = out.map.source.chains;
  const SkeletonChains& t = out.map.target.chains;
  for (const std::string& n : s.notes) out.notes.push_back("source: " + n);
  for (const std::string& n : t.notes) out.notes.push_back("target: " + n);
  // `roles` names a limb's entries (a and b in the role table's order) to say which one side lacks.
  auto pair_line = [&](const std::string& name, const std::vector<int>& a, const std::vector<int>& b,
                       const std::vector<const char*>& roles = {}) {
    const bool has_a = std::any_of(a.begin(), a.end(), [](int j) { return j >= 0; });
    const bool has_b = std::any_of(b.begin(), b.end(), [](int j) { return j >= 0; });
    if (has_a && has_b) {
      std::string line = name + ": " + chain_text(source, a) + " -> " + chain_text(target, b);
      if (!roles.empty() && a.size() == roles.size() && b.size() == roles.size()) {
        std::vector<std::string> unpaired;
        for (std::size_t r = 0; r < roles.size(); ++r)
          if ((a[r] >= 0) != (b[r] >= 0))
            unpaired.push_back(
                std::string(roles[r]) + " (only the " + (a[r] >= 0 ? "source" : "target") +
                " has one: " + (a[r] >= 0 ? source.joint(a[r]).name : target.joint(b[r]).name) + ")");
        if (!unpaired.empty()) line += "; unpaired: " + kg::text::join(unpaired, ", ");
      }
      out.matched.push_back(line);
    } else if (has_a || has_b) {
      out.unmatched.push_back(name + ": only the " + (has_a ? "source" : "target") + " has it (" +
                              (has_a ? chain_text(source, a) : chain_text(target, b)) + ")");
    } else {
      out.unmatched.push_back(name + ": neither skeleton has it");
    }
  };
  pair_line("pelvis", {s.pelvis}, {t.pelvis});
  pair_line("spine", s.spine, t.spine);
  pair_line("neck", s.neck, t.neck);
  const char* sides[] = {"left", "right"};
  for (int k = 0; k < 2; ++k)
    pair_line(std::string(sides[k]) + "_leg", limb_joints(s.legs[k], true), limb_joints(t.legs[k], true),
              role_names(true));
  for (int k = 0; k < 2; ++k)
    pair_line(std::string(sides[k]) + "_arm", limb_joints(s.arms[k], false), limb_joints(t.arms[k], false),
              role_names(false));
  for (const std::string& m : s.missing) out.unmatched.push_back("source: " + m);
  for (const std::string& m : t.missing) out.unmatched.push_back("target: " + m);
  return out;
}

}  // namespace kg::retarget
