// The spacetime solver of Gleicher 1998 §6: finds the displacement maps d (bspline.hpp) that,
// added to the initial estimates m1 of one or two characters, make the constraints hold again
// while changing the motion as little as possible. It minimises the damped least-squares
// objective (eq. 4)
//     F(x) = 1/2 sum_rows (w_r rho_r(x))^2 + 1/2 eps x^T M x
// over the B-spline controls x of every free channel, where rho_r = r for an equality row and
// min(r, 0) for an inequality row (the active set: a violated inequality row acts as an equality,
// a satisfied one drops out; re-evaluated at every iterate), w_r the constraint's weight, and M
// diagonal: a root translation channel weighs 1, a rotation channel the square of the reach of its
// joint (the largest rest-pose distance from the joint to a point it moves, at least 2 cm), so
// the damping measures how far a control moves the figure's points in metres, whatever the
// channel's unit.
//
// Each Gauss-Newton step solves (J^T J + eps M) dx = -(J^T rho + eps M x) (eq. 5 with M for I).
// J is analytic: d row / d control = (d row / d world points, from the kind) * point_jacobian
// (kinematics.hpp) * B-spline basis weight. The normal matrix is assembled from per-frame blocks
// (a frame's rows touch only the channels of its points' ancestor chains, and 4 consecutive
// controls per channel) into a banded matrix over the controls, ordered control-major (every
// channel of one control time together; only channels some active row touches enter, the others
// have the diagonal system (eps + lambda) M dx = -eps M x), and factored by a dense banded Cholesky of our
// own (measured 6-7x faster than Eigen's SimplicialLLT on the same matrices, before the latter's
// ordering: bench_retarget). A row reading two frames far apart (same_place over a long plant)
// widens the band to span them: still exact, only slower. Steps carry a Levenberg-Marquardt term
// lambda M (matrix only, adapted per iteration) and a backtracking (Armijo) line search on F.
// Inequality rows that are satisfied at x but that the full step would cross by more than the
// tolerance join a working set before the step is solved again (they then resist moving along
// their Jacobian without pulling: their residual counts as 0 while satisfied), and leave it once
// the iterate is well inside them; this keeps joint limits from cutting every step short.
// Soft constraints (Constraint::soft, §8's best matching motion) are objective terms: their rows
// weigh in F, but a pass that has them goes on past the required rows' tolerance until F stops
// falling (min_decrease, min_step) or max_iterations, it converges when the required rows hold,
// and soft rows appear in no violation figure and never make the solve densify.
// When a pass ends with constraints still violated past tolerance and `densify` is set, the
// solve restarts from m1 + d with every key spacing halved (down to 1 frame), §4 step 5.
//
//   SpacetimeProblem problem;
//   problem.characters.push_back({.initial = m1, .frames_per_key = spacing.frames_per_key});
//   problem.constraints = &set;                                   // not owned, outlives the solve
//   problem.kinds = [&](const std::string& n) { return table.find(n); };
//   SpacetimeResult result = solve_spacetime(problem);
//   if (!result.converged()) std::cerr << result.message << '\n';
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "kg/motion/motion.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/constraints.hpp"
#include "kg/retarget/displacement.hpp"

namespace kg::retarget {

// One character of the problem.
struct CharacterProblem {
  // The initial estimate m1 on the target skeleton (metres, radians). All characters of one
  // problem have the same frame count and rate.
  motion::Motion initial;
  // Morphing (§5): the skeleton of each frame (frame_count() entries, same structure as
  // initial.skeleton). Empty: initial.skeleton for every frame.
  std::vector<std::shared_ptr<const motion::Skeleton>> skeleton_per_frame{};
  // Frames between controls, per channel (channel_count() entries, each >= 1). Empty: 4 for all.
  std::vector<int> frames_per_key{};
  // Channels the solve must not change (channel_count() entries). Empty: every channel free.
  std::vector<bool> frozen{};
};

struct SpacetimeOptions {
  double epsilon = 1e-4;  // damping weight of x^T M x (dimensionless, see above; > 0)
  // Converged when every row is within these. 1 mm is the acceptance figure (the paper
  // met a quarter inch); a tighter tolerance that the key spacing cannot reach makes the solve
  // densify keys (step 5), which buys accuracy with high frequencies.
  double equality_tolerance = 1e-3;    // |r| of every equality row, metres or radians (> 0)
  double inequality_tolerance = 1e-3;  // max(0, -r) of every inequality row (> 0)
  int max_iterations = 40;             // Gauss-Newton iterations per pass (>= 0; 0: m1 as it is)
  bool densify = true;                 // §4 step 5: retry with halved key spacing when violated

  // The Levenberg-Marquardt term lambda M added to the matrix of each step (not to F; M as in
  // the header comment, so lambda is dimensionless like epsilon). Every pass starts at
  // initial_damping; an accepted full step (alpha = 1) multiplies lambda by damping_decrease,
  // down to min_damping; a shortened one by damping_increase / alpha, up to max_damping.
  double initial_damping = 1e-3;   // >= 0, finite
  double damping_decrease = 0.25;  // in (0, 1]
  double damping_increase = 8;     // >= 1, finite
  double min_damping = 1e-8;       // >= 0, finite
  double max_damping = 1e4;        // >= min_damping, finite
  // The backtracking (Armijo) line search on F: alpha = 1, line_search_shrink, its square, ...,
  // line_search_steps lengths at most; alpha is taken when F(x + alpha dx) <= F(x) + armijo alpha
  // (the slope of F along dx). None taken: the pass stops ("line search failed").
  double armijo = 1e-4;             // in (0, 1)
  double line_search_shrink = 0.5;  // in (0, 1)
  int line_search_steps = 30;       // >= 1
  // The working set (header comment): a step is solved again at most working_set_resolves times
  // with the inequality rows it would cross (0: never); a held row leaves the set once its
  // residual exceeds working_set_release x inequality_tolerance.
  int working_set_resolves = 2;       // >= 0
  double working_set_release = 10.0;  // >= 0, finite
  // Stopping tests after an accepted step that did not converge ("no further progress"): the
  // step's max-norm alpha |dx| below min_step (units of the controls: metres or radians); F
  // decreased by at most min_decrease (after a full step) or min_decrease_short (after a
  // shortened one) of its value before the step; or the worst violation stuck (above stuck_ratio
  // times the previous iteration's) while F decreased by at most stuck_decrease of its value.
  double min_step = 1e-10;           // >= 0, finite
  double min_decrease = 1e-4;        // in [0, 1)
  double min_decrease_short = 1e-7;  // in [0, 1)
  double stuck_ratio = 0.99;         // in [0, 1]
  double stuck_decrease = 5e-3;      // in [0, 1)
  // With denser keys still to try (densify), a pass stops ("keys too far apart") when its worst
  // violation is above stall_ratio times its value stall_window iterations before: it has done
  // what its spacing can, the next pass starts from there.
  int stall_window = 2;       // iterations, >= 1
  double stall_ratio = 0.95;  // in [0, 1]
  // Called with one line per iteration (objective, worst violation, step length, active rows)
  // when set; for diagnostics.
  std::function<void(const std::string&)> trace{};

  // Throws std::invalid_argument naming the field, its value and its range when a field is out
  // of the range stated above (DESIGN.md 15).
  void validate() const;
};

struct SpacetimeProblem {
  std::vector<CharacterProblem> characters;    // one or two (PointRef::character indexes them)
  const ConstraintSet* constraints = nullptr;  // not owned
  KindFinder kinds;
  SpacetimeOptions options{};
};

enum class SpacetimeStatus { Converged, NotConverged };
const char* to_string(SpacetimeStatus status);  // "converged", "not converged"

// Final state of one constraint kind's rows.
struct KindReport {
  std::string kind;
  int rows = 0;                 // equality + inequality rows over all samples
  int active_rows = 0;          // equality rows + violated inequality rows at the end
  double worst_equality = 0;    // max |r| of the equality rows (metres or radians)
  double worst_inequality = 0;  // max(0, -r) of the inequality rows
  double worst() const { return worst_equality > worst_inequality ? worst_equality : worst_inequality; }
};

// A constraint still violated past tolerance at the end.
struct ViolatedConstraint {
  std::string kind, label;
  double worst = 0;     // metres or radians
  int first_frame = 0;  // span of its violated samples (their first frames)
  int last_frame = 0;
  bool in_metres = true;  // false when it reads only channel values
};

// The outcome, as data (DESIGN.md tier 3): a solve that cannot meet its constraints is reported
// here, not thrown.
struct SpacetimeResult {
  std::vector<motion::Motion> motions;  // m1 + d per character, on the initial motions' skeletons
  SpacetimeStatus status = SpacetimeStatus::NotConverged;
  std::string message;                       // "converged in 5 iterations ..." or "did not converge: ..."
  int iterations = 0;                        // Gauss-Newton iterations over all passes
  int passes = 0;                            // 1 + densified retries
  double seconds = 0;                        // wall time of the whole solve
  std::vector<KindReport> kinds;             // sorted by kind name
  std::vector<ViolatedConstraint> violated;  // worst first
  int unknowns = 0;                          // free controls of the last pass
  int active_rows = 0;                       // at the end
  int total_rows = 0;
  int bandwidth = 0;                             // of the last factored normal matrix
  std::vector<std::vector<int>> frames_per_key;  // per character, of the last pass
  double worst_violation() const;
  bool converged() const { return status == SpacetimeStatus::Converged; }
};

// Solves. Throws std::invalid_argument (naming the constraint's label where there is one) for a
// malformed problem: options that validate() refuses, no characters, more characters than
// given, mismatched frame counts or channel layouts, an unknown kind, a constraint its kind
// refuses, a frame, joint or channel out of range. Everything else (not converged) is in the
// result.
SpacetimeResult solve_spacetime(const SpacetimeProblem& problem);

// Diagonal of M for one skeleton (channel_count() entries, see the header comment), m^2 per
// unit of the channel squared.
Eigen::VectorXd channel_sensitivity(const motion::Skeleton& skeleton);

// The layouts of the problem's characters (frames_per_key or 4), and the full unknown vector
// x = [x of character 0, x of character 1] their controls make (frozen channels included).
std::vector<DisplacementLayout> spacetime_layouts(const SpacetimeProblem& problem);

// Every row of the problem at x (weighted residuals w r, inequality rows unclipped) and the
// dense Jacobian d(w r)/dx over the full unknown vector: for tests and diagnostics, through the
// same analytic chain the solver assembles from.
struct SpacetimeLinearization {
  Eigen::VectorXd residual;
  Eigen::MatrixXd jacobian;
  std::vector<bool> inequality;
};
SpacetimeLinearization linearize_spacetime(const SpacetimeProblem& problem, const Eigen::VectorXd& x);

}  // namespace kg::retarget
