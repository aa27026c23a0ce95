// The body model of a skeleton: classes, bones, masses, inertias, overrides and torque limits
// (the rules are in body_build.hpp).
#include "kg/body/body_build.hpp"
#include "kg/base/pattern.hpp"
#include "kg/base/text.hpp"

#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <stdexcept>

#include <Eigen/Eigenvalues>

namespace kg::body {

namespace {

using kg::Error;
using motion::Skeleton;

kg::Pattern compile(const std::string& pattern, const kg::SourceLocation& where, const std::string& what) {
  try {
    return kg::Pattern::compile(pattern);
  } catch (const std::invalid_argument& e) {
    throw Error(what + ": " + e.what(), where);
  }
}

// For each joint, the index of the first pattern matching its whole name (-1: none); for each
// pattern, every joint it matches (taken or shadowed by an earlier pattern).
struct Matches {
  std::vector<int> owner;
  std::vector<std::vector<int>> matched;
};

template <class Rule>
Matches match_first(const Skeleton& skeleton, const std::vector<Rule>& patterns, const std::string& what) {
  Matches m{std::vector<int>(static_cast<std::size_t>(skeleton.joint_count()), -1),
            std::vector<std::vector<int>>(patterns.size())};
  for (std::size_t p = 0; p < patterns.size(); ++p) {
    const kg::Pattern re = compile(patterns[p].pattern, patterns[p].where, what);
    for (int j = 0; j < skeleton.joint_count(); ++j) {
      if (!re.full_match(skeleton.joint(j).name)) continue;
      m.matched[p].push_back(j);
      if (m.owner[static_cast<std::size_t>(j)] < 0)
        m.owner[static_cast<std::size_t>(j)] = static_cast<int>(p);
    }
  }
  return m;
}

template <class Rule>
void require_matches(const Skeleton& skeleton, const std::vector<Rule>& patterns, const Matches& m,
                     const std::string& what) {
  for (std::size_t p = 0; p < patterns.size(); ++p)
    if (m.matched[p].empty())
      throw Error(
          what + " pattern " + text::excerpt(patterns[p].pattern) +
              " matches no joint of the skeleton (the whole name must match; joints: " +
              [&] {
                std::vector<std::string> names;
                for (int j = 0; j < skeleton.joint_count() && j < 12; ++j)
                  names.push_back(skeleton.joint(j).name);
                return text::join(names) + (skeleton.joint_count() > 12 ? ", ..." : "");
              }() +
              ")",
          patterns[p].where);
}

SegmentClass successor(SegmentClass c) {
  switch (c) {
    case SegmentClass::Trunk:
      return SegmentClass::HeadNeck;
    case SegmentClass::UpperArm:
      return SegmentClass::Forearm;
    case SegmentClass::Forearm:
      return SegmentClass::Hand;
    case SegmentClass::Thigh:
      return SegmentClass::Shank;
    case SegmentClass::Shank:
      return SegmentClass::Foot;
    default:
      return SegmentClass::Massless;
  }
}

// Metres: shorter offsets make no bone (files write a joint at its parent's origin as -0.00,
// some as 1e-7).
constexpr double kZeroLength = 1e-4;

// A unit vector perpendicular to u.
Eigen::Vector3d any_perpendicular(const Eigen::Vector3d& u) {
  const Eigen::Vector3d trial = std::abs(u.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  return (trial - trial.dot(u) * u).normalized();
}

// Solid cylinder along unit axis u: mass m, radius r, length l; inertia about its centre.
Eigen::Matrix3d cylinder_inertia(double m, double r, double l, const Eigen::Vector3d& u) {
  const Eigen::Matrix3d along = u * u.transpose();
  return m * ((3 * r * r + l * l) / 12 * (Eigen::Matrix3d::Identity() - along) + r * r / 2 * along);
}

}  // namespace

void check_segment_inertia(const Eigen::Matrix3d& I, const std::string& what) {
  if (!I.allFinite()) throw std::invalid_argument(what + ": inertia is not finite");
  if ((I - I.transpose()).cwiseAbs().maxCoeff() > 1e-9 * std::max(1.0, I.cwiseAbs().maxCoeff()))
    throw std::invalid_argument(what + ": inertia is not symmetric");
  const Eigen::Vector3d ev =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(I, Eigen::EigenvaluesOnly).eigenvalues();
  if (!(ev.minCoeff() > 0))
    throw std::invalid_argument(what + ": inertia is not positive definite (principal moments " +
                                text::significant(ev[0], 4) + ", " + text::significant(ev[1], 4) + ", " +
                                text::significant(ev[2], 4) + " kg m²)");
  // A rigid body's principal moments obey the triangle inequality (each is a sum of two second
  // moments of its mass distribution).
  if (ev[2] > (ev[0] + ev[1]) * (1 + 1e-9))
    throw std::invalid_argument(what + ": no rigid body has these principal moments (" +
                                text::significant(ev[0], 4) + ", " + text::significant(ev[1], 4) + ", " +
                                text::significant(ev[2], 4) +
                                " kg m²: the largest exceeds the sum of the others)");
}

namespace {

void check_spec(const BodySpec& spec) {
  const std::string table = to_string(spec.table);
  if (!std::isfinite(spec.mass) || spec.mass < 0)
    throw std::invalid_argument("body mass " + text::significant(spec.mass, 4) +
                                ": expected a finite number of kg");
  if (spec.table != BodyTable::Cylinders && !(spec.mass > 0))
    throw std::invalid_argument("body mass " + text::significant(spec.mass, 4) + " kg with table " + table +
                                ": expected > 0 (0 means 'from the volumes' only with cylinders)");
  for (int c = 0; c < kSegmentClassCount; ++c) {
    const double r = spec.radii[static_cast<std::size_t>(c)];
    if (!std::isfinite(r) || !(r > 0))
      throw std::invalid_argument(std::string("cylinder radius of ") +
                                  to_string(static_cast<SegmentClass>(c)) + " " + text::significant(r, 4) +
                                  ": expected metres > 0");
  }
  if (!std::isfinite(spec.friction) || spec.friction < 0)
    throw std::invalid_argument("friction " + text::significant(spec.friction, 4) +
                                ": expected a finite number >= 0");
  if (!spec.gravity.allFinite()) throw std::invalid_argument("gravity: expected a finite vector (m/s²)");
  for (const SegmentOverride& o : spec.segments) {
    const std::string what = "segments " + text::excerpt(o.pattern);
    auto positive = [&](const std::optional<double>& v, const char* name) {
      if (v && (!std::isfinite(*v) || !(*v > 0)))
        throw Error(what + "." + name + " " + text::significant(*v, 4) + ": expected a finite number > 0",
                    o.where);
    };
    positive(o.mass, "mass");
    positive(o.mass_scale, "mass_scale");
    positive(o.radius, "radius");
    if (o.mass && o.mass_scale) throw Error(what + ": give mass or mass_scale, not both", o.where);
    if (o.com && !o.com->allFinite()) throw Error(what + ".com: expected finite metres", o.where);
    if (o.inertia) {
      try {
        check_segment_inertia(*o.inertia, what + ".inertia");
      } catch (const std::invalid_argument& e) {
        throw Error(e.what(), o.where);
      }
    }
  }
  for (const TorqueLimit& t : spec.torque_limits) {
    if (t.values.empty()) throw Error("torque_limits " + text::excerpt(t.pattern) + ": no value", t.where);
    for (double v : t.values)
      if (std::isnan(v) || !(v > 0))
        throw Error("torque_limits " + text::excerpt(t.pattern) + ": " + text::significant(v, 4) +
                        " is no bound (expected N m > 0, or .inf for unlimited)",
                    t.where);
  }
}

// World rotations and positions of every joint at `frame`.
void pose(const Skeleton& s, motion::FrameRef frame, std::vector<Eigen::Isometry3d>& world) {
  world.assign(static_cast<std::size_t>(s.joint_count()), Eigen::Isometry3d::Identity());
  motion::forward_kinematics(s, frame, world);
}

}  // namespace

const std::vector<ClassPattern>& default_class_patterns() {
  using C = SegmentClass;
  static const std::vector<ClassPattern> patterns = {
      // Helpers first: they must not fall into a limb's run. iClone's neck "twists" are its neck.
      {"CC_Base_NeckTwist[0-9]+", C::HeadNeck},
      {".*(Eye|Jaw|Tongue|Teeth|FacialBone|Breast|RibsTwist|ShareBone).*", C::Massless},
      {"CC_Base_[LR]_(Upperarm|Forearm|Thigh|Calf)Twist[0-9]+", C::Massless},
      {"joint_Root|RL_BoneRoot", C::Massless},  // off-body roots (Bandai's on the floor)
      // Clavicles and hip connectors: their mass is the trunk's.
      {"[lr](clavicle|hipjoint)|[lr](Collar|Buttock)|CC_Base_[LR]_Clavicle|Shoulder_[LR]|[lr]Torso_Clavicle|"
       "(Left|Right)Shoulder",
       C::Massless},
      {"(lower|upper)?neck|head|Neck[0-9]*|Head|CC_Base_Head|torso_head", C::HeadNeck},
      {"root|hip|lowerback|upperback|thorax|abdomen[0-9]*|chest[A-Za-z]*|Hips|Spine[0-9]*|Chest|UpperChest|"
       "CC_Base_(Hip|Pelvis|Waist|Spine[0-9]+)|RootJoint|pelvis_lowerback|lowerback_torso",
       C::Trunk},
      {"[lr]humerus|[lr]Shldr[A-Za-z]*|CC_Base_[LR]_Upperarm|UpperArm_[LR]|[lr]Shoulder|(Left|Right)(Arm|"
       "UpperArm)",
       C::UpperArm},
      {"[lr]radius|[lr]Fore[Aa]rm[A-Za-z]*|CC_Base_[LR]_Forearm|LowerArm_[LR]|[lr]Elbow|(Left|Right)(ForeArm|"
       "LowerArm)",
       C::Forearm},
      {"[lr](wrist|hand|fingers|thumb)|[lr](Hand|Thumb|Index|Mid|Ring|Pinky|Carpal)[0-9]*|"
       "CC_Base_[LR]_(Hand|Thumb|Index|Mid|Ring|Pinky)[0-9]*|Hand_[LR]|[lr]Wrist|(Left|Right)Hand[A-Za-z]*[0-"
       "9]*",
       C::Hand},
      {"[lr]femur|[lr]Thigh[A-Za-z]*|CC_Base_[LR]_Thigh|UpperLeg_[LR]|[lr]Hip|(Left|Right)(UpLeg|UpperLeg|"
       "Thigh)",
       C::Thigh},
      {"[lr]tibia|[lr]Shin[A-Za-z]*|CC_Base_[LR]_Calf|LowerLeg_[LR]|[lr]Knee|(Left|Right)(Leg|LowerLeg|Shin|"
       "Calf)",
       C::Shank},
      {"[lr](foot|toes)|[lr](Foot|Toe)[A-Za-z]*[0-9]*|CC_Base_[LR]_(Foot|ToeBase|[A-Za-z]*Toe[0-9]*)|(Foot|"
       "Toes)_[LR]|"
       "[lr](Ankle|ToeJoint)|(Left|Right)(Foot|ToeBase|Toe[A-Za-z_]*)",
       C::Foot},
  };
  return patterns;
}

std::vector<SegmentClass> classify_joints(const Skeleton& skeleton,
                                          const std::vector<ClassPattern>& patterns) {
  std::vector<ClassPattern> all = patterns;
  const std::vector<ClassPattern>& defaults = default_class_patterns();
  all.insert(all.end(), defaults.begin(), defaults.end());
  const Matches m = match_first(skeleton, all, "classes");
  std::vector<SegmentClass> out(static_cast<std::size_t>(skeleton.joint_count()), SegmentClass::Massless);
  for (std::size_t j = 0; j < out.size(); ++j)
    if (m.owner[j] >= 0) out[j] = all[static_cast<std::size_t>(m.owner[j])].segment_class;
  return out;
}

std::vector<Eigen::Vector3d> segment_bones(const Skeleton& skeleton,
                                           const std::vector<SegmentClass>& classes) {
  const int n = skeleton.joint_count();
  if (static_cast<int>(classes.size()) != n)
    throw std::invalid_argument("segment_bones: " + std::to_string(classes.size()) + " classes for " +
                                std::to_string(n) + " joints");
  std::vector<std::vector<int>> children(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j)
    if (skeleton.joint(j).parent >= 0)
      children[static_cast<std::size_t>(skeleton.joint(j).parent)].push_back(j);
  std::vector<Eigen::Vector3d> bones(static_cast<std::size_t>(n), Eigen::Vector3d::Zero());
  for (int j = 0; j < n; ++j) {
    const SegmentClass c = classes[static_cast<std::size_t>(j)];
    const SegmentClass next = successor(c);
    std::array<std::vector<Eigen::Vector3d>, 4> tiers;
    // A massless child at the joint's origin (a helper such as iClone's FacialBone, CMU's
    // hipjoints) is looked through: its children stand in its place, at their rest positions.
    const std::function<void(int, const Eigen::Vector3d&)> add = [&](int k, const Eigen::Vector3d& base) {
      const Eigen::Vector3d at = base + skeleton.joint(k).offset;
      const SegmentClass ck = classes[static_cast<std::size_t>(k)];
      if (ck == SegmentClass::Massless && at.norm() <= kZeroLength) {
        for (int g : children[static_cast<std::size_t>(k)]) add(g, at);
        return;
      }
      const int tier = (next != SegmentClass::Massless && ck == next) ? 0
                       : (c != SegmentClass::Massless && ck == c)     ? 1
                                                                      : 3;
      tiers[static_cast<std::size_t>(tier)].push_back(at);
    };
    for (int k : children[static_cast<std::size_t>(j)]) add(k, Eigen::Vector3d::Zero());
    tiers[2] = skeleton.joint(j).end_sites;
    for (const std::vector<Eigen::Vector3d>& tier : tiers) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      int count = 0;
      for (const Eigen::Vector3d& v : tier)
        if (v.norm() > kZeroLength) {
          sum += v;
          ++count;
        }
      if (count > 0) {
        bones[static_cast<std::size_t>(j)] = sum / count;
        break;
      }
    }
  }
  return bones;
}

Eigen::RowVectorXd rest_pose_values(const Skeleton& skeleton) {
  Eigen::RowVectorXd v = Eigen::RowVectorXd::Zero(skeleton.channel_count());
  for (const motion::Joint& j : skeleton.joints())
    for (std::size_t c = 0; c < j.channels.size(); ++c)
      if (!motion::is_rotation(j.channels[c].kind))
        v[j.first_channel + static_cast<int>(c)] = j.offset[motion::axis_index(j.channels[c].kind)];
  return v;
}

namespace {

// Index of joint j in the per-joint vectors.
std::size_t J(int j) {
  return static_cast<std::size_t>(j);
}

// The joints no class pattern matched, and those matched to massless.
struct ClassNames {
  std::vector<std::string> unmatched, massless;
};

// Classes: the spec's patterns (each must match a joint), then the defaults.
ClassNames match_classes(const Skeleton& s, const BodySpec& spec, BuiltBody& out) {
  const int n = s.joint_count();
  std::vector<ClassPattern> all = spec.classes;
  all.insert(all.end(), default_class_patterns().begin(), default_class_patterns().end());
  const Matches user = match_first(s, all, "classes");
  require_matches(s, spec.classes, user, "classes");
  out.classes.assign(J(n), SegmentClass::Massless);
  ClassNames names;
  for (int j = 0; j < n; ++j) {
    const int owner = user.owner[J(j)];
    if (owner >= 0) out.classes[J(j)] = all[J(owner)].segment_class;
    if (owner < 0)
      names.unmatched.push_back(s.joint(j).name);
    else if (out.classes[J(j)] == SegmentClass::Massless)
      names.massless.push_back(s.joint(j).name);
  }
  for (std::size_t p = 0; p < spec.classes.size(); ++p) {
    std::vector<std::string> matched;
    for (int j : user.matched[p])
      if (user.owner[J(j)] == static_cast<int>(p)) matched.push_back(s.joint(j).name);
    out.notes.push_back(
        "classes " + text::excerpt(spec.classes[p].pattern) + " -> " +
        to_string(spec.classes[p].segment_class) + ": " +
        (matched.empty() ? std::string("no joint left (earlier patterns took them)") : text::join(matched)));
  }
  return names;
}

// The joints of a class form its groups: one per head_neck and trunk, the connected runs of each
// limb class.
struct Groups {
  std::vector<int> of_joint;  // -1: massless
  std::vector<SegmentClass> segment_class;
  std::vector<std::vector<int>> joints;
  std::vector<double> length;  // of the joints' bones together
};

Groups group_segments(const Skeleton& s, const BuiltBody& out) {
  const int n = s.joint_count();
  Groups groups;
  groups.of_joint.assign(J(n), -1);
  std::array<int, kSegmentClassCount> single_group;
  single_group.fill(-1);
  for (int j = 0; j < n; ++j) {
    const SegmentClass c = out.classes[J(j)];
    if (c == SegmentClass::Massless) continue;
    const int parent = s.joint(j).parent;
    int g = -1;
    if (!is_paired(c)) {
      g = single_group[J(index_of(c))];
    } else if (parent >= 0 && out.classes[J(parent)] == c) {
      g = groups.of_joint[J(parent)];
    }
    if (g < 0) {
      g = static_cast<int>(groups.segment_class.size());
      groups.segment_class.push_back(c);
      groups.joints.emplace_back();
      if (!is_paired(c)) single_group[J(index_of(c))] = g;
    }
    groups.of_joint[J(j)] = g;
    groups.joints[J(g)].push_back(j);
  }
  groups.length.assign(groups.segment_class.size(), 0.0);
  for (int j = 0; j < n; ++j)
    if (groups.of_joint[J(j)] >= 0) groups.length[J(groups.of_joint[J(j)])] += out.bones[J(j)].norm();
  return groups;
}

// Every table segment must be there: one group (two runs for a limb) with a bone.
void require_table_segments(const Skeleton& s, const Groups& groups, const ClassNames& names) {
  std::vector<std::string> missing;
  for (int c = 0; c < kSegmentClassCount; ++c) {
    const SegmentClass sc = static_cast<SegmentClass>(c);
    std::vector<std::string> runs;
    bool zero = false;
    for (std::size_t g = 0; g < groups.segment_class.size(); ++g) {
      if (groups.segment_class[g] != sc) continue;
      std::vector<std::string> joint_names;
      for (int j : groups.joints[g]) joint_names.push_back(s.joint(j).name);
      runs.push_back(text::join(joint_names, "+"));
      zero = zero || !(groups.length[g] > kZeroLength);
    }
    const std::size_t want = is_paired(sc) ? 2 : 1;
    const std::string name = to_string(sc);
    if (runs.empty())
      missing.push_back(name + " (no joint matched" +
                        (is_paired(sc) ? "; expected a left and a right)" : ")"));
    else if (runs.size() != want)
      missing.push_back(name + " (" + std::to_string(runs.size()) + " separate runs of joints: " +
                        text::join(runs, ", ") + "; expected a left and a right)");
    else if (zero)
      missing.push_back(name + " (" + text::join(runs, ", ") +
                        ": no bone, every joint's children and End Sites are at its origin)");
  }
  if (missing.empty()) return;
  std::vector<std::string> candidates = names.unmatched;
  candidates.insert(candidates.end(), names.massless.begin(), names.massless.end());
  throw std::invalid_argument("the skeleton lacks table segments: " + text::join(missing, "; ") +
                              ". Map its joints to classes in a body file (`file`), joint-name regex (the "
                              "whole name) to class, e.g.\n"
                              "  version: 1\n"
                              "  classes:\n"
                              "    \"LeftUpLeg|RightUpLeg\": thigh\n"
                              "classes: " +
                              text::join(segment_class_names()) + ". Joints without a class: " +
                              (candidates.empty() ? std::string("none") : text::join(candidates)));
}

// Anatomical directions in the reference pose, and every joint's world frame in it.
struct AnatomicalFrame {
  std::vector<Eigen::Isometry3d> world;
  Eigen::Vector3d lateral, forward;
};

AnatomicalFrame anatomical_frame(const Skeleton& s, const Eigen::RowVectorXd* reference_pose,
                                 const Groups& groups, std::vector<std::string>& notes) {
  const Eigen::RowVectorXd rest = rest_pose_values(s);
  const Eigen::RowVectorXd& ref = reference_pose != nullptr ? *reference_pose : rest;
  if (ref.size() != s.channel_count())
    throw std::invalid_argument("build_body_model: reference pose of " + std::to_string(ref.size()) +
                                " values for " + std::to_string(s.channel_count()) + " channels");
  AnatomicalFrame frame;
  pose(s, ref, frame.world);
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  Eigen::Vector3d lateral = Eigen::Vector3d::Zero();
  for (SegmentClass pair : {SegmentClass::Thigh, SegmentClass::UpperArm}) {
    std::vector<Eigen::Vector3d> heads;
    for (std::size_t g = 0; g < groups.segment_class.size(); ++g)
      if (groups.segment_class[g] == pair)
        heads.push_back(frame.world[J(groups.joints[g].front())].translation());
    if (heads.size() != 2) continue;
    Eigen::Vector3d d = heads[0] - heads[1];
    d -= d.dot(up) * up;
    if (d.norm() > 1e-3) {
      lateral = d.normalized();
      break;
    }
  }
  if (lateral.isZero()) {
    lateral = s.file_to_world * Eigen::Vector3d::UnitX();
    lateral -= lateral.dot(up) * up;
    lateral = lateral.norm() > 1e-6 ? lateral.normalized() : Eigen::Vector3d::UnitX();
    notes.push_back(
        "no left/right thighs or upper arms apart in the reference pose: the file's X axis "
        "taken as mediolateral for the inertias' axes");
  }
  frame.lateral = lateral;
  frame.forward = up.cross(lateral).normalized();
  return frame;
}

// A segment of the table's fractions f: its share of the group's mass by bone length (l of the
// group's L), its CoM on the bone, its inertia about the axes across the bone nearest the
// anteroposterior and mediolateral directions (R: the joint's world rotation in the reference
// pose).
SegmentInertia table_segment(const SegmentFractions& f, double body_mass, const Eigen::Vector3d& bone,
                             double L, const Eigen::Matrix3d& R, const AnatomicalFrame& frame) {
  const double l = bone.norm();
  const Eigen::Vector3d u = bone / l;
  SegmentInertia seg;
  seg.mass = f.mass * body_mass * l / L;
  seg.com = f.com * bone;
  const Eigen::Vector3d fwd = R.transpose() * frame.forward, lat = R.transpose() * frame.lateral;
  Eigen::Vector3d a = fwd - fwd.dot(u) * u, m;
  if (a.norm() < 0.5) {  // the bone lies within 30 degrees of the anteroposterior axis
    m = lat - lat.dot(u) * u;
    m = m.norm() > 1e-6 ? m.normalized() : any_perpendicular(u);
    a = u.cross(m);
  } else {
    a.normalize();
    m = u.cross(a);
  }
  const double girth = f.r_longitudinal * f.r_longitudinal / 2 * L * L;
  const double r_sag2 =
      std::max(f.r_sagittal * f.r_sagittal - f.r_longitudinal * f.r_longitudinal / 2, 0.0) * l * l + girth;
  const double r_trans2 =
      std::max(f.r_transverse * f.r_transverse - f.r_longitudinal * f.r_longitudinal / 2, 0.0) * l * l +
      girth;
  const double r_long2 = f.r_longitudinal * f.r_longitudinal * L * L;
  seg.inertia =
      seg.mass * (r_sag2 * a * a.transpose() + r_trans2 * m * m.transpose() + r_long2 * u * u.transpose());
  return seg;
}

// Masses, CoMs, inertias, from the table or as cylinders of water. Returns the joints of a class
// that have no bone, so no mass.
std::vector<std::string> mass_properties(const Skeleton& s, const BodySpec& spec, const Groups& groups,
                                         const AnatomicalFrame& frame, BuiltBody& out) {
  const int n = s.joint_count();
  out.body.segments.assign(J(n), SegmentInertia{});
  const bool cylinders = spec.table == BodyTable::Cylinders;
  const AnthropometricTable* table = cylinders ? nullptr : &anthropometric_table(spec.table);
  std::vector<std::string> zero_length;
  for (int j = 0; j < n; ++j) {
    const SegmentClass c = out.classes[J(j)];
    if (c == SegmentClass::Massless) continue;
    const Eigen::Vector3d& bone = out.bones[J(j)];
    const double l = bone.norm();
    if (!(l > kZeroLength)) {
      zero_length.push_back(s.joint(j).name);
      continue;
    }
    SegmentInertia& seg = out.body.segments[J(j)];
    if (cylinders) {
      const double r = spec.radii[J(index_of(c))];
      seg.mass = kWaterDensity * std::numbers::pi * r * r * l;
      seg.com = bone / 2;
      seg.inertia = cylinder_inertia(seg.mass, r, l, bone / l);
      continue;
    }
    seg = table_segment(table->segment(c), spec.mass, bone, groups.length[J(groups.of_joint[J(j)])],
                        frame.world[J(j)].rotation(), frame);
  }
  return zero_length;
}

// Rescales the masses to the body mass asked for (cylinders with mass 0 keep their volumes'),
// and notes where they came from and which joints have none.
void rescale_to_body_mass(const BodySpec& spec, const std::vector<std::string>& zero_length,
                          const ClassNames& names, BuiltBody& out) {
  BodyModel& body = out.body;
  const bool cylinders = spec.table == BodyTable::Cylinders;
  const AnthropometricTable* table = cylinders ? nullptr : &anthropometric_table(spec.table);
  double sum = 0;
  for (const SegmentInertia& seg : body.segments) sum += seg.mass;
  const std::string source = cylinders ? std::string("cylinders of water (1000 kg/m³)")
                                       : std::string(to_string(spec.table)) + ": " + table->citation;
  if (!(sum > 0)) throw std::invalid_argument("build_body_model: the body has no mass");
  if (cylinders && spec.mass == 0) {
    out.notes.push_back("body: " + source + ", " + text::significant(sum, 4) + " kg from the volumes");
  } else {
    const double k = spec.mass / sum;
    for (SegmentInertia& seg : body.segments) {
      seg.mass *= k;
      seg.inertia *= k;
    }
    out.notes.push_back(
        "body: " + source + ", " + text::significant(spec.mass, 4) + " kg" +
        (cylinders
             ? " (volumes " + text::significant(sum, 4) + " kg, rescaled by " + text::significant(k, 4) + ")"
             : (std::abs(k - 1) > 1e-12
                    ? " (the table's fractions sum to " + text::significant(100 * table->mass_sum(), 6) +
                          "%: rescaled by " + text::significant(k, 6) + ")"
                    : std::string())));
  }
  if (!zero_length.empty())
    out.notes.push_back("no bone, so no mass (children and End Sites at the joint's origin): " +
                        text::join(zero_length));
  if (!names.massless.empty()) out.notes.push_back("massless by class: " + text::join(names.massless));
  if (!names.unmatched.empty())
    out.notes.push_back("massless, no class pattern matched: " + text::join(names.unmatched));
}

// One override on a joint with a class (`what` names both in messages).
void override_segment(const SegmentOverride& o, const std::string& what, const Eigen::Vector3d& bone,
                      SegmentInertia& seg) {
  if (o.radius) {
    if (!(bone.norm() > kZeroLength))
      throw Error(what + " has no bone for a cylinder along it: give `inertia` instead of `radius`", o.where);
    seg.mass = kWaterDensity * std::numbers::pi * *o.radius * *o.radius * bone.norm();
    seg.com = bone / 2;
    seg.inertia = cylinder_inertia(seg.mass, *o.radius, bone.norm(), bone.normalized());
  }
  if (o.mass) {
    if (seg.mass > 0) {
      seg.inertia *= *o.mass / seg.mass;
    } else if (!o.inertia) {
      throw Error(what + " has no bone, so no shape: give its `inertia` with its mass", o.where);
    }
    seg.mass = *o.mass;
  }
  if (o.mass_scale) {
    seg.mass *= *o.mass_scale;
    seg.inertia *= *o.mass_scale;
  }
  if (o.com) seg.com = *o.com;
  if (o.inertia) {
    if (!(seg.mass > 0)) throw Error(what + " has no mass: give its `mass` with its inertia", o.where);
    seg.inertia = *o.inertia;
  }
}

// Overrides, after the masses: the first matching pattern wins per joint.
void apply_overrides(const Skeleton& s, const BodySpec& spec, BuiltBody& out) {
  const Matches om = match_first(s, spec.segments, "segments");
  require_matches(s, spec.segments, om, "segments");
  for (std::size_t p = 0; p < spec.segments.size(); ++p) {
    const SegmentOverride& o = spec.segments[p];
    std::vector<std::string> done;
    for (int j : om.matched[p]) {
      if (om.owner[J(j)] != static_cast<int>(p)) continue;
      const std::string& name = s.joint(j).name;
      SegmentInertia& seg = out.body.segments[J(j)];
      const std::string what = "segments " + text::excerpt(o.pattern) + ": joint " + text::in_quotes(name);
      if (out.classes[J(j)] == SegmentClass::Massless) {
        if (o.mass || o.radius || o.inertia)
          throw Error(
              what + " is massless (class): map it to a segment class under `classes:` to give it mass",
              o.where);
        continue;
      }
      const double before = seg.mass;
      override_segment(o, what, out.bones[J(j)], seg);
      done.push_back(name + " " + text::significant(before, 4) + " -> " + text::significant(seg.mass, 4) +
                     " kg");
    }
    out.notes.push_back(
        "segments " + text::excerpt(o.pattern) + ": " +
        (done.empty() ? std::string("no joint left (earlier patterns took them)") : text::join(done)));
  }
}

void sum_class_masses(BuiltBody& out) {
  for (std::size_t j = 0; j < out.classes.size(); ++j) {
    const SegmentClass c = out.classes[j];
    const double m = out.body.segments[j].mass;
    out.body.segment_class.push_back(m > 0 ? to_string(c) : "");
    if (c != SegmentClass::Massless) out.class_mass[J(index_of(c))] += m;
  }
}

// The floating base is unactuated, the rest unlimited until a pattern says. Returns which joints
// are the floating base.
std::vector<bool> unactuate_floating_base(const Skeleton& s, BuiltBody& out) {
  const int n = s.joint_count();
  BodyModel& body = out.body;
  const int channels = s.channel_count();
  const double inf = std::numeric_limits<double>::infinity();
  body.torque_min = Eigen::VectorXd::Constant(channels, -inf);
  body.torque_max = Eigen::VectorXd::Constant(channels, inf);
  std::vector<bool> floating(J(n), false);
  std::vector<std::string> base;
  for (int j = 0; j < n; ++j) {
    const int parent = s.joint(j).parent;
    floating[J(j)] = parent < 0 || (floating[J(parent)] && out.classes[J(parent)] == SegmentClass::Massless);
    if (!floating[J(j)]) continue;
    const motion::Joint& jt = s.joint(j);
    const auto count = static_cast<Eigen::Index>(jt.channels.size());
    body.torque_min.segment(jt.first_channel, count).setZero();
    body.torque_max.segment(jt.first_channel, count).setZero();
    if (count > 0) base.push_back(jt.name);
  }
  if (!base.empty()) out.notes.push_back("unactuated (floating base): " + text::join(base));
  return floating;
}

// Bounds joint jt's channels by the limit t: one value for every rotation channel, or one per channel.
void limit_joint(const TorqueLimit& t, const motion::Joint& jt, BodyModel& body) {
  if (t.values.size() != 1 && t.values.size() != jt.channels.size())
    throw Error("torque_limits " + text::excerpt(t.pattern) + ": " + std::to_string(t.values.size()) +
                    " values for joint " + text::in_quotes(jt.name) + ", which has " +
                    std::to_string(jt.channels.size()) + " channels (give one value, or one per channel)",
                t.where);
  for (std::size_t c = 0; c < jt.channels.size(); ++c) {
    const bool single = t.values.size() == 1;
    if (single && !motion::is_rotation(jt.channels[c].kind)) continue;
    const double v = single ? t.values[0] : t.values[c];
    body.torque_min[jt.first_channel + static_cast<int>(c)] = -v;
    body.torque_max[jt.first_channel + static_cast<int>(c)] = v;
  }
}

// Torque limits: the first matching pattern wins per joint; the floating base stays unactuated.
void apply_torque_limits(const Skeleton& s, const BodySpec& spec, const std::vector<bool>& floating,
                         BuiltBody& out) {
  const Matches tm = match_first(s, spec.torque_limits, "torque_limits");
  require_matches(s, spec.torque_limits, tm, "torque_limits");
  for (std::size_t p = 0; p < spec.torque_limits.size(); ++p) {
    const TorqueLimit& t = spec.torque_limits[p];
    std::vector<std::string> done, skipped;
    for (int j : tm.matched[p]) {
      if (tm.owner[J(j)] != static_cast<int>(p)) continue;
      const motion::Joint& jt = s.joint(j);
      if (floating[J(j)]) {
        skipped.push_back(jt.name);
        continue;
      }
      limit_joint(t, jt, out.body);
      done.push_back(jt.name);
    }
    if (done.empty() && !skipped.empty())
      throw Error("torque_limits " + text::excerpt(t.pattern) + " matches only the floating base (" +
                      text::join(skipped) + "), whose channels are unactuated: their bounds are always 0",
                  t.where);
    out.notes.push_back(
        "torque_limits " + text::excerpt(t.pattern) + " = " +
        (t.values.size() == 1 ? text::significant(t.values[0], 4) + " N m"
                              : std::to_string(t.values.size()) + " values") +
        ": " + (done.empty() ? std::string("no joint left (earlier patterns took them)") : text::join(done)));
  }
}

}  // namespace

BuiltBody build_body_model(std::shared_ptr<const Skeleton> skeleton_ptr, const BodySpec& spec,
                           const Eigen::RowVectorXd* reference_pose) {
  if (!skeleton_ptr) throw std::invalid_argument("build_body_model: no skeleton");
  const Skeleton& s = *skeleton_ptr;
  if (s.joint_count() == 0) throw std::invalid_argument("build_body_model: the skeleton has no joint");
  check_spec(spec);

  BuiltBody out;
  const ClassNames names = match_classes(s, spec, out);
  out.bones = segment_bones(s, out.classes);
  const Groups groups = group_segments(s, out);
  require_table_segments(s, groups, names);
  const AnatomicalFrame frame = anatomical_frame(s, reference_pose, groups, out.notes);
  out.body.skeleton = skeleton_ptr;
  const std::vector<std::string> zero_length = mass_properties(s, spec, groups, frame, out);
  rescale_to_body_mass(spec, zero_length, names, out);
  apply_overrides(s, spec, out);
  sum_class_masses(out);
  const std::vector<bool> floating = unactuate_floating_base(s, out);
  apply_torque_limits(s, spec, floating, out);
  out.body.friction = spec.friction;
  out.body.gravity = spec.gravity;
  check_body_model(out.body);
  return out;
}

Eigen::Vector3d body_com(const BodyModel& body, motion::FrameRef frame) {
  if (!body.skeleton) throw std::invalid_argument("body_com: no skeleton");
  std::vector<Eigen::Isometry3d> world;
  pose(*body.skeleton, frame, world);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double mass = 0;
  for (std::size_t j = 0; j < body.segments.size(); ++j) {
    sum += body.segments[j].mass * (world[j] * body.segments[j].com);
    mass += body.segments[j].mass;
  }
  if (!(mass > 0)) throw std::invalid_argument("body_com: the body has no mass");
  return sum / mass;
}

void check_body_model(const BodyModel& body, const std::string& who) {
  if (!body.skeleton) throw std::invalid_argument(who + ": no skeleton");
  const Skeleton& s = *body.skeleton;
  const auto n = static_cast<std::size_t>(s.joint_count());
  if (body.segments.size() != n || body.segment_class.size() != n)
    throw std::invalid_argument(who + ": " + std::to_string(body.segments.size()) + " segments and " +
                                std::to_string(body.segment_class.size()) + " classes for " +
                                std::to_string(n) + " joints");
  const auto channels = static_cast<Eigen::Index>(s.channel_count());
  if (body.torque_min.size() != channels || body.torque_max.size() != channels)
    throw std::invalid_argument(who + ": torque bounds of " + std::to_string(body.torque_min.size()) +
                                " and " + std::to_string(body.torque_max.size()) + " values for " +
                                std::to_string(channels) + " channels");
  for (std::size_t j = 0; j < n; ++j) {
    const SegmentInertia& seg = body.segments[j];
    const std::string what = who + ": joint " + text::in_quotes(s.joint(static_cast<int>(j)).name);
    if (!std::isfinite(seg.mass) || seg.mass < 0)
      throw std::invalid_argument(what + ": mass " + text::significant(seg.mass, 4));
    if (!seg.com.allFinite()) throw std::invalid_argument(what + ": centre of mass is not finite");
    if (seg.mass > 0)
      check_segment_inertia(seg.inertia, what);
    else if (!seg.inertia.isZero())
      throw std::invalid_argument(what + ": inertia without mass");
  }
  for (Eigen::Index c = 0; c < channels; ++c)
    if (std::isnan(body.torque_min[c]) || std::isnan(body.torque_max[c]) ||
        body.torque_min[c] > body.torque_max[c])
      throw std::invalid_argument(who + ": channel " + s.channel_name(static_cast<int>(c)) + " bounds [" +
                                  text::significant(body.torque_min[c], 4) + ", " +
                                  text::significant(body.torque_max[c], 4) + "]");
  if (!std::isfinite(body.friction) || body.friction < 0)
    throw std::invalid_argument(who + ": friction " + text::significant(body.friction, 4));
  if (!body.gravity.allFinite()) throw std::invalid_argument(who + ": gravity is not finite");
}

}  // namespace kg::body
