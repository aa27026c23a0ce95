// Contacts (contacts.hpp): detected feet, per-frame touching vertices with their Jacobians, the
// linearised friction cone and N = Jᵀ P.
#include "kg/retime/contacts.hpp"
#include "kg/base/option_check.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "kg/base/text.hpp"
#include "kg/motion/kinematics.hpp"

namespace kg::retime {

namespace {

// "Joint[x y z]" in find_point's syntax, exactly (17 digits round-trip a double).
std::string point_spec(const motion::Skeleton& sk, const ContactVertex& v) {
  std::ostringstream s;
  s << std::setprecision(17) << sk.joint(v.joint).name << "[" << v.local.x() << " " << v.local.y() << " "
    << v.local.z() << "]";
  return s.str();
}

bool is_ancestor(const motion::Skeleton& sk, int ancestor, int joint) {
  for (int j = sk.joint(joint).parent; j >= 0; j = sk.joint(j).parent)
    if (j == ancestor) return true;
  return false;
}

// The feet detect_footplants would watch: the joints of its automatic points that have no
// ancestor among the others (the ankle of an ankle + toe-tip pair, or a lone foot with an End Site).
std::vector<int> automatic_feet(const motion::Motion& m) {
  motion::Motion first{m.skeleton, m.values.topRows(std::min(1, m.frame_count())), m.fps, m.name};
  const motion::FootplantDetection d = motion::detect_footplants(first, {});
  std::vector<int> joints;
  for (const motion::PlantPoint& p : d.points) joints.push_back(p.point.joint);
  std::vector<int> feet;
  for (int j : joints) {
    const bool below_another = std::any_of(joints.begin(), joints.end(),
                                           [&](int other) { return is_ancestor(*m.skeleton, other, j); });
    if (!below_another && std::find(feet.begin(), feet.end(), j) == feet.end()) feet.push_back(j);
  }
  return feet;
}

// The joint carrying the toe tip and the tip in that joint's frame.
std::pair<int, Eigen::Vector3d> toe_tip(const motion::Skeleton& sk, int foot) {
  int toe = -1;
  for (int j = 0; j < sk.joint_count(); ++j) {
    if (sk.joint(j).parent != foot) continue;
    if (toe < 0 || (sk.joint(toe).end_sites.empty() && !sk.joint(j).end_sites.empty())) toe = j;
  }
  if (toe >= 0)
    return {toe, sk.joint(toe).end_sites.empty() ? Eigen::Vector3d::Zero() : sk.joint(toe).end_sites.front()};
  if (!sk.joint(foot).end_sites.empty()) return {foot, sk.joint(foot).end_sites.front()};
  throw std::invalid_argument("contacts: foot '" + sk.joint(foot).name +
                              "' has neither a child (toe) nor an End Site to find its tip");
}

// Marks the pair of foot vertices that detection point `point` watches as touching in `on` (one
// frame's activity): point 2 foot is the heel (vertices 3 and 0 of that foot), 2 foot + 1 the tip
// (vertices 1 and 2).
void activate_pair(std::vector<bool>& on, std::size_t point) {
  const std::size_t foot = point / 2;
  const bool is_tip = point % 2 == 1;
  on[4 * foot + (is_tip ? 1 : 0)] = true;
  on[4 * foot + (is_tip ? 2 : 3)] = true;
}

// FootContactOptions::support_acceleration: in each run of frames without any active vertex
// that a plant bounds, from that end inwards and for as long as the root is held up, activates the
// pair of every detection point within the leave height. Only next to plants: a figure gliding
// over the floor without ever planting is not taken for one standing. Returns the frames it gave
// contact.
int touch_where_supported(const motion::Motion& m, const motion::FootplantDetection& d,
                          const FootContactOptions& o, std::vector<std::vector<bool>>& active) {
  const int frames = m.frame_count();
  const int k = std::max(1, static_cast<int>(std::lround(m.fps / 30.0)));
  if (o.support_acceleration == 0 || frames < 2 * k + 1) return 0;
  const motion::Skeleton& sk = *m.skeleton;
  std::vector<double> root_height(static_cast<std::size_t>(frames));
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(sk.joint_count()));
  for (int f = 0; f < frames; ++f) {
    motion::forward_kinematics(sk, m.values.row(f), world);
    root_height[static_cast<std::size_t>(f)] = world.front().translation().y();
  }
  const double leave = o.plants.height_threshold * o.plants.hysteresis;
  const double to_per_second2 = (m.fps / k) * (m.fps / k);
  const auto idle = [&](int f) {
    const std::vector<bool>& on = active[static_cast<std::size_t>(f)];
    return std::none_of(on.begin(), on.end(), [](bool b) { return b; });
  };
  // Activates frame f's pairs near the floor if the root is held up there; false if not.
  const auto touch = [&](int f) {
    if (f < k || f + k >= frames) return false;
    const auto y = [&](int g) { return root_height[static_cast<std::size_t>(g)]; };
    if ((y(f + k) - 2 * y(f) + y(f - k)) * to_per_second2 <= -motion::kEarthGravity + o.support_acceleration)
      return false;
    std::vector<bool>& on = active[static_cast<std::size_t>(f)];
    bool touched = false;
    for (std::size_t i = 0; i < d.points.size(); ++i) {
      const motion::PlantPoint& point = d.points[i];
      const std::size_t at = static_cast<std::size_t>(f);
      if (point.heights[at] - point.rest_levels[at] > leave) continue;
      activate_pair(on, i);
      touched = true;
    }
    return touched;
  };
  int supported = 0;
  for (int first = 0; first < frames;) {
    if (!idle(first)) {
      ++first;
      continue;
    }
    int last = first;
    while (last + 1 < frames && idle(last + 1)) ++last;
    int from = first, to = last;
    if (first > 0)
      while (from <= to && touch(from)) ++from, ++supported;
    if (last + 1 < frames)
      while (to >= from && touch(to)) --to, ++supported;
    first = last + 1;
  }
  return supported;
}

}  // namespace

bool ContactFrame::touching(int patch) const {
  return std::any_of(points.begin(), points.end(), [&](const ContactPoint& p) { return p.patch == patch; });
}

std::vector<int> ContactFrame::patches() const {
  std::vector<int> out;
  for (const ContactPoint& p : points)
    if (out.empty() || out.back() != p.patch) out.push_back(p.patch);
  return out;
}

Contacts assemble_contacts(const motion::Motion& m, std::vector<ContactPatch> patches,
                           const std::vector<std::vector<bool>>& active) {
  m.check();
  const motion::Skeleton& sk = *m.skeleton;
  std::size_t vertex_count = 0;
  for (std::size_t p = 0; p < patches.size(); ++p) {
    if (patches[p].vertices.empty())
      throw std::invalid_argument("contacts: patch '" + patches[p].name + "' has no vertices");
    for (std::size_t q = 0; q < p; ++q)
      if (patches[q].name == patches[p].name)
        throw std::invalid_argument("contacts: two patches are named '" + patches[p].name + "'");
    for (const ContactVertex& v : patches[p].vertices)
      if (v.joint < 0 || v.joint >= sk.joint_count() || !v.local.allFinite())
        throw std::invalid_argument("contacts: patch '" + patches[p].name + "' has a vertex on joint " +
                                    std::to_string(v.joint) + " (the skeleton has " +
                                    std::to_string(sk.joint_count()) + ") or not finite");
    vertex_count += patches[p].vertices.size();
  }
  if (static_cast<int>(active.size()) != m.frame_count())
    throw std::invalid_argument("contacts: activity for " + std::to_string(active.size()) +
                                " frames, the clip has " + std::to_string(m.frame_count()));
  Contacts c;
  c.skeleton = m.skeleton;
  c.fps = m.fps;
  c.frames.resize(static_cast<std::size_t>(m.frame_count()));
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(sk.joint_count()));
  const int channels = sk.channel_count();
  for (int f = 0; f < m.frame_count(); ++f) {
    const std::vector<bool>& on = active[static_cast<std::size_t>(f)];
    if (on.size() != vertex_count)
      throw std::invalid_argument("contacts: frame " + std::to_string(f) + " gives activity for " +
                                  std::to_string(on.size()) + " vertices, the patches have " +
                                  std::to_string(vertex_count));
    if (std::none_of(on.begin(), on.end(), [](bool b) { return b; })) continue;
    motion::forward_kinematics(sk, m.values.row(f), world);
    std::size_t k = 0;
    for (std::size_t p = 0; p < patches.size(); ++p)
      for (std::size_t v = 0; v < patches[p].vertices.size(); ++v, ++k) {
        if (!on[k]) continue;
        const ContactVertex& cv = patches[p].vertices[v];
        ContactPoint point;
        point.patch = static_cast<int>(p);
        point.vertex = static_cast<int>(v);
        point.world = world[static_cast<std::size_t>(cv.joint)] * cv.local;
        point.jacobian.resize(3, channels);
        motion::point_jacobian(sk, m.values.row(f), world, cv.joint, cv.local, point.jacobian);
        c.frames[static_cast<std::size_t>(f)].points.push_back(std::move(point));
      }
  }
  c.patches = std::move(patches);
  return c;
}

int flattest_frame(const motion::Motion& m, int foot) {
  const motion::Skeleton& sk = *m.skeleton;
  if (foot < 0 || foot >= sk.joint_count())
    throw std::invalid_argument("contacts: foot joint " + std::to_string(foot) + " out of range");
  const auto [tip_joint, tip_local] = toe_tip(sk, foot);
  const int frames = m.frame_count();
  std::vector<double> ball(static_cast<std::size_t>(frames)), tip(static_cast<std::size_t>(frames));
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(sk.joint_count()));
  for (int f = 0; f < frames; ++f) {
    motion::forward_kinematics(sk, m.values.row(f), world);
    const Eigen::Isometry3d& t = world[static_cast<std::size_t>(tip_joint)];
    tip[static_cast<std::size_t>(f)] = (t * tip_local).y();
    ball[static_cast<std::size_t>(f)] =
        tip_joint == foot ? tip[static_cast<std::size_t>(f)] : t.translation().y();
  }
  auto low = [](std::vector<double> v) {
    if (v.empty()) return 0.0;
    const auto k = static_cast<std::ptrdiff_t>(0.05 * static_cast<double>(v.size() - 1));
    std::nth_element(v.begin(), v.begin() + k, v.end());
    return v[static_cast<std::size_t>(k)];
  };
  const double ball_low = low(ball), tip_low = low(tip);
  int best = 0;
  double best_score = std::numeric_limits<double>::infinity();
  for (int f = 0; f < frames; ++f) {
    const double score =
        std::max(ball[static_cast<std::size_t>(f)] - ball_low, tip[static_cast<std::size_t>(f)] - tip_low);
    if (score < best_score) {
      best_score = score;
      best = f;
    }
  }
  return best;
}

void FootContactOptions::validate() const {
  using options::require;
  const char* o = "FootContactOptions";
  require(options::non_negative(heel_ratio), o, "heel_ratio", heel_ratio, ">= 0 and finite");
  require(options::positive(width_ratio), o, "width_ratio", width_ratio, "> 0 and finite");
  require(options::non_negative(support_acceleration), o, "support_acceleration", support_acceleration,
          ">= 0 and finite (m/s^2; 0: off)");
  plants.validate();
}

ContactPatch foot_patch(const motion::Skeleton& sk, motion::FrameRef pose, int foot,
                        const FootContactOptions& o, ContactVertex* heel_out, ContactVertex* tip_out) {
  if (foot < 0 || foot >= sk.joint_count())
    throw std::invalid_argument("contacts: foot joint " + std::to_string(foot) + " out of range");
  o.validate();
  const auto [tip_joint, tip_local] = toe_tip(sk, foot);
  if (pose.size() != sk.channel_count())
    throw std::invalid_argument("contacts: a pose of " + std::to_string(pose.size()) + " values for " +
                                std::to_string(sk.channel_count()) + " channels");
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(sk.joint_count()));
  motion::forward_kinematics(sk, pose, world);
  const Eigen::Isometry3d& foot_world = world[static_cast<std::size_t>(foot)];
  const Eigen::Isometry3d& tip_world = world[static_cast<std::size_t>(tip_joint)];
  const Eigen::Vector3d ankle = foot_world.translation();
  const Eigen::Vector3d tip = tip_world * tip_local;
  const Eigen::Vector3d ball = tip_joint == foot ? tip : tip_world.translation();
  Eigen::Vector3d forward = tip - ankle;
  forward.y() = 0;
  const double d = forward.norm();
  if (!(d > 1e-6))
    throw std::invalid_argument("contacts: the toe tip of foot '" + sk.joint(foot).name +
                                "' is not ahead of its ankle");
  forward /= d;
  const Eigen::Vector3d side = forward.cross(Eigen::Vector3d::UnitY()).normalized();
  const double sole = std::min(ball.y(), tip.y());
  Eigen::Vector3d heel = ankle - o.heel_ratio * d * forward;
  heel.y() = sole;
  Eigen::Vector3d toe = tip;
  toe.y() = sole;
  const double half_width = 0.5 * o.width_ratio * (1 + o.heel_ratio) * d;
  const Eigen::Isometry3d to_foot = foot_world.inverse(), to_tip = tip_world.inverse();
  ContactPatch patch;
  patch.name = sk.joint(foot).name;
  patch.vertices = {{foot, to_foot * (heel + half_width * side)},
                    {tip_joint, to_tip * (toe + half_width * side)},
                    {tip_joint, to_tip * (toe - half_width * side)},
                    {foot, to_foot * (heel - half_width * side)}};
  if (heel_out) *heel_out = {foot, to_foot * heel};
  if (tip_out) *tip_out = {tip_joint, to_tip * toe};
  return patch;
}

Contacts detect_contacts(const motion::Motion& m, const FootContactOptions& o) {
  o.validate();
  m.check();
  const motion::Skeleton& sk = *m.skeleton;
  std::vector<int> feet;
  for (const std::string& name : o.feet) {
    const int j = sk.find_joint(name);
    if (j < 0) {
      std::string msg = "contacts: unknown foot joint " + text::in_quotes(name);
      const std::string near = motion::nearest_joint_name(sk, name);
      if (!near.empty()) msg += " (did you mean " + text::in_quotes(near) + "?)";
      throw std::invalid_argument(msg);
    }
    feet.push_back(j);
  }
  if (feet.empty()) feet = automatic_feet(m);
  if (feet.empty()) throw std::invalid_argument("contacts: no foot found; name the foot joints");

  std::vector<ContactPatch> patches;
  motion::FootplantOptions plants = o.plants;
  plants.points.clear();
  std::vector<std::string> notes;
  for (int foot : feet) {
    ContactVertex heel, tip;
    const int flat = flattest_frame(m, foot);
    patches.push_back(foot_patch(sk, m.values.row(flat), foot, o, &heel, &tip));
    plants.points.push_back(point_spec(sk, heel));
    plants.points.push_back(point_spec(sk, tip));
    const ContactPatch& p = patches.back();
    std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(sk.joint_count()));
    motion::forward_kinematics(sk, m.values.row(flat), world);
    auto at = [&](const ContactVertex& v) { return world[static_cast<std::size_t>(v.joint)] * v.local; };
    notes.push_back("foot " + p.name + ": heel on " + sk.joint(heel.joint).name + ", tip on " +
                    sk.joint(tip.joint).name + ", built at frame " + std::to_string(flat) + ", length " +
                    text::significant((at(p.vertices[1]) - at(p.vertices[0])).norm(), 3) + " m, width " +
                    text::significant((at(p.vertices[1]) - at(p.vertices[2])).norm(), 3) + " m");
  }
  const motion::FootplantDetection d = motion::detect_footplants(m, plants);
  const int frames = m.frame_count();
  std::vector<std::vector<bool>> active(static_cast<std::size_t>(frames),
                                        std::vector<bool>(4 * feet.size(), false));
  for (const motion::Footplant& plant : d.plants)
    for (int f = plant.first_frame; f <= plant.last_frame; ++f)
      activate_pair(active[static_cast<std::size_t>(f)], static_cast<std::size_t>(plant.point));
  const int supported = touch_where_supported(m, d, o, active);
  if (supported > 0)
    notes.push_back(std::to_string(supported) +
                    " frames without plants touch where the root is held up (support_acceleration " +
                    text::significant(o.support_acceleration, 3) +
                    " m/s²): a foot near the floor however fast it moves");
  Contacts c = assemble_contacts(m, std::move(patches), active);
  c.source = "detected";
  c.notes = std::move(notes);
  for (const std::string& n : d.notes)
    if (n.rfind("floor", 0) == 0) c.notes.push_back(n);
  if (!d.floor_estimated)
    c.notes.push_back("floor (given): " + text::significant(d.floor, 3) + " m: the soles touch within " +
                      text::significant(o.plants.height_threshold, 3) + " m of it");
  return c;
}

Eigen::Matrix<double, 3, 4> friction_basis(double mu) {
  if (!(mu >= 0) || !std::isfinite(mu))
    throw std::invalid_argument("friction coefficient " + text::significant(mu, 3) +
                                ": expected a finite number >= 0");
  const double n = 1 / std::sqrt(1 + mu * mu), t = mu * n;
  Eigen::Matrix<double, 3, 4> P;
  P << t, -t, 0, 0,  //
      n, n, n, n,    //
      0, 0, t, -t;
  return P;
}

void contact_generalised_forces(const ContactFrame& frame, int channel_count, double mu, Eigen::MatrixXd& N) {
  const Eigen::Matrix<double, 3, 4> P = friction_basis(mu);
  N.resize(channel_count, 4 * static_cast<Eigen::Index>(frame.points.size()));
  for (std::size_t i = 0; i < frame.points.size(); ++i) {
    const auto& J = frame.points[i].jacobian;
    if (J.cols() != channel_count)
      throw std::invalid_argument("contacts: a point's Jacobian has " + std::to_string(J.cols()) +
                                  " columns, expected " + std::to_string(channel_count));
    N.middleCols<4>(4 * static_cast<Eigen::Index>(i)).noalias() = J.transpose() * P;
  }
}

}  // namespace kg::retime
