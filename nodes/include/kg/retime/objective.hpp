// The retiming objective of McCann et al. 2006 (§3.5 eq. 14, §3.6), baked: per source frame, the
// integrand
//   α |(p̈, ṗ²) − c|²  +  β |τ(p̈, ṗ²) − τ'|² / τ_scale²
// where c is the closest point of the frame's hull (hulls.hpp: feasibility) and τ the generalised
// forces of the force model (force_model.hpp), affine in (p̈, ṗ²) on each sector of the hull's fan,
// so the torque term is, per sector, a quadratic with six coefficients (those of ṗ⁴, p̈², ṗ²p̈, ṗ²,
// p̈ and 1): evaluating it no longer depends on the number of channels. τ_scale (N m) makes the
// torque term dimensionless (torque_scale below), so α and β weigh comparable quantities whatever
// the body. Between frames the two frames' integrands are interpolated linearly in source time.
//
// In flight (no contact) the hull is the single least-squares point of the root's rows, and the
// feasibility term is measured in those rows rather than in the plane: α |r(p̈, ṗ²)|² / W² − its
// least value, where r is the root's residual (what nothing could supply: zero on a ballistic
// path) and W the body's weight, so a flight played too fast or slow costs what the wrong gravity
// costs, and the direction the rows hardly determine (p̈ at the apex) costs little. It is a
// quadratic too, baked like the torque term, weighted α times ObjectiveWeights::flight.
//
//   BakedObjective objective(hulls, torques, targets, {.alpha = 1000, .beta = 1, .torque_scale = s});
//   int hint = 0;
//   SampleCost c = objective.evaluate(1.25, 0.0, 1.0, hint);   // at source 1.25 s, original timing
#pragma once

#include <array>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "kg/retime/hulls.hpp"
#include "kg/retime/path_torques.hpp"
#include "kg/retime/retimer.hpp"
#include "kg/retime/time_optimal.hpp"

namespace kg::retime {

// The six coefficients of a quadratic in (a, b) = (p̈, ṗ²):
//   q[0] b² + q[1] a² + q[2] a b + q[3] b + q[4] a + q[5].
using Quadratic = std::array<double, 6>;

inline double evaluate(const Quadratic& q, double a, double b) {
  return q[0] * b * b + q[1] * a * a + q[2] * a * b + q[3] * b + q[4] * a + q[5];
}

// |t0 + ta a + tb b − target|² · weight as a Quadratic (all vectors of one size).
Quadratic bake_quadratic(const Eigen::VectorXd& t0, const Eigen::VectorXd& ta, const Eigen::VectorXd& tb,
                         const Eigen::VectorXd& target, double weight);

struct ObjectiveWeights {
  double alpha = 1000;      // feasibility: per (plane unit)² of distance to the hull
  double beta = 1;          // torque: per (τ_scale)² of torque error
  double torque_scale = 1;  // N m (> 0)
  // Multiplies α on flight frames (>= 0). A flight played at the wrong speed shows a wrong
  // gravity, which viewers notice at once (Reitsma & Pollard 2003, sensitivity to errors in
  // ballistic motion); a ground phase a little beyond its hull does not show as plainly. When no
  // timing meets every hull (a duration shorter than the shortest feasible), this says which
  // gives: above 1 the flight keeps its speed and the ground phases take the excess. Frames at
  // takeoff and landing, whose least-squares points an impulse moves, weigh as much, so large
  // values let them pull their neighbours.
  double flight = 1;
};

// The generalised forces of the original timing (0, 1) with the centre's contact forces, per frame
// (channel_count each): τ' for "keep the look". Flight and infeasible frames give the forces at
// (0, 1) with their single point's λ (the root's rows then show what no contact could supply).
std::vector<Eigen::VectorXd> original_torques(const Hulls& hulls, std::span<const FrameTorques> torques);

// RMS over frames and actuated channels (all but the root joints') of `torques` (channel_count
// of `skeleton` each), N m; 1 when that is 0.
double torque_scale(const motion::Skeleton& skeleton, std::span<const Eigen::VectorXd> torques);

class BakedObjective final : public PathObjective {
 public:
  // Bakes every frame's sectors (the Bake step). `hulls` is not owned and must outlive the
  // objective; torques and targets have one entry per frame (channel_count each). Throws
  // std::invalid_argument for sizes that disagree, fewer than 2 frames or weights out of range.
  // `skeleton` gives the root's rows (its root joints' channels).
  BakedObjective(const Hulls& hulls, std::span<const FrameTorques> torques,
                 std::span<const Eigen::VectorXd> targets, const motion::Skeleton& skeleton,
                 double source_fps, const ObjectiveWeights& weights);

  // `hint`: the caller's cursor (start it at 0, pass it back; any value is accepted and gives the
  // same cost up to rounding): it holds the fan sectors of the last two frames met, so that
  // successive samples start their sector searches where the last ones ended.
  SampleCost evaluate(double p, double pddot, double pdot_squared, int& hint) const override;
  double source_duration() const override { return (static_cast<double>(frames_.size()) - 1) / fps_; }
  double source_fps() const override { return fps_; }

  // The two parts of one frame's integrand at (p̈, ṗ²), and whether the point lies in its hull
  // (within `tolerance` plane units).
  struct Parts {
    double feasibility = 0;  // α |q − c|² (flight: α · flight · the excess)
    double torque = 0;       // β |τ − τ'|² / τ_scale²
    bool inside = false;
  };
  Parts parts(int frame, double pddot, double pdot_squared, double tolerance = 1e-9) const;
  // For a flight frame, the timings whose root residual stays within `tolerance` of the body's
  // weight: an ellipse about the least-squares point (a polygon of `sides` vertices,
  // counter-clockwise; an extent the rows do not bound is cut at `extent` plane units); empty when
  // even the least-squares point leaves more (a contact the detection missed). For a feasible
  // frame, the hull's vertices; for an infeasible one, empty (no timing of it is physical).
  Polygon admissible_region(int frame, double tolerance, int sides = 16, double extent = 100) const;
  // For a flight frame, (|r|² − least |r|²) / W² at (p̈, ṗ²), whatever the weights; 0 for other frames.
  double flight_excess(int frame, double pddot, double pdot_squared) const {
    return kg::retime::evaluate(flight_[static_cast<std::size_t>(frame)], pddot, pdot_squared);
  }
  // The flight term's quadratic of a frame ((|r|² − least |r|²) / W², before α; all zero off
  // flight) and the torque term's quadratic of one fan sector (β |τ − τ'|² / τ_scale²).
  const Quadratic& flight_quadratic(int frame) const { return flight_[static_cast<std::size_t>(frame)]; }
  const Quadratic& quadratic(int frame, int sector) const {
    const int first = frames_[static_cast<std::size_t>(frame)].first_sector;
    return sectors_[static_cast<std::size_t>(first + sector)].q;
  }

 private:
  // What evaluate reads, per frame and per sector in contiguous arrays (a sample touches one
  // frame record and one sector record of each of its two frames, and the hull's vertices only
  // when the nearest point is not found on or at the ends of the edge the sector faces), copied
  // from the hulls at baking.
  struct FrameData {
    double centre_x = 0, centre_y = 0;  // the fan's centre (plane units)
    int first_sector = 0, sector_count = 0;
    int first_vertex = 0, vertex_count = 0;
    bool flight = false;
  };
  struct alignas(64) SectorData {
    double from_x, from_y, to_x, to_y;  // the wedge (FanSector::from, to)
    Quadratic q;                        // its torque term
    // The hull edge the sector faces (vertex `edge` -> edge + 1), where the search for the
    // nearest point starts: its first vertex, edge vector and squared length (-1 for hulls of
    // fewer than 3 vertices and point edges, which take the general search).
    double edge_x, edge_y, along_x, along_y, length_squared;
    int edge;
    bool triangle;              // a fan triangle of the hull (in_hull and >= 3 vertices)
    double before_x, before_y;  // the edge before (into edge_x, edge_y)
    double end_x, end_y;        // the facing edge's last vertex
    double after_x, after_y;    // the edge after (out of end_x, end_y)
  };

  const Hulls& hulls_;
  double fps_;
  ObjectiveWeights weights_;
  double flight_alpha_ = 0;  // weights_.alpha * weights_.flight
  int last_frame_ = 0;
  std::vector<FrameData> frames_;
  std::vector<SectorData> sectors_;        // every frame's fan sectors, frame after frame
  std::vector<Eigen::Vector2d> vertices_;  // every frame's hull vertices, frame after frame
  std::vector<Quadratic> flight_;          // per frame: |r|² / W² − its least (zero off flight)
  std::vector<double> flight_least_;       // per frame: |r|² / W² at the least-squares point
};

}  // namespace kg::retime
