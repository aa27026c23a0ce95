// The two ladder constraints of Gleicher 1998 §7.2, less restrictive than fixed hand and foot
// plants: a footplant the solver may slide along a rung, a hand-hold it may slide along a rail.
// Both keep a point on the segment from A to B (world, metres):
//
//   ladder.rung   points 1 (e.g. the ball of the foot). params [ax ay az bx by bz] or
//                 [ax ay az bx by bz margin]: the rung from A to B, margin (metres, default 0)
//                 keeps the point that far inside either end. Rows (relation must be equal):
//                   0, 1  equality: the components of p - A along e1 and e2, two unit vectors
//                         orthogonal to the rung direction u = (B - A) / |B - A| and to each
//                         other (so the point's distance from the rung's line is |(r0, r1)|);
//                   2     inequality: s - margin >= 0, s = u . (p - A) (how far along from A);
//                   3     inequality: (|B - A| - margin) - s >= 0.
//   ladder.rail   the same rows for a hand on a rail (a vertical or slanted segment); its default
//                 margin is 0.04 m, half a hand's width, so the whole grip stays on the rail.
//
// e1 = normalise(u x a), a the world axis least aligned with u; e2 = u x e1: fixed per rung, so
// the rows are linear in p and their derivatives are exact. Rows are unweighted (the solver
// multiplies by Constraint::weight).
#pragma once

#include <memory>

#include "kg/retarget/constraints.hpp"

namespace kg::ladder {

std::shared_ptr<const retarget::ConstraintKind> make_rung_kind();
std::shared_ptr<const retarget::ConstraintKind> make_rail_kind();

}  // namespace kg::ladder
