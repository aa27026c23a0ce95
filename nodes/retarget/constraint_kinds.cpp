// The seven built-in constraint kinds (Gleicher 1998 §3.5) with analytic derivatives, the kind
// table and the evaluation helpers of constraint_kinds.hpp.
#include "kg/retarget/constraint_kinds.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "kg/base/error.hpp"
#include "kg/base/text.hpp"
#include "kg/motion/kinematics.hpp"

namespace kg::retarget {

const char* to_string(Relation relation) {
  switch (relation) {
    case Relation::Equal:
      return "equal";
    case Relation::AtLeast:
      return "at_least";
    case Relation::AtMost:
      return "at_most";
  }
  return "?";
}

Relation relation_from_string(const std::string& text) {
  if (text == "equal") return Relation::Equal;
  if (text == "at_least") return Relation::AtLeast;
  if (text == "at_most") return Relation::AtMost;
  throw std::invalid_argument("relation " + text::in_quotes(text) + ": expected equal, at_least or at_most");
}

std::string sample_locals_problem(const Constraint& c) {
  for (const Sample& s : c.samples) {
    if (!s.locals.empty() && s.locals.size() != c.points.size())
      return "a sample gives " + std::to_string(s.locals.size()) + " point offsets for " +
             std::to_string(c.points.size()) + " points";
    for (const Eigen::Vector3d& l : s.locals)
      if (!l.allFinite()) return "a sample's point offset is not finite";
  }
  return "";
}

int ConstraintSet::character_count() const {
  int n = 0;
  for (const Constraint& c : constraints) {
    for (const PointRef& p : c.points) n = std::max(n, p.character + 1);
    for (const ChannelRef& ch : c.channels) n = std::max(n, ch.character + 1);
  }
  return n;
}

namespace {

// Smoothing of norms: sqrt(|v|^2 + kNormEps2) stays differentiable at 0 and differs from |v| by
// under 1e-11 m beyond a millimetre.
constexpr double kNormEps2 = 1e-12;

[[noreturn]] void fail(const Constraint& c, const std::string& what) {
  throw std::invalid_argument("constraint '" + c.label + "' (" + c.kind + "): " + what);
}

std::string count_text(std::size_t n, const char* noun) {
  return std::to_string(n) + " " + noun + (n == 1 ? "" : "s");
}

// What every kind checks: shapes of points/channels, samples, weight and finite numbers.
void check_common(const Constraint& c, std::size_t points, std::size_t min_channels,
                  std::size_t max_channels) {
  if (c.points.size() != points)
    fail(c, "expects " + count_text(points, "point") + ", got " + std::to_string(c.points.size()));
  if (c.channels.size() < min_channels || c.channels.size() > max_channels) {
    if (min_channels == max_channels)
      fail(c,
           "expects " + count_text(min_channels, "channel") + ", got " + std::to_string(c.channels.size()));
    fail(c, "expects at least " + count_text(min_channels, "channel") + ", got " +
                std::to_string(c.channels.size()));
  }
  for (const PointRef& p : c.points) {
    if (p.character < 0 || p.joint < 0) fail(c, "a point has no joint or a negative character");
    if (!p.local.allFinite()) fail(c, "a point's local offset is not finite");
  }
  for (const ChannelRef& ch : c.channels)
    if (ch.character < 0 || ch.channel < 0) fail(c, "a channel has no index or a negative character");
  if (!(c.weight > 0) || !std::isfinite(c.weight)) fail(c, "weight must be positive and finite");
  if (c.samples.empty()) fail(c, "has no samples (frames)");
  const std::size_t frames = c.points.size() + c.channels.size();
  if (const std::string problem = sample_locals_problem(c); !problem.empty()) fail(c, problem);
  for (const Sample& s : c.samples) {
    if (s.frames.size() != frames)
      fail(c, "a sample has " + std::to_string(s.frames.size()) + " frames, expected " +
                  std::to_string(frames) + " (one per point, then one per channel)");
    for (int f : s.frames)
      if (f < 0) fail(c, "a sample has the negative frame " + std::to_string(f));
    if (!s.params.empty() && s.params.size() != c.params.size())
      fail(c, "a sample has " + std::to_string(s.params.size()) + " params, the constraint " +
                  std::to_string(c.params.size()));
  }
}

void check_params_count(const Constraint& c, std::initializer_list<std::size_t> allowed,
                        const char* meaning) {
  for (std::size_t n : allowed)
    if (c.params.size() == n) return;
  fail(c, "expects params " + std::string(meaning) + ", got " + std::to_string(c.params.size()) + " numbers");
}

// Every sample's params (and the constraint's) are not NaN; `finite_pattern` kinds also keep the
// constraint's pattern of infinite bounds, since rows() depends on it.
void check_numbers(const Constraint& c, bool allow_inf, bool finite_pattern) {
  auto check_one = [&](const std::vector<double>& ps) {
    for (std::size_t i = 0; i < ps.size(); ++i) {
      if (std::isnan(ps[i])) fail(c, "param " + std::to_string(i) + " is NaN");
      if (!allow_inf && std::isinf(ps[i])) fail(c, "param " + std::to_string(i) + " is infinite");
      if (finite_pattern && std::isfinite(ps[i]) != std::isfinite(c.params[i]))
        fail(c, "a sample's param " + std::to_string(i) +
                    " differs from the constraint's in being finite (the rows would change)");
    }
  };
  check_one(c.params);
  for (const Sample& s : c.samples) check_one(s.params);
}

void check_mask(const Constraint& c, std::span<const double> mask) {
  int on = 0;
  for (double m : mask) {
    if (m != 0 && m != 1) fail(c, "a mask entry must be 0 or 1");
    on += m == 1;
  }
  if (on == 0) fail(c, "the mask fixes no axis");
}

double sign_of(Relation r) {
  return r == Relation::AtMost ? -1.0 : 1.0;
}

// ---- parameter_range -------------------------------------------------------------------------
class ParameterRange final : public ConstraintKind {
 public:
  std::string name() const override { return "parameter_range"; }
  std::string doc() const override {
    return "channel values in [min, max] (params [min, max], +-inf allowed; inequality rows), or "
           "params [value] with relation equal, at_least or at_most";
  }
  void check(const Constraint& c) const override {
    check_common(c, 0, 1, std::numeric_limits<std::size_t>::max());
    check_params_count(c, {1, 2}, "[min, max] or [value]");
    check_numbers(c, c.params.size() == 2, c.params.size() == 2);
    if (c.params.size() == 2) {
      if (c.relation != Relation::Equal)
        fail(c, "a [min, max] range takes relation equal (its rows are inequalities)");
      auto bad = [&](const std::vector<double>& p) { return p[0] > p[1]; };
      if (bad(c.params)) fail(c, "min > max");
      for (const Sample& s : c.samples)
        if (!s.params.empty() && bad(s.params)) fail(c, "a sample has min > max");
      if (!std::isfinite(c.params[0]) && !std::isfinite(c.params[1])) fail(c, "both bounds are infinite");
    }
  }
  int rows(const Constraint& c) const override {
    const int n = static_cast<int>(c.channels.size());
    if (c.params.size() != 2) return n;
    return n * (std::isfinite(c.params[0]) + std::isfinite(c.params[1]));
  }
  bool is_inequality(const Constraint& c, int) const override {
    return c.params.size() == 2 || c.relation != Relation::Equal;
  }
  void evaluate(const Constraint& c, std::span<const double> params, std::span<const Eigen::Vector3d>,
                std::span<const double> values, Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd>,
                Eigen::Ref<Eigen::MatrixXd> dv) const override {
    if (c.params.size() == 1) {
      const double s = sign_of(c.relation);
      for (std::size_t i = 0; i < values.size(); ++i) {
        r[static_cast<Eigen::Index>(i)] = s * (values[i] - params[0]);
        dv(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i)) = s;
      }
      return;
    }
    Eigen::Index row = 0;
    const bool lo = std::isfinite(c.params[0]), hi = std::isfinite(c.params[1]);
    for (std::size_t i = 0; i < values.size(); ++i) {
      const auto col = static_cast<Eigen::Index>(i);
      if (lo) {
        r[row] = values[i] - params[0];
        dv(row++, col) = 1;
      }
      if (hi) {
        r[row] = params[1] - values[i];
        dv(row++, col) = -1;
      }
    }
  }
};

// ---- position --------------------------------------------------------------------------------
class Position final : public ConstraintKind {
 public:
  std::string name() const override { return "position"; }
  std::string doc() const override {
    return "a point at a location on the masked world axes: params [x y z mx my mz] (or [x y z]: all axes)";
  }
  void check(const Constraint& c) const override {
    check_common(c, 1, 0, 0);
    check_params_count(c, {3, 6}, "[x y z] or [x y z mx my mz]");
    check_numbers(c, false, false);
    if (c.params.size() == 6) {
      check_mask(c, std::span(c.params).subspan(3));
      for (const Sample& s : c.samples)
        if (!s.params.empty() && !std::equal(s.params.begin() + 3, s.params.end(), c.params.begin() + 3))
          fail(c, "a sample's mask differs from the constraint's");
    }
  }
  int rows(const Constraint& c) const override { return mask_count(c.params, 3); }
  bool is_inequality(const Constraint& c, int) const override { return c.relation != Relation::Equal; }
  void evaluate(const Constraint& c, std::span<const double> params, std::span<const Eigen::Vector3d> points,
                std::span<const double>, Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> dp,
                Eigen::Ref<Eigen::MatrixXd>) const override {
    const double s = sign_of(c.relation);
    Eigen::Index row = 0;
    for (int a = 0; a < 3; ++a) {
      if (!masked(c.params, 3, a)) continue;
      r[row] = s * (points[0][a] - params[static_cast<std::size_t>(a)]);
      dp(row++, a) = s;
    }
  }

  // Shared with follow_path: params[mask_at + a] is axis a's mask (all on when absent).
  static bool masked(const std::vector<double>& params, std::size_t mask_at, int a) {
    return params.size() < mask_at + 3 || params[mask_at + static_cast<std::size_t>(a)] != 0;
  }
  static int mask_count(const std::vector<double>& params, std::size_t mask_at) {
    return masked(params, mask_at, 0) + masked(params, mask_at, 1) + masked(params, mask_at, 2);
  }
};

// ---- region ----------------------------------------------------------------------------------
class Region final : public ConstraintKind {
 public:
  std::string name() const override { return "region"; }
  std::string doc() const override {
    return "a point inside a box: params [minx miny minz maxx maxy maxz] (+-inf allowed); inequality rows";
  }
  void check(const Constraint& c) const override {
    check_common(c, 1, 0, 0);
    check_params_count(c, {6}, "[minx miny minz maxx maxy maxz]");
    check_numbers(c, true, true);
    auto bad = [](const std::vector<double>& p) { return p[0] > p[3] || p[1] > p[4] || p[2] > p[5]; };
    if (bad(c.params)) fail(c, "a min bound exceeds its max");
    for (const Sample& s : c.samples)
      if (!s.params.empty() && bad(s.params)) fail(c, "a sample's min bound exceeds its max");
    if (rows(c) == 0) fail(c, "every bound is infinite");
    if (c.relation != Relation::Equal) fail(c, "takes relation equal (its rows are inequalities already)");
  }
  int rows(const Constraint& c) const override {
    int n = 0;
    for (double v : c.params) n += std::isfinite(v);
    return n;
  }
  bool is_inequality(const Constraint&, int) const override { return true; }
  void evaluate(const Constraint& c, std::span<const double> params, std::span<const Eigen::Vector3d> points,
                std::span<const double>, Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> dp,
                Eigen::Ref<Eigen::MatrixXd>) const override {
    Eigen::Index row = 0;
    for (int a = 0; a < 3; ++a) {
      if (std::isfinite(c.params[static_cast<std::size_t>(a)])) {
        r[row] = points[0][a] - params[static_cast<std::size_t>(a)];
        dp(row++, a) = 1;
      }
      if (std::isfinite(c.params[static_cast<std::size_t>(a + 3)])) {
        r[row] = params[static_cast<std::size_t>(a + 3)] - points[0][a];
        dp(row++, a) = -1;
      }
    }
  }
};

// ---- same_place ------------------------------------------------------------------------------
class SamePlace final : public ConstraintKind {
 public:
  std::string name() const override { return "same_place"; }
  std::string doc() const override {
    return "a point at the same (free) place at two frames: points [p, p], sample frames [fa, fb], params [] "
           "or a mask [mx my mz] (non-skid: [1 0 1])";
  }
  void check(const Constraint& c) const override {
    check_common(c, 2, 0, 0);
    check_params_count(c, {0, 3}, "[] or a mask [mx my mz]");
    check_numbers(c, false, false);
    if (c.params.size() == 3) check_mask(c, c.params);
    for (const Sample& s : c.samples)
      if (!s.params.empty() && s.params != c.params) fail(c, "a sample's mask differs from the constraint's");
    if (c.relation != Relation::Equal) fail(c, "takes relation equal only");
  }
  int rows(const Constraint& c) const override { return Position::mask_count(c.params, 0); }
  bool is_inequality(const Constraint&, int) const override { return false; }
  void evaluate(const Constraint& c, std::span<const double>, std::span<const Eigen::Vector3d> points,
                std::span<const double>, Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> dp,
                Eigen::Ref<Eigen::MatrixXd>) const override {
    Eigen::Index row = 0;
    for (int a = 0; a < 3; ++a) {
      if (!Position::masked(c.params, 0, a)) continue;
      r[row] = points[1][a] - points[0][a];
      dp(row, a) = -1;
      dp(row++, 3 + a) = 1;
    }
  }
};

// ---- follow_path -----------------------------------------------------------------------------
class FollowPath final : public ConstraintKind {
 public:
  std::string name() const override { return "follow_path"; }
  std::string doc() const override {
    return "a point p following another point q at an offset: points [p, q], params [ox oy oz] or "
           "[ox oy oz mx my mz]; rows p - q - o on the masked axes";
  }
  void check(const Constraint& c) const override {
    check_common(c, 2, 0, 0);
    check_params_count(c, {0, 3, 6}, "[], [ox oy oz] or [ox oy oz mx my mz]");
    check_numbers(c, false, false);
    if (c.params.size() == 6) {
      check_mask(c, std::span(c.params).subspan(3));
      for (const Sample& s : c.samples)
        if (!s.params.empty() && !std::equal(s.params.begin() + 3, s.params.end(), c.params.begin() + 3))
          fail(c, "a sample's mask differs from the constraint's");
    }
  }
  int rows(const Constraint& c) const override { return Position::mask_count(c.params, 3); }
  bool is_inequality(const Constraint& c, int) const override { return c.relation != Relation::Equal; }
  void evaluate(const Constraint& c, std::span<const double> params, std::span<const Eigen::Vector3d> points,
                std::span<const double>, Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> dp,
                Eigen::Ref<Eigen::MatrixXd>) const override {
    const double s = sign_of(c.relation);
    Eigen::Index row = 0;
    for (int a = 0; a < 3; ++a) {
      if (!Position::masked(c.params, 3, a)) continue;
      const double o = params.size() >= 3 ? params[static_cast<std::size_t>(a)] : 0.0;
      r[row] = s * (points[0][a] - points[1][a] - o);
      dp(row, a) = s;
      dp(row++, 3 + a) = -s;
    }
  }
};

// ---- distance --------------------------------------------------------------------------------
class Distance final : public ConstraintKind {
 public:
  std::string name() const override { return "distance"; }
  std::string doc() const override {
    return "two points a distance apart: points [p, q], params [d] metres; |p - q| = d, >= d (at_least), "
           "<= d (at_most)";
  }
  void check(const Constraint& c) const override {
    check_common(c, 2, 0, 0);
    check_params_count(c, {1}, "[d]");
    check_numbers(c, false, false);
    if (c.params[0] < 0) fail(c, "the distance is negative");
    for (const Sample& s : c.samples)
      if (!s.params.empty() && s.params[0] < 0) fail(c, "a sample's distance is negative");
  }
  int rows(const Constraint&) const override { return 1; }
  bool is_inequality(const Constraint& c, int) const override { return c.relation != Relation::Equal; }
  void evaluate(const Constraint& c, std::span<const double> params, std::span<const Eigen::Vector3d> points,
                std::span<const double>, Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> dp,
                Eigen::Ref<Eigen::MatrixXd>) const override {
    const double s = sign_of(c.relation);
    const Eigen::Vector3d v = points[0] - points[1];
    const double n = std::sqrt(v.squaredNorm() + kNormEps2);
    r[0] = s * (n - params[0]);
    const Eigen::Vector3d g = s * v / n;
    dp.block<1, 3>(0, 0) = g.transpose();
    dp.block<1, 3>(0, 3) = -g.transpose();
  }
};

// ---- orientation -----------------------------------------------------------------------------
class Orientation final : public ConstraintKind {
 public:
  std::string name() const override { return "orientation"; }
  std::string doc() const override {
    return "the vector from p to q along a direction: points [p, q]; equal: params [dx dy dz], rows "
           "(q - p)/|q - p| - d; at_most / at_least: params [dx dy dz angle_rad], the angle to d at most / "
           "at least angle";
  }
  void check(const Constraint& c) const override {
    check_common(c, 2, 0, 0);
    if (c.relation == Relation::Equal)
      check_params_count(c, {3}, "[dx dy dz] with relation equal");
    else
      check_params_count(c, {4}, "[dx dy dz max_angle_rad] with relation at_most or at_least");
    check_numbers(c, false, false);
    auto bad = [](const std::vector<double>& p) { return Eigen::Vector3d(p[0], p[1], p[2]).norm() < 1e-9; };
    if (bad(c.params)) fail(c, "the direction is zero");
    for (const Sample& s : c.samples)
      if (!s.params.empty() && bad(s.params)) fail(c, "a sample's direction is zero");
  }
  int rows(const Constraint& c) const override { return c.relation == Relation::Equal ? 3 : 1; }
  bool is_inequality(const Constraint& c, int) const override { return c.relation != Relation::Equal; }
  void evaluate(const Constraint& c, std::span<const double> params, std::span<const Eigen::Vector3d> points,
                std::span<const double>, Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> dp,
                Eigen::Ref<Eigen::MatrixXd>) const override {
    const Eigen::Vector3d d = Eigen::Vector3d(params[0], params[1], params[2]).normalized();
    const Eigen::Vector3d v = points[1] - points[0];
    const double n = std::sqrt(v.squaredNorm() + kNormEps2);
    const Eigen::Vector3d u = v / n;
    // du/dq = (I - u u^T) / n (with the smoothed norm: (I - v v^T / n^2) / n); du/dp = -du/dq.
    const Eigen::Matrix3d du = (Eigen::Matrix3d::Identity() - v * v.transpose() / (n * n)) / n;
    if (c.relation == Relation::Equal) {
      r.head<3>() = u - d;
      dp.block<3, 3>(0, 0) = -du;
      dp.block<3, 3>(0, 3) = du;
      return;
    }
    const double s = c.relation == Relation::AtMost ? 1.0 : -1.0;
    r[0] = s * (u.dot(d) - std::cos(params[3]));
    const Eigen::RowVector3d g = s * d.transpose() * du;
    dp.block<1, 3>(0, 0) = -g;
    dp.block<1, 3>(0, 3) = g;
  }
};

std::vector<std::shared_ptr<const ConstraintKind>> builtin_kinds() {
  return {std::make_shared<ParameterRange>(), std::make_shared<Position>(),   std::make_shared<Region>(),
          std::make_shared<SamePlace>(),      std::make_shared<FollowPath>(), std::make_shared<Distance>(),
          std::make_shared<Orientation>()};
}

}  // namespace

// ---- table -----------------------------------------------------------------------------------
ConstraintKindTable ConstraintKindTable::builtin() {
  static const std::vector<std::shared_ptr<const ConstraintKind>> kinds = builtin_kinds();
  ConstraintKindTable table;
  for (const auto& k : kinds) table.add(k);
  return table;
}

void ConstraintKindTable::add(std::shared_ptr<const ConstraintKind> kind) {
  if (!kind) throw std::invalid_argument("constraint kind table: null kind");
  std::string name = kind->name();
  if (kinds_.count(name) != 0)
    throw std::invalid_argument("constraint kind '" + name + "' is already in the table");
  kinds_.emplace(std::move(name), std::move(kind));
}

const ConstraintKind* ConstraintKindTable::find(const std::string& name) const {
  auto it = kinds_.find(name);
  return it == kinds_.end() ? nullptr : it->second.get();
}

std::shared_ptr<const ConstraintKind> ConstraintKindTable::find_shared(const std::string& name) const {
  auto it = kinds_.find(name);
  return it == kinds_.end() ? nullptr : it->second;
}

std::vector<std::string> ConstraintKindTable::names() const {
  std::vector<std::string> out;
  for (const auto& [name, kind] : kinds_) out.push_back(name);
  return out;
}

namespace {
[[noreturn]] void throw_unknown_kind(const Constraint& c, const std::vector<std::string>& known) {
  std::string msg =
      "constraint '" + c.label + "': unknown kind '" + c.kind + "' (known: " + text::join(known);
  const std::string near = kg::nearest_name(c.kind, known);
  if (!near.empty()) msg += "; did you mean " + text::in_quotes(near) + "?";
  throw std::invalid_argument(msg + ")");
}
}  // namespace

ConstraintKindTable kinds_for(const ConstraintSet& set, const ConstraintKindLookup& lookup) {
  ConstraintKindTable table = ConstraintKindTable::builtin();
  for (const Constraint& c : set.constraints) {
    if (table.find(c.kind) != nullptr) continue;
    std::shared_ptr<const ConstraintKind> kind = lookup ? lookup(c.kind) : nullptr;
    if (!kind) throw_unknown_kind(c, table.names());
    if (kind->name() != c.kind)
      throw std::invalid_argument("constraint kind extension '" + c.kind + "' calls itself '" + kind->name() +
                                  "'");
    table.add(std::move(kind));
  }
  return table;
}

void check_constraints(const ConstraintSet& set, const ConstraintKindTable& kinds) {
  for (const Constraint& c : set.constraints) {
    const ConstraintKind* kind = kinds.find(c.kind);
    if (kind == nullptr) throw_unknown_kind(c, kinds.names());
    kind->check(c);
  }
}

// ---- evaluation ------------------------------------------------------------------------------
PoseCache::PoseCache(std::span<const motion::Motion> motions, std::span<const SkeletonAt> skeleton_at)
    : motions_(motions) {
  world_.resize(motions.size());
  for (std::size_t c = 0; c < motions.size(); ++c) {
    const motion::Motion& m = motions[c];
    if (!m.skeleton)
      throw std::invalid_argument("pose cache: character " + std::to_string(c) + " has no skeleton");
    const int joints = m.skeleton->joint_count();
    world_[c].resize(static_cast<std::size_t>(m.frame_count()) * static_cast<std::size_t>(joints));
    const bool morphing = c < skeleton_at.size() && skeleton_at[c];
    for (int f = 0; f < m.frame_count(); ++f) {
      const std::shared_ptr<const motion::Skeleton> at_frame = morphing ? skeleton_at[c](f) : nullptr;
      motion::forward_kinematics(at_frame ? *at_frame : *m.skeleton, m.values.row(f),
                                 std::span(world_[c]).subspan(static_cast<std::size_t>(f) * joints, joints));
    }
  }
}

int PoseCache::frame_count(int character) const {
  return motions_[static_cast<std::size_t>(character)].frame_count();
}

Eigen::Vector3d PoseCache::point(const PointRef& p, int frame) const {
  if (p.character < 0 || p.character >= character_count())
    throw std::out_of_range("character " + std::to_string(p.character) + " of " +
                            std::to_string(character_count()));
  const motion::Motion& m = motions_[static_cast<std::size_t>(p.character)];
  const int joints = m.skeleton->joint_count();
  if (p.joint < 0 || p.joint >= joints)
    throw std::out_of_range("joint " + std::to_string(p.joint) + " of character " +
                            std::to_string(p.character) + " (it has " + std::to_string(joints) + ")");
  if (frame < 0 || frame >= m.frame_count())
    throw std::out_of_range("frame " + std::to_string(frame) + " of character " +
                            std::to_string(p.character) + " (it has " + std::to_string(m.frame_count()) +
                            ")");
  return world_[static_cast<std::size_t>(p.character)][static_cast<std::size_t>(frame) * joints + p.joint] *
         p.local;
}

double PoseCache::value(const ChannelRef& ch, int frame) const {
  if (ch.character < 0 || ch.character >= character_count())
    throw std::out_of_range("character " + std::to_string(ch.character) + " of " +
                            std::to_string(character_count()));
  const motion::Motion& m = motions_[static_cast<std::size_t>(ch.character)];
  if (ch.channel < 0 || ch.channel >= m.values.cols())
    throw std::out_of_range("channel " + std::to_string(ch.channel) + " of character " +
                            std::to_string(ch.character));
  if (frame < 0 || frame >= m.frame_count())
    throw std::out_of_range("frame " + std::to_string(frame) + " of character " +
                            std::to_string(ch.character) + " (it has " + std::to_string(m.frame_count()) +
                            ")");
  return m.values(frame, ch.channel);
}

namespace {
// Scratch of one constraint's evaluation, reused across its samples.
struct Scratch {
  std::vector<Eigen::Vector3d> points;
  std::vector<double> values;
  Eigen::MatrixXd dp, dv;
};

void evaluate_into(const ConstraintKind& kind, const Constraint& c, const Sample& s, const PoseCache& poses,
                   Scratch& scratch, Eigen::VectorXd& r) {
  const std::size_t np = c.points.size(), nc = c.channels.size();
  if (s.frames.size() != np + nc)
    throw std::out_of_range("constraint '" + c.label + "': a sample has " + std::to_string(s.frames.size()) +
                            " frames, expected " + std::to_string(np + nc));
  scratch.points.resize(np);
  scratch.values.resize(nc);
  try {
    for (std::size_t i = 0; i < np; ++i) scratch.points[i] = poses.point(point_at(c, s, i), s.frames[i]);
    for (std::size_t i = 0; i < nc; ++i) scratch.values[i] = poses.value(c.channels[i], s.frames[np + i]);
  } catch (const std::out_of_range& e) {
    throw std::out_of_range("constraint '" + c.label + "': " + e.what());
  }
  const int rows = kind.rows(c);
  r.setZero(rows);
  scratch.dp.setZero(rows, static_cast<Eigen::Index>(3 * np));
  scratch.dv.setZero(rows, static_cast<Eigen::Index>(nc));
  const std::vector<double>& params = s.params.empty() ? c.params : s.params;
  kind.evaluate(c, params, scratch.points, scratch.values, r, scratch.dp, scratch.dv);
}
}  // namespace

void evaluate_sample(const ConstraintKind& kind, const Constraint& constraint, const Sample& sample,
                     const PoseCache& poses, Eigen::VectorXd& residual) {
  Scratch scratch;
  evaluate_into(kind, constraint, sample, poses, scratch, residual);
}

double ViolationSummary::worst() const {
  double w = 0;
  for (const KindViolation& k : kinds) w = std::max(w, k.worst);
  return w;
}

const KindViolation* ViolationSummary::find(const std::string& kind) const {
  for (const KindViolation& k : kinds)
    if (k.kind == kind) return &k;
  return nullptr;
}

ViolationSummary summarize_violations(const ConstraintSet& set, const ConstraintKindTable& kinds,
                                      const PoseCache& poses, double tolerance) {
  std::map<std::string, KindViolation> by_kind;
  std::map<std::string, double> sums;
  Scratch scratch;
  Eigen::VectorXd r;
  for (const Constraint& c : set.constraints) {
    if (c.soft) continue;  // an objective term: never a violation
    const ConstraintKind* kind = kinds.find(c.kind);
    if (kind == nullptr) throw_unknown_kind(c, kinds.names());
    KindViolation& kv = by_kind[c.kind];
    kv.kind = c.kind;
    double& sum = sums[c.kind];
    const int rows = kind->rows(c);
    std::vector<char> inequality(static_cast<std::size_t>(rows));
    for (int i = 0; i < rows; ++i) inequality[static_cast<std::size_t>(i)] = kind->is_inequality(c, i);
    for (const Sample& s : c.samples) {
      evaluate_into(*kind, c, s, poses, scratch, r);
      for (int i = 0; i < rows; ++i) {
        const bool ineq = inequality[static_cast<std::size_t>(i)] != 0;
        const double v = row_violation(r[i], ineq);
        ++kv.rows;
        if (!ineq || r[i] < 0) {
          ++kv.counted_rows;
          sum += v;
        }
        if (v > tolerance) ++kv.violated_rows;
        if (kv.worst_frame < 0 || v > kv.worst) {
          kv.worst = v;
          kv.worst_label = c.label;
          kv.worst_frame = s.frames.empty() ? -1 : s.frames[0];
        }
      }
    }
  }
  ViolationSummary out;
  for (auto& [name, kv] : by_kind) {
    kv.mean = kv.counted_rows > 0 ? sums[name] / kv.counted_rows : 0.0;
    out.kinds.push_back(std::move(kv));
  }
  return out;
}

ViolationSummary summarize_violations(const ConstraintSet& set, const ConstraintKindTable& kinds,
                                      std::span<const motion::Motion> motions, double tolerance) {
  const PoseCache poses(motions);
  return summarize_violations(set, kinds, poses, tolerance);
}

}  // namespace kg::retarget
