// The body model (retime.body_model, body_build.hpp, anthropometry.hpp): the tables, the class
// mapping and masses on every skeleton of the data, the centre of mass, inertias, water
// cylinders, body files with their error table, and the node alone and in a graph.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include <Eigen/Eigenvalues>

#include "../support/fuzzed_patterns.hpp"
#include "../support/node_context.hpp"
#include "../support/temp_dir.hpp"
#include "kg/base/error.hpp"
#include "kg/body/body_build.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/graph/executor.hpp"
#include "kg/graph/yaml_io.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/io/bvh.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/retime/nodes.hpp"
#include "kg/synth/figure.hpp"
#include "kg/synth/synthesize.hpp"

namespace fs = std::filesystem;
using namespace kg;
using body::BodySpec;
using body::BodyTable;
using body::BuiltBody;
using body::SegmentClass;

namespace {

const fs::path kData = KG_DATA_DIR;

template <class F>
std::string thrown(F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

int joint(const motion::Skeleton& s, const std::string& name) {
  const int j = s.find_joint(name);
  INFO(name);
  REQUIRE(j >= 0);
  return j;
}

std::set<std::string> joints_of(const BuiltBody& b, const std::string& cls) {
  std::set<std::string> out;
  for (int j = 0; j < b.body.skeleton->joint_count(); ++j)
    if (b.body.segment_class[static_cast<std::size_t>(j)] == cls) out.insert(b.body.skeleton->joint(j).name);
  return out;
}

// Every massive segment's inertia symmetric positive definite, and a rigid body's (triangle
// inequality); massless ones all zero.
void check_physical(const body::BodyModel& body) {
  for (std::size_t j = 0; j < body.segments.size(); ++j) {
    const body::SegmentInertia& s = body.segments[j];
    INFO(body.skeleton->joint(static_cast<int>(j)).name);
    CHECK(std::isfinite(s.mass));
    CHECK(s.mass >= 0);
    if (s.mass == 0) {
      CHECK(s.inertia.isZero());
      continue;
    }
    CHECK((s.inertia - s.inertia.transpose()).cwiseAbs().maxCoeff() <=
          1e-12 * s.inertia.cwiseAbs().maxCoeff());
    const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(s.inertia).eigenvalues();
    CHECK(ev.minCoeff() > 0);
    CHECK(ev[2] <= ev[0] + ev[1] + 1e-12);
  }
}

// CoM height above the lowest joint or End Site, as a fraction of the figure's vertical extent,
// at frame values `frame`.
double com_height_fraction(const body::BodyModel& body, const Eigen::RowVectorXd& frame) {
  const motion::Skeleton& s = *body.skeleton;
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(s.joint_count()));
  motion::forward_kinematics(s, frame, world);
  double lo = 1e9, hi = -1e9;
  for (int j = 0; j < s.joint_count(); ++j) {
    const Eigen::Isometry3d& w = world[static_cast<std::size_t>(j)];
    lo = std::min(lo, w.translation().y());
    hi = std::max(hi, w.translation().y());
    for (const Eigen::Vector3d& e : s.joint(j).end_sites) {
      lo = std::min(lo, (w * e).y());
      hi = std::max(hi, (w * e).y());
    }
  }
  return (body::body_com(body, frame).y() - lo) / (hi - lo);
}

std::shared_ptr<const motion::Skeleton> figure() {
  return synth::make_figure(1.75).skeleton;
}

// The per-class masses a table gives for body mass M (both sides of a limb), after the rescale
// to exactly M.
double expected_class_mass(BodyTable t, SegmentClass c, double M) {
  const body::AnthropometricTable& table = body::anthropometric_table(t);
  return table.segment(c).mass * (body::is_paired(c) ? 2 : 1) * M / table.mass_sum();
}

// A CSV of the data's anthropometry folder: first column -> column `col` (0-based).
std::map<std::string, double> read_csv(const fs::path& path, int col) {
  std::map<std::string, double> out;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::stringstream ss(line);
    std::string cell;
    std::vector<std::string> cells;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (static_cast<int>(cells.size()) > col) out[cells[0]] = std::stod(cells[static_cast<std::size_t>(col)]);
  }
  return out;
}

}  // namespace

TEST_CASE("tables: fractions sum to 100% up to rounding, printed values, rigid-body radii",
          "[retime][body]") {
  for (BodyTable t : {BodyTable::Dempster, BodyTable::ZatsiorskyMale, BodyTable::ZatsiorskyFemale,
                      BodyTable::DeLevaMale, BodyTable::DeLevaFemale}) {
    const body::AnthropometricTable& table = body::anthropometric_table(t);
    INFO(body::to_string(t));
    CHECK(table.mass_sum() == Approx(1.0).margin(1.5e-4));  // de Leva female prints 99.99%
    for (int c = 0; c < body::kSegmentClassCount; ++c) {
      const body::SegmentFractions& f = table.segments[static_cast<std::size_t>(c)];
      INFO(body::to_string(static_cast<SegmentClass>(c)));
      CHECK(f.mass > 0);
      CHECK(f.com > 0.3);
      CHECK(f.com < 0.8);
      // The radii must describe some rigid body.
      CHECK_NOTHROW(body::check_segment_inertia(
          Eigen::Vector3d(f.r_sagittal * f.r_sagittal, f.r_transverse * f.r_transverse,
                          f.r_longitudinal * f.r_longitudinal)
              .asDiagonal()
              .toDenseMatrix(),
          "table row"));
    }
  }
  using C = SegmentClass;
  const auto& male = body::anthropometric_table(BodyTable::DeLevaMale);
  CHECK(male.segment(C::Thigh).mass == Approx(0.1416));
  CHECK(male.segment(C::Thigh).com == Approx(0.4095));
  CHECK(male.segment(C::HeadNeck).com == Approx(1 - 0.5002));  // printed from the vertex
  CHECK(male.segment(C::Trunk).com == Approx(1 - 0.5138));     // printed from C7
  CHECK(male.segment(C::Trunk).r_sagittal == Approx(0.328));
  CHECK(male.segment(C::Hand).r_longitudinal == Approx(0.401));
  const auto& dempster = body::anthropometric_table(BodyTable::Dempster);
  CHECK(dempster.segment(C::Trunk).mass == Approx(0.497));
  CHECK(dempster.segment(C::Foot).r_transverse == Approx(0.475));
  CHECK(body::anthropometric_table(BodyTable::ZatsiorskyMale).segment(C::UpperArm).mass == Approx(0.0270));
  CHECK(body::anthropometric_table(BodyTable::DeLevaFemale).segment(C::Thigh).mass == Approx(0.1478));
  CHECK_THAT(thrown([] { body::anthropometric_table(BodyTable::Cylinders); }), Catch::Contains("no table"));
  for (const std::string& name : body::body_table_names())
    CHECK(body::to_string(*body::body_table_from_string(name)) == name);
  for (const std::string& name : body::segment_class_names())
    CHECK(body::to_string(*body::segment_class_from_string(name)) == name);
}

TEST_CASE("embedded mass fractions agree with the data's anthropometry CSVs", "[retime][body][data]") {
  const fs::path dir = kData / "anthropometry";
  if (!fs::exists(dir / "dempster1955.csv") || !fs::exists(dir / "zats-selu1979m.csv") ||
      !fs::exists(dir / "zats-selu1979f.csv")) {
    WARN("skipped: anthropometry CSVs not found under " << dir);
    return;
  }
  using C = SegmentClass;
  auto pct = [](BodyTable t, C c) { return 100 * body::anthropometric_table(t).segment(c).mass; };

  // Zatsiorsky-Seluyanov male: the CSV's printed fractions, exactly.
  const auto zm = read_csv(dir / "zats-selu1979m.csv", 1);
  const std::pair<const char*, C> male_rows[] = {
      {"headneck", C::HeadNeck}, {"trunk", C::Trunk}, {"arm", C::UpperArm}, {"forearm", C::Forearm},
      {"hand", C::Hand},         {"thigh", C::Thigh}, {"leg", C::Shank},    {"foot", C::Foot}};
  for (const auto& [name, c] : male_rows) {
    INFO(name);
    REQUIRE(zm.count(name));
    CHECK(pct(BodyTable::ZatsiorskyMale, c) == Approx(zm.at(name)).margin(1e-9));
    // de Leva kept them, printing 2.71 / 1.62 for the upper arm and forearm.
    CHECK(pct(BodyTable::DeLevaMale, c) == Approx(zm.at(name)).margin(0.0101));
  }
  // Female: the trunk is thorax + abdomen + pelvis there; de Leva's female fractions are these.
  const auto zf = read_csv(dir / "zats-selu1979f.csv", 1);
  const std::pair<const char*, C> female_rows[] = {
      {"headneck", C::HeadNeck}, {"arm", C::UpperArm}, {"forearm", C::Forearm}, {"hand", C::Hand},
      {"thigh", C::Thigh},       {"leg", C::Shank},    {"foot", C::Foot}};
  for (const auto& [name, c] : female_rows) {
    INFO(name);
    REQUIRE(zf.count(name));
    CHECK(pct(BodyTable::ZatsiorskyFemale, c) == Approx(zf.at(name)).margin(1e-9));
    CHECK(pct(BodyTable::DeLevaFemale, c) == Approx(zf.at(name)).margin(1e-9));
  }
  const double trunk_f = zf.at("thorax") + zf.at("abdo") + zf.at("pelvis");
  CHECK(pct(BodyTable::ZatsiorskyFemale, C::Trunk) == Approx(trunk_f).margin(1e-9));
  CHECK(pct(BodyTable::DeLevaFemale, C::Trunk) == Approx(trunk_f).margin(1e-9));

  // Dempster: Winter's presentation rounds the cadaver fractions rescaled to 100% (the CSV's
  // MassRescaled) and folds both shoulders into the trunk; they agree to 0.2 points.
  const auto d = read_csv(dir / "dempster1955.csv", 2);
  const std::pair<const char*, C> dempster_rows[] = {
      {"headneck", C::HeadNeck}, {"arm", C::UpperArm}, {"forearm", C::Forearm}, {"hand", C::Hand},
      {"thigh", C::Thigh},       {"leg", C::Shank},    {"foot", C::Foot}};
  for (const auto& [name, c] : dempster_rows) {
    INFO(name);
    REQUIRE(d.count(name));
    CHECK(pct(BodyTable::Dempster, c) == Approx(d.at(name)).margin(0.11));
  }
  const double trunk_d = d.at("chest") + d.at("abdopelvis") + 2 * d.at("shoulder");
  CHECK(pct(BodyTable::Dempster, C::Trunk) == Approx(trunk_d).margin(0.2));
}

TEST_CASE("synthetic figure: classes, masses by class and by bone length, CoM height, inertias",
          "[retime][body]") {
  const auto skel = figure();
  const BuiltBody b = body::build_body_model(skel, BodySpec{});
  const body::BodyModel& body = b.body;
  CHECK(body.total_mass() == Approx(70).epsilon(1e-12));
  CHECK(joints_of(b, "trunk") == std::set<std::string>{"Hips", "Spine", "Chest"});
  CHECK(joints_of(b, "head_neck") == std::set<std::string>{"Neck", "Head"});
  CHECK(joints_of(b, "upper_arm") == std::set<std::string>{"LeftArm", "RightArm"});
  CHECK(joints_of(b, "foot") ==
        std::set<std::string>{"LeftFoot", "LeftToeBase", "RightFoot", "RightToeBase"});
  CHECK(joints_of(b, "") == std::set<std::string>{"LeftShoulder", "RightShoulder"});
  for (int c = 0; c < body::kSegmentClassCount; ++c)
    CHECK(
        b.class_mass[static_cast<std::size_t>(c)] ==
        Approx(expected_class_mass(BodyTable::DeLevaMale, static_cast<SegmentClass>(c), 70)).epsilon(1e-12));
  // One foot's mass, 1.37%, shared by bone length between the foot and its toes.
  const int foot = joint(*skel, "LeftFoot"), toe = joint(*skel, "LeftToeBase");
  const double lf = b.bones[static_cast<std::size_t>(foot)].norm(),
               lt = b.bones[static_cast<std::size_t>(toe)].norm();
  CHECK(body.segments[static_cast<std::size_t>(foot)].mass == Approx(0.0137 * 70 * lf / (lf + lt)));
  CHECK(body.segments[static_cast<std::size_t>(toe)].mass == Approx(0.0137 * 70 * lt / (lf + lt)));
  // The thigh: CoM at 40.95% of the bone from the hip; the bone ends at the knee.
  const int thigh = joint(*skel, "LeftUpLeg");
  CHECK((b.bones[static_cast<std::size_t>(thigh)] - skel->joint(joint(*skel, "LeftLeg")).offset).norm() <
        1e-12);
  CHECK(
      (body.segments[static_cast<std::size_t>(thigh)].com - 0.4095 * b.bones[static_cast<std::size_t>(thigh)])
          .norm() < 1e-12);
  // Its inertia: radii 32.9% across, 14.9% along the bone (straight down, -Y).
  const double L = b.bones[static_cast<std::size_t>(thigh)].norm(), m = 0.1416 * 70;
  const Eigen::Matrix3d& I = body.segments[static_cast<std::size_t>(thigh)].inertia;
  CHECK(I(1, 1) == Approx(m * std::pow(0.149 * L, 2)));
  CHECK(I(0, 0) == Approx(m * std::pow(0.329 * L, 2)));
  CHECK(I(2, 2) == Approx(m * std::pow(0.329 * L, 2)));
  // The trunk's sagittal radius (about the anteroposterior axis, world Z: the figure faces +Z)
  // and transverse one (about X) differ; the split keeps the whole trunk's torsion exact.
  double trunk_mass = 0, trunk_length = 0, torsion = 0;
  Eigen::Vector3d trunk_com = Eigen::Vector3d::Zero();
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(skel->joint_count()));
  motion::forward_kinematics(*skel, body::rest_pose_values(*skel), world);
  for (const char* name : {"Hips", "Spine", "Chest"}) {
    const int j = joint(*skel, name);
    const body::SegmentInertia& s = body.segments[static_cast<std::size_t>(j)];
    trunk_mass += s.mass;
    trunk_length += b.bones[static_cast<std::size_t>(j)].norm();
    torsion += s.inertia(1, 1);
    trunk_com += s.mass * (world[static_cast<std::size_t>(j)] * s.com);
    CHECK(s.inertia(2, 2) > s.inertia(0, 0));  // sagittal 32.8% > transverse 30.6% of the length
  }
  trunk_com /= trunk_mass;
  CHECK(trunk_mass == Approx(0.4346 * 70));
  CHECK(torsion == Approx(trunk_mass * std::pow(0.169 * trunk_length, 2)).epsilon(1e-12));
  // The pieces' moments about the trunk's CoM add up to about the table's (CoMs at 48.62% of
  // each piece rather than the middle make the small difference).
  double about_x = 0;
  for (const char* name : {"Hips", "Spine", "Chest"}) {
    const int j = joint(*skel, name);
    const body::SegmentInertia& s = body.segments[static_cast<std::size_t>(j)];
    const double dy = (world[static_cast<std::size_t>(j)] * s.com).y() - trunk_com.y();
    about_x += s.inertia(0, 0) + s.mass * dy * dy;
  }
  CHECK(about_x == Approx(trunk_mass * std::pow(0.306 * trunk_length, 2)).epsilon(0.05));
  check_physical(body);
  // Standing, arms down: the CoM at about 55% of the stature (the figure spans it exactly).
  const double h = com_height_fraction(body, body::rest_pose_values(*skel));
  CHECK(h > 0.53);
  CHECK(h < 0.58);
  // Root channels unactuated; every other channel unlimited.
  const motion::Joint& root = skel->joint(0);
  for (int c = 0; c < skel->channel_count(); ++c) {
    const bool base = c < root.first_channel + static_cast<int>(root.channels.size());
    CHECK(body.torque_min[c] == (base ? 0.0 : -INFINITY));
    CHECK(body.torque_max[c] == (base ? 0.0 : INFINITY));
  }
  CHECK(body.friction == 0.5);
  CHECK(body.gravity.isApprox(Eigen::Vector3d(0, -9.81, 0)));
}

TEST_CASE("every table on one figure: masses by class follow the table, rescaled to the mass asked",
          "[retime][body]") {
  const auto skel = figure();
  for (BodyTable t : {BodyTable::Dempster, BodyTable::ZatsiorskyMale, BodyTable::ZatsiorskyFemale,
                      BodyTable::DeLevaMale, BodyTable::DeLevaFemale}) {
    INFO(body::to_string(t));
    BodySpec spec;
    spec.table = t;
    spec.mass = 61.9;
    const BuiltBody b = body::build_body_model(skel, spec);
    CHECK(b.body.total_mass() == Approx(61.9).epsilon(1e-12));
    for (int c = 0; c < body::kSegmentClassCount; ++c)
      CHECK(b.class_mass[static_cast<std::size_t>(c)] ==
            Approx(expected_class_mass(t, static_cast<SegmentClass>(c), 61.9)).epsilon(1e-12));
    check_physical(b.body);
    const double h = com_height_fraction(b.body, body::rest_pose_values(*skel));
    CHECK(h > 0.52);
    CHECK(h < 0.59);
  }
}

TEST_CASE("the data's skeletons: classes, masses by class, CoM height, floating base",
          "[retime][body][data]") {
  struct Case {
    std::string file;  // under the data folder; .asf pairs with <stem>_15.amc
    bool frame0;       // orient and measure in frame 0 (the rest pose is not standing)
    double com_lo, com_hi;
    std::map<std::string, std::set<std::string>> classes;  // expected joints with mass, per class
    std::set<std::string> floating;
  };
  auto lr = [](std::initializer_list<std::string> names) {
    std::set<std::string> out;
    for (const std::string& n : names) {
      out.insert("l" + n);
      out.insert("r" + n);
    }
    return out;
  };
  auto sides = [](const std::string& prefix, std::initializer_list<std::string> names,
                  const std::string& suffix = "") {
    std::set<std::string> out;
    for (const char* side : {"L", "R"})
      for (const std::string& n : names) out.insert(prefix + side + "_" + n + suffix);
    return out;
  };
  std::set<std::string> daz_hand = lr({"Hand"}), iclone_hand = sides("CC_Base_", {"Hand"});
  for (const char* f : {"Thumb", "Index", "Mid", "Ring", "Pinky"})
    for (const char* k : {"1", "2"}) {
      daz_hand.merge(lr({std::string(f) + k}));
      iclone_hand.merge(sides("CC_Base_", {std::string(f) + k}));
    }
  const std::map<std::string, std::set<std::string>> cmu = {
      {"trunk", {"root", "lowerback", "upperback", "thorax"}},
      {"head_neck", {"lowerneck", "upperneck", "head"}},
      {"upper_arm", lr({"humerus"})},
      {"forearm", lr({"radius"})},
      {"hand", lr({"wrist", "hand", "fingers", "thumb"})},
      {"thigh", lr({"femur"})},
      {"shank", lr({"tibia"})},
      {"foot", lr({"foot", "toes"})},
      {"", lr({"hipjoint", "clavicle"})}};
  std::map<std::string, std::set<std::string>> mb = cmu;
  mb[""] = lr({"clavicle"});
  const Case cases[] = {
      {"cmu/asf_amc/16.asf", true, 0.53, 0.60, cmu, {"root"}},
      {"cmu/bvh_motionbuilder/16_15.bvh", true, 0.53, 0.60, mb, {"root"}},
      {"cmu/bvh_daz/02_01.bvh",
       false,
       0.55,  // T-pose, and no head top (the eyes are its highest point): a little high
       0.63,
       {{"trunk", {"hip", "abdomen", "chest"}},
        {"head_neck", {"neck", "head"}},
        {"upper_arm", lr({"Shldr"})},
        {"forearm", lr({"ForeArm"})},
        {"hand", daz_hand},
        {"thigh", lr({"Thigh"})},
        {"shank", lr({"Shin"})},
        {"foot", lr({"Foot"})},
        {"", {"leftEye", "rightEye", "lCollar", "rCollar", "lButtock", "rButtock"}}},
       {"hip"}},
      {"cmu/bvh_iclone_cc_rig/002_06.bvh",
       true,  // the prepended T-pose; the rest pose has every bone along +Y
       0.55,
       0.63,
       {{"trunk", {"CC_Base_Hip", "CC_Base_Pelvis", "CC_Base_Waist", "CC_Base_Spine01", "CC_Base_Spine02"}},
        {"head_neck", {"CC_Base_NeckTwist01", "CC_Base_NeckTwist02", "CC_Base_Head"}},
        {"upper_arm", sides("CC_Base_", {"Upperarm"})},
        {"forearm", sides("CC_Base_", {"Forearm"})},
        {"hand", iclone_hand},
        {"thigh", sides("CC_Base_", {"Thigh"})},
        {"shank", sides("CC_Base_", {"Calf"})},
        {"foot", sides("CC_Base_", {"Foot", "ToeBase"})}},
       {"CC_Base_Hip"}},
      {"other_skeletons/games105/walk60.bvh",
       false,  // a T-pose: arms raised
       0.55,
       0.63,
       {{"trunk", {"RootJoint", "pelvis_lowerback", "lowerback_torso"}},
        {"head_neck", {"torso_head"}},
        {"upper_arm", lr({"Shoulder"})},
        {"forearm", lr({"Elbow"})},
        {"hand", lr({"Wrist"})},
        {"thigh", lr({"Hip"})},
        {"shank", lr({"Knee"})},
        {"foot", lr({"Ankle", "ToeJoint"})},
        {"", lr({"Torso_Clavicle"})}},
       {"RootJoint"}},
      {"other_skeletons/bandai_namco/dataset-1_run_normal_001.bvh",
       true,  // running; bones lie along X in the rest pose
       0.53,
       0.65,
       {{"trunk", {"Hips", "Spine", "Chest"}},
        {"head_neck", {"Neck", "Head"}},
        {"upper_arm", {"UpperArm_L", "UpperArm_R"}},
        {"forearm", {"LowerArm_L", "LowerArm_R"}},
        {"hand", {"Hand_L", "Hand_R"}},
        {"thigh", {"UpperLeg_L", "UpperLeg_R"}},
        {"shank", {"LowerLeg_L", "LowerLeg_R"}},
        {"foot", {"Foot_L", "Foot_R", "Toes_L", "Toes_R"}},
        {"", {"joint_Root", "Shoulder_L", "Shoulder_R"}}},
       {"joint_Root", "Hips"}},  // Hips hangs from a massless root on the floor
  };
  for (const Case& c : cases) {
    INFO(c.file);
    const fs::path path = kData / c.file;
    if (!fs::exists(path)) {
      WARN("skipped: " << path << " not found");
      continue;
    }
    io::ImportedMotion in;
    if (path.extension() == ".asf") {
      const fs::path amc = path.parent_path() / (path.stem().string() + "_15.amc");
      in = io::import_asf_amc(path.string(), amc.string(), {});
    } else {
      in = io::import_bvh(path, {});
    }
    const motion::Motion& m = in.motion;
    const Eigen::RowVectorXd ref =
        c.frame0 ? Eigen::RowVectorXd(m.values.row(0)) : body::rest_pose_values(*m.skeleton);
    const BuiltBody b = body::build_body_model(m.skeleton, BodySpec{}, &ref);
    for (const auto& [cls, names] : c.classes) {
      INFO("class '" << cls << "'");
      const std::set<std::string> got = joints_of(b, cls);
      if (cls.empty()) {  // massless: these at least (zero-length joints join them)
        for (const std::string& n : names) CHECK(got.count(n) == 1);
      } else {
        CHECK(got == names);
      }
    }
    CHECK(b.body.total_mass() == Approx(70).epsilon(1e-12));
    for (int k = 0; k < body::kSegmentClassCount; ++k)
      CHECK(b.class_mass[static_cast<std::size_t>(k)] ==
            Approx(expected_class_mass(BodyTable::DeLevaMale, static_cast<SegmentClass>(k), 70))
                .epsilon(1e-12));
    check_physical(b.body);
    const double h = com_height_fraction(b.body, ref);
    INFO("CoM at " << h << " of the figure's height");
    CHECK(h > c.com_lo);
    CHECK(h < c.com_hi);
    for (int j = 0; j < m.skeleton->joint_count(); ++j) {
      const motion::Joint& jt = m.skeleton->joint(j);
      const bool base = c.floating.count(jt.name) == 1;
      for (std::size_t k = 0; k < jt.channels.size(); ++k) {
        INFO(jt.name);
        CHECK((b.body.torque_max[jt.first_channel + static_cast<int>(k)] == 0) == base);
      }
    }
  }
}

TEST_CASE("CMU 16.asf: each side's limb mass, shared by bone length, the root carries the pelvis",
          "[retime][body][data]") {
  const fs::path asf = kData / "cmu/asf_amc/16.asf", amc = kData / "cmu/asf_amc/16_15.amc";
  if (!fs::exists(asf) || !fs::exists(amc)) {
    WARN("skipped: " << asf << " not found");
    return;
  }
  const io::ImportedMotion in = io::import_asf_amc(asf.string(), amc.string(), {});
  const motion::Skeleton& s = *in.motion.skeleton;
  const BuiltBody b = body::build_body_model(in.motion.skeleton, BodySpec{});
  auto mass = [&](const std::string& n) {
    return b.body.segments[static_cast<std::size_t>(joint(s, n))].mass;
  };
  auto length = [&](const std::string& n) { return b.bones[static_cast<std::size_t>(joint(s, n))].norm(); };
  CHECK(mass("lfemur") == Approx(0.1416 * 70));
  CHECK(mass("rfemur") == Approx(0.1416 * 70));
  CHECK(mass("lfoot") + mass("ltoes") == Approx(0.0137 * 70));
  CHECK(mass("lfoot") / mass("ltoes") == Approx(length("lfoot") / length("ltoes")));
  CHECK(mass("lwrist") + mass("lhand") + mass("lfingers") + mass("lthumb") == Approx(0.0061 * 70));
  // The root's children all start at its origin; through its massless hipjoints its bone
  // reaches the middle of the hips, the pelvis.
  const Eigen::Vector3d mid_hips =
      0.5 * (s.joint(joint(s, "lfemur")).offset + s.joint(joint(s, "rfemur")).offset);
  CHECK((b.bones[0] - mid_hips).norm() < 1e-12);
  CHECK(mass("root") ==
        Approx(0.4346 * 70 * length("root") /
               (length("root") + length("lowerback") + length("upperback") + length("thorax"))));
}

TEST_CASE("cylinders of water: masses from volumes, or rescaled to a mass", "[retime][body]") {
  // A stick figure with known bones: everything straight, metres.
  auto s = std::make_shared<motion::Skeleton>();
  using K = motion::ChannelKind;
  const std::vector<motion::Channel> rot = {
      {.kind = K::Zrotation}, {.kind = K::Xrotation}, {.kind = K::Yrotation}};
  std::vector<motion::Channel> root_ch = {
      {.kind = K::Xposition}, {.kind = K::Yposition}, {.kind = K::Zposition}};
  root_ch.insert(root_ch.end(), rot.begin(), rot.end());
  const int hips = s->add_joint({.name = "Hips", .channels = root_ch});
  const int chest = s->add_joint({.name = "Chest", .parent = hips, .offset = {0, 0.5, 0}, .channels = rot});
  const int neck = s->add_joint(
      {.name = "Neck", .parent = chest, .offset = {0, 0.1, 0}, .channels = rot, .end_sites = {{0, 0.2, 0}}});
  (void)neck;
  for (double side : {1.0, -1.0}) {
    const std::string p = side > 0 ? "Left" : "Right";
    const int arm =
        s->add_joint({.name = p + "Arm", .parent = chest, .offset = {side * 0.2, 0.1, 0}, .channels = rot});
    const int fore =
        s->add_joint({.name = p + "ForeArm", .parent = arm, .offset = {0, -0.3, 0}, .channels = rot});
    s->add_joint({.name = p + "Hand",
                  .parent = fore,
                  .offset = {0, -0.25, 0},
                  .channels = rot,
                  .end_sites = {{0, -0.15, 0}}});
    const int up =
        s->add_joint({.name = p + "UpLeg", .parent = hips, .offset = {side * 0.1, 0, 0}, .channels = rot});
    const int leg = s->add_joint({.name = p + "Leg", .parent = up, .offset = {0, -0.45, 0}, .channels = rot});
    s->add_joint({.name = p + "Foot",
                  .parent = leg,
                  .offset = {0, -0.4, 0},
                  .channels = rot,
                  .end_sites = {{0, 0, 0.2}}});
  }
  BodySpec spec;
  spec.table = BodyTable::Cylinders;
  spec.mass = 0;
  const BuiltBody b = body::build_body_model(s, spec);
  const auto r = body::default_cylinder_radii();
  auto volume_mass = [](double radius, double length) { return 1000 * M_PI * radius * radius * length; };
  auto idx = [](SegmentClass c) { return static_cast<std::size_t>(body::index_of(c)); };
  const auto seg = [&](const std::string& n) {
    return b.body.segments[static_cast<std::size_t>(joint(*s, n))];
  };
  CHECK(seg("LeftUpLeg").mass == Approx(volume_mass(r[idx(SegmentClass::Thigh)], 0.45)));
  CHECK(seg("LeftLeg").mass == Approx(volume_mass(r[idx(SegmentClass::Shank)], 0.4)));
  CHECK(seg("Hips").mass == Approx(volume_mass(r[idx(SegmentClass::Trunk)], 0.5)));
  CHECK(seg("Chest").mass == Approx(volume_mass(r[idx(SegmentClass::Trunk)], 0.1)));
  CHECK(seg("Neck").mass == Approx(volume_mass(r[idx(SegmentClass::HeadNeck)], 0.2)));
  double total = 0;
  for (const auto& x : b.body.segments) total += x.mass;
  CHECK(b.body.total_mass() == Approx(total));
  // A solid cylinder: m r²/2 about its axis (the thigh points down -Y), m (3r² + l²)/12 across;
  // CoM at the middle.
  const body::SegmentInertia thigh = seg("LeftUpLeg");
  const double rt = r[idx(SegmentClass::Thigh)];
  CHECK(thigh.inertia(1, 1) == Approx(thigh.mass * rt * rt / 2));
  CHECK(thigh.inertia(0, 0) == Approx(thigh.mass * (3 * rt * rt + 0.45 * 0.45) / 12));
  CHECK(thigh.inertia(2, 2) == Approx(thigh.inertia(0, 0)));
  CHECK((thigh.com - Eigen::Vector3d(0, -0.225, 0)).norm() < 1e-12);
  check_physical(b.body);

  // A mass rescales every segment alike (a density).
  spec.mass = 80;
  const BuiltBody scaled = body::build_body_model(s, spec);
  CHECK(scaled.body.total_mass() == Approx(80));
  const double k = 80 / total;
  CHECK(scaled.body.segments[static_cast<std::size_t>(joint(*s, "LeftUpLeg"))].mass ==
        Approx(k * thigh.mass));
  CHECK(scaled.body.segments[static_cast<std::size_t>(joint(*s, "LeftUpLeg"))].inertia.isApprox(
      k * thigh.inertia));

  // Radii from a body file.
  const body::LoadedBodySpec f =
      body::parse_body_yaml("version: 1\ntable: cylinders\nmass: 0\nradii: {thigh: 0.1}\n", "cyl.yaml");
  const BuiltBody wide = body::build_body_model(s, f.spec);
  CHECK(wide.body.segments[static_cast<std::size_t>(joint(*s, "LeftUpLeg"))].mass ==
        Approx(volume_mass(0.1, 0.45)));
  CHECK(wide.body.segments[static_cast<std::size_t>(joint(*s, "LeftLeg"))].mass ==
        Approx(seg("LeftLeg").mass));
}

TEST_CASE("body file: table, mass, classes, overrides, torque limits, friction, gravity", "[retime][body]") {
  const auto skel = figure();
  const std::string text =
      "version: 1\n"
      "table: dempster\n"
      "mass: 80\n"
      "classes:\n"
      "  \"(Left|Right)Shoulder\": trunk\n"  // clavicles join the trunk, before the defaults
      "segments:\n"
      "  LeftUpLeg: {mass_scale: 10}\n"  // McCann et al. Fig. 11
      "  \"Left.*\": {mass: 2.5}\n"      // first match wins: LeftUpLeg keeps its scale
      "  Head:\n"
      "    com: [0, 0.1, 0.02]\n"
      "    inertia: [0.02, 0.015, 0.018, 0.001, 0, 0]\n"
      "  RightHand: {radius: 0.04}\n"
      "torque_limits:\n"
      "  \".*(Leg|UpLeg)\": 300\n"
      "  LeftFoot: [100, 50, .inf]\n"
      "  \".*\": 150\n"
      "friction: 0.8\n"
      "gravity: [1, -9, 0]\n";
  const body::LoadedBodySpec f = body::parse_body_yaml(text, "body.yaml");
  CHECK(f.given == std::vector<std::string>{"table", "mass", "classes", "segments", "torque_limits",
                                            "friction", "gravity"});
  const BuiltBody b = body::build_body_model(skel, f.spec);
  const motion::Skeleton& s = *skel;
  auto seg = [&](const std::string& n) { return b.body.segments[static_cast<std::size_t>(joint(s, n))]; };
  CHECK(b.body.segment_class[static_cast<std::size_t>(joint(s, "LeftShoulder"))] == "trunk");
  // Dempster's thigh is 10% of 80 kg; ten times that now.
  CHECK(seg("LeftUpLeg").mass ==
        Approx(10 * 0.100 * 80 / body::anthropometric_table(BodyTable::Dempster).mass_sum()));
  CHECK(seg("RightUpLeg").mass ==
        Approx(0.100 * 80 / body::anthropometric_table(BodyTable::Dempster).mass_sum()));
  CHECK(seg("LeftArm").mass == Approx(2.5));
  CHECK(seg("LeftShoulder").mass == Approx(2.5));  // a trunk piece now, so it may take a mass
  CHECK((seg("Head").com - Eigen::Vector3d(0, 0.1, 0.02)).norm() < 1e-12);
  CHECK(seg("Head").inertia(0, 1) == Approx(0.001));
  CHECK(seg("Head").inertia(1, 1) == Approx(0.015));
  const double hand = b.bones[static_cast<std::size_t>(joint(s, "RightHand"))].norm();
  CHECK(seg("RightHand").mass == Approx(1000 * M_PI * 0.04 * 0.04 * hand));
  // The override changes the total: it is no longer the 80 kg asked.
  double expected = 80 + 9 * seg("RightUpLeg").mass;
  CHECK(b.body.total_mass() > expected);  // the "Left.*" masses add more
  bool noted = false;
  for (const std::string& n : b.notes)
    noted = noted || n.find("segments 'LeftUpLeg': LeftUpLeg") != std::string::npos;
  CHECK(noted);

  const motion::Joint& knee = s.joint(joint(s, "LeftLeg"));
  CHECK(b.body.torque_max[knee.first_channel] == 300);
  CHECK(b.body.torque_min[knee.first_channel + 2] == -300);
  const motion::Joint& foot = s.joint(joint(s, "LeftFoot"));
  CHECK(b.body.torque_max[foot.first_channel] == 100);
  CHECK(b.body.torque_max[foot.first_channel + 1] == 50);
  CHECK(b.body.torque_max[foot.first_channel + 2] == INFINITY);
  CHECK(b.body.torque_max[s.joint(joint(s, "Neck")).first_channel] == 150);
  CHECK(b.body.torque_max[0] == 0);  // the root stays unactuated under ".*"
  CHECK(b.body.friction == 0.8);
  CHECK(b.body.gravity.isApprox(Eigen::Vector3d(1, -9, 0)));
  check_physical(b.body);

  // A magnitude means straight down; keys not given keep the base spec.
  BodySpec base;
  base.mass = 55;
  base.friction = 0.3;
  const body::LoadedBodySpec g = body::parse_body_yaml("version: 1\ngravity: 1.62\n", "moon.yaml", base);
  CHECK(g.spec.gravity.isApprox(Eigen::Vector3d(0, -1.62, 0)));
  CHECK(g.spec.mass == 55);
  CHECK(g.spec.friction == 0.3);
  CHECK(g.given == std::vector<std::string>{"gravity"});
}

TEST_CASE("body file errors name file:line:column and the key", "[retime][body]") {
  struct Case {
    const char* text;
    const char* where;
    const char* says;
  };
  const Case parse_cases[] = {
      {"table: dempster\n", "bad.yaml:1:1", "missing 'version: 1'"},
      {"version: 2\n", "bad.yaml:1:10", "unsupported version '2'"},
      {"version: 1\nmas: 70\n", "bad.yaml:2:1", "unknown key 'mas' in the body file (did you mean 'mass'?)"},
      {"version: 1\ntable: de_leva\n", "bad.yaml:2:8", "table: unknown table 'de_leva'"},
      {"version: 1\nmass: 0\n", "bad.yaml:2:7", "mass 0 kg with table de_leva_male: expected > 0"},
      {"version: 1\nmass: -3\n", "bad.yaml:2:7", "mass: expected a number >= 0"},
      {"version: 1\nmass: heavy\n", "bad.yaml:2:7", "mass: expected a number, got 'heavy'"},
      {"version: 1\nmass: .nan\n", "bad.yaml:2:7", "mass: expected a number"},
      {"version: 1\nmass: 1e999\n", "bad.yaml:2:7", "mass: expected a number"},
      {"version: 1\nfriction: -0.1\n", "bad.yaml:2:11", "friction: expected a number >= 0"},
      {"version: 1\ngravity: -9.81\n", "bad.yaml:2:10", "gravity: expected a magnitude >= 0"},
      {"version: 1\ngravity: [0, -9.81]\n", "bad.yaml:2:10", "gravity: expected 3 numbers"},
      {"version: 1\nradii: {thigh: 0}\n", "bad.yaml:2:16", "radii.thigh: expected a number > 0"},
      {"version: 1\nradii: {thgh: 0.1}\n", "bad.yaml:2:9",
       "unknown class 'thgh' in radii (did you mean 'thigh'?)"},
      {"version: 1\nclasses:\n  \"Left(\": thigh\n", "bad.yaml:3:3",
       "classes: bad regular expression 'Left(': missing )"},
      {"version: 1\nclasses:\n  LeftUpLeg: thy\n", "bad.yaml:3:14", "classes.LeftUpLeg: unknown class 'thy'"},
      {"version: 1\nsegments:\n  LeftUpLeg: {mas: 3}\n", "bad.yaml:3:15",
       "unknown key 'mas' in segments.LeftUpLeg (did you mean 'mass'?)"},
      {"version: 1\nsegments:\n  LeftUpLeg: {mass: 0}\n", "bad.yaml:3:21",
       "segments.LeftUpLeg.mass: expected a number > 0"},
      {"version: 1\nsegments:\n  LeftUpLeg: {mass: -2}\n", "bad.yaml:3:21",
       "segments.LeftUpLeg.mass: expected a number > 0"},
      {"version: 1\nsegments:\n  LeftUpLeg: {mass_scale: inf}\n", "bad.yaml:3:27",
       "segments.LeftUpLeg.mass_scale: infinity is not allowed here (expected a finite number), got 'inf'"},
      {"version: 1\nmass: .inf\n", "bad.yaml:2:7",
       "mass: infinity is not allowed here (expected a finite number), got '.inf'"},
      {"version: 1\ngravity: [0, -.Inf, 0]\n", "bad.yaml:2:14",
       "gravity[1]: infinity is not allowed here (expected a finite number), got '-.Inf'"},
      {"version: 1\nsegments:\n  LeftUpLeg: {mass: 2, mass_scale: 2}\n", "bad.yaml:3:24",
       "segments.LeftUpLeg: give mass or mass_scale, not both"},
      {"version: 1\nsegments:\n  LeftUpLeg: {com: [0, 1]}\n", "bad.yaml:3:20",
       "segments.LeftUpLeg.com: expected 3 numbers"},
      {"version: 1\nsegments:\n  LeftUpLeg: {inertia: [1, 1, -1]}\n", "bad.yaml:3:24",
       "not positive definite"},
      {"version: 1\nsegments:\n  LeftUpLeg: {inertia: [1, 1, 5]}\n", "bad.yaml:3:24", "no rigid body"},
      {"version: 1\nsegments:\n  LeftUpLeg: {inertia: [1, 1]}\n", "bad.yaml:3:24",
       "expected 3 numbers (principal"},
      {"version: 1\nsegments:\n  LeftUpLeg: {}\n", "bad.yaml:3:14", "expected at least one of"},
      {"version: 1\nsegments:\n  \"[\": {mass: 1}\n", "bad.yaml:3:3", "segments: bad regular expression '['"},
      {"version: 1\ntorque_limits:\n  \"(?!Hips)\": 100\n", "bad.yaml:3:3",
       "torque_limits: bad regular expression '(?!Hips)': unsupported group '(?!'"},
      {"version: 1\ntorque_limits:\n  LeftLeg: 0\n", "bad.yaml:3:12",
       "torque_limits.LeftLeg: expected N m > 0"},
      {"version: 1\ntorque_limits:\n  LeftLeg: [10, -1]\n", "bad.yaml:3:17",
       "torque_limits.LeftLeg[1]: expected N m > 0"},
      {"version: 1\ntorque_limits:\n  LeftLeg: []\n", "bad.yaml:3:12", "got an empty list"},
      {"version: 1\ntorque_limits:\n  LeftLeg: 1\n  LeftLeg: 2\n", "bad.yaml:4:3", "duplicate key 'LeftLeg'"},
      {"version: 1\nsegments: [1, 2]\n", "bad.yaml:2:11", "segments must be a map"},
      {"version: 1\nmass: {x: 1\n", "bad.yaml:", "malformed YAML"},
      {"", "bad.yaml:1:1", "empty body file"},
  };
  for (const Case& c : parse_cases) {
    INFO(c.text);
    std::string message;
    try {
      body::parse_body_yaml(c.text, "bad.yaml");
    } catch (const kg::Error& e) {
      message = e.what();
    }
    INFO(message);
    CHECK(message.rfind(c.where, 0) == 0);
    CHECK(message.find(c.says) != std::string::npos);
  }

  // Errors found against the skeleton, still located in the file.
  const auto skel = figure();
  const Case build_cases[] = {
      {"version: 1\nclasses:\n  Spine2: trunk\n", "bad.yaml:3:3",
       "classes pattern 'Spine2' matches no joint"},
      {"version: 1\nsegments:\n  Leg: {mass: 1}\n", "bad.yaml:3:3",
       "segments pattern 'Leg' matches no joint"},
      {"version: 1\ntorque_limits:\n  Knee: 100\n", "bad.yaml:3:3",
       "torque_limits pattern 'Knee' matches no joint"},
      {"version: 1\ntorque_limits:\n  LeftLeg: [1, 2]\n", "bad.yaml:3:3",
       "2 values for joint 'LeftLeg', which has 3 channels"},
      {"version: 1\ntorque_limits:\n  Hips: 100\n", "bad.yaml:3:3", "matches only the floating base (Hips)"},
      {"version: 1\nsegments:\n  LeftShoulder: {mass: 1}\n", "bad.yaml:3:3",
       "joint 'LeftShoulder' is massless (class): map it to a segment class"},
  };
  for (const Case& c : build_cases) {
    INFO(c.text);
    std::string message;
    try {
      body::build_body_model(skel, body::parse_body_yaml(c.text, "bad.yaml").spec);
    } catch (const kg::Error& e) {
      message = e.what();
    }
    INFO(message);
    CHECK(message.rfind(c.where, 0) == 0);
    CHECK(message.find(c.says) != std::string::npos);
  }

  // A zero-length joint needs a shape for a mass: CMU-like root (children at its origin).
  auto tiny = std::make_shared<motion::Skeleton>(*skel);
  const int root_end = tiny->add_joint({.name = "LeftHandEnd", .parent = joint(*tiny, "LeftHand")});
  (void)root_end;
  CHECK_THAT(
      thrown([&] {
        body::build_body_model(
            tiny, body::parse_body_yaml("version: 1\nsegments:\n  LeftHandEnd: {mass: 1}\n", "z.yaml").spec);
      }),
      Catch::Contains("z.yaml:3:3: segments 'LeftHandEnd': joint 'LeftHandEnd' has no bone, so no shape"));
  CHECK_THAT(
      thrown([&] {
        body::build_body_model(
            tiny,
            body::parse_body_yaml("version: 1\nsegments:\n  LeftHandEnd: {radius: 0.1}\n", "z.yaml").spec);
      }),
      Catch::Contains("has no bone for a cylinder along it"));
  const BuiltBody given = body::build_body_model(
      tiny, body::parse_body_yaml(
                "version: 1\nsegments:\n  LeftHandEnd: {mass: 1, inertia: [1e-3, 1e-3, 1e-3]}\n", "z.yaml")
                .spec);
  CHECK(given.body.segments.back().mass == 1);

  // A skeleton without thighs: the message says what is missing and how to map it.
  auto no_legs = std::make_shared<motion::Skeleton>();
  for (int j = 0; j < skel->joint_count(); ++j) {
    motion::Joint jt = skel->joint(j);
    if (jt.name.find("UpLeg") != std::string::npos) jt.name.replace(jt.name.find("UpLeg"), 5, "Femur");
    no_legs->add_joint(jt);
  }
  const std::string missing = thrown([&] { body::build_body_model(no_legs, BodySpec{}); });
  INFO(missing);
  CHECK(missing.find("lacks table segments: thigh (no joint matched; expected a left and a right)") !=
        std::string::npos);
  CHECK(missing.find("classes:\n    \"LeftUpLeg|RightUpLeg\": thigh") != std::string::npos);
  CHECK(missing.find("LeftFemur") != std::string::npos);  // among the joints without a class
  // Mapped in a file, it builds.
  const body::LoadedBodySpec fixed =
      body::parse_body_yaml("version: 1\nclasses:\n  \"(Left|Right)Femur\": thigh\n", "legs.yaml");
  CHECK(body::build_body_model(no_legs, fixed.spec)
            .class_mass[static_cast<std::size_t>(body::index_of(SegmentClass::Thigh))] ==
        Approx(2 * 0.1416 * 70));
  // Only one thigh: two runs expected.
  const std::string one = thrown([&] {
    body::build_body_model(
        no_legs, body::parse_body_yaml("version: 1\nclasses:\n  LeftFemur: thigh\n", "l.yaml").spec);
  });
  CHECK(one.find("thigh (1 separate runs of joints: LeftFemur; expected a left and a right)") !=
        std::string::npos);

  // Programmatic specs are checked too.
  BodySpec bad;
  bad.mass = 0;
  CHECK_THAT(thrown([&] { body::build_body_model(skel, bad); }), Catch::Contains("expected > 0"));
  bad = BodySpec{};
  bad.friction = NAN;
  CHECK_THAT(thrown([&] { body::build_body_model(skel, bad); }), Catch::Contains("friction"));
  bad = BodySpec{};
  bad.radii[0] = -1;
  CHECK_THAT(thrown([&] { body::build_body_model(skel, bad); }),
             Catch::Contains("cylinder radius of head_neck"));
  CHECK_THAT(thrown([&] { body::load_body_yaml("/nonexistent/body.yaml"); }), Catch::Contains("body.yaml"));
}

TEST_CASE("body file and spec: fuzzed patterns refused at their place with a short excerpt",
          "[retime][body]") {
  const auto skel = figure();
  const auto start = std::chrono::steady_clock::now();
  for (const kg::test::FuzzedPattern& p : kg::test::fuzzed_patterns()) {
    const auto error = [&](const auto& read) {
      try {
        read();
      } catch (const kg::Error& e) {
        return std::string(e.what());
      }
      return std::string("no kg::Error");
    };
    // In a body file: refused when read, at the key.
    const std::pair<std::string, std::string> keys[] = {
        {"classes", "thigh"}, {"segments", "{mass: 1}"}, {"torque_limits", "100"}};
    for (const auto& [what, value] : keys)
      kg::test::check_refusal(
          error([&, &what = what, &value = value] {  // clang before 16 captures no structured binding
            body::parse_body_yaml("version: 1\n" + what + ":\n" + kg::test::explicit_entry(p.text, value, 2),
                                  "deep.yaml");
          }),
          "deep.yaml:3:5: " + what + ": ", p);
    // In a spec made in code: refused when building, at the pattern's `where`.
    BodySpec spec;
    spec.classes.push_back({p.text, SegmentClass::Thigh, {"spec.yaml", 7, 5}});
    kg::test::check_refusal(error([&] { body::build_body_model(skel, spec); }),
                            "spec.yaml:7:5: classes: ", p);
    spec = BodySpec{};
    spec.segments.push_back({.pattern = p.text, .mass = 1.0, .where = {"spec.yaml", 8, 5}});
    kg::test::check_refusal(error([&] { body::build_body_model(skel, spec); }),
                            "spec.yaml:8:5: segments: ", p);
    spec = BodySpec{};
    spec.torque_limits.push_back({.pattern = p.text, .values = {100}, .where = {"spec.yaml", 9, 5}});
    kg::test::check_refusal(error([&] { body::build_body_model(skel, spec); }),
                            "spec.yaml:9:5: torque_limits: ", p);
  }
  CHECK(kg::test::seconds_since(start) < 10);
}

TEST_CASE("check_body_model refuses inconsistent models", "[retime][body]") {
  const BuiltBody b = body::build_body_model(figure(), BodySpec{});
  CHECK_NOTHROW(body::check_body_model(b.body));
  body::BodyModel m = b.body;
  m.segments.pop_back();
  CHECK_THAT(thrown([&] { body::check_body_model(m); }), Catch::Contains("segments and"));
  m = b.body;
  m.segments[5].inertia(0, 0) = -1;
  CHECK_THAT(thrown([&] { body::check_body_model(m); }), Catch::Contains("inertia"));
  m = b.body;
  m.torque_min[10] = 5;
  m.torque_max[10] = 1;
  CHECK_THAT(thrown([&] { body::check_body_model(m); }), Catch::Contains("bounds [5, 1]"));
  m = b.body;
  m.segments[3].mass = -1;
  CHECK_THAT(thrown([&] { body::check_body_model(m); }), Catch::Contains("mass -1"));
}

TEST_CASE("retime.body_model node: params, a body file, the log, and errors", "[retime][body][node]") {
  const graph::Registry registry = test::registry_of(retime_body_node_types());
  const synth::Synthesis walk = synth::synthesize_walk({.steps = 2, .fps = 30});
  {
    test::NodeContext ctx = test::run_node(registry, "retime.body_model",
                                           test::params_for(registry, "retime.body_model", {{"mass", 80.0}}),
                                           {{"motion", graph::Value::make(walk.motion)}});
    const body::BodyModel& body = ctx.outputs.at("body").get<body::BodyModel>();
    CHECK(body.total_mass() == Approx(80));
    CHECK(body.skeleton == walk.motion.skeleton);
    CHECK(std::get<double>(ctx.figures.at("total_mass")) == Approx(80));
    CHECK(std::get<double>(ctx.figures.at("mass_thigh")) == Approx(2 * 0.1416 * 80));
    CHECK(std::get<std::string>(ctx.figures.at("table")) == "de_leva_male");
    CHECK(std::get<std::int64_t>(ctx.figures.at("channels_unactuated")) == 6);
    const double h = std::get<double>(ctx.figures.at("com_height_fraction_frame0"));
    CHECK(h > 0.5);
    CHECK(h < 0.6);
    CHECK(ctx.logged("total 80 kg: head_neck"));
    CHECK(ctx.logged("thigh 22.66 kg"));
    CHECK(ctx.logged("massless by class: LeftShoulder, RightShoulder"));
  }
  test::TempDir dir;
  const fs::path file =
      dir.write("heavy.yaml",
                "version: 1\nmass: 60\ngravity: 3.7\nsegments:\n  LeftUpLeg: {mass_scale: 10}\n"
                "torque_limits:\n  \".*\": 200\n");
  test::NodeContext ctx =
      test::run_node(registry, "retime.body_model",
                     test::params_for(registry, "retime.body_model",
                                      {{"file", file.string()}, {"table", std::string("dempster")}}),
                     {{"motion", graph::Value::make(walk.motion)}});
  const body::BodyModel& body = ctx.outputs.at("body").get<body::BodyModel>();
  CHECK(body.gravity.isApprox(Eigen::Vector3d(0, -3.7, 0)));
  CHECK(ctx.logged("sets mass = 60 kg (param mass = 70 kg not used)"));
  CHECK(ctx.logged("sets gravity = [0, -3.7, 0] m/s²"));
  CHECK(std::get<std::string>(ctx.figures.at("table")) == "dempster");  // the param, the file has none
  CHECK(std::get<double>(ctx.figures.at("mass_thigh")) == Approx(11 * 0.100 * 60));
  CHECK(std::get<std::int64_t>(ctx.figures.at("channels_limited")) ==
        walk.motion.skeleton->channel_count() - 6);

  // Errors: a bad param combination when the graph loads, a bad file when it runs.
  CHECK_THAT(thrown([&] {
               registry.create_node("retime.body_model",
                                    test::params_for(registry, "retime.body_model", {{"mass", 0.0}}));
             }),
             Catch::Contains("expected > 0"));
  CHECK_NOTHROW(registry.create_node(
      "retime.body_model",
      test::params_for(registry, "retime.body_model", {{"mass", 0.0}, {"table", std::string("cylinders")}})));
  const fs::path bad = dir.write("bad.yaml", "version: 1\nsegments:\n  Knee: {mass: 3}\n");
  CHECK_THAT(thrown([&] {
               test::run_node(registry, "retime.body_model",
                              test::params_for(registry, "retime.body_model", {{"file", bad.string()}}),
                              {{"motion", graph::Value::make(walk.motion)}});
             }),
             Catch::Contains(bad.string() + ":3:3: segments pattern 'Knee' matches no joint"));
}

TEST_CASE("retime.body_model in a graph: a synthesized jump's body through load_graph and run_graph",
          "[retime][body][node]") {
  graph::Registry registry;
  register_builtin_nodes(registry);
  const std::string text =
      "version: 1\n"
      "nodes:\n"
      "  clip: {type: motion.synthesize, params: {kind: jump, fps: 30}}\n"
      "  body: {type: retime.body_model, params: {table: cylinders, mass: 0, friction: 0.7}}\n"
      "connections:\n"
      "  - {from: clip.motion, to: body.motion}\n";
  const graph::Graph g = graph::load_graph_from_string(text, "body_graph.yaml", registry);
  std::vector<std::string> logs;
  const graph::RunResult r = graph::run_graph(
      g, registry,
      {.jobs = 1, .on_log = [&](const std::string&, const std::string& m) { logs.push_back(m); }});
  INFO((r.nodes.size() > 1 ? r.nodes[1].message : std::string()));
  REQUIRE(r.ok);
  const body::BodyModel& body = r.outputs.at("body.body").get<body::BodyModel>();
  CHECK(body.friction == 0.7);
  // A 1.75 m figure of water cylinders weighs about 69 kg (anthropometry.hpp's radii).
  CHECK(body.total_mass() > 60);
  CHECK(body.total_mass() < 78);
  bool summary = false;
  for (const std::string& l : logs) summary = summary || l.find("kg from the volumes") != std::string::npos;
  CHECK(summary);

  // A wrong type on the port is refused before anything runs.
  const std::string wrong =
      "version: 1\n"
      "nodes:\n"
      "  clip: {type: motion.synthesize}\n"
      "  body: {type: retime.body_model, params: {table: de_leva}}\n"
      "connections:\n"
      "  - {from: clip.motion, to: body.motion}\n";
  CHECK_THAT(thrown([&] { graph::load_graph_from_string(wrong, "w.yaml", registry); }),
             Catch::Contains("w.yaml:4"));
}

TEST_CASE("one take in two formats (16_15 as ASF/AMC and as MotionBuilder BVH) has one centre of mass",
          "[retime][body][data]") {
  const fs::path asf = kData / "cmu/asf_amc/16.asf", amc = kData / "cmu/asf_amc/16_15.amc";
  const fs::path bvh = kData / "cmu/bvh_motionbuilder/16_15.bvh";
  if (!fs::exists(asf) || !fs::exists(amc) || !fs::exists(bvh)) {
    WARN("skipped: the 16_15 files not found under " << kData);
    return;
  }
  // ASF root and hipjoints at the pelvis centre, MotionBuilder's femurs hanging from the root
  // directly, ASF bone axes against BVH offsets: other skeletons, the same body.
  const motion::Motion a = io::import_asf_amc(asf.string(), amc.string(), {.trim = "none"}).motion;
  const motion::Motion b = io::import_bvh(bvh, {.trim = "none"}).motion;
  REQUIRE(a.frame_count() == b.frame_count());
  const Eigen::RowVectorXd ra = a.values.row(0), rb = b.values.row(0);
  const BuiltBody ba = body::build_body_model(a.skeleton, BodySpec{}, &ra);
  const BuiltBody bb = body::build_body_model(b.skeleton, BodySpec{}, &rb);
  for (int f : {0, a.frame_count() / 2, a.frame_count() - 1}) {
    INFO("frame " << f);
    const Eigen::Vector3d ca = body::body_com(ba.body, a.values.row(f)),
                          cb = body::body_com(bb.body, b.values.row(f));
    CHECK((ca - cb).norm() < 1e-3);
  }
  for (const char* name : {"root", "lowerback", "lfemur", "rtibia", "lfoot", "ltoes", "head", "rwrist"}) {
    INFO(name);
    const auto& sa = ba.body.segments[static_cast<std::size_t>(joint(*a.skeleton, name))];
    const auto& sb = bb.body.segments[static_cast<std::size_t>(joint(*b.skeleton, name))];
    CHECK(sa.mass == Approx(sb.mass).epsilon(1e-5));  // the BVH rounds offsets to 6 digits
  }
}
