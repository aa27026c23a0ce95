// A constraint-kind plugin: `example.plane` keeps a point on a plane, or on one side of it, for
// the retargeting solvers (retarget.spacetime, retarget.per_frame_ik) and retarget.metrics. A
// kind is a kg::retarget::ConstraintKind (kg/retarget/constraints.hpp) that turns the world
// positions of a constraint's points into residual rows and their exact derivatives; it travels
// in the plugin record as a `kg.ConstraintKind` extension, and constraint files then name it like
// a built-in kind:
//
//   - kind: example.plane
//     relation: at_most                  # equal (on the plane), at_least / at_most (a side)
//     points: [{joint: Head}]
//     params: [0, 1, 0, 1.7]             # n = (0, 1, 0), d = 1.7: the head below y = 1.7 m
//     frames: [0, 40]
#include <cmath>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "kg/graph/plugin_abi.hpp"
#include "kg/retarget/constraints.hpp"  // ConstraintKind, Constraint, Relation
#include "kg/retarget/nodes.hpp"        // its interface name, kg.ConstraintKind

namespace {

using kg::retarget::Constraint;
using kg::retarget::Relation;

// params [nx ny nz d]: the plane n . p = d (world, metres; n need not be unit). One row, the
// signed distance g = (n . p - d) / |n|: equal wants g = 0; at_least g >= 0 (the side n points
// to); at_most g <= 0, as the row -g >= 0.
class PlaneKind final : public kg::retarget::ConstraintKind {
 public:
  std::string name() const override { return "example.plane"; }
  std::string doc() const override {
    return "A point on the plane n . p = d (relation equal) or on one side of it (at_least: where "
           "n points, at_most: the other side). points 1; params [nx ny nz d], world metres. Rows: "
           "1, the signed distance (inequality unless equal).";
  }

  void check(const Constraint& c) const override {
    const std::string who = "constraint '" + c.label + "' (example.plane): ";
    if (c.points.size() != 1 || !c.channels.empty())
      throw std::invalid_argument(who + "expects 1 point and no channels, got " +
                                  std::to_string(c.points.size()) + " points and " +
                                  std::to_string(c.channels.size()) + " channels");
    check_params(who, c.params, "params");
    for (const kg::retarget::Sample& s : c.samples) {
      if (s.frames.size() != 1)
        throw std::invalid_argument(who + "each sample reads 1 frame, got " +
                                    std::to_string(s.frames.size()));
      if (!s.params.empty()) check_params(who, s.params, "sample params");
    }
  }

  int rows(const Constraint&) const override { return 1; }
  bool is_inequality(const Constraint& c, int) const override { return c.relation != Relation::Equal; }

  void evaluate(const Constraint& c, std::span<const double> params, std::span<const Eigen::Vector3d> points,
                std::span<const double>, Eigen::Ref<Eigen::VectorXd> residual,
                Eigen::Ref<Eigen::MatrixXd> d_points, Eigen::Ref<Eigen::MatrixXd>) const override {
    const Eigen::Vector3d n(params[0], params[1], params[2]);
    const double length = n.norm();
    const double sign = c.relation == Relation::AtMost ? -1.0 : 1.0;
    residual(0) = sign * (n.dot(points[0]) - params[3]) / length;
    d_points.row(0) = (sign / length) * n.transpose();
  }

 private:
  static void check_params(const std::string& who, const std::vector<double>& p, const char* what) {
    if (p.size() != 4)
      throw std::invalid_argument(who + what + " must be [nx ny nz d], got " + std::to_string(p.size()) +
                                  " numbers");
    for (double v : p)
      if (!std::isfinite(v)) throw std::invalid_argument(who + what + " must be finite");
    if (Eigen::Vector3d(p[0], p[1], p[2]).norm() < 1e-9)
      throw std::invalid_argument(who + "the normal (nx, ny, nz) is zero");
  }
};

kg::graph::PluginRecord make_record() {
  kg::graph::PluginRecord record{"example.plane", "1.0.0"};
  auto kind = std::make_shared<const PlaneKind>();
  record.add_extension<kg::retarget::ConstraintKind>(kind->name(), kind, kind->doc());
  return record;
}

}  // namespace

KG_PLUGIN(make_record)
