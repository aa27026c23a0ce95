// Torque limits observed in the source motion (McCann et al. 2006 §3.2 eq. 12, §4: "Torque limits
// were determined by observing the joint torques over several actions"): each actuated channel
// bounded to ±max(margin · the largest |τ| one or more clips need at their own timing, floor).
//
//   ClipLoads walk{&contacts, torques.frames, "16_15"};      // detect_contacts, path_torques
//   TorqueLimitEstimate e = estimate_torque_limits(body, std::span(&walk, 1), {.margin = 1.5, .floor = 5});
//   Hulls h = build_hulls(e.body, contacts, torques.frames, {});   // (0, 1) inside every feasible hull
//
// What a clip needs. τ = velocity·ṗ² + acceleration·p̈ + gravity·g − N λ (path_torques.hpp) depends
// on how the contact forces λ share the load, so the hulls' own answer decides it: every clip's
// hulls are built (build_hulls, `hulls` options) with the body's actuated channels unlimited, and
// each frame's τ is taken at its hull centre (hulls.hpp §3.4) with the centre's λ, the least
// summed patch forces there:
//   - Feasible, (0, 1) inside: τ at the original timing (0, 1);
//   - Feasible, (0, 1) outside (no contact force moves the root as captured at this speed, e.g. a
//     foot slipping beyond friction): τ at the hull's point nearest (0, 1), the nearest timing any
//     body could play; no limit can make (0, 1) itself feasible there;
//   - Flight: τ at (0, 1) without contact forces. The limbs' torques do not depend on the root's
//     residual (nothing a joint does changes what the root lacks), so these are exactly what the
//     captured limbs need in the air; the hull's least-squares point would bend them by the
//     capture's departure from a ballistic root;
//   - Infeasible (contact, but no λ >= 0 at any timing in the box explains the root: captured
//     motion is not exactly physical): skipped by default (InfeasibleFrames::Skip). Their
//     least-squares point moves the timing to wherever the root's residual is least, up to the box
//     (p̈ = ±20, ṗ² = 0 by default), so its torques measure the capture's error rather than the actor's
//     strength; InfeasibleFrames::LeastSquares takes τ there anyway (the hull's single point and its λ).
// Limits are symmetric, ±max(margin · peak, floor): a clip shows the strength a joint used, not
// which direction is the stronger one.
//
// Guarantee. With margin >= 1 every frame used at its hull centre (Feasible frames) keeps that
// centre's timing and λ within the new limits, so after build_hulls with the estimated body (and
// the same contacts, coefficients and hull options) each such frame is still Feasible and its centre (the
// original timing when it was inside) lies inside or on the boundary of its hull, up to the hull tolerance
// (the found polygon lies inside the true projection by at most `tolerance`). The peak frame of each channel
// sits on the boundary when margin == 1. A margin below 1 (a weaker character, §1) gives the guarantee up:
// the clip's own timing then breaks the limits at its peaks.
//
// Channels. Unactuated channels keep [0, 0]: the roots' (joints without a parent) and every
// channel the body already bounds to [0, 0] (body_build's floating base, e.g. Bandai's Hips under
// an off-body root). Position channels of other joints (constant bone offsets in Bandai's files:
// they hold the skeleton together) keep the body's bounds unless `position_channels` (then their
// limits are in newtons). A joint whose segment is massless is treated like any other: its torque
// is what its subtree and the contacts on it need (a CMU clavicle carries the arm), so it gets a
// real limit; a channel that never works (nothing massive beyond it, no contact on its subtree: a
// massless helper at the end of a chain, an eye or a jaw) observes 0, and one that barely works
// (de Leva's 53 g CMU fingers, a few hundredths of a newton metre) little more: both get the
// floor. A floor of 0 pins a never-working channel at 0, which no retiming changes (its τ is 0 at
// every timing) but which reads as "unactuated": prefer a small positive floor.
//
// Symmetry (`symmetric`): mirrored joints share the larger of their two limits channel by channel.
// Joints pair when swapping the side markers of one kind in a name gives the other's name and
// both have the same channel kinds in the same order (channel k pairs with channel k). The kinds:
// a leading l, r, L or R (lfemur/rfemur, lThigh/rThigh); every Left/Right, left/right or
// LEFT/RIGHT (LeftUpLeg/RightUpLeg); every one-letter token l, r, L or R between separators
// _ . - or space (CC_Base_L_Thigh, Thigh_R, UpperLeg.L). Each joint pairs at most once, with the
// first match in joint order; a joint without a partner keeps its own limits.
//
// Every function checks its inputs and throws std::invalid_argument naming the clip, frame or
// option at fault. Costs: one build_hulls per clip with only the roots' rows (the LPs are small).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "kg/body/body_model.hpp"
#include "kg/retime/contacts.hpp"
#include "kg/retime/hulls.hpp"
#include "kg/retime/path_torques.hpp"

namespace kg::retime {

// One clip's contacts and torque coefficients (not owned; they must outlive the call). Both cover
// the same frames and the body's channels; torques usually PathTorques::frames.
struct ClipLoads {
  const Contacts* contacts = nullptr;
  std::span<const FrameTorques> torques{};
  std::string name{};  // for notes and messages; "" names it "clip <index>"
};

enum class InfeasibleFrames : std::uint8_t {
  Skip,          // not observed (the default; see the header comment)
  LeastSquares,  // observed at the hull's least-squares point with its λ
};

struct TorqueLimitOptions {
  double margin = 1.5;     // > 0, finite: limits = margin x the observed peak; >= 1 for the guarantee
  double floor = 0;        // >= 0, finite: N m (N on position channels), the least limit of any channel
  bool symmetric = false;  // mirrored joints share their limits (header comment)
  bool position_channels = false;  // also bound non-root position channels (newtons)
  InfeasibleFrames infeasible = InfeasibleFrames::Skip;
  HullOptions hulls{};  // for the unlimited hulls whose centres give λ
  // Throws std::invalid_argument naming the field, its value and its range when a field is out
  // of the range stated above (DESIGN.md 15); node factories call it when the graph loads.
  void validate() const;
};

// How a frame was observed.
enum class FrameUse : std::uint8_t {
  Original,      // Feasible, τ at (0, 1)
  Nearest,       // Feasible with (0, 1) outside: τ at the hull's nearest point
  Flight,        // τ at (0, 1), no contact force
  LeastSquares,  // Infeasible, τ at the least-squares point (InfeasibleFrames::LeastSquares)
  Skipped,       // Infeasible, not observed
};
const char* to_string(FrameUse use);  // "original", "nearest", "flight", "least-squares", "skipped"

struct ObservedFrame {
  FrameUse use = FrameUse::Original;
  Eigen::Vector2d timing{0.0, 1.0};  // (p̈, ṗ²) where τ was taken (the unlimited hull's centre,
                                     // or (0, 1) in flight); (0, 1) for Skipped
};

struct TorqueLimitEstimate {
  body::BodyModel body;  // the input body with torque_min / torque_max set as above
  // Per channel (channel_count): the largest |τ| observed over every clip (N m, N on position
  // channels; 0 where unobserved or unactuated), and where: clip index and frame, -1 if none.
  Eigen::VectorXd peak{};
  std::vector<int> peak_clip{}, peak_frame{};
  // Per channel: the limit was estimated (actuated and not a position channel kept as it was).
  std::vector<bool> estimated{};
  // Per channel: the channel whose peak set its limit (itself, or its mirror with `symmetric`).
  std::vector<int> limit_from{};
  std::vector<std::pair<int, int>> mirrored_joints{};  // joint index pairs (left-ish first as found)
  std::vector<std::vector<ObservedFrame>> frames{};    // per clip, per frame
  int count(FrameUse use) const;                       // frames of every clip observed so
  std::vector<std::string> notes{};                    // for people: counts, pairs, floored channels
};

// The limits above for `body` from the clips (at least one). Throws std::invalid_argument for no
// clip, a clip without contacts, frame or channel counts that disagree, a bad body
// (check_body_model), margin <= 0, a negative floor or either not finite, bad hull options.
TorqueLimitEstimate estimate_torque_limits(const body::BodyModel& body, std::span<const ClipLoads> clips,
                                           const TorqueLimitOptions& options = {});
// One clip.
TorqueLimitEstimate estimate_torque_limits(const body::BodyModel& body, const Contacts& contacts,
                                           std::span<const FrameTorques> torques,
                                           const TorqueLimitOptions& options = {});

// `body` with the channels estimate_torque_limits would estimate (per `position_channels`) set to
// ±infinity, the others as they are: the body of the unlimited hulls.
body::BodyModel without_torque_limits(const body::BodyModel& body, bool position_channels = false);

// Pairs of mirrored joints (indices, each joint in at most one pair) by the name rules above.
std::vector<std::pair<int, int>> mirrored_joints(const motion::Skeleton& skeleton);

}  // namespace kg::retime
