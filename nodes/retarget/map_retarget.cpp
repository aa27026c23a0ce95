// Retargeting through a skeleton map: the adapted figure's proportions, the feature constraints
// on the target, and the target's placed rest pose (map_retarget.hpp).
#include "kg/retarget/map_retarget.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <initializer_list>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "kg/base/text.hpp"
#include "kg/motion/filters.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/motion/rotations.hpp"
#include "kg/retarget/constraint_io.hpp"
#include "kg/retarget/initial_estimate.hpp"
#include "kg/retarget/target.hpp"

namespace kg::retarget {

namespace {

using motion::Motion;
using motion::Skeleton;

void check_side(const SkeletonChains& c, const Skeleton& sk, const char* side) {
  auto check = [&](int j) {
    if (j >= sk.joint_count())
      throw std::invalid_argument(std::string("skeleton map: the ") + side + " chains name joint " +
                                  std::to_string(j) + ", outside its skeleton of " +
                                  std::to_string(sk.joint_count()) + " joints");
  };
  check(c.pelvis);
  for (int j : c.spine) check(j);
  for (int j : c.neck) check(j);
  for (const auto* limbs : {&c.legs, &c.arms})
    for (const Limb& l : *limbs)
      for (int j : {l.root, l.upper, l.middle, l.lower, l.end}) check(j);
}

std::string metres(double x) {
  return kg::text::significant(x, 3) + " m";
}

}  // namespace

Target adapted_target(const SkeletonMap& map, std::shared_ptr<const Skeleton> source_ptr,
                      const Skeleton& target, std::vector<std::string>* notes) {
  if (!source_ptr) throw std::invalid_argument("adapted_target: no source skeleton");
  const Skeleton& source = *source_ptr;
  const SkeletonChains& s = map.source.chains;
  const SkeletonChains& t = map.target.chains;
  check_side(s, source, "source");
  check_side(t, target, "target");
  auto note = [&](const std::string& line) {
    if (notes != nullptr) notes->push_back(line);
  };
  const std::vector<Eigen::Vector3d> ps = source.rest_world_origins(), pt = target.rest_world_origins();
  // The overall factor: the legs' length ratio (a rest pose need not stand: iClone's bones point
  // elsewhere, and its rest hip height is 2 cm), else the rest hip heights'.
  double leg_s = 0, leg_t = 0;
  for (int side = 0; side < 2; ++side) {
    const Limb &a = s.legs[side], &b = t.legs[side];
    if (!a.found() || !b.found()) continue;
    leg_s += (ps[a.middle] - ps[a.upper]).norm() + (ps[a.lower] - ps[a.middle]).norm();
    leg_t += (pt[b.middle] - pt[b.upper]).norm() + (pt[b.lower] - pt[b.middle]).norm();
  }
  const double hs = rest_hip_height(source), ht = rest_hip_height(target);
  double overall = 1.0;
  if (leg_s > 0 && leg_t > 0) {
    overall = leg_t / leg_s;
    note("overall factor " + kg::text::significant(overall, 4) + " (the legs' lengths: source " +
         metres(leg_s) + ", target " + metres(leg_t) + "), for joints in no chain");
  } else if (hs > 0 && ht > 0) {
    overall = ht / hs;
    note("overall factor " + kg::text::significant(overall, 4) +
         " (no legs on both; rest hip heights: source " + metres(hs) + ", target " + metres(ht) +
         "), for joints in no chain");
  } else {
    note("overall factor 1 (no legs on both, and a rest hip height is zero), for joints in no chain");
  }
  auto fig = std::make_shared<Skeleton>(source);
  const Eigen::Matrix3d& W = source.file_to_world;
  for (int j = 0; j < fig->joint_count(); ++j) {
    motion::Joint& jt = fig->joint_mut(j);
    jt.offset *= overall;
    for (Eigen::Vector3d& e : jt.end_sites) e *= overall;
  }
  const double tiny = 1e-6 * std::max({hs, ht, leg_s, leg_t, 1e-3});
  auto scale_joint = [&](int j, double k) {
    motion::Joint& jt = fig->joint_mut(j);
    jt.offset = source.joint(j).offset * k;
    for (std::size_t e = 0; e < jt.end_sites.size(); ++e) jt.end_sites[e] = source.joint(j).end_sites[e] * k;
  };
  // A segment of a limb (top -> bottom on the tree): scaled to the target's length, its direction
  // the source's, since the source's joint angles are expressed against it.
  auto segment = [&](const std::string& what, int top, int bottom, int t_top, int t_bottom) {
    const double ls = (ps[bottom] - ps[top]).norm(), lt = (pt[t_bottom] - pt[t_top]).norm();
    double k = overall;
    if (ls > tiny && lt > tiny) {
      k = lt / ls;
      note(what + ": factor " + kg::text::significant(k, 4) + " (source " + metres(ls) + ", target " +
           metres(lt) + ")");
    } else {
      note(what + ": a length is zero (source " + metres(ls) + ", target " + metres(lt) +
           "): overall factor");
    }
    std::vector<int> path;
    int j = bottom;
    for (; j >= 0 && j != top; j = source.joint(j).parent) path.push_back(j);
    if (j != top) {
      note(what + ": " + source.joint(bottom).name + " is not below " + source.joint(top).name +
           " in the source; kept at the overall factor");
      return k;
    }
    for (int p : path) scale_joint(p, k);
    return k;
  };
  auto below = [&](int top, double k) {
    std::vector<char> in(static_cast<std::size_t>(source.joint_count()), 0);
    in[static_cast<std::size_t>(top)] = 1;
    for (int j = top + 1; j < source.joint_count(); ++j) {
      const int p = source.joint(j).parent;
      if (p >= 0 && in[static_cast<std::size_t>(p)]) {
        in[static_cast<std::size_t>(j)] = 1;
        scale_joint(j, k);
      }
    }
    std::vector<Eigen::Vector3d>& tips = fig->joint_mut(top).end_sites;
    for (std::size_t e = 0; e < tips.size(); ++e) tips[e] = source.joint(top).end_sites[e] * k;
  };

  const char* sides[] = {"left", "right"};
  for (int leg = 1; leg >= 0; --leg)
    for (int side = 0; side < 2; ++side) {
      const Limb& a = leg ? s.legs[side] : s.arms[side];
      const Limb& b = leg ? t.legs[side] : t.arms[side];
      if (!a.found() || !b.found()) continue;
      const std::string name = std::string(sides[side]) + (leg ? "_leg" : "_arm");
      segment(name + (leg ? " thigh" : " upper arm"), a.upper, a.middle, b.upper, b.middle);
      double k = segment(name + (leg ? " shin" : " forearm"), a.middle, a.lower, b.middle, b.lower);
      if (leg && a.end >= 0 && b.end >= 0) k = segment(name + " foot", a.lower, a.end, b.lower, b.end);
      below(leg && a.end >= 0 && b.end >= 0 ? a.end : a.lower, k);
    }

  // The trunk's connections (pelvis -> chest, chest -> head, pelvis -> each hip, chest -> each
  // shoulder) take the target's rest vectors, turned into the source's body frame: where the
  // target's hips, shoulders and head sit on its trunk is where the adapted figure's do.
  struct Link {
    std::string what;
    int top, bottom, t_top, t_bottom;
  };
  std::vector<Link> links;
  const int s_chest = s.spine.empty() ? -1 : s.spine.back(), t_chest = t.spine.empty() ? -1 : t.spine.back();
  if (s.pelvis >= 0 && t.pelvis >= 0 && s_chest >= 0 && t_chest >= 0)
    links.push_back({"spine (pelvis -> chest)", s.pelvis, s_chest, t.pelvis, t_chest});
  if (s_chest >= 0 && t_chest >= 0 && !s.neck.empty() && !t.neck.empty())
    links.push_back({"neck (chest -> head)", s_chest, s.neck.back(), t_chest, t.neck.back()});
  for (int side = 0; side < 2; ++side) {
    if (s.pelvis >= 0 && t.pelvis >= 0 && s.legs[side].found() && t.legs[side].found())
      links.push_back({std::string(sides[side]) + " hip (pelvis -> hip)", s.pelvis, s.legs[side].upper,
                       t.pelvis, t.legs[side].upper});
    if (s_chest >= 0 && t_chest >= 0 && s.arms[side].found() && t.arms[side].found())
      links.push_back({std::string(sides[side]) + " shoulder (chest -> shoulder)", s_chest,
                       s.arms[side].upper, t_chest, t.arms[side].upper});
  }
  if (!links.empty()) {
    const Eigen::Matrix3d align =
        body_frame(s, source, "source") * body_frame(t, target, "target").transpose();
    auto is_ancestor_or_self = [&](int a, int j) {
      for (; j >= 0; j = source.joint(j).parent)
        if (j == a) return true;
      return false;
    };
    for (const Link& l : links) {
      std::vector<int> path;
      int j = l.bottom;
      for (; j >= 0 && j != l.top; j = source.joint(j).parent) path.push_back(j);
      if (j != l.top) {
        note(l.what + ": " + source.joint(l.bottom).name + " is not below " + source.joint(l.top).name +
             " in the source; kept at the overall factor");
        continue;
      }
      // Joints this link shares with another (iClone's CC_Base_Pelvis carries both hips) stay.
      std::vector<int> own;
      Eigen::Vector3d shared = Eigen::Vector3d::Zero(), mine = Eigen::Vector3d::Zero();
      for (int p : path) {
        bool is_shared = false;
        for (const Link& other : links)
          if (&other != &l && !is_ancestor_or_self(l.bottom, other.bottom) &&
              is_ancestor_or_self(p, other.bottom))
            is_shared = true;
        const Eigen::Vector3d v = W * fig->joint(p).offset;
        (is_shared ? shared : mine) += v;
        if (!is_shared) own.push_back(p);
      }
      const Eigen::Vector3d want = align * (pt[l.t_bottom] - pt[l.t_top]) - shared;
      if (own.empty()) {
        note(l.what + ": every joint on it is shared with another connection; kept");
        continue;
      }
      if (mine.norm() <= tiny) {
        for (int p : own) fig->joint_mut(p).offset.setZero();
        fig->joint_mut(own.front()).offset = W.transpose() * want;
      } else if (want.norm() <= tiny) {
        for (int p : own) fig->joint_mut(p).offset.setZero();
      } else {
        const Eigen::Matrix3d turn =
            Eigen::Quaterniond::FromTwoVectors(mine, want).toRotationMatrix() * (want.norm() / mine.norm());
        for (int p : own) fig->joint_mut(p).offset = W.transpose() * (turn * (W * fig->joint(p).offset));
      }
      const double angle = mine.norm() > tiny && want.norm() > tiny
                               ? std::acos(std::clamp(mine.normalized().dot(want.normalized()), -1.0, 1.0))
                               : 0.0;
      note(l.what + ": the target's rest vector, " + metres(want.norm()) + " (source " + metres(mine.norm()) +
           ", turned " + kg::text::significant(angle * 180 / std::numbers::pi, 3) + " deg)");
    }
  }
  // Below the head: the neck link's length ratio.
  if (s_chest >= 0 && !s.neck.empty()) {
    const double ls = (ps[s.neck.back()] - ps[s_chest]).norm();
    const std::vector<Eigen::Vector3d> pf = fig->rest_world_origins();
    const double lf = (pf[s.neck.back()] - pf[s_chest]).norm();
    if (ls > tiny && lf > tiny) below(s.neck.back(), lf / ls);
  }
  return skeleton_target(std::move(source_ptr), *fig, "adapted figure", notes);
}

Motion adapt_clip(const Motion& clip, const SkeletonMap& map, const Skeleton& target,
                  std::vector<std::string>* notes) {
  const Target adapted = adapted_target(map, clip.skeleton, target, notes);
  Motion out = scale_translation(clip, adapted);
  out.skeleton = adapted.skeleton;
  return out;
}

ConstraintSet feature_constraints(const std::vector<FeaturePair>& pairs,
                                  const std::vector<Eigen::Matrix3d>& offsets, const Motion& adapted,
                                  const Skeleton& target) {
  if (offsets.size() != pairs.size())
    throw std::invalid_argument("feature_constraints: " + std::to_string(offsets.size()) +
                                " rest offsets for " + std::to_string(pairs.size()) + " pairs");
  if (!adapted.skeleton)
    throw std::invalid_argument("feature_constraints: the adapted motion has no skeleton");
  const Skeleton& sk = *adapted.skeleton;
  auto check_point = [&](const motion::PointRef& p, const Skeleton& on, const std::string& pair,
                         const char* side) {
    if (p.joint < 0 || p.joint >= on.joint_count())
      throw std::invalid_argument("feature pair '" + pair + "': its " + side + " joint " +
                                  std::to_string(p.joint) + " is outside the " + side + " skeleton");
  };
  for (const FeaturePair& p : pairs) {
    check_point(p.source.point, sk, p.name, "source");
    check_point(p.target.point, target, p.name, "target");
    if (p.kind == FeatureKind::Direction) {
      check_point(p.source.to, sk, p.name, "source");
      check_point(p.target.to, target, p.name, "target");
    }
  }
  const int frames = adapted.frame_count();
  // World transforms of the adapted figure, frame by frame.
  std::vector<std::vector<Eigen::Isometry3d>> world(static_cast<std::size_t>(frames),
                                                    std::vector<Eigen::Isometry3d>(sk.joint_count()));
  for (int f = 0; f < frames; ++f) motion::forward_kinematics(sk, adapted.values.row(f), world[f]);
  auto at = [&](int f, const motion::PointRef& p) { return Eigen::Vector3d(world[f][p.joint] * p.local); };

  ConstraintSet set;
  constexpr double kAxisLength = 0.1;  // m; orientation rows compare unit vectors, so any length serves
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const FeaturePair& p = pairs[i];
    auto make = [&](const char* kind, std::string label) {
      Constraint c;
      c.kind = kind;
      c.label = std::move(label);
      c.weight = p.hard ? kHardWeight * p.weight : p.weight;
      c.soft = !p.hard;
      c.samples.reserve(static_cast<std::size_t>(frames));
      return c;
    };
    auto finish = [&](Constraint& c) {
      if (!c.samples.empty()) c.params = c.samples.front().params;
      if (!c.samples.empty()) set.constraints.push_back(std::move(c));
    };
    switch (p.kind) {
      case FeatureKind::Position: {
        Constraint c = make("position", p.name);
        c.points = {p.target.point};
        for (int f = 0; f < frames; ++f) {
          const Eigen::Vector3d x = at(f, p.source.point);
          c.samples.push_back({.frames = {f}, .params = {x.x(), x.y(), x.z(), 1, 1, 1}});
        }
        finish(c);
        break;
      }
      case FeatureKind::Direction: {
        Constraint c = make("orientation", p.name);
        c.points = {p.target.point, p.target.to};
        for (int f = 0; f < frames; ++f) {
          const Eigen::Vector3d d = at(f, p.source.to) - at(f, p.source.point);
          if (!(d.norm() > 1e-9)) continue;  // a source segment of no length points nowhere this frame
          const Eigen::Vector3d u = d.normalized();
          c.samples.push_back({.frames = {f, f}, .params = {u.x(), u.y(), u.z()}});
        }
        finish(c);
        break;
      }
      case FeatureKind::Orientation: {
        for (int axis = 0; axis < 2; ++axis) {
          Constraint c = make("orientation", p.name + (axis == 0 ? ".x" : ".y"));
          motion::PointRef tip = p.target.point;
          tip.local += kAxisLength * Eigen::Vector3d::Unit(axis);
          c.points = {p.target.point, tip};
          for (int f = 0; f < frames; ++f) {
            const Eigen::Matrix3d r = world[f][p.source.point.joint].linear() * offsets[i];
            const Eigen::Vector3d u = r.col(axis);
            c.samples.push_back({.frames = {f, f}, .params = {u.x(), u.y(), u.z()}});
          }
          finish(c);
        }
        break;
      }
    }
  }
  return set;
}

Motion placed_rest_pose(const SkeletonMap& map, const Eigen::Matrix3d& pelvis_offset, const Motion& adapted,
                        std::shared_ptr<const Skeleton> target, std::vector<std::string>* notes) {
  if (!target || !adapted.skeleton)
    throw std::invalid_argument("placed_rest_pose: a motion without a skeleton");
  const int ps = map.source.chains.pelvis, pt = map.target.chains.pelvis;
  if (ps < 0 || pt < 0)
    throw std::invalid_argument(std::string("placed_rest_pose: the ") + (ps < 0 ? "source" : "target") +
                                " has no pelvis in the map, so the target cannot be placed");
  if (ps >= adapted.skeleton->joint_count() || pt >= target->joint_count())
    throw std::invalid_argument("placed_rest_pose: a pelvis outside its skeleton");
  const Skeleton& tk = *target;
  const int frames = adapted.frame_count();
  Eigen::RowVectorXd rest = Eigen::RowVectorXd::Zero(tk.channel_count());
  for (const motion::Joint& j : tk.joints())
    for (std::size_t c = 0; c < j.channels.size(); ++c)
      if (!motion::is_rotation(j.channels[c].kind))
        rest[j.first_channel + static_cast<int>(c)] = j.offset[motion::axis_index(j.channels[c].kind)];
  int root = pt;
  while (tk.joint(root).parent >= 0) root = tk.joint(root).parent;
  std::vector<Eigen::Isometry3d> tw(static_cast<std::size_t>(tk.joint_count()));
  motion::forward_kinematics(tk, rest, tw);
  const Eigen::Isometry3d root_from_pelvis = tw[root].inverse() * tw[pt];

  const motion::Joint& rj = tk.joint(root);
  const motion::RotationOrder order = motion::rotation_order(rj);
  const std::array<int, 3> rot_index = motion::rotation_channel_indices(rj);
  bool has_position = false;
  for (const motion::Channel& c : rj.channels) has_position = has_position || !motion::is_rotation(c.kind);
  auto note = [&](const std::string& line) {
    if (notes != nullptr) notes->push_back(line);
  };
  if (!has_position)
    note("target root " + rj.name + " has no position channels: it stays where its rest pose has it");
  if (order.count < 3)
    note("target root " + rj.name + " has " + std::to_string(order.count) +
         " rotation channels, not 3: its turn follows the source's only as far as they reach");

  Motion out{target, motion::FrameMatrix(frames, tk.channel_count()), adapted.fps, adapted.name};
  std::vector<Eigen::Isometry3d> sw(static_cast<std::size_t>(adapted.skeleton->joint_count()));
  Eigen::Vector3d previous = Eigen::Vector3d::Zero();
  for (int f = 0; f < frames; ++f) {
    motion::forward_kinematics(*adapted.skeleton, adapted.values.row(f), sw);
    Eigen::Isometry3d pelvis = Eigen::Isometry3d::Identity();
    pelvis.linear() = sw[ps].linear() * pelvis_offset;
    pelvis.translation() = sw[ps].translation();
    const Eigen::Isometry3d root_world = pelvis * root_from_pelvis.inverse();
    Eigen::RowVectorXd q = rest;
    // The root's local transform: world = file_to_world * local (it has no parent).
    const Eigen::Matrix3d local_r = tk.file_to_world.transpose() * root_world.linear();
    const Eigen::Vector3d local_t = tk.file_to_world.transpose() * root_world.translation();
    for (std::size_t c = 0; c < rj.channels.size(); ++c)
      if (!motion::is_rotation(rj.channels[c].kind))
        q[rj.first_channel + static_cast<int>(c)] = local_t[motion::axis_index(rj.channels[c].kind)];
    if (order.count > 0) {
      const Eigen::Matrix3d e = rj.axis.transpose() * local_r * rj.axis;
      const Eigen::Vector3d angles = motion::matrix_to_euler(e, order, previous);
      for (int a = 0; a < order.count; ++a)
        q[rj.first_channel + rot_index[static_cast<std::size_t>(a)]] = angles[a];
      previous = angles;
    }
    out.values.row(f) = q;
  }
  return out;
}

void MapRetargetOptions::validate() const {
  if (!(smooth_seconds > 0) || !std::isfinite(smooth_seconds))
    throw std::invalid_argument("map retarget: smooth_seconds " + std::to_string(smooth_seconds) +
                                " (expected a finite number > 0, seconds)");
  if (frames_per_key < 1)
    throw std::invalid_argument("map retarget: frames_per_key " + std::to_string(frames_per_key) +
                                " (expected an integer >= 1)");
  ik.validate();
  spacetime.validate();
}

MapRetargetResult retarget_onto(const Motion& clip, const SkeletonMap& map,
                                std::shared_ptr<const Skeleton> target, const KindFinder& kinds,
                                const MapRetargetOptions& options) {
  options.validate();
  if (!clip.skeleton || !target)
    throw std::invalid_argument("retarget_onto: a clip or target without a skeleton");
  using Clock = std::chrono::steady_clock;
  auto seconds_since = [](Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
  };
  MapRetargetResult out;
  auto t0 = Clock::now();
  out.adapted = adapt_clip(clip, map, *target, &out.notes);
  out.pairs = feature_pairs(map);
  const std::vector<Eigen::Matrix3d> offsets = rest_offsets(map, out.pairs, *clip.skeleton, *target);
  out.constraints = feature_constraints(out.pairs, offsets, out.adapted, *target);
  out.feature_constraints = static_cast<int>(out.constraints.constraints.size());
  ConstraintSet limits = joint_limit_constraints(*target, 0, clip.frame_count());
  for (Constraint& c : limits.constraints) c.weight = kHardWeight;
  merge_constraints(out.constraints, limits);
  Eigen::Matrix3d pelvis_offset = Eigen::Matrix3d::Identity();
  for (std::size_t i = 0; i < out.pairs.size(); ++i)
    if (out.pairs[i].name == "pelvis.orientation") pelvis_offset = offsets[i];
  const Motion start = placed_rest_pose(map, pelvis_offset, out.adapted, target, &out.notes);
  out.seconds_adapt = seconds_since(t0);

  t0 = Clock::now();
  out.baseline = solve_per_frame_ik(start, out.constraints, kinds, options.ik);
  out.seconds_ik = seconds_since(t0);

  t0 = Clock::now();
  Motion m1 = out.baseline.motion;
  m1.values = motion::gaussian_smoothed(m1.values, std::max(options.smooth_seconds * m1.fps, 1e-3),
                                        motion::CurveEnds::OddReflection);
  SpacetimeProblem problem;
  problem.characters.push_back(
      {.initial = std::move(m1),
       .frames_per_key =
           std::vector<int>(static_cast<std::size_t>(target->channel_count()), options.frames_per_key)});
  problem.constraints = &out.constraints;
  problem.kinds = kinds;
  problem.options = options.spacetime;
  out.solve = solve_spacetime(problem);
  out.seconds_spacetime = seconds_since(t0);
  return out;
}

}  // namespace kg::retarget
