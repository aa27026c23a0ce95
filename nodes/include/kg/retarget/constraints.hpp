// Constraints of a retargeting problem (Gleicher 1998, §3.5): features of the motion that must
// hold again on the new character. A constraint reads points fixed on segments (or channel
// values) of one or two characters at given frames and yields residual rows; the solvers,
// the per-frame IK baseline and the metrics all evaluate constraints only through the
// ConstraintKind interface, so built-in kinds and kinds loaded from plugins are alike.
//
// Row convention: an equality row wants r = 0; an inequality row wants r >= 0 (the solver's
// active set adds a violated inequality row as if it were an equality and drops it once it
// is satisfied). Units: metres for points, the channel's unit (metres or radians) for values.
//
//   Constraint plant{.kind = "position", .label = "LeftToe plant 2",
//                    .points = {{.joint = toe, .local = {0, 0, 0.05}}},
//                    .params = {x, y, z, 1, 1, 1}};          // target, then the axes it fixes
//   for (int f = 40; f <= 55; ++f) plant.samples.push_back({.frames = {f}});
//   ConstraintSet set; set.constraints.push_back(plant);
#pragma once

#include <memory>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "kg/motion/skeleton.hpp"

namespace kg::retarget {

using motion::PointRef;  // kg/motion/skeleton.hpp

// One frame channel of a character (for parameter constraints such as joint limits).
struct ChannelRef {
  int character = 0;
  int channel = -1;
};

// How the kind's measured quantity g relates to its target t (params): Equal g = t,
// AtLeast g >= t, AtMost g <= t. Kinds with a natural two-sided form (region, range) ignore it
// and produce their own inequality rows.
enum class Relation { Equal, AtLeast, AtMost };
const char* to_string(Relation relation);  // "equal", "at_least", "at_most"

// One instant (or, for two-time constraints, a few instants) at which a constraint is sampled:
// point i is read at frames[i] (frames.size() == points.size() + channels.size(); channels
// after points). `params`, when not empty, replaces the constraint's params for this sample
// (a target that moves per frame). `locals`, when not empty (points.size() entries, metres in
// each point's joint frame), replaces the points' local offsets for this sample: a point on a
// segment whose length changes over the clip (a morphing target, §5).
struct Sample {
  std::vector<int> frames;
  std::vector<double> params{};
  std::vector<Eigen::Vector3d> locals{};
};

struct Constraint {
  std::string kind;   // built-in: parameter_range, position, region, same_place, follow_path,
                      // distance, orientation; or a plugin's kind name
  std::string label;  // for reports and messages, e.g. "LeftToe plant 2"
  Relation relation = Relation::Equal;
  std::vector<PointRef> points{};
  std::vector<ChannelRef> channels{};
  std::vector<double> params{};  // the kind's numbers (see each kind's doc)
  std::vector<Sample> samples{};
  double weight = 1.0;  // row scale in least squares
  // An objective term, not a requirement (§8's "best matching motion": features a target of
  // another structure can only approach): its rows enter the least squares with `weight` like any
  // others, but no solver waits for them to hold and they count in no violation or unmet figure.
  bool soft = false;
};

// Point i of `constraint` as sample `sample` reads it (its local offset replaced by the sample's).
inline PointRef point_at(const Constraint& constraint, const Sample& sample, std::size_t i) {
  PointRef p = constraint.points[i];
  if (!sample.locals.empty()) p.local = sample.locals[i];
  return p;
}

// "" when every sample's `locals` suit `constraint` (none, or one finite offset per point), else
// what is wrong, for the caller's message: kind-independent, so the solver checks plugin kinds' too.
std::string sample_locals_problem(const Constraint& constraint);

struct ConstraintSet {
  std::vector<Constraint> constraints;
  // Number of characters the constraints refer to (max PointRef/ChannelRef character + 1).
  int character_count() const;
};

// The interface of a constraint kind: the `kg.ConstraintKind` extension of the registry
// (graph/registry.hpp). Plugins export std::shared_ptr<const ConstraintKind> as the extension's
// factory; the solver asks the registry for kinds by name. Implementations are stateless and
// thread-safe.
class ConstraintKind {
 public:
  virtual ~ConstraintKind() = default;
  virtual std::string name() const = 0;
  virtual std::string doc() const = 0;
  // Throws std::invalid_argument (naming the constraint's label) when points, channels, params
  // or sample shapes do not suit the kind.
  virtual void check(const Constraint& constraint) const = 0;
  // Rows one sample yields (fixed per constraint).
  virtual int rows(const Constraint& constraint) const = 0;
  // Whether row `row` is an inequality (want r >= 0) rather than an equality (want r = 0).
  virtual bool is_inequality(const Constraint& constraint, int row) const = 0;
  // Residuals of one sample and their derivatives: `points` are the world positions (metres)
  // of constraint.points at the sample's frames, `values` the channel values of
  // constraint.channels; params are the sample's (or the constraint's). d_points is
  // rows x (3 * points.size()), d_values rows x values.size(); both arrive zeroed.
  virtual void evaluate(const Constraint& constraint, std::span<const double> params,
                        std::span<const Eigen::Vector3d> points, std::span<const double> values,
                        Eigen::Ref<Eigen::VectorXd> residual, Eigen::Ref<Eigen::MatrixXd> d_points,
                        Eigen::Ref<Eigen::MatrixXd> d_values) const = 0;
};

}  // namespace kg::retarget
