// The feasible timings of each frame (McCann et al. 2006 §3.3, eq. 13, fig. 4): the projection
// onto the (p̈, ṗ²) plane of the polytope of (p̈, ṗ², λ) where the generalised forces
//
//   τ = velocity·ṗ² + acceleration·p̈ + gravity·g − N λ          (path_torques.hpp, contacts.hpp)
//
// lie within the body's torque limits, the root's rows are 0 (nothing but the contacts moves the
// root) and λ >= 0 (contact forces inside the linearised friction cones). p̈ is in source seconds
// per output second², ṗ² is dimensionless (the original timing is (p̈, ṗ²) = (0, 1)); "plane
// units" below measure distances in that plane with both axes as they are.
//
// How (GLPK): each frame's LP is built once (rows: the root's channels, fixed; every other channel
// with a finite torque limit; columns: p̈, ṗ², λ) and solved for the directions of maximum extent:
// `initial_directions` swept counter-clockwise from straight down (−ṗ²), then each edge of the
// polygon found so far is refined by maximising along its outward normal, inserting the new vertex
// when it lies more than `tolerance` beyond the edge, recursively, until every edge holds. Between
// directions only the objective changes: GLPK restarts from the previous optimal basis (primal
// simplex, presolver off). The found polygon lies inside the true projection (its vertices are
// feasible) and the true projection lies inside the found polygon with every edge pushed out by
// `tolerance` (fig. 4). λ is kept at every vertex.
//
// The box: unbounded directions (a standing frame allows any timing) are cut by
// |p̈| <= pddot_max and ṗ² <= pdot2_max; vertices on the box say so (on_box). ṗ² >= 0 is physics.
//
// The centre (§3.4): λ at the original timing (0, 1) from the LP minimising "the summed absolute
// value of contact patch forces": Σ_p |F_px| + F_py + |F_pz| over the touching patches p, F_p =
// Σ_{j in p} λ_j b_j (the L1 norm of each patch's force, so that it stays an LP). Not Σλ: every
// basis force has the same vertical component 1/√(1+μ²), so Σλ = √(1+μ²) times the total vertical
// force, which the root's rows fix; Σλ cannot choose. The L1 norms refuse feet pushing against
// each other; how double support shares the weight is left to the simplex's vertex. If (0, 1) is
// outside the hull, the centre is the hull's nearest point and the message says so.
//
// Frames without a hull are explicit (status, message), and their hull is one point:
//   - Flight (no touching vertex, and a floating base: a root with channels): the (p̈, ṗ²) in the
//     box minimising the squared residual of the root's rows (a two-unknown bounded least
//     squares; a ballistic frame gives exactly (0, 1)). A fixed base (no root channel) without
//     contact keeps its LP: its torque limits alone bound the hull (Bobrow's robot arm);
//   - Infeasible (an empty polytope: no (p̈, ṗ², λ >= 0) meets every row; captured motion is not exactly
//     physical, nor is a body model): the (p̈, ṗ², λ >= 0) in the box minimising the summed squared
//     violation of every row (the root's equalities and the torque limits), by a bounded-variable
//     least squares (Stark & Parker's BVLS, active set, each row's violation modelled by a slack
//     bounded to its limits).
// Both add a tie-breaking Tikhonov term 1e-9 times the problem's scale towards (0, 1) and λ = 0,
// so that a rank-deficient frame (a ballistic apex: p̈ is free) takes the point nearest (0, 1).
//
//   Hulls h = build_hulls(body, contacts, torques, {});
//   const FrameHull& f = h.frames[12];      // f.vertices counter-clockwise, f.lambda[i] at each
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "kg/body/body_model.hpp"
#include "kg/retime/contacts.hpp"
#include "kg/retime/path_torques.hpp"

namespace kg::retime {

struct HullOptions {
  double pddot_max = 20.0;     // box: |p̈| <= this, source seconds per output second² (> 0)
  double pdot2_max = 16.0;     // box: ṗ² <= this (16: four times the original speed; > 0)
  double tolerance = 1e-3;     // plane units (> 0): how far the true hull may reach beyond an edge
  int initial_directions = 8;  // >= 3, swept counter-clockwise from straight down
  int max_lps = 256;           // per frame (>= initial_directions + 1); reaching it is reported
  // Throws std::invalid_argument naming the field, its value and its range when a field is out
  // of the range stated above (DESIGN.md 15); node factories call it when the graph loads.
  void validate() const;
};

enum class HullStatus : std::uint8_t {
  Feasible,    // the polytope is not empty: vertices from LPs
  Flight,      // no contact, floating base: one least-squares point of the root's rows
  Infeasible,  // an empty polytope (contact, or a fixed base): one least-squares point of every row
};
const char* to_string(HullStatus status);  // "feasible", "flight", "infeasible"

// Sides of the box a vertex lies on (bits of FrameHull::on_box).
inline constexpr std::uint8_t kBoxPddotMin = 1, kBoxPddotMax = 2, kBoxPdot2Max = 4;

// One sector of the force model's fan (force_model.hpp builds and reads these): the wedge from
// direction `from` counter-clockwise to `to` (at most 180 degrees) about the centre, in which λ is
// affine: λ(p̈, ṗ²) = lambda0 + lambda_pddot·p̈ + lambda_pdot2·ṗ² (one entry per column of N).
struct FanSector {
  Eigen::Vector2d from = Eigen::Vector2d::Zero();  // plane units, centre -> node
  Eigen::Vector2d to = Eigen::Vector2d::Zero();
  int edge = 0;          // hull edge (vertex edge -> edge + 1) this sector faces or touches
  bool in_hull = false;  // the triangle (centre, from, to) is part of the hull (a fan triangle);
                         // false: a wedge outside the hull (the centre on its boundary)
  Eigen::VectorXd lambda0{}, lambda_pddot{}, lambda_pdot2{};
};

struct FrameHull {
  HullStatus status = HullStatus::Feasible;
  std::string message;                      // why (Flight, Infeasible) and notes: centre outside,
                                            // degenerate hull, LP limit reached; "" when none
  std::vector<Eigen::Vector2d> vertices{};  // (p̈, ṗ²), counter-clockwise: 1 (a point), 2 (a
                                            // segment) or more
  std::vector<Eigen::VectorXd> lambda{};    // per vertex: λ, newtons, >= 0, one per column of N
  std::vector<std::uint8_t> on_box{};       // per vertex: kBox* bits
  Eigen::Vector2d centre{0.0, 1.0};         // (p̈, ṗ²)
  Eigen::VectorXd centre_lambda{};
  bool centre_is_original = true;  // centre == (0, 1); false: (0, 1) lies outside
  int lp_count = 0;                // LPs solved for this frame (centre included)
  // Flight, Infeasible: Euclidean norm of the rows' violations at the point (N and N m mixed, as
  // the rows are); Feasible: 0.
  double residual = 0;

  // The frame's contact model, so that the force model needs nothing else:
  Eigen::MatrixXd N{};                  // channel_count x columns: generalised force per newton of λ
  Eigen::Matrix3Xd force_directions{};  // 3 x columns: world unit force of each column
  Eigen::Matrix3Xd points{};            // 3 x columns: world point the force acts at, metres
  std::vector<int> column_patch{};      // per column: index into Contacts::patches

  std::vector<FanSector> sectors{};  // the force model's fan (force_model.hpp), >= 3 sectors

  int column_count() const { return static_cast<int>(N.cols()); }
};

struct Hulls {
  std::vector<FrameHull> frames{};  // one per frame of the clip
  HullOptions options{};
  Eigen::Vector3d gravity{0.0, -9.81, 0.0};  // m/s², world: the body's, used by every row
  double friction = 0.5;
  std::vector<std::string> patch_names{};  // Contacts::patches' names

  int count(HullStatus status) const;
};

// Every frame's hull and fan. torques[f] are frame f's coefficients (channel_count each, the
// body's skeleton's channels); contacts must have as many frames. Throws std::invalid_argument for
// sizes that disagree or options out of range. The root's channels are those of joints without a
// parent: their rows are fixed at 0 whatever the body's limits say.
Hulls build_hulls(const body::BodyModel& body, const Contacts& contacts,
                  std::span<const FrameTorques> torques, const HullOptions& options);

// One frame's hull and fan (build_hulls does this for every frame, sharing its buffers).
FrameHull build_frame_hull(const body::BodyModel& body, const ContactFrame& contact,
                           const FrameTorques& torques, const HullOptions& options);

// The largest violation of any row (N or N m) by the timing x = (p̈, ṗ²) with contact forces λ
// (hull.column_count() entries): τ outside [torque_min, torque_max], a root row away from 0, or a
// negative λ. For checks and reports.
double max_row_violation(const body::BodyModel& body, const FrameTorques& torques, const FrameHull& hull,
                         const Eigen::Vector2d& x, const Eigen::VectorXd& lambda);

}  // namespace kg::retime
