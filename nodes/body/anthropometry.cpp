// The anthropometric tables, as published, and their conversion to the fractions of
// anthropometry.hpp. Every number below is printed in the source named beside it; the few
// derived ones are computed here from printed ones, and say how.
#include "kg/body/anthropometry.hpp"

#include <stdexcept>

namespace kg::body {

namespace {

constexpr const char* kClassNames[] = {"head_neck", "trunk", "upper_arm", "forearm", "hand",
                                       "thigh",     "shank", "foot",      "massless"};
constexpr const char* kTableNames[] = {"dempster",     "zatsiorsky_male", "zatsiorsky_female",
                                       "de_leva_male", "de_leva_female",  "cylinders"};

// One row of de Leva (1996) Table 4 as printed: mass (% of body mass), CM position (% of the
// segment length from the row's "origin" landmark), radii of gyration (% of the length) in the
// sagittal, transverse and longitudinal columns. `origin_distal` marks rows whose printed
// origin is the segment's distal end in a pelvis-rooted skeleton (head measured from the
// vertex, trunk from the cervicale), whose CM we measure from the other end.
struct PrintedRow {
  double mass, cm, r_sag, r_trans, r_long;
  bool origin_distal = false;
};

SegmentFractions from_printed(const PrintedRow& r) {
  return {.mass = r.mass / 100,
          .com = r.origin_distal ? 1 - r.cm / 100 : r.cm / 100,
          .r_sagittal = r.r_sag / 100,
          .r_transverse = r.r_trans / 100,
          .r_longitudinal = r.r_long / 100};
}

// de Leva P. (1996) Adjustments to Zatsiorsky-Seluyanov's segment inertia parameters. Journal
// of Biomechanics 29(9):1223-1230, Table 4. Zatsiorsky & Seluyanov's CM positions and radii were
// relative to bony landmarks; de Leva re-referenced them to joint centres, which is what a
// skeleton's bones join. Where Table 4 gives two definitions of a segment we take the one whose
// ends are a skeleton's joints:
//   head+neck: VERT-CERV (vertex to C7: the neck base joint to the head's End Site), CM printed
//              from the vertex;
//   trunk:     CERV-MIDH (C7 to the mid-hip point: the spine joints from the pelvis up), CM
//              printed from C7;
//   shank:     KJC-AJC (knee to ankle joint centre), not KJC-LMAL (lateral malleolus).
// Upper arm SJC-EJC, forearm EJC-WJC, hand WJC-MET3 (third metacarpal head), thigh HJC-KJC, foot
// HEEL-TTIP (toe tip; no joint marks the heel, so the foot bone from the ankle stands for it).
// The printed columns: "sagittal" is the radius about the anteroposterior axis (the axis lying
// in the sagittal plane), "transverse" about the mediolateral axis: that reading makes the
// trunk's frontal-plane moment the larger, as a trunk wider than deep must have.
constexpr PrintedRow kDeLevaMale[kSegmentClassCount] = {
    {6.94, 50.02, 30.3, 31.5, 26.1, true},   // head+neck, VERT-CERV
    {43.46, 51.38, 32.8, 30.6, 16.9, true},  // trunk, CERV-MIDH
    {2.71, 57.72, 28.5, 26.9, 15.8},         // upper arm
    {1.62, 45.74, 27.6, 26.5, 12.1},         // forearm
    {0.61, 79.00, 62.8, 51.3, 40.1},         // hand
    {14.16, 40.95, 32.9, 32.9, 14.9},        // thigh
    {4.33, 43.95, 25.1, 24.6, 10.2},         // shank, KJC-AJC
    {1.37, 44.15, 25.7, 24.5, 12.4},         // foot
};
constexpr PrintedRow kDeLevaFemale[kSegmentClassCount] = {
    {6.68, 48.41, 27.1, 29.5, 26.1, true},   // head+neck, VERT-CERV
    {42.57, 49.64, 30.7, 29.2, 14.7, true},  // trunk, CERV-MIDH
    {2.55, 57.54, 27.8, 26.0, 14.8},         // upper arm
    {1.38, 45.59, 26.1, 25.7, 9.4},          // forearm
    {0.56, 74.74, 53.1, 45.4, 33.5},         // hand
    {14.78, 36.12, 36.9, 36.4, 16.2},        // thigh
    {4.81, 43.52, 26.7, 26.3, 9.2},          // shank, KJC-AJC
    {1.29, 40.14, 29.9, 27.9, 13.9},         // foot
};

// Zatsiorsky V. M., Seluyanov V. N. (1983) The mass and inertia characteristics of the main
// segments of the human body. Biomechanics VIII-B, 1152-1159 (the Russian original is of 1979,
// hence the CSVs' names). Mass fractions (%) as the data's wspr/body-segment-param CSVs carry
// them (zats-selu1979m/f.csv; the female trunk there is thorax 15.45 + abdomen 14.65 + pelvis
// 12.47). Their own CM and radii are measured from bony landmarks rather than joint centres, the
// very thing de Leva corrected, so the geometry of these tables is de Leva's Table 4 (above).
// The male upper arm and forearm are 2.70 and 1.63 in the CSV against de Leva's 2.71 and 1.62;
// the female fractions equal de Leva's.
constexpr double kZatsiorskyMaleMass[kSegmentClassCount] = {6.94, 43.46, 2.70, 1.63, 0.61, 14.16, 4.33, 1.37};
constexpr double kZatsiorskyFemaleMass[kSegmentClassCount] = {
    6.68, 15.45 + 14.65 + 12.47, 2.55, 1.38, 0.56, 14.78, 4.81, 1.29};

// Dempster W. T. (1955) Space requirements of the seated operator. WADC-TR-55-159, in Winter's
// presentation: Winter D. A. (2009) Biomechanics and Motor Control of Human Movement, 4th ed.,
// Table 4.1: mass fraction, CM from the proximal end, radius of gyration about the CM (one,
// for a transverse axis), all of the segment length.
struct WinterRow {
  double mass, cm_proximal, r_cg;
};
constexpr WinterRow kWinter[kSegmentClassCount] = {
    {0.081, 0, 0},           // head and neck (C7-T1 to ear canal; CM at 1.000: see below)
    {0.497, 0.50, 0},        // trunk (greater trochanter to glenohumeral joint; no radius printed)
    {0.028, 0.436, 0.322},   // upper arm
    {0.016, 0.430, 0.303},   // forearm
    {0.006, 0.506, 0.297},   // hand
    {0.100, 0.433, 0.323},   // thigh
    {0.0465, 0.433, 0.302},  // leg (shank)
    {0.0145, 0.50, 0.475},   // foot
};

AnthropometricTable make_de_leva(BodyTable id, const PrintedRow (&rows)[kSegmentClassCount],
                                 const char* cite) {
  AnthropometricTable t{.table = id, .citation = cite};
  for (int c = 0; c < kSegmentClassCount; ++c)
    t.segments[static_cast<std::size_t>(c)] = from_printed(rows[c]);
  return t;
}

AnthropometricTable make_zatsiorsky(BodyTable id, const double (&mass)[kSegmentClassCount],
                                    const PrintedRow (&geometry)[kSegmentClassCount], const char* cite) {
  AnthropometricTable t = make_de_leva(id, geometry, cite);
  for (int c = 0; c < kSegmentClassCount; ++c) t.segments[static_cast<std::size_t>(c)].mass = mass[c] / 100;
  return t;
}

AnthropometricTable make_dempster() {
  AnthropometricTable t{.table = BodyTable::Dempster,
                        .citation =
                            "Dempster (1955) in Winter (2009) Table 4.1; head, trunk radii and "
                            "longitudinal radii from de Leva (1996) Table 4 (male)"};
  for (int c = 0; c < kSegmentClassCount; ++c) {
    const WinterRow& w = kWinter[c];
    const SegmentFractions leva = from_printed(kDeLevaMale[c]);
    SegmentFractions& s = t.segments[static_cast<std::size_t>(c)];
    s.mass = w.mass;
    if (c == index_of(SegmentClass::HeadNeck)) {
      // Winter puts the head-and-neck CM at the ear canal (1.000 of C7-T1 to ear canal), a
      // landmark no skeleton has; on the C7-vertex line a skeleton's neck and head span, the ear
      // canal lies about half way up, where de Leva's head CM is: his geometry stands in.
      s.com = leva.com;
      s.r_sagittal = leva.r_sagittal;
      s.r_transverse = leva.r_transverse;
      s.r_longitudinal = leva.r_longitudinal;
    } else if (c == index_of(SegmentClass::Trunk)) {
      // Winter prints the trunk's CM (0.50) but no radius of gyration: de Leva's trunk radii.
      s.com = w.cm_proximal;
      s.r_sagittal = leva.r_sagittal;
      s.r_transverse = leva.r_transverse;
      s.r_longitudinal = leva.r_longitudinal;
    } else {
      // One printed radius serves both transverse axes; Dempster's pendulum measured none about
      // the long axis, so it takes de Leva's ratio of longitudinal to mean transverse radius.
      s.com = w.cm_proximal;
      s.r_sagittal = w.r_cg;
      s.r_transverse = w.r_cg;
      s.r_longitudinal = w.r_cg * leva.r_longitudinal / (0.5 * (leva.r_sagittal + leva.r_transverse));
    }
  }
  return t;
}

}  // namespace

const char* to_string(SegmentClass c) {
  return kClassNames[static_cast<int>(c)];
}

std::optional<SegmentClass> segment_class_from_string(std::string_view name) {
  for (int c = 0; c <= kSegmentClassCount; ++c)
    if (name == kClassNames[c]) return static_cast<SegmentClass>(c);
  return std::nullopt;
}

std::vector<std::string> segment_class_names() {
  return {std::begin(kClassNames), std::end(kClassNames)};
}

const char* to_string(BodyTable t) {
  return kTableNames[static_cast<int>(t)];
}

std::optional<BodyTable> body_table_from_string(std::string_view name) {
  for (int t = 0; t < 6; ++t)
    if (name == kTableNames[t]) return static_cast<BodyTable>(t);
  return std::nullopt;
}

std::vector<std::string> body_table_names() {
  return {std::begin(kTableNames), std::end(kTableNames)};
}

double AnthropometricTable::mass_sum() const {
  double sum = 0;
  for (int c = 0; c < kSegmentClassCount; ++c)
    sum += segments[static_cast<std::size_t>(c)].mass * (is_paired(static_cast<SegmentClass>(c)) ? 2 : 1);
  return sum;
}

const AnthropometricTable& anthropometric_table(BodyTable t) {
  static const AnthropometricTable dempster = make_dempster();
  static const AnthropometricTable zm =
      make_zatsiorsky(BodyTable::ZatsiorskyMale, kZatsiorskyMaleMass, kDeLevaMale,
                      "Zatsiorsky & Seluyanov (1983) mass fractions, de Leva (1996) Table 4 geometry (male)");
  static const AnthropometricTable zf = make_zatsiorsky(
      BodyTable::ZatsiorskyFemale, kZatsiorskyFemaleMass, kDeLevaFemale,
      "Zatsiorsky & Seluyanov (1983) mass fractions, de Leva (1996) Table 4 geometry (female)");
  static const AnthropometricTable lm =
      make_de_leva(BodyTable::DeLevaMale, kDeLevaMale, "de Leva (1996) J. Biomech. 29(9), Table 4 (male)");
  static const AnthropometricTable lf = make_de_leva(BodyTable::DeLevaFemale, kDeLevaFemale,
                                                     "de Leva (1996) J. Biomech. 29(9), Table 4 (female)");
  switch (t) {
    case BodyTable::Dempster:
      return dempster;
    case BodyTable::ZatsiorskyMale:
      return zm;
    case BodyTable::ZatsiorskyFemale:
      return zf;
    case BodyTable::DeLevaMale:
      return lm;
    case BodyTable::DeLevaFemale:
      return lf;
    case BodyTable::Cylinders:
      break;
  }
  throw std::invalid_argument("anthropometric_table: 'cylinders' is no table (segments are water cylinders)");
}

std::array<double, kSegmentClassCount> default_cylinder_radii() {
  return {0.075, 0.135, 0.045, 0.035, 0.025, 0.085, 0.05, 0.04};
}

}  // namespace kg::body
