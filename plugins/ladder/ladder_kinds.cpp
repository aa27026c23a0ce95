// ladder.rung and ladder.rail (ladder_kinds.hpp).
#include "ladder_kinds.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

namespace kg::ladder {
namespace {

using retarget::Constraint;
using retarget::Relation;

class SegmentKind final : public retarget::ConstraintKind {
 public:
  SegmentKind(std::string name, std::string doc, double default_margin)
      : name_(std::move(name)), doc_(std::move(doc)), default_margin_(default_margin) {}

  std::string name() const override { return name_; }
  std::string doc() const override { return doc_; }

  void check(const Constraint& c) const override {
    const std::string who = "constraint '" + c.label + "' (" + name_ + "): ";
    if (c.points.size() != 1 || !c.channels.empty())
      throw std::invalid_argument(who + "expects 1 point and no channels, got " +
                                  std::to_string(c.points.size()) + " points and " +
                                  std::to_string(c.channels.size()) + " channels");
    if (c.relation != Relation::Equal)
      throw std::invalid_argument(who +
                                  "relation must be equal (the kind makes its own inequality rows), got " +
                                  retarget::to_string(c.relation));
    check_params(who, c.params, "params");
    for (const retarget::Sample& s : c.samples) {
      if (s.frames.size() != 1)
        throw std::invalid_argument(who + "each sample reads 1 frame, got " +
                                    std::to_string(s.frames.size()));
      if (!s.params.empty()) check_params(who, s.params, "sample params");
    }
  }

  int rows(const Constraint&) const override { return 4; }
  bool is_inequality(const Constraint&, int row) const override { return row >= 2; }

  void evaluate(const Constraint&, std::span<const double> params, std::span<const Eigen::Vector3d> points,
                std::span<const double>, Eigen::Ref<Eigen::VectorXd> residual,
                Eigen::Ref<Eigen::MatrixXd> d_points, Eigen::Ref<Eigen::MatrixXd>) const override {
    const Eigen::Vector3d a(params[0], params[1], params[2]);
    const Eigen::Vector3d b(params[3], params[4], params[5]);
    const double margin = params.size() > 6 ? params[6] : default_margin_;
    const Eigen::Vector3d axis = b - a;
    const double length = axis.norm();
    const Eigen::Vector3d u = axis / length;
    Eigen::Index least = 0;
    u.cwiseAbs().minCoeff(&least);
    const Eigen::Vector3d e1 = u.cross(Eigen::Vector3d::Unit(least)).normalized();
    const Eigen::Vector3d e2 = u.cross(e1);
    const Eigen::Vector3d d = points[0] - a;
    const double s = u.dot(d);
    residual(0) = e1.dot(d);
    residual(1) = e2.dot(d);
    residual(2) = s - margin;
    residual(3) = (length - margin) - s;
    d_points.row(0) = e1.transpose();
    d_points.row(1) = e2.transpose();
    d_points.row(2) = u.transpose();
    d_points.row(3) = -u.transpose();
  }

 private:
  void check_params(const std::string& who, const std::vector<double>& p, const char* what) const {
    if (p.size() != 6 && p.size() != 7)
      throw std::invalid_argument(who + what +
                                  " must be [ax ay az bx by bz] or [ax ay az bx by bz margin], got " +
                                  std::to_string(p.size()) + " numbers");
    for (double v : p)
      if (!std::isfinite(v)) throw std::invalid_argument(who + what + " must be finite");
    const double length = (Eigen::Vector3d(p[3], p[4], p[5]) - Eigen::Vector3d(p[0], p[1], p[2])).norm();
    if (length < 1e-6)
      throw std::invalid_argument(who + "the ends A and B coincide (a segment needs a direction)");
    const double margin = p.size() > 6 ? p[6] : default_margin_;
    if (margin < 0 || 2 * margin > length)
      throw std::invalid_argument(who + "margin " + std::to_string(margin) +
                                  " m must be in [0, half the length " + std::to_string(length / 2) + " m]");
  }

  std::string name_, doc_;
  double default_margin_;
};

}  // namespace

std::shared_ptr<const retarget::ConstraintKind> make_rung_kind() {
  return std::make_shared<const SegmentKind>("ladder.rung",
                                             "A footplant that may slide along a ladder rung (Gleicher 1998 "
                                             "7.2). points 1; params [ax ay az bx by bz] "
                                             "or [... margin]: the rung from A to B, world metres, margin "
                                             "(default 0) keeping the point inside the ends. "
                                             "Rows: 2 equality (the point's offset from the rung's line, "
                                             "orthogonal components), 2 inequality (between "
                                             "A and B).",
                                             0.0);
}

std::shared_ptr<const retarget::ConstraintKind> make_rail_kind() {
  return std::make_shared<const SegmentKind>(
      "ladder.rail",
      "A hand-hold that may slide along a ladder rail, a vertical or slanted segment (Gleicher 1998 7.2). "
      "points 1; params [ax ay az bx by bz] or [... margin]: the rail from A to B, world metres, margin "
      "(default "
      "0.04, half a hand) keeping the grip inside the ends. Rows: 2 equality (offset from the rail's line), "
      "2 "
      "inequality (between A and B).",
      0.04);
}

}  // namespace kg::ladder
