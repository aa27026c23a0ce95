// Key spacing of the displacement map (Gleicher 1998, §3.7): how many frames apart the
// B-spline control points of each channel's displacement curve are. Fewer keys cannot
// represent high frequencies, so the spacing bounds the frequency content of the adaptation.
//
// The automatic choice (choose_key_spacing), the paper's heuristic made precise:
//   1. Band-pass (Laplacian) pyramid of every channel (Bruderlin & Williams 1995), undecimated
//      ("a trous"): G_0 = the channel, G_{k+1} = G_k smoothed by the binomial B-spline kernel
//      (1 4 6 4 1) / 16 with taps 2^k frames apart, L_k = G_k - G_{k+1}, k = 0 .. 4. L_0 holds
//      periods of 2 to about 4 frames; L_k (k >= 1) peaks at a period of about 3.8 x 2^k
//      frames (7, 15, 30, 61) and keeps half its power from about 0.65 to 1.6 times that. Ends
//      are extended by point reflection (x[-m] = 2 x[0] - x[m]), which keeps straight lines
//      straight: a steady drift (a walk's forward travel) puts no energy into any band.
//      Rotation channels are unwrapped first.
//   2. Energy of level k: the sum over frames and channels of L_k^2 (radians; position
//      channels divided by the skeleton's rest height, so one body height counts as one radian);
//      its fraction is over the five bands (the residual G_5, DC included, is not counted).
//   3. k* = the lowest (highest-frequency) level whose fraction exceeds `threshold`; the spacing
//      is 2^k* frames clamped to [2, 8]: L_0 or L_1 -> 2, L_2 -> 4, L_3 or L_4 -> 8; no energy
//      at all (a still clip) -> 8. Why 2^k "coincides" with L_k: L_k is the detail a grid of
//      2^k frames holds and one of 2^(k+1) does not (a decimated pyramid stores it every 2^k
//      frames), and a cubic B-spline with keys every h frames (response sinc^4) keeps half the
//      power of periods down to about 4.5 h, just above L_k's peak period for h = 2^k.
//   Default threshold 0.1: a band holding under 10 % of the band energy is incidental detail.
//   Why not lower: captured clips keep 2 to 8 % of their band energy in the finest bands (marker
//   noise, a converter's interpolated frames), and at 0.05 that alone chose 2-frame keys for
//   walks; at 0.1 walks take the paper's 4 (§7.1). Measured at 30 Hz (graphs/retarget.yaml's
//   key_spacing figures): walks 16_15 (MotionBuilder BVH: L_0 0.063, L_1 0.086, L_2 0.21), 07_05,
//   02_01 and the jump 13_11 (L_0 0.080, L_1 0.058, L_2 0.15) -> 4 frames; the run 09_06 (L_1
//   0.116) -> 2, the run 02_03 (L_1 0.085) -> 4; 0.2 gives walks 8. The bands overlap: a pure
//   tone at L_{k+1}'s peak puts about 22 % of the band energy into L_k, so the rule leans to the
//   level one finer than the dominant content (denser keys); raise the threshold for smoother
//   adaptations.
//
//   KeySpacingOptions o{.threshold = 0.1, .spacing = 0, .groups = "arm|hand|Arm|Hand=2"};
//   std::vector<KeyGroupChoice> details;
//   KeySpacing keys = choose_key_spacing(motion, o, &details);
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "kg/base/pattern.hpp"
#include "kg/motion/motion.hpp"

namespace kg::retarget {

struct KeySpacing {
  // Frames between control points, per frame channel (skeleton.channel_count() entries; one
  // character). Typically 2, 4 or 8.
  std::vector<int> frames_per_key;
  // How it was chosen, for reports: "pyramid: level energies ..., threshold ..." or "by hand".
  std::string reason;
  // The rate the frames count at (frames per second; 0: the rate of the motion they are used with).
  double fps = 0;
};

// --- Additive (issue 3): the decomposition and the choice. ---

inline constexpr int kPyramidLevels = 5;  // band levels L_0 .. L_4

// The undecimated band-pass pyramid of one signal (frames samples): levels + 1 vectors,
// L_0 .. L_{levels-1}, then the residual G_levels; they sum to the signal exactly.
std::vector<Eigen::VectorXd> band_pass_pyramid(const Eigen::Ref<const Eigen::VectorXd>& signal,
                                               int levels = kPyramidLevels);

struct PyramidEnergy {
  std::vector<double> energy;    // per level, summed over the channels (see the header comment)
  std::vector<double> fraction;  // energy / its sum (all 0 when the sum is 0)
};

// Energies of `channels` (frame channel indices) of `motion`.
PyramidEnergy pyramid_energy(const motion::Motion& motion, const std::vector<int>& channels,
                             int levels = kPyramidLevels);

// The spacing the energies call for (header comment, step 3); `level` gets k* (-1: no level
// exceeds the threshold, spacing 8).
int spacing_for_energy(const PyramidEnergy& energy, double threshold, int* level = nullptr);

// One `groups` item: joints whose name contains a match of `pattern` (a regular expression in
// RE2 syntax, kg/base/pattern.hpp, searched in the name: Pattern::partial_match, so "Arm"
// matches LeftArm and LeftForeArm) take `spacing` frames (0: chosen automatically from that
// group's channels alone).
struct KeyGroup {
  kg::Pattern pattern;
  int spacing = 0;
};
// "arm|hand|Arm|Hand=2; leg|Leg=8": items separated by ';', each regex=spacing (split at the
// last '='; blanks around items trimmed), each pattern compiled once here. Throws
// std::invalid_argument naming the item (a short excerpt of it) for a missing '=', a spacing
// that is not an integer >= 0, or a bad regular expression (Pattern::compile's message).
std::vector<KeyGroup> parse_key_groups(const std::string& text);

struct KeySpacingOptions {
  double threshold = 0.1;  // fraction of the band energy, in (0, 1)
  int spacing = 0;         // frames per key for channels in no group; 0 = automatic
  std::string groups{};    // parse_key_groups text; "" = one group of every channel
  // Throws std::invalid_argument naming the field, its value and its range when a field is out
  // of the range stated above (DESIGN.md 15); node factories call it when the graph loads.
  void validate() const;
};

// What was decided for one group of channels (the first entry: the channels in no group).
struct KeyGroupChoice {
  std::string pattern;      // "" for the channels in no group
  std::vector<int> joints;  // matched joints (first matching group wins)
  int channels = 0;
  int spacing = 0;
  bool automatic = false;
  int level = -1;        // k* when automatic
  PyramidEnergy energy;  // when automatic
};

// Throws std::invalid_argument for a bad threshold, a negative spacing, bad groups text or a
// group matching no joint.
KeySpacing choose_key_spacing(const motion::Motion& motion, const KeySpacingOptions& options,
                              std::vector<KeyGroupChoice>* details = nullptr);

}  // namespace kg::retarget
