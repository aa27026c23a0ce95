// The contact-force model of a frame (McCann et al. 2006 §3.4, fig. 5): λ, hence the contact
// forces and the generalised forces τ, as piecewise affine functions of the timing (p̈, ṗ²).
//
// Each frame's hull (hulls.hpp) is triangulated as a fan from its centre: one sector per hull
// edge, between the rays from the centre through the edge's two vertices. The sectors cover the
// whole plane, so every timing has a sector:
//   - inside the hull, λ is the barycentric interpolation of the centre's and the two vertices' λ,
//     which meets every row (the rows are linear and all three are feasible);
//   - outside the hull, a timing falls into the sector of its direction from the centre and λ is
//     extrapolated linearly from the same three (it may then break rows, even turn negative: the
//     timing is infeasible, which the objective's feasibility term measures);
//   - when the centre lies on the hull's boundary ((0, 1) outside the hull, or a degenerate hull:
//     a point or a segment), the wedges outside it are filled by sectors bounded by the outward
//     normals of the edges at the centre, in which λ varies along the edge and stays constant
//     along the normal (constant λ = the centre's between two normals).
// Per sector λ(p̈, ṗ²) = λ0 + λa·p̈ + λb·ṗ², hence τ = T0 + Ta·p̈ + Tb·ṗ² with
//   T0 = gravity·g − N λ0,   Ta = acceleration − N λa,   Tb = velocity − N λb.
//
// Queries take a sector hint (in/out): a query near the last one starts from its sector and walks
// to the neighbours, so successive close queries cost amortised constant time (§3.6).
//
//   int hint = 0;
//   Eigen::VectorXd lambda;
//   lambda_at(hull, {pddot, pdot2}, hint, lambda);
//   SectorTorques t;
//   sector_torques(hull, hint, torques[f], hulls.gravity, t);   // τ = t.t0 + t.pddot p̈ + t.pdot2 ṗ²
//   HullPoint c = closest_point(hull, {pddot, pdot2}, hint);    // the feasibility term's c
#pragma once

#include <span>
#include <vector>

#include <Eigen/Core>

#include "kg/numerics/convex_nearest.hpp"
#include "kg/retime/hulls.hpp"
#include "kg/retime/path_torques.hpp"

namespace kg::retime {

// Fills hull.sectors from hull.vertices, hull.lambda, hull.centre and hull.centre_lambda
// (build_hulls calls it; a hull made by hand needs it too). Throws std::invalid_argument when the
// hull has no vertex or λ sizes disagree.
void build_fan(FrameHull& hull);

// The sector containing the timing x = (p̈, ṗ²) (plane units). `hint`: a sector index to start
// from (any value; out-of-range values start at 0). Points on a ray between two sectors belong to
// either; the centre itself to the hint.
int find_sector(const FrameHull& hull, const Eigen::Vector2d& x, int hint = 0);

// λ at x (newtons, hull.column_count() entries; `lambda` is resized, no allocation when it has that
// size already). `hint` is read and set to x's sector.
void lambda_at(const FrameHull& hull, const Eigen::Vector2d& x, int& hint, Eigen::VectorXd& lambda);

// The affine generalised forces of one sector: τ = t0 + pddot·p̈ + pdot2·ṗ² (channel_count each,
// N or N m). `gravity` is the world gravity the hull was built with (Hulls::gravity), m/s².
struct SectorTorques {
  Eigen::VectorXd t0{}, pddot{}, pdot2{};
};
void sector_torques(const FrameHull& hull, int sector, const FrameTorques& torques,
                    const Eigen::Vector3d& gravity, SectorTorques& out);

// The contact force on each touching patch (world, newtons) and its centre of pressure (world,
// metres: the vertices' points weighted by their vertical forces; their mean when no vertical
// force), for the contact forces λ (e.g. lambda_at's).
struct PatchForce {
  int patch = 0;  // index into Contacts::patches
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  Eigen::Vector3d centre_of_pressure = Eigen::Vector3d::Zero();
};
std::vector<PatchForce> patch_forces(const FrameHull& hull, const Eigen::VectorXd& lambda);

// The point of the hull nearest to x (plane units) and its squared distance (0 inside). `hint` as
// in find_sector: with it the search starts at x's sector and walks along the boundary from the
// edge that sector faces until the nearest point is certified (the answer does not depend on it).
using HullPoint = numerics::NearestPoint;
HullPoint closest_point(const FrameHull& hull, const Eigen::Vector2d& x, int& hint);

// The same for a convex polygon given by its vertices (counter-clockwise; 1 is a point, 2 a
// segment), by looking at every edge: no fan needed.
HullPoint closest_point_on_polygon(std::span<const Eigen::Vector2d> vertices, const Eigen::Vector2d& x);

}  // namespace kg::retime
