// Target characters: scaled copies of the source skeleton, morphs, and their overall scale.
#include "kg/retarget/target.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

namespace kg::retarget {

namespace {

using motion::Joint;
using motion::Skeleton;

void check_factors(const Skeleton& source, const Eigen::VectorXd& factors, const std::string& what) {
  if (factors.size() != source.joint_count()) {
    std::ostringstream s;
    s << what << ": " << factors.size() << " factors for a skeleton of " << source.joint_count() << " joints";
    throw std::invalid_argument(s.str());
  }
  for (int j = 0; j < factors.size(); ++j)
    if (!std::isfinite(factors[j]) || !(factors[j] > 0)) {
      std::ostringstream s;
      s << what << ": factor " << factors[j] << " for joint '" << source.joint(j).name
        << "' (expected a finite number > 0)";
      throw std::invalid_argument(s.str());
    }
}

// The lowest rest-pose point: its joint, and the End Site index on it (-1: the joint origin).
struct LowPoint {
  int joint = -1;
  int end_site = -1;
};

LowPoint lowest_point(const Skeleton& s) {
  const std::vector<Eigen::Vector3d> origin = s.rest_origins();
  LowPoint low;
  double lowest = std::numeric_limits<double>::infinity();
  for (int j = 0; j < s.joint_count(); ++j) {
    const Eigen::Vector3d& o = origin[static_cast<std::size_t>(j)];
    const double y = s.file_to_world.row(1).dot(o);
    if (y < lowest - 1e-12) lowest = y, low = {j, -1};
    const auto& tips = s.joint(j).end_sites;
    for (std::size_t e = 0; e < tips.size(); ++e) {
      const double ye = s.file_to_world.row(1).dot(o + tips[e]);
      if (ye < lowest - 1e-12) lowest = ye, low = {j, static_cast<int>(e)};
    }
  }
  return low;
}

int root_of(const Skeleton& s, int joint) {
  while (joint >= 0 && s.joint(joint).parent >= 0) joint = s.joint(joint).parent;
  return joint;
}

// Height of the root of `p.joint` above point p in s's rest pose (world Y).
double height_above(const Skeleton& s, const LowPoint& p) {
  const std::vector<Eigen::Vector3d> origin = s.rest_origins();
  const int root = root_of(s, p.joint);
  Eigen::Vector3d point = origin[static_cast<std::size_t>(p.joint)];
  if (p.end_site >= 0) point += s.joint(p.joint).end_sites[static_cast<std::size_t>(p.end_site)];
  return s.file_to_world.row(1).dot(origin[static_cast<std::size_t>(root)] - point);
}

// Summed offset lengths from the root (its own offset excluded) down to p.
double chain_length(const Skeleton& s, const LowPoint& p) {
  double length =
      p.end_site >= 0 ? s.joint(p.joint).end_sites[static_cast<std::size_t>(p.end_site)].norm() : 0;
  for (int j = p.joint; j >= 0 && s.joint(j).parent >= 0; j = s.joint(j).parent)
    length += s.joint(j).offset.norm();
  return length;
}

}  // namespace

std::shared_ptr<const Skeleton> scaled_skeleton(const Skeleton& source, const Eigen::VectorXd& factors) {
  check_factors(source, factors, "scaled_skeleton");
  auto out = std::make_shared<Skeleton>(source);
  for (int j = 0; j < out->joint_count(); ++j) {
    Joint& jt = out->joint_mut(j);
    jt.offset *= factors[j];
    for (Eigen::Vector3d& tip : jt.end_sites) tip *= factors[j];
  }
  return out;
}

std::shared_ptr<const Skeleton> Target::skeleton_at(double t) const {
  if (!morphing()) return skeleton;
  return scaled_skeleton(*source, joint_factors(t));
}

Eigen::VectorXd Target::joint_factors(double t) const {
  if (morphing()) {
    if (t <= key_times.front()) return key_factors.front();
    if (t >= key_times.back()) return key_factors.back();
    const auto it = std::upper_bound(key_times.begin(), key_times.end(), t);
    const std::size_t k =
        static_cast<std::size_t>(it - key_times.begin());  // key_times[k-1] <= t < key_times[k]
    const double u = (t - key_times[k - 1]) / (key_times[k] - key_times[k - 1]);
    return (1 - u) * key_factors[k - 1] + u * key_factors[k];
  }
  Eigen::VectorXd f = Eigen::VectorXd::Ones(source->joint_count());
  for (int j = 0; j < source->joint_count(); ++j) {
    const double n = source->joint(j).offset.norm();
    if (n > 0) f[j] = skeleton->joint(j).offset.norm() / n;
  }
  return f;
}

double rest_hip_height(const Skeleton& skeleton, int* chain_end) {
  const LowPoint low = lowest_point(skeleton);
  if (chain_end != nullptr) *chain_end = low.joint;
  return low.joint < 0 ? 0.0 : height_above(skeleton, low);
}

double Target::overall_scale(double t) const {
  const std::shared_ptr<const Skeleton> target = skeleton_at(t);
  const LowPoint low = lowest_point(*source);
  if (low.joint < 0) return 1.0;
  const double hs = height_above(*source, low);
  if (hs > 1e-9) {
    const double ht = height_above(*target, low);
    if (ht > 0) return ht / hs;
  }
  const double ls = chain_length(*source, low);
  return ls > 0 ? chain_length(*target, low) / ls : 1.0;
}

Target uniform_target(std::shared_ptr<const Skeleton> source, double scale) {
  if (!source) throw std::invalid_argument("uniform_target: no source skeleton");
  if (!std::isfinite(scale) || !(scale > 0)) {
    std::ostringstream s;
    s << "scale " << scale << ": expected a finite number > 0";
    throw std::invalid_argument(s.str());
  }
  const Eigen::VectorXd factors = Eigen::VectorXd::Constant(source->joint_count(), scale);
  return factor_target(std::move(source), factors);
}

Target factor_target(std::shared_ptr<const Skeleton> source, const Eigen::VectorXd& factors) {
  if (!source) throw std::invalid_argument("factor_target: no source skeleton");
  Target t;
  t.skeleton = scaled_skeleton(*source, factors);
  t.source = std::move(source);
  return t;
}

Target morph_target(std::shared_ptr<const Skeleton> source, std::vector<double> key_times,
                    std::vector<Eigen::VectorXd> key_factors) {
  if (!source) throw std::invalid_argument("morph_target: no source skeleton");
  if (key_times.empty()) throw std::invalid_argument("morph_target: no keys");
  if (key_times.size() != key_factors.size())
    throw std::invalid_argument("morph_target: " + std::to_string(key_times.size()) + " key times but " +
                                std::to_string(key_factors.size()) + " factor vectors");
  for (std::size_t k = 0; k < key_times.size(); ++k) {
    if (!std::isfinite(key_times[k]))
      throw std::invalid_argument("morph_target: key " + std::to_string(k) + " has a non-finite time");
    if (k > 0 && !(key_times[k] > key_times[k - 1])) {
      std::ostringstream s;
      s << "morph_target: key times must increase strictly, key " << k << " at " << key_times[k]
        << " s follows " << key_times[k - 1] << " s";
      throw std::invalid_argument(s.str());
    }
    check_factors(*source, key_factors[k], "morph key " + std::to_string(k));
  }
  Target t;
  t.key_times = std::move(key_times);
  t.key_factors = std::move(key_factors);
  t.source = std::move(source);
  t.skeleton = scaled_skeleton(*t.source, t.joint_factors(0.0));
  return t;
}

void check_same_structure(const Skeleton& target, const Skeleton& source, const std::string& what) {
  auto fail = [&](const std::string& message) { throw std::invalid_argument(what + ": " + message); };
  if (target.joint_count() != source.joint_count())
    fail("target skeleton has " + std::to_string(target.joint_count()) + " joints, source " +
         std::to_string(source.joint_count()));
  for (int j = 0; j < source.joint_count(); ++j) {
    const Joint& a = target.joint(j);
    const Joint& b = source.joint(j);
    const std::string n = std::to_string(j);
    if (a.name != b.name)
      fail("joint " + n + " is '" + a.name + "' in the target, '" + b.name + "' in the source");
    if (a.parent != b.parent) {
      auto parent = [](const Skeleton& s, int p) {
        return p < 0 ? std::string("none (a root)") : "'" + s.joint(p).name + "'";
      };
      fail("joint " + n + " '" + a.name + "' has parent " + parent(target, a.parent) + " in the target, " +
           parent(source, b.parent) + " in the source");
    }
    bool same = a.channels.size() == b.channels.size();
    for (std::size_t c = 0; same && c < a.channels.size(); ++c)
      same = a.channels[c].kind == b.channels[c].kind;
    if (!same) {
      auto list = [](const Joint& jt) {
        std::string s;
        for (const motion::Channel& c : jt.channels)
          s += (s.empty() ? "" : " ") + std::string(motion::to_string(c.kind));
        return s.empty() ? std::string("none") : s;
      };
      fail("joint " + n + " '" + a.name + "' has channels " + list(a) + " in the target, " + list(b) +
           " in the source");
    }
    if (a.end_sites.size() != b.end_sites.size())
      fail("joint " + n + " '" + a.name + "' has " + std::to_string(a.end_sites.size()) +
           " End Sites in the target, " + std::to_string(b.end_sites.size()) + " in the source");
  }
}

Target skeleton_target(std::shared_ptr<const Skeleton> source, const Skeleton& other, const std::string& what,
                       std::vector<std::string>* notes) {
  if (!source) throw std::invalid_argument("skeleton_target: no source skeleton");
  check_same_structure(other, *source, what);
  auto out = std::make_shared<Skeleton>(*source);
  int axes_differ = 0;
  std::string first_axis;
  // Offsets in the other file's coordinates, brought to the source's: world = F file.
  const Eigen::Matrix3d to_source = source->file_to_world.transpose() * other.file_to_world;
  for (int j = 0; j < out->joint_count(); ++j) {
    Joint& jt = out->joint_mut(j);
    jt.offset = to_source * other.joint(j).offset;
    jt.end_sites = other.joint(j).end_sites;
    for (Eigen::Vector3d& tip : jt.end_sites) tip = to_source * tip;
    if (!jt.axis.isApprox(other.joint(j).axis, 1e-9)) {
      if (axes_differ++ == 0) first_axis = jt.name;
    }
  }
  if (notes != nullptr) {
    if (axes_differ > 0)
      notes->push_back(what + ": " + std::to_string(axes_differ) + " joints (first '" + first_axis +
                       "') have other rotation axes in the target; the source's are kept, since the motion's "
                       "angles are expressed in them");
    if (!other.file_to_world.isApprox(source->file_to_world, 1e-9))
      notes->push_back(
          what + ": another up axis than the source's; its offsets were rotated into the source's axes");
  }
  Target t;
  t.skeleton = std::move(out);
  t.source = std::move(source);
  return t;
}

double height_factor(const Target& target, const PointRef& point, double t) {
  const motion::Skeleton& s = *target.source;
  if (point.joint < 0 || point.joint >= s.joint_count())
    throw std::invalid_argument("height factor: joint " + std::to_string(point.joint) + " out of range");
  const Eigen::VectorXd factors = target.joint_factors(t);
  double weight = 0, sum = 0;
  auto add = [&](double length, double factor) {
    weight += length;
    sum += length * factor;
  };
  add(point.local.norm(), factors[point.joint]);
  auto below = [&](int j) {  // j lies under the point's joint
    for (j = s.joint(j).parent; j >= 0; j = s.joint(j).parent)
      if (j == point.joint) return true;
    return false;
  };
  for (int j = 0; j < s.joint_count(); ++j) {
    if (!below(j)) continue;
    add(s.joint(j).offset.norm(), factors[j]);
    for (const Eigen::Vector3d& e : s.joint(j).end_sites) add(e.norm(), factors[j]);
  }
  if (point.local.isZero())
    for (const Eigen::Vector3d& e : s.joint(point.joint).end_sites) add(e.norm(), factors[point.joint]);
  return weight > 1e-9 ? sum / weight : target.overall_scale(t);
}

ConstraintSet constraints_on_target(const ConstraintSet& constraints, const Target& target, int character,
                                    double fps) {
  if (target.morphing() && !(fps > 0 && std::isfinite(fps)))
    throw std::invalid_argument(
        "constraints on a morphing target: the clip's frame rate is needed to scale points "
        "per frame (got " +
        std::to_string(fps) + ")");
  const Eigen::VectorXd factors = target.joint_factors(0.0);
  std::map<int, Eigen::VectorXd> factors_at;  // frame -> factors, when morphing
  auto factor = [&](int joint, int frame) {
    if (!target.morphing()) return factors[joint];
    auto it = factors_at.find(frame);
    if (it == factors_at.end()) it = factors_at.emplace(frame, target.joint_factors(frame / fps)).first;
    return it->second[joint];
  };
  auto moves = [&](const PointRef& p) {
    return p.character == character && p.joint >= 0 && p.joint < factors.size();
  };
  ConstraintSet moved = constraints;
  for (Constraint& c : moved.constraints) {
    if (std::none_of(c.points.begin(), c.points.end(), moves)) continue;
    for (Sample& s : c.samples) {
      if (s.locals.empty() && !target.morphing()) continue;
      if (s.locals.empty())
        for (const PointRef& p : c.points) s.locals.push_back(p.local);
      for (std::size_t i = 0; i < c.points.size() && i < s.locals.size() && i < s.frames.size(); ++i)
        if (moves(c.points[i])) s.locals[i] *= factor(c.points[i].joint, s.frames[i]);
    }
    for (PointRef& p : c.points)
      if (moves(p)) p.local *= factors[p.joint];
  }
  return moved;
}

}  // namespace kg::retarget
