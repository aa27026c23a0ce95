// The retiming objective of McCann et al. 2006 (§3.5 eq. 14, §3.6), baked: per source frame, the
// integrand
//   α |(p̈, ṗ²) − c|²  +  β |τ(p̈, ṗ²) − τ'|² / τ_scale²
// where c is the closest point of the frame's hull (feasibility) and τ the generalised forces of
// the force model (piecewise affine in (p̈, ṗ²) over the hull's fan of sectors around its centre),
// so the torque term is, per sector, a quadratic with six coefficients (those of ṗ⁴, p̈², ṗ²p̈,
// ṗ², p̈ and 1). τ_scale (N m) makes the torque term dimensionless: the RMS of the source's
// actuated generalised forces, so α and β weigh comparable quantities whatever the body.
// Between frames, the two frames' integrands are interpolated linearly in source time.
//
//   BakedObjective objective = ...;                         // retime.retime builds it
//   int hint = 0;
//   SampleCost c = objective.evaluate(1.25, 0.0, 1.0, hint);   // at source 1.25 s, original timing
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "kg/retime/retimer.hpp"

namespace kg::retime {

// The six coefficients of a quadratic in (a, b) = (p̈, ṗ²):
//   q[0] b² + q[1] a² + q[2] a b + q[3] b + q[4] a + q[5].
using Quadratic = std::array<double, 6>;

// |t0 + ta a + tb b − target|² · weight as a Quadratic (all vectors of one size).
Quadratic bake_quadratic(const Eigen::VectorXd& t0, const Eigen::VectorXd& ta, const Eigen::VectorXd& tb,
                         const Eigen::VectorXd& target, double weight);

// One source frame's baked integrand.
struct BakedFrame {
  // The hull, counter-clockwise in (p̈, ṗ²); 1 vertex for a frame whose polytope is empty
  // (the closest point), 2 for a segment. Sectors: sector k spans the rays from `centre` through
  // vertices k and k + 1 (cyclically); with fewer than 3 vertices there is one sector.
  std::vector<Eigen::Vector2d> vertices{};
  Eigen::Vector2d centre = Eigen::Vector2d(0, 1);
  std::vector<Quadratic> sectors{};  // β-weighted torque term per sector
  std::vector<double> angles{};      // angle of each vertex around centre (radians, increasing)
};

// The frames' integrands; evaluate() interpolates them linearly in source time. Build with
// add frames in order, then finish().
class BakedObjective final : public PathObjective {
 public:
  BakedObjective(double source_fps, double alpha) : fps_(source_fps), alpha_(alpha) {}
  void add_frame(BakedFrame frame);
  // Sorts out the sectors' angles; call once after the last add_frame.
  void finish();

  SampleCost evaluate(double p, double pddot, double pdot_squared, int& hint) const override;
  double source_duration() const override { return (static_cast<double>(frames_.size()) - 1) / fps_; }
  double source_fps() const override { return fps_; }

  // The two parts of one frame's integrand at (p̈, ṗ²), and whether the point lies in its hull
  // (within `tolerance` in the plane).
  struct Parts {
    double feasibility = 0;  // α |q − c|²
    double torque = 0;       // β |τ − τ'|² / τ_scale²
    bool inside = false;
    int sector = 0;
  };
  Parts parts(int frame, double pddot, double pdot_squared, double tolerance = 1e-9) const;
  const std::vector<BakedFrame>& frames() const { return frames_; }

 private:
  struct FrameCost {
    double value, d_a, d_b;
  };
  FrameCost frame_cost(int frame, double a, double b, int& sector_hint) const;
  int sector_of(const BakedFrame& f, const Eigen::Vector2d& q, int hint) const;

  double fps_, alpha_;
  std::vector<BakedFrame> frames_;
};

// The point of convex polygon `vertices` (counter-clockwise; 1 or 2 vertices: a point or a
// segment) closest to q; q itself when inside.
Eigen::Vector2d closest_point(const std::vector<Eigen::Vector2d>& vertices, const Eigen::Vector2d& q);

}  // namespace kg::retime
