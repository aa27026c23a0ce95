// Published body-segment parameters (anthropometric tables) and the water cylinders McCann et
// al. (2006, §4) used instead: what the body model (body_build.hpp) turns into each joint's
// mass, centre of mass and inertia.
//
//   const AnthropometricTable& t = anthropometric_table(BodyTable::DeLevaMale);
//   double thigh_kg = t.segment(SegmentClass::Thigh).mass * 70.0;       // one thigh, 9.91 kg
//   double com_m = t.segment(SegmentClass::Thigh).com * thigh_length;   // from the hip
//
// Every fraction is dimensionless: masses of the whole body mass (one segment, so one side for
// the limbs), centre of mass and radii of gyration of the segment's length, the CoM measured
// from the proximal end (the joint the segment hangs from in a skeleton rooted at the pelvis:
// hip for the thigh, the neck base for head+neck, the pelvis for the trunk). Radii of gyration
// are about the segment's CoM: sagittal about the anteroposterior axis, transverse about the
// mediolateral axis, longitudinal about the segment's long axis (de Leva's columns; see
// anthropometry.cpp for which printed column is which, and for every value's source).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace kg::body {

// The table segments, plus Massless for joints that carry none (eyes, twist helpers, clavicles).
enum class SegmentClass : std::uint8_t {
  HeadNeck,
  Trunk,
  UpperArm,
  Forearm,
  Hand,
  Thigh,
  Shank,
  Foot,
  Massless
};
inline constexpr int kSegmentClassCount = 8;  // table segments, Massless excluded

// "head_neck", "trunk", "upper_arm", "forearm", "hand", "thigh", "shank", "foot", "massless".
const char* to_string(SegmentClass c);
std::optional<SegmentClass> segment_class_from_string(std::string_view name);
// All nine names, in enum order (for messages).
std::vector<std::string> segment_class_names();
// Limbs: a table row describes one of two (left and right).
inline bool is_paired(SegmentClass c) {
  return c >= SegmentClass::UpperArm && c != SegmentClass::Massless;
}
inline int index_of(SegmentClass c) {
  return static_cast<int>(c);
}

enum class BodyTable : std::uint8_t {
  Dempster,
  ZatsiorskyMale,
  ZatsiorskyFemale,
  DeLevaMale,
  DeLevaFemale,
  Cylinders
};
// "dempster", "zatsiorsky_male", "zatsiorsky_female", "de_leva_male", "de_leva_female", "cylinders".
const char* to_string(BodyTable t);
std::optional<BodyTable> body_table_from_string(std::string_view name);
std::vector<std::string> body_table_names();

struct SegmentFractions {
  double mass = 0;            // of the body mass, one segment
  double com = 0;             // of the segment length, from the proximal end
  double r_sagittal = 0;      // radius of gyration about the anteroposterior axis, of the length
  double r_transverse = 0;    // about the mediolateral axis
  double r_longitudinal = 0;  // about the long axis
};

struct AnthropometricTable {
  BodyTable table = BodyTable::DeLevaMale;
  const char* citation = "";
  std::array<SegmentFractions, kSegmentClassCount> segments{};  // indexed by SegmentClass

  const SegmentFractions& segment(SegmentClass c) const { return segments[static_cast<std::size_t>(c)]; }
  // Sum of the mass fractions over the whole body, limbs counted twice (1 up to the table's
  // rounding).
  double mass_sum() const;
};

// The embedded tables (static storage). Throws std::invalid_argument for BodyTable::Cylinders,
// which is no table.
const AnthropometricTable& anthropometric_table(BodyTable t);

// Water, kg/m³: the density McCann et al. gave every cylinder.
inline constexpr double kWaterDensity = 1000.0;

// Default radii (metres) of the solid cylinders, per table segment: chosen so that a 1.75 m
// figure of synth::make_figure's proportions weighs about 69 kg at water density, with each
// segment near de Leva's male mass (head_neck 0.075, trunk 0.135, upper_arm 0.045, forearm
// 0.035, hand 0.025, thigh 0.085, shank 0.05, foot 0.04).
std::array<double, kSegmentClassCount> default_cylinder_radii();

}  // namespace kg::body
