// Skeleton maps: chains found on every skeleton of ../shared/data agree with the presets in
// graphs/maps, stay the same when the skeleton is renamed, re-rooted or turned Z up, and map
// files are read, written and refused at their lines.
#include <catch2/catch.hpp>

#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "kg/base/atomic_file.hpp"
#include "kg/base/error.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/io/bvh.hpp"
#include "kg/io/import_options.hpp"
#include "kg/io/urdf.hpp"
#include "kg/retarget/skeleton_map.hpp"

namespace fs = std::filesystem;
using namespace kg;
using namespace kg::retarget;
using Catch::Matchers::Contains;
using motion::Skeleton;

namespace {

const fs::path kData = fs::path(KG_DATA_DIR);
const fs::path kMaps = fs::path(KG_SOURCE_DIR) / "graphs" / "maps";

struct Case {
  const char* file;    // under ../shared/data
  const char* preset;  // under graphs/maps
};
const Case kCases[] = {
    {"cmu/asf_amc/07.asf", "cmu_asf.yaml"},
    {"cmu/bvh_cmu_names/16_01.bvh", "cmu_bvh.yaml"},
    {"cmu/bvh_motionbuilder/16_15.bvh", "cmu_motionbuilder.yaml"},
    {"cmu/bvh_daz/07_05.bvh", "daz.yaml"},
    {"cmu/bvh_iclone_cc_rig/007_05.bvh", "iclone_cc.yaml"},
    {"other_skeletons/bandai_namco/dataset-1_dash_normal_001.bvh", "bandai_namco.yaml"},
    {"other_skeletons/games105/walk60.bvh", "games105.yaml"},
    {"robots/unitree_g1/g1_29dof.urdf", "unitree_g1.yaml"},
};

std::shared_ptr<const Skeleton> load(const fs::path& p) {
  const std::string ext = p.extension().string();
  if (ext == ".asf") return io::read_asf(p.string()).skeleton;
  if (ext == ".urdf") return io::read_urdf(p.string()).skeleton;
  return io::import_bvh(p, io::ImportOptions{}).motion.skeleton;
}

// The chains as "role=joint" lines, for comparing across skeletons and printing on failure.
std::string named(const SkeletonChains& c, const Skeleton& s) {
  std::map<std::string, std::string> m;
  auto n = [&](int j) { return j < 0 ? std::string("-") : s.joint(j).name; };
  auto list = [&](const std::vector<int>& v) {
    std::string out;
    for (int j : v) out += n(j) + " ";
    return out;
  };
  m["pelvis"] = n(c.pelvis);
  m["spine"] = list(c.spine);
  m["neck"] = list(c.neck);
  const char* sides[] = {"left", "right"};
  for (int k = 0; k < 2; ++k) {
    const Limb& l = c.legs[k];
    const Limb& a = c.arms[k];
    const std::string leg = std::string(sides[k]) + "_leg.", arm = std::string(sides[k]) + "_arm.";
    m[leg + "hip"] = n(l.upper), m[leg + "knee"] = n(l.middle), m[leg + "ankle"] = n(l.lower),
            m[leg + "toe"] = n(l.end);
    m[arm + "clavicle"] = n(a.root), m[arm + "shoulder"] = n(a.upper), m[arm + "elbow"] = n(a.middle);
    m[arm + "wrist"] = n(a.lower);
  }
  std::string out;
  for (const auto& [role, joint] : m) out += role + "=" + joint + "\n";
  return out;
}

bool have_data() {
  if (fs::exists(kData / kCases[0].file)) return true;
  WARN("skipped: " << (kData / kCases[0].file).string() << " not found (the data lives in ../shared/data)");
  return false;
}

// A copy of `s` whose joints are named j0, j1, ... (no names to go by).
std::shared_ptr<Skeleton> renamed(const Skeleton& s, const std::string& prefix = "j") {
  auto out = std::make_shared<Skeleton>();
  for (int j = 0; j < s.joint_count(); ++j) {
    motion::Joint joint = s.joint(j);
    joint.name = prefix + std::to_string(j);
    out->add_joint(joint);
  }
  out->file_to_world = s.file_to_world;
  return out;
}

}  // namespace

TEST_CASE("find_chains on every skeleton of ../shared/data gives its preset", "[skeleton_map][data]") {
  if (!have_data()) return;
  for (const Case& c : kCases) {
    INFO(c.file);
    const auto sk = load(kData / c.file);
    const SkeletonChains found = find_chains(*sk);
    const SkeletonChains preset =
        parse_chains_preset(read_input_file(kMaps / c.preset, "preset"), (kMaps / c.preset).string(), *sk);
    for (const std::string& n : found.notes) UNSCOPED_INFO(n);
    for (const std::string& m : found.missing) UNSCOPED_INFO("missing: " << m);
    CHECK(found.missing.empty());
    CHECK(named(found, *sk) == named(preset, *sk));
  }
}

TEST_CASE("auto-mapping any pair of the data's skeletons gives both presets' chains",
          "[skeleton_map][data]") {
  if (!have_data()) return;
  std::vector<std::shared_ptr<const Skeleton>> sks;
  std::vector<std::string> presets;
  for (const Case& c : kCases) {
    sks.push_back(load(kData / c.file));
    presets.push_back(
        named(parse_chains_preset(read_input_file(kMaps / c.preset, "preset"), c.preset, *sks.back()),
              *sks.back()));
  }
  for (std::size_t a = 0; a < sks.size(); ++a)
    for (std::size_t b = 0; b < sks.size(); ++b) {
      if (a == b) continue;
      INFO(kCases[a].file << " -> " << kCases[b].file);
      const ProposedMap p = propose_map(*sks[a], *sks[b]);
      CHECK(named(p.map.source.chains, *sks[a]) == presets[a]);
      CHECK(named(p.map.target.chains, *sks[b]) == presets[b]);
      // Every chain both have is matched; the G1 has no clavicles, Daz no toes: still matched.
      CHECK(p.matched.size() == 7);
      // The pairs the chains give, and the file written reads back to the same pairs.
      const std::vector<FeaturePair> pairs = feature_pairs(p.map);
      CHECK(pairs.size() >= 20);
      std::ostringstream os;
      write_skeleton_map(os, p.map, *sks[a], *sks[b]);
      const SkeletonMap back = parse_skeleton_map(os.str(), "proposed.yaml", *sks[a], *sks[b]);
      CHECK(named(back.source.chains, *sks[a]) == presets[a]);
      CHECK(named(back.target.chains, *sks[b]) == presets[b]);
      CHECK(feature_pairs(back).size() == pairs.size());
    }
}

TEST_CASE("chains do not change when a skeleton is turned Z up, re-rooted, or its units change",
          "[skeleton_map][data]") {
  if (!have_data()) return;
  for (const Case& c : kCases) {
    INFO(c.file);
    const auto sk = load(kData / c.file);
    const auto base = named(find_chains(*sk), *sk);
    // Z up: the same tree with file_to_world turned (a Z-up export of the same figure).
    auto z = std::make_shared<Skeleton>(*sk);
    z->file_to_world = io::z_up_to_y_up() * sk->file_to_world;
    CHECK(named(find_chains(*z), *z) == base);
    // Centimetres: every offset x100.
    auto cm = std::make_shared<Skeleton>(*sk);
    for (int j = 0; j < cm->joint_count(); ++j) {
      cm->joint_mut(j).offset *= 100;
      for (Eigen::Vector3d& e : cm->joint_mut(j).end_sites) e *= 100;
    }
    CHECK(named(find_chains(*cm), *cm) == base);
    // A static root above the old one (a scene node some exporters add).
    auto rooted = std::make_shared<Skeleton>();
    rooted->add_joint({.name = "SceneRoot", .parent = -1});
    for (int j = 0; j < sk->joint_count(); ++j) {
      motion::Joint joint = sk->joint(j);
      joint.parent = joint.parent < 0 ? 0 : joint.parent + 1;
      rooted->add_joint(joint);
    }
    rooted->file_to_world = sk->file_to_world;
    CHECK(named(find_chains(*rooted), *rooted) == base);
  }
}

TEST_CASE("chains of a renamed human skeleton come from its structure", "[skeleton_map][data]") {
  if (!have_data()) return;
  // Without names the middle joints come from segment lengths and the sides from the rest pose's
  // toes; the BVH humans of the data keep their knees, ankles and elbows (the G1's 1-DOF chains
  // and the Daz and iClone rigs' connector bones need names, see the header). The sides are
  // compared as a pair: 16_15's rest pose points its toes down and back, so the rest pose
  // cannot tell its left (the names can).
  for (const char* file : {"cmu/bvh_motionbuilder/16_15.bvh", "other_skeletons/games105/walk60.bvh",
                           "other_skeletons/bandai_namco/dataset-1_dash_normal_001.bvh"}) {
    INFO(file);
    const auto sk = load(kData / file);
    const auto anon = renamed(*sk);
    const SkeletonChains a = find_chains(*anon), b = find_chains(*sk);
    for (const std::string& n : a.notes) UNSCOPED_INFO(n);
    CHECK(a.pelvis == b.pelvis);
    CHECK(a.spine == b.spine);
    auto both = [](const std::array<Limb, 2>& limbs, int Limb::*role) {
      return std::set<int>{limbs[0].*role, limbs[1].*role};
    };
    for (int Limb::*role : {&Limb::middle, &Limb::lower}) {
      CHECK(both(a.legs, role) == both(b.legs, role));
      CHECK(both(a.arms, role) == both(b.arms, role));
    }
  }
}

TEST_CASE("a skeleton that is not a humanoid says what is missing", "[skeleton_map]") {
  Skeleton chain;
  chain.add_joint({.name = "a", .parent = -1});
  chain.add_joint({.name = "b", .parent = 0, .offset = {0, 1, 0}});
  chain.add_joint({.name = "c", .parent = 1, .offset = {0, 1, 0}});
  const SkeletonChains c = find_chains(chain);
  REQUIRE(c.missing.size() == 1);
  CHECK_THAT(c.missing[0], Contains("no pair of mirrored limbs"));
  const ProposedMap p = propose_map(chain, chain);
  CHECK(p.matched.empty());
}

namespace {

// A small humanoid (metres, Y up, facing +Z, left at +X), names the user chose.
std::shared_ptr<Skeleton> little_figure() {
  auto s = std::make_shared<Skeleton>();
  using motion::Channel;
  using K = motion::ChannelKind;
  const std::vector<Channel> rot = {{K::Zrotation}, {K::Xrotation}, {K::Yrotation}};
  std::vector<Channel> root = {{K::Xposition}, {K::Yposition}, {K::Zposition}};
  root.insert(root.end(), rot.begin(), rot.end());
  s->add_joint({.name = "pelvis", .parent = -1, .offset = {0, 1, 0}, .channels = root});
  for (int side = 0; side < 2; ++side) {
    const double x = side == 0 ? 0.1 : -0.1;
    const std::string p = side == 0 ? "L_" : "R_";
    const int hip =
        s->add_joint({.name = p + "thigh", .parent = 0, .offset = {x, -0.05, 0}, .channels = rot});
    const int knee =
        s->add_joint({.name = p + "knee", .parent = hip, .offset = {0, -0.45, 0}, .channels = rot});
    const int ankle =
        s->add_joint({.name = p + "ankle", .parent = knee, .offset = {0, -0.45, 0}, .channels = rot});
    s->add_joint({.name = p + "toe",
                  .parent = ankle,
                  .offset = {0, -0.05, 0.12},
                  .channels = rot,
                  .end_sites = {{0, 0, 0.05}}});
  }
  const int chest = s->add_joint({.name = "chest", .parent = 0, .offset = {0, 0.4, 0}, .channels = rot});
  for (int side = 0; side < 2; ++side) {
    const double x = side == 0 ? 1 : -1;
    const std::string p = side == 0 ? "L_" : "R_";
    const int sh = s->add_joint(
        {.name = p + "upperarm", .parent = chest, .offset = {0.18 * x, 0.1, 0}, .channels = rot});
    const int el =
        s->add_joint({.name = p + "elbow", .parent = sh, .offset = {0.3 * x, 0, 0}, .channels = rot});
    s->add_joint({.name = p + "hand",
                  .parent = el,
                  .offset = {0.26 * x, 0, 0},
                  .channels = rot,
                  .end_sites = {{0.08 * x, 0, 0}}});
  }
  s->add_joint(
      {.name = "head", .parent = chest, .offset = {0, 0.2, 0}, .channels = rot, .end_sites = {{0, 0.2, 0}}});
  return s;
}

std::string map_error(const std::string& text, const Skeleton& s, const Skeleton& t) {
  try {
    parse_skeleton_map(text, "m.yaml", s, t);
  } catch (const kg::Error& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST_CASE("a skeleton map file is read with its pairs and changes", "[skeleton_map]") {
  const auto s = little_figure();
  const auto t = renamed(*s, "k");  // same structure, other names
  const SkeletonMap m = parse_skeleton_map(R"(version: 1
source:
  file: little.bvh
  chains:
    pelvis: pelvis
    left_leg: {hip: L_thigh, knee: L_knee, ankle: L_ankle, toe: L_toe}
target:
  chains:
    pelvis: k0
    left_leg: {hip: k1, knee: k2, ankle: k3}
pairs:
  - {name: left_leg.ankle, weight: 10}
  - {name: heel, kind: position, source: {joint: L_ankle, offset: [0, -0.05, -0.04]}, target: k3, hard: true}
  - {kind: direction, source: {from: L_knee, to: L_toe}, target: {from: k2, to: k4}, weight: 0.5}
)",
                                           "m.yaml", *s, *t);
  CHECK(m.source.file == "little.bvh");
  const std::vector<FeaturePair> pairs = feature_pairs(m);
  std::map<std::string, const FeaturePair*> by_name;
  for (const FeaturePair& p : pairs) by_name[p.name] = &p;
  REQUIRE(by_name.count("left_leg.ankle"));
  CHECK(by_name["left_leg.ankle"]->weight == 10);
  CHECK(by_name.count("left_leg.toe") == 0);  // the target names no toe
  CHECK(by_name.count("left_leg.knee") == 1);
  CHECK(by_name.count("right_leg.knee") == 0);
  REQUIRE(by_name.count("heel"));
  CHECK(by_name["heel"]->hard);
  CHECK(by_name["heel"]->source.point.local.isApprox(Eigen::Vector3d(0, -0.05, -0.04)));
  REQUIRE(by_name.count("direction L_knee -> k2"));
  CHECK(by_name["direction L_knee -> k2"]->target.to.joint == 4);
  // Written and read back: the same pairs.
  std::ostringstream os;
  write_skeleton_map(os, m, *s, *t);
  INFO(os.str());
  const std::vector<FeaturePair> again = feature_pairs(parse_skeleton_map(os.str(), "again.yaml", *s, *t));
  REQUIRE(again.size() == pairs.size());
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    CHECK(again[i].name == pairs[i].name);
    CHECK(again[i].weight == pairs[i].weight);
    CHECK(again[i].hard == pairs[i].hard);
    CHECK(again[i].source.point.local == pairs[i].source.point.local);
  }
}

TEST_CASE("a bad skeleton map is refused at its line, naming the nearest joint", "[skeleton_map]") {
  const auto s = little_figure();
  const auto& t = *s;
  const std::string head = "version: 1\nsource: {chains: {pelvis: pelvis}}\n";
  CHECK_THAT(
      map_error(head + "target:\n  chains:\n    left_leg: {hip: L_thigh, knee: L_kne, ankle: L_ankle}\n", *s,
                t),
      Contains("m.yaml:5:") && Contains("no joint 'L_kne'") && Contains("nearest: 'L_knee'"));
  CHECK_THAT(map_error(head + "target:\n  chains:\n    left_leg: {hip: L_thigh, ankle: L_ankle}\n", *s, t),
             Contains("m.yaml:5:") && Contains("missing 'knee'"));
  CHECK_THAT(map_error(head + "target:\n  chains:\n    tail: [pelvis]\n", *s, t),
             Contains("m.yaml:5:") && Contains("tail"));
  CHECK_THAT(
      map_error(
          head + "target: {chains: {pelvis: pelvis}}\npairs:\n  - {kind: pose, source: head, target: head}\n",
          *s, t),
      Contains("m.yaml:5:") && Contains("unknown kind 'pose'"));
  CHECK_THAT(
      map_error(head + "target: {chains: {pelvis: pelvis}}\npairs:\n  - {name: pelvis.positon, weight: 2}\n",
                *s, t),
      Contains("m.yaml:5:") && Contains("did you mean 'pelvis.position'"));
  CHECK_THAT(
      map_error(head +
                    "target: {chains: {pelvis: pelvis}}\npairs:\n  - {kind: position, source: head, target: "
                    "head, weight: -1}\n",
                *s, t),
      Contains("m.yaml:5:") && Contains("weight"));
  CHECK_THAT(
      map_error(head +
                    "target: {chains: {pelvis: pelvis}}\npairs:\n  - {kind: direction, source: head, target: "
                    "head}\n",
                *s, t),
      Contains("m.yaml:5:") && Contains("{from: POINT, to: POINT}"));
  CHECK_THAT(map_error("version: 1\ntarget: {chains: {}}\n", *s, t), Contains("missing 'source'"));
  CHECK_THAT(map_error("version: 2\nsource: {}\ntarget: {}\n", *s, t), Contains("version"));
  CHECK_THAT(
      map_error(head +
                    "target: {chains: {pelvis: pelvis}}\npairs:\n  - {kind: position, source: head, target: "
                    "{joint: head, offset: [0, 1]}}\n",
                *s, t),
      Contains("m.yaml:5:") && Contains("[x, y, z]"));
}

TEST_CASE("rest offsets make a T-pose and an A-pose agree and follow a turned frame", "[skeleton_map]") {
  const auto s = little_figure();
  // The target: the same figure with the arms hanging 45 degrees down (an A-pose) and turned
  // to face +X in its file (file_to_world turns it back), so its frames point elsewhere.
  auto t = std::make_shared<Skeleton>(*s);
  const Eigen::AngleAxisd down(-M_PI / 4, Eigen::Vector3d::UnitZ());
  for (int j = 0; j < t->joint_count(); ++j) {
    const std::string& n = t->joint(j).name;
    if (n == "L_elbow" || n == "L_hand") t->joint_mut(j).offset = down * t->joint(j).offset;
  }
  const SkeletonMap m = propose_map(*s, *t).map;
  SkeletonMap with_pair = m;
  FeaturePair upper;
  upper.name = "upper";
  upper.kind = FeatureKind::Orientation;
  upper.source.point.joint = s->find_joint("L_upperarm");
  upper.target.point.joint = t->find_joint("L_upperarm");
  with_pair.pairs.push_back(upper);
  const std::vector<FeaturePair> pairs = feature_pairs(with_pair);
  const std::vector<Eigen::Matrix3d> r = rest_offsets(with_pair, pairs, *s, *t);
  REQUIRE(r.size() == pairs.size());
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    INFO(pairs[i].name);
    if (pairs[i].name == "upper") {
      // The target's arm points 45 degrees below the source's: R takes the target's rest arm
      // direction onto the source's.
      const Eigen::Vector3d target_arm = (down * Eigen::Vector3d::UnitX());
      CHECK((r[i] * target_arm).isApprox(Eigen::Vector3d::UnitX(), 1e-9));
    } else {
      CHECK(r[i].isApprox(Eigen::Matrix3d::Identity(), 1e-12));
    }
  }
  // A target whose file is turned 90 degrees about up: every trunk offset is that turn.
  auto turned = std::make_shared<Skeleton>(*s);
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  for (int j = 0; j < turned->joint_count(); ++j) {
    turned->joint_mut(j).offset = turn.transpose() * turned->joint(j).offset;
    for (Eigen::Vector3d& e : turned->joint_mut(j).end_sites) e = turn.transpose() * e;
  }
  turned->file_to_world = turn;
  const SkeletonMap mt = propose_map(*s, *turned).map;
  const std::vector<FeaturePair> pt = feature_pairs(mt);
  const std::vector<Eigen::Matrix3d> rt = rest_offsets(mt, pt, *s, *turned);
  for (std::size_t i = 0; i < pt.size(); ++i)
    if (pt[i].kind == FeatureKind::Orientation) {
      INFO(pt[i].name);
      // target_world = source_world * R; at rest source_world = I, target_world = turn.
      CHECK(rt[i].isApprox(turn, 1e-9));
    }
}
