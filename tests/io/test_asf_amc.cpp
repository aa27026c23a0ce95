// ASF/AMC reader: the CMU files in ../shared/data, the mapping onto skeleton.hpp checked against
// an independent mocapPlayer-style forward kinematics and against MotionBuilder's BVH conversion
// of the same take, the nodes, and a table of malformed inputs plus truncations of real files.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "../support/node_context.hpp"
#include "../support/temp_dir.hpp"
#include "kg/base/error.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/io/bvh.hpp"
#include "kg/io/nodes.hpp"
#include "kg/motion/kinematics.hpp"
#include "test_asf_amc_data.hpp"

namespace fs = std::filesystem;
using kg::Error;
using kg::io::AsfSkeleton;
using kg::motion::ChannelKind;
using kg::motion::Motion;
using kg::test::NodeContext;
using kg::test::params_for;
using kg::test::read_file;
using kg::test::run_node;

namespace {

const fs::path kData = fs::path(KG_DATA_DIR) / "cmu";
const fs::path kAsfDir = kData / "asf_amc";
constexpr double kAsfMetres = 0.0254 / 0.45;  // CMU's FAQ: (1 / 0.45) * 2.54 / 100
constexpr double kDeg = std::numbers::pi / 180.0;

bool have(const std::vector<fs::path>& files) {
  for (const fs::path& f : files) {
    if (!fs::exists(f)) {
      WARN("skipped: " << f.string() << " not found (real mocap data lives in ../shared/data)");
      return false;
    }
  }
  return true;
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

// A small valid pair (test_asf_amc_data.hpp), the base of the malformed-input table.
const std::string& kAsf = kg::test::kTinyAsf;
const std::string& kAmc = kg::test::kTinyAmc;

// Line and message of the Error `f` throws; fails the test if it throws anything else.
template <class F>
std::pair<int, std::string> error_of(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return {e.where().line, e.what()};
  }
  FAIL("no kg::Error thrown");
  return {};
}

// mocapPlayer's reading of ASF/AMC, written independently of the reader from the format's
// description: each bone has a local frame C (its axis, world-aligned at rest); a child's frame
// is its parent's frame moved by the parent's direction * length expressed in the parent's local
// frame, then rotated by C_parent^-1 C_child, then by the AMC rotation Rz Ry Rx.
struct RefBone {
  std::string name;
  std::string parent;
  Eigen::Vector3d dir = Eigen::Vector3d::Zero();
  double length = 0;
  Eigen::Matrix3d C = Eigen::Matrix3d::Identity();
  std::vector<std::string> dofs;
};

Eigen::Matrix3d rot(int axis, double deg) {
  return Eigen::AngleAxisd(deg * kDeg, Eigen::Vector3d::Unit(axis)).toRotationMatrix();
}

std::map<std::string, RefBone> reference_asf(const std::string& text) {
  std::map<std::string, RefBone> bones;
  bones["root"].name = "root";
  std::istringstream in(text);
  std::string line;
  RefBone cur;
  bool in_hierarchy = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string key;
    if (!(ls >> key)) continue;
    if (key == ":hierarchy") in_hierarchy = true;
    if (in_hierarchy) {
      if (key == "begin" || key == "end" || key == ":hierarchy") continue;
      std::string child;
      while (ls >> child) bones[child].parent = key;
      continue;
    }
    if (key == "name") ls >> cur.name;
    if (key == "direction") ls >> cur.dir.x() >> cur.dir.y() >> cur.dir.z();
    if (key == "length") ls >> cur.length;
    if (key == "axis" && !cur.name.empty()) {
      double x, y, z;
      ls >> x >> y >> z;
      cur.C = rot(2, z) * rot(1, y) * rot(0, x);  // every axis of the CMU files is XYZ
    }
    if (key == "dof") {
      std::string d;
      while (ls >> d) cur.dofs.push_back(d);
    }
    if (key == "end" && !cur.name.empty()) {
      bones[cur.name] = cur;
      cur = RefBone{};
    }
  }
  return bones;
}

// World positions (file units) of every bone's joint for every frame of an AMC text.
std::vector<std::map<std::string, Eigen::Vector3d>> reference_positions(const std::string& asf_text,
                                                                        const std::string& amc_text) {
  const auto bones = reference_asf(asf_text);
  std::vector<std::map<std::string, std::vector<double>>> frames;
  std::istringstream in(amc_text);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#' || line[0] == ':') continue;
    std::istringstream ls(line);
    std::string name;
    ls >> name;
    if (std::isdigit(static_cast<unsigned char>(name[0]))) {
      frames.emplace_back();
      continue;
    }
    double v;
    auto& vals = frames.back()[name];
    while (ls >> v) vals.push_back(v);
  }
  std::vector<std::map<std::string, Eigen::Vector3d>> out;
  for (const auto& frame : frames) {
    std::map<std::string, Eigen::Isometry3d> M;
    std::map<std::string, Eigen::Vector3d> pos;
    // Root: TX TY TZ RX RY RZ, drawn as translate, then rotate z, y, x.
    const auto& r = frame.at("root");
    Eigen::Isometry3d root = Eigen::Isometry3d::Identity();
    root.translate(Eigen::Vector3d(r[0], r[1], r[2]));
    root.rotate(rot(2, r[5]) * rot(1, r[4]) * rot(0, r[3]));
    M["root"] = root;
    pos["root"] = root.translation();
    // Parents before children: repeat until every bone is placed.
    while (M.size() < bones.size()) {
      for (const auto& [name, b] : bones) {
        if (M.count(name) || !M.count(b.parent)) continue;
        const RefBone& p = bones.at(b.parent);
        Eigen::Isometry3d m = M[b.parent];
        m.translate(p.C.transpose() * p.dir * p.length);
        m.rotate(p.C.transpose() * b.C);
        double rx = 0, ry = 0, rz = 0;
        if (!b.dofs.empty()) {
          const auto& v = frame.at(name);
          for (std::size_t i = 0; i < b.dofs.size(); ++i) {
            if (b.dofs[i] == "rx") rx = v[i];
            if (b.dofs[i] == "ry") ry = v[i];
            if (b.dofs[i] == "rz") rz = v[i];
          }
        }
        m.rotate(rot(2, rz) * rot(1, ry) * rot(0, rx));
        M[name] = m;
        pos[name] = m.translation();
      }
    }
    out.push_back(std::move(pos));
  }
  return out;
}

// The ASF/AMC nodes and the motion formats io.import_motion picks from.
const kg::graph::Registry& io_registry() {
  static const kg::graph::Registry registry = [] {
    kg::graph::Registry r = kg::test::registry_of(kg::asf_amc_node_types());
    for (kg::graph::Extension& format : kg::io::builtin_motion_format_extensions())
      r.add_extension(std::move(format));
    return r;
  }();
  return registry;
}

const kg::graph::NodeType& node_type(const std::string& name) {
  return kg::test::node_type(io_registry(), name);
}

bool contains(const std::vector<std::string>& lines, const std::string& part) {
  for (const auto& l : lines)
    if (l.find(part) != std::string::npos) return true;
  return false;
}

}  // namespace

TEST_CASE("asf: the tiny figure maps onto skeleton.hpp's conventions", "[io][asf]") {
  const AsfSkeleton asf = kg::io::parse_asf(kAsf, "tiny.asf");
  const auto& s = *asf.skeleton;
  CHECK(asf.version == "1.10");
  CHECK(asf.name == "tiny");
  CHECK(asf.documentation == "two bones");
  REQUIRE(asf.length_unit.has_value());
  CHECK(*asf.declared_metres_per_unit() == Approx(kAsfMetres));
  REQUIRE(s.joint_count() == 3);
  CHECK(s.channel_count() == 6 + 3 + 1);

  const auto& root = s.joint(0);
  CHECK(root.name == "root");
  // RX RY RZ apply x first, so they compose as Z, Y, X.
  REQUIRE(root.channels.size() == 6);
  CHECK(root.channels[0].kind == ChannelKind::Xposition);
  CHECK(root.channels[2].kind == ChannelKind::Zposition);
  CHECK(root.channels[3].kind == ChannelKind::Zrotation);
  CHECK(root.channels[4].kind == ChannelKind::Yrotation);
  CHECK(root.channels[5].kind == ChannelKind::Xrotation);
  CHECK(std::isinf(root.channels[3].min));

  const auto& femur = s.joint(s.find_joint("lfemur"));
  CHECK(femur.offset.isZero());  // children of the root start at the root position
  CHECK(femur.axis.isApprox(Eigen::AngleAxisd(20 * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix()));
  REQUIRE(femur.channels.size() == 3);
  CHECK(femur.channels[0].kind == ChannelKind::Zrotation);
  CHECK(femur.channels[0].min == Approx(-60 * kDeg));
  CHECK(femur.channels[0].max == Approx(70 * kDeg));
  CHECK(femur.channels[1].kind == ChannelKind::Yrotation);
  CHECK(femur.channels[1].min == Approx(-70 * kDeg));
  CHECK(femur.channels[2].kind == ChannelKind::Xrotation);
  CHECK(femur.channels[2].min == Approx(-160 * kDeg));
  CHECK(femur.channels[2].max == Approx(20 * kDeg));
  CHECK(femur.end_sites.empty());

  const auto& tibia = s.joint(s.find_joint("ltibia"));
  CHECK(tibia.offset.isApprox(Eigen::Vector3d(0, -7, 0)));  // the parent's direction * length
  REQUIRE(tibia.end_sites.size() == 1);                     // a leaf: its own tip
  CHECK(tibia.end_sites[0].isApprox(Eigen::Vector3d(0, -7, 0)));

  // AMC values land permuted: lfemur "rx ry rz" = 11 0 0 goes to its Xrotation channel.
  const Motion m = kg::io::parse_amc(kAmc, "tiny.amc", asf);
  REQUIRE(m.frame_count() == 2);
  CHECK(m.fps == 120.0);
  CHECK(m.name == "tiny");
  CHECK(m.values(1, femur.first_channel + 2) == Approx(11 * kDeg));
  CHECK(m.values(1, femur.first_channel + 0) == 0.0);
  CHECK(m.values(1, 3) == Approx(3 * kDeg));  // root Zrotation <- RZ, the 6th value
  CHECK(m.values(1, 5) == Approx(1 * kDeg));  // root Xrotation <- RX
  CHECK(m.values(1, 1) == 17.0);
  CHECK(m.values(1, tibia.first_channel) == Approx(21 * kDeg));
  CHECK_NOTHROW(m.check());
}

TEST_CASE("asf: CRLF, tabs, radians and dofs in another order read the same", "[io][asf]") {
  const AsfSkeleton a = kg::io::parse_asf(kAsf, "tiny.asf");
  const Motion ma = kg::io::parse_amc(kAmc, "tiny.amc", a);

  std::string crlf;
  for (char c : kAsf) {
    if (c == '\n') crlf += '\r';
    crlf += c == ' ' ? '\t' : c;
  }
  const AsfSkeleton b = kg::io::parse_asf(crlf, "tiny_crlf.asf");
  const Motion mb = kg::io::parse_amc(replaced(kAmc, "lfemur 10 0 0\n", "lfemur\t10\t0\t0\r\n"), "t.amc", b);
  CHECK(ma.values.isApprox(mb.values));

  // Radians in the ASF (limits and axis) and in the AMC.
  std::string rad = replaced(kAsf, "angle deg", "angle rad");
  rad = replaced(rad, "(-160.0 20.0)", "(-inf 0.5)");
  const AsfSkeleton c = kg::io::parse_asf(rad, "rad.asf");
  const auto& femur = c.skeleton->joint(c.skeleton->find_joint("lfemur"));
  CHECK(std::isinf(femur.channels[2].min));
  CHECK(femur.channels[2].max == 0.5);
  CHECK(femur.axis.isApprox(Eigen::AngleAxisd(20.0, Eigen::Vector3d::UnitZ()).toRotationMatrix()));
  const Motion mc = kg::io::parse_amc(replaced(kAmc, ":DEGREES", ":RADIANS"), "r.amc", c);
  CHECK(mc.values(1, femur.first_channel + 2) == 11.0);

  // `dof rz rx`: R = Rx Rz, channels [X, Z], AMC values in file order.
  const AsfSkeleton d =
      kg::io::parse_asf(replaced(kAsf, "dof rx ry rz\n    limits (-160.0 20.0)\n           (-70.0 70.0)\n",
                                 "dof rz rx\n    limits (-160.0 20.0)\n"),
                        "order.asf");
  const auto& f2 = d.skeleton->joint(d.skeleton->find_joint("lfemur"));
  REQUIRE(f2.channels.size() == 2);
  CHECK(f2.channels[0].kind == ChannelKind::Xrotation);
  CHECK(f2.channels[0].max == Approx(70 * kDeg));  // the second pair belongs to rx
  CHECK(f2.channels[1].kind == ChannelKind::Zrotation);
  CHECK(f2.channels[1].min == Approx(-160 * kDeg));
  const Motion md = kg::io::parse_amc(
      replaced(replaced(kAmc, "lfemur 10 0 0", "lfemur 5 6"), "lfemur 11 0 0", "lfemur 7 8"), "o.amc", d);
  CHECK(md.values(0, f2.first_channel + 0) == Approx(6 * kDeg));  // rx
  CHECK(md.values(0, f2.first_channel + 1) == Approx(5 * kDeg));  // rz
}

TEST_CASE("asf: translation dofs move a bone by C t from its rest offset", "[io][asf]") {
  const std::string text =
      replaced(replaced(kAsf, "    dof rx\n    limits (-10.0 170.0)\n", "    dof tx ty rx\n"),
               "axis 0 0 20 XYZ\n    dof tx", "axis 0 0 90 XYZ\n    dof tx");
  const AsfSkeleton asf = kg::io::parse_asf(text, "t.asf");
  const auto& s = *asf.skeleton;
  const int tib = s.find_joint("ltibia");
  const auto& j = s.joint(tib);
  REQUIRE(j.channels.size() == 4);
  CHECK(j.channels[0].kind == ChannelKind::Xposition);
  CHECK(j.channels[2].kind == ChannelKind::Zposition);
  CHECK(j.channels[3].kind == ChannelKind::Xrotation);
  const Motion m = kg::io::parse_amc(
      replaced(replaced(kAmc, "ltibia 20\n", "ltibia 1 2 0\n"), "ltibia 21\n", "ltibia 1 2 0\n"), "t.amc",
      asf);
  // C = Rz(90): t = (1, 2, 0) in the bone's axis frame is (-2, 1, 0) in the rest frame.
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(s.joint_count()));
  kg::motion::forward_kinematics(s, m.values.row(0), world);
  const Eigen::Vector3d knee_rest =
      world[static_cast<std::size_t>(s.find_joint("lfemur"))] * Eigen::Vector3d(0, -7, 0);
  const Eigen::Vector3d moved = world[static_cast<std::size_t>(tib)].translation();
  const Eigen::Matrix3d femur_rot = world[static_cast<std::size_t>(s.find_joint("lfemur"))].linear();
  CHECK((femur_rot.transpose() * (moved - knee_rest)).isApprox(Eigen::Vector3d(-2, 1, 0), 1e-12));
}

TEST_CASE("asf/amc: the three CMU pairs load", "[io][asf][data]") {
  struct Pair {
    const char* asf;
    const char* amc;
    int frames;
  };
  for (const Pair& p : {Pair{"16.asf", "16_15.amc", 471}, Pair{"07.asf", "07_05.amc", 517},
                        Pair{"09.asf", "09_06.amc", 141}}) {
    if (!have({kAsfDir / p.asf, kAsfDir / p.amc})) return;
    INFO(p.amc);
    const AsfSkeleton asf = kg::io::read_asf((kAsfDir / p.asf).string());
    const auto& s = *asf.skeleton;
    CHECK(s.joint_count() == 31);  // 30 bones + root
    CHECK(asf.bones.size() == 31);
    int moving = 0;
    for (const auto& b : asf.bones) moving += b.dofs.empty() ? 0 : 1;
    CHECK(moving == 29);  // the hip joints have no dofs
    CHECK(s.channel_count() == 62);
    CHECK(asf.declared_metres_per_unit().value() == Approx(kAsfMetres).epsilon(1e-12));
    CHECK(asf.notes.empty());

    // 29 bone lines per frame, counted in the text independently of the reader.
    const std::string text = read_file(kAsfDir / p.amc);
    std::istringstream in(text);
    std::string line;
    int frame_lines = 0, bone_lines = 0;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#' || line[0] == ':') continue;
      if (std::isdigit(static_cast<unsigned char>(line[0]))) {
        ++frame_lines;
      } else {
        ++bone_lines;
      }
    }
    CHECK(frame_lines == p.frames);
    CHECK(bone_lines == 29 * p.frames);

    const Motion m = kg::io::read_amc((kAsfDir / p.amc).string(), asf);
    CHECK(m.frame_count() == p.frames);
    CHECK(m.fps == 120.0);
    CHECK_NOTHROW(m.check());

    // Joint limits: every rotation channel of a bone is limited, the root's are not.
    for (int j = 1; j < s.joint_count(); ++j)
      for (const auto& c : s.joint(j).channels) CHECK((std::isfinite(c.min) && std::isfinite(c.max)));
    const auto& femur = s.joint(s.find_joint("rfemur"));
    CHECK(femur.channels[2].kind == ChannelKind::Xrotation);
    CHECK(femur.channels[2].min == Approx(-160 * kDeg));
    CHECK(femur.channels[0].kind == ChannelKind::Zrotation);
    CHECK(femur.channels[0].max == Approx(60 * kDeg));
    for (const char* leaf : {"ltoes", "rtoes", "head", "lfingers", "rthumb"})
      CHECK(s.joint(s.find_joint(leaf)).end_sites.size() == 1);
  }
}

TEST_CASE("asf/amc: forward kinematics equals an independent mocapPlayer-style evaluation",
          "[io][asf][data]") {
  for (const char* stem : {"16_15", "09_06"}) {
    const std::string subject = std::string(stem).substr(0, 2);
    const fs::path asf_path = kAsfDir / (subject + ".asf"), amc_path = kAsfDir / (std::string(stem) + ".amc");
    if (!have({asf_path, amc_path})) return;
    const std::string asf_text = read_file(asf_path), amc_text = read_file(amc_path);
    const AsfSkeleton asf = kg::io::parse_asf(asf_text, asf_path.string());
    const Motion m = kg::io::parse_amc(amc_text, amc_path.string(), asf);
    const Eigen::MatrixXd ours = kg::motion::joint_world_positions(m);  // file units (raw read)
    const auto ref = reference_positions(asf_text, amc_text);
    REQUIRE(static_cast<int>(ref.size()) == m.frame_count());
    double worst = 0;
    for (int f = 0; f < m.frame_count(); ++f) {
      for (int j = 0; j < m.skeleton->joint_count(); ++j) {
        const Eigen::Vector3d a = ours.row(f).segment<3>(3 * j).transpose();
        const Eigen::Vector3d b = ref[static_cast<std::size_t>(f)].at(m.skeleton->joint(j).name);
        worst = std::max(worst, (a - b).norm());
      }
    }
    INFO(stem << ": worst joint distance " << worst << " file units");
    CHECK(worst < 1e-9);
  }
}

// The cross-check. MotionBuilder 7.5 converted 16_15 to BVH in cm with its own rest pose
// (straight legs, other bone axes, ZXY channels) and without the zero-dof hip connectors, so
// what can agree are the world positions of the joint ORIGINS of the 29 bones both files have.
//
// Conversion applied: the ASF side goes to metres by its :units (length 0.45: 0.0254 / 0.45 m
// per unit, CMU's FAQ formula), the BVH side by units cm. Both files are +Y up and share the
// world axes and origin (the BVH's root translation is the AMC's times 0.0254 / 0.45 * 100), so
// no rotation or translation aligns them: none is applied.
//
// What the data shows: MotionBuilder kept the AMC's values only on its own 30 Hz keys (frames 0,
// 4, 8, ...) and interpolated the three 120 Hz frames between them. On the keys every joint
// agrees to print precision (worst 0.006 mm; the BVH prints 6 significant digits, 0.01 mm at a
// metre). Between keys, joints below bones without an ASF axis still agree (worst 0.024 mm: the
// trunk, hips and shoulders), while joints below a bone with an axis (femur, humerus, ...) move
// off by up to 20 mm from frame 8 on, and by 423 mm on frames 1-3, where the AMC's left arm jumps
// from a "0 0 0" placeholder to the captured pose and MotionBuilder's curve sweeps across.
// A wrong convention (Euler order of the dofs, sign or side of the axis) puts the knee alone
// 23 to 78 mm off on the keys, so the key check below separates right from wrong by 3 orders.
TEST_CASE("asf/amc 16_15 and MotionBuilder's 16_15.bvh give the same joint trajectories", "[io][asf][data]") {
  const fs::path asf = kAsfDir / "16.asf", amc = kAsfDir / "16_15.amc",
                 bvh = kData / "bvh_motionbuilder" / "16_15.bvh";
  if (!have({asf, amc, bvh})) return;
  const auto ours = kg::io::import_asf_amc(asf.string(), amc.string(),
                                           {.units = "auto", .up = "y", .fps = 0, .trim = "none"});
  const auto theirs = kg::io::import_bvh(bvh, {.units = "cm", .up = "y", .fps = 0, .trim = "none"});
  const Motion& a = ours.motion;
  const Motion& b = theirs.motion;
  REQUIRE(a.frame_count() == 471);
  REQUIRE(b.frame_count() == 471);
  CHECK(a.fps == Approx(b.fps).epsilon(1e-5));
  CHECK(a.skeleton->source_unit_metres == Approx(kAsfMetres));
  const auto& sa = *a.skeleton;

  // Joints whose every ancestor has an identity ASF axis: MotionBuilder's in-between frames are
  // exact for them too.
  auto plain_chain = [&](int j) {
    for (int p = sa.joint(j).parent; p >= 0; p = sa.joint(p).parent)
      if (!sa.joint(p).axis.isIdentity(1e-12)) return false;
    return true;
  };

  const Eigen::MatrixXd pa = kg::motion::joint_world_positions(a);
  const Eigen::MatrixXd pb = kg::motion::joint_world_positions(b);
  std::vector<std::string> matched, unmatched, plain;
  double worst_key = 0, worst_plain = 0, worst_between = 0;
  std::string worst_key_joint;
  for (int ja = 0; ja < sa.joint_count(); ++ja) {
    const std::string& name = sa.joint(ja).name;
    const int jb = b.skeleton->find_joint(name);
    if (jb < 0) {
      unmatched.push_back(name);
      continue;
    }
    matched.push_back(name);
    if (plain_chain(ja)) plain.push_back(name);
    for (int f = 0; f < a.frame_count(); ++f) {
      const double d = (pa.row(f).segment<3>(3 * ja) - pb.row(f).segment<3>(3 * jb)).norm();
      if (f % 4 == 0 && d > worst_key) worst_key = d, worst_key_joint = name;
      if (plain_chain(ja)) worst_plain = std::max(worst_plain, d);
      if (f % 4 != 0 && f >= 8) worst_between = std::max(worst_between, d);
    }
  }
  // MotionBuilder dropped exactly the two zero-dof hip connectors.
  CHECK(unmatched == std::vector<std::string>{"lhipjoint", "rhipjoint"});
  CHECK(matched.size() == 29);
  for (const char* must : {"root", "lfemur", "ltibia", "lfoot", "ltoes", "rfemur", "rtibia", "rfoot", "rtoes",
                           "head", "lwrist", "rwrist", "lfingers", "rthumb"})
    CHECK(std::find(matched.begin(), matched.end(), must) != matched.end());
  CHECK(plain.size() == 13);  // root, lfemur, rfemur, the spine, neck, head, clavicles, humeri

  INFO("on 30 Hz keys: worst " << worst_key * 1000 << " mm (" << worst_key_joint << "); every frame, "
                               << plain.size() << " plain-chain joints: worst " << worst_plain * 1000
                               << " mm; between keys from frame 8: worst " << worst_between * 1000 << " mm");
  CHECK(worst_key < 0.05e-3);    // 0.05 mm, every joint, frames 0, 4, ..., 468
  CHECK(worst_plain < 0.05e-3);  // 0.05 mm, every frame
  CHECK(worst_between < 25e-3);  // MotionBuilder's interpolation, not ours
  CHECK(worst_between > 5e-3);   // ... which really is there: the keys are the test
}

TEST_CASE("asf/amc vs the Daz BVHs: frame counts and durations agree", "[io][asf][data]") {
  struct Pair {
    const char* subject;
    const char* stem;
    int amc_frames;
  };
  for (const Pair& p : {Pair{"07", "07_05", 517}, Pair{"09", "09_06", 141}}) {
    const fs::path asf = kAsfDir / (std::string(p.subject) + ".asf"),
                   amc = kAsfDir / (std::string(p.stem) + ".amc"),
                   bvh = kData / "bvh_daz" / (std::string(p.stem) + ".bvh");
    if (!have({asf, amc, bvh})) return;
    INFO(p.stem);
    const auto a = kg::io::import_asf_amc(asf.string(), amc.string(), {.trim = "none"});
    const auto b = kg::io::import_bvh(bvh, {.trim = "none"});
    CHECK(a.motion.frame_count() == p.amc_frames);
    // cgspeed's Daz files prepend one synthetic T-pose frame.
    CHECK(b.motion.frame_count() == p.amc_frames + 1);
    // Without it, the same span of time at the same rate.
    const double daz_duration = (b.motion.frame_count() - 2) / b.motion.fps;
    CHECK(a.motion.duration() == Approx(daz_duration).margin(0.5 / 120));
    CHECK(a.motion.fps == Approx(b.motion.fps).epsilon(1e-5));
    // trim auto drops that frame, and the curve MotionBuilder drew out of it (frames 1..4).
    const auto trimmed = kg::io::import_bvh(bvh, {});
    CHECK(trimmed.motion.frame_count() == p.amc_frames + 1 - 5);
  }
}

TEST_CASE("asf/amc import: units, fps and notes", "[io][asf][data]") {
  const fs::path asf = kAsfDir / "16.asf", amc = kAsfDir / "16_15.amc";
  if (!have({asf, amc})) return;
  const auto def = kg::io::import_asf_amc(asf.string(), amc.string(), {.trim = "none"});
  CHECK(def.motion.fps == 120.0);
  CHECK(contains(def.notes, "no frame rate"));
  CHECK(contains(def.notes, "declares asf"));
  CHECK(def.motion.skeleton->rest_height() > 1.4);
  CHECK(def.motion.skeleton->rest_height() < 2.0);
  // rfemur length 7.12424 is 40.21 cm (MotionBuilder's offset: 40.2124).
  const auto& s = *def.motion.skeleton;
  CHECK(s.joint(s.find_joint("rtibia")).offset.norm() == Approx(0.402124).epsilon(1e-5));

  const auto cm = kg::io::import_asf_amc(asf.string(), amc.string(),
                                         {.units = "cm", .up = "y", .fps = 30, .trim = "none"});
  CHECK(cm.motion.fps == 30.0);
  CHECK_FALSE(contains(cm.notes, "no frame rate"));
  CHECK(cm.motion.skeleton->source_unit_metres == 0.01);
  CHECK(cm.motion.values(0, 1) == Approx(17.2598 * 0.01));
  CHECK(def.motion.values(0, 1) == Approx(17.2598 * kAsfMetres));
  // Angles are not touched by units.
  CHECK(cm.motion.values(0, 3) == Approx(def.motion.values(0, 3)));
}

TEST_CASE("asf alone: import_motion reads its rest pose as one frame in metres", "[io][asf][data]") {
  const fs::path asf = kAsfDir / "16.asf", amc = kAsfDir / "16_15.amc";
  if (!have({asf, amc})) return;
  const auto rest = kg::io::import_motion(asf.string(), "", {});
  const auto clip = kg::io::import_asf_amc(asf.string(), amc.string(), {.trim = "none"});
  CHECK(rest.motion.frame_count() == 1);
  CHECK(rest.motion.values.isZero(0));
  CHECK(contains(rest.notes, "an ASF skeleton alone"));
  const auto& a = *rest.motion.skeleton;
  const auto& b = *clip.motion.skeleton;
  REQUIRE(a.joint_count() == b.joint_count());
  for (int j = 0; j < a.joint_count(); ++j) CHECK((a.joint(j).offset - b.joint(j).offset).norm() < 1e-12);
  CHECK_THROWS_WITH(kg::io::import_motion(asf.string(), amc.string(), {}),
                    Catch::Contains("the skeleton itself"));
}

TEST_CASE("asf/amc nodes: io.import_asf_amc and io.import_motion", "[io][asf][nodes]") {
  const auto& asf_type = node_type("io.import_asf_amc");
  const auto& any_type = node_type("io.import_motion");
  for (const char* p : {"skeleton", "path", "units", "up", "fps", "trim"}) {
    CHECK(asf_type.spec.find_param(p) != nullptr);
    CHECK(any_type.spec.find_param(p) != nullptr);
  }
  CHECK(asf_type.spec.find_param("skeleton")->required);
  CHECK_FALSE(any_type.spec.find_param("skeleton")->required);
  CHECK(asf_type.spec.find_output("motion")->type == "kg.Motion");
  CHECK(any_type.spec.find_output("skeleton")->type == "kg.Skeleton");

  const fs::path asf = kAsfDir / "16.asf", amc = kAsfDir / "16_15.amc",
                 bvh = kData / "bvh_motionbuilder" / "16_15.bvh";
  if (!have({asf, amc, bvh})) return;
  {
    const NodeContext ctx = run_node(asf_type, params_for(asf_type.spec, {{"skeleton", asf.string()},
                                                                          {"path", amc.string()},
                                                                          {"trim", std::string("none")}}));
    const auto& m = ctx.outputs.at("motion").get<Motion>();
    CHECK(m.frame_count() == 471);
    CHECK(ctx.outputs.at("skeleton").get_shared<kg::motion::Skeleton>() == m.skeleton);
    CHECK(std::get<std::int64_t>(ctx.figures.at("frames")) == 471);
    CHECK(std::get<std::string>(ctx.figures.at("units")) == "asf");
    CHECK(ctx.logged("120 fps"));
  }
  const kg::graph::Registry& registry = io_registry();
  {  // the skeleton guessed from the subject prefix, and said so
    const NodeContext ctx =
        run_node(registry, "io.import_motion", params_for(any_type.spec, {{"path", amc.string()}}));
    // trim auto: the AMC's first two frames hold the left arm's "0 0 0" placeholder.
    CHECK(ctx.outputs.at("motion").get<Motion>().frame_count() == 469);
    CHECK(ctx.logged("frames 0..1 are calibration"));
    CHECK(ctx.logged("16.asf"));
    CHECK(ctx.logged("skeleton not given"));
  }
  {  // a .bvh dispatches to the BVH reader
    const NodeContext ctx = run_node(
        registry, "io.import_motion",
        params_for(any_type.spec,
                   {{"path", bvh.string()}, {"up", std::string("y")}, {"trim", std::string("none")}}));
    CHECK(ctx.outputs.at("motion").get<Motion>().skeleton->find_joint("lhipjoint") < 0);
    CHECK(ctx.outputs.at("motion").get<Motion>().frame_count() == 471);
  }
  {  // an .amc without a findable .asf, a .bvh with a skeleton, an unknown extension
    const kg::test::TempDir dir;
    const fs::path lone = dir.write("lone.amc", kAmc);
    CHECK_THROWS_WITH(
        run_node(registry, "io.import_motion", params_for(any_type.spec, {{"path", lone.string()}})),
        Catch::Contains("needs its skeleton"));
    CHECK_THROWS_WITH(
        run_node(registry, "io.import_motion",
                 params_for(any_type.spec, {{"path", bvh.string()}, {"skeleton", asf.string()}})),
        Catch::Contains("holds its own skeleton"));
    CHECK_THROWS_WITH(run_node(registry, "io.import_motion",
                               params_for(any_type.spec, {{"path", (dir / "x.c3d").string()}})),
                      Catch::Contains("no motion reader claims '.c3d'; readers: .amc (ASF/AMC, skeleton "
                                      ".asf), .asf (ASF skeleton), .bvh (BVH)"));
  }
}

TEST_CASE("asf: malformed inputs fail with file:line and what was expected", "[io][asf][errors]") {
  struct Case {
    const char* what;
    std::string text;
    int line;
    const char* message;
  };
  const std::vector<Case> cases{
      {"empty file", "", 1, "expected a ':root' section, got end of file"},
      {"text before a section", "hello\n" + kAsf, 1, "expected a section keyword"},
      {"misspelt section", replaced(kAsf, ":bonedata", ":bonedat"), 15, "did you mean ':bonedata'"},
      {"repeated section", replaced(kAsf, ":name tiny\n", ":name tiny\n:name again\n"), 4, "second ':name'"},
      {"unknown unit", replaced(kAsf, "mass 1.0", "time 1.0"), 5, "got 'time'"},
      {"bad angle unit", replaced(kAsf, "angle deg", "angle grad"), 7,
       "expected angle unit 'deg' or 'rad', got 'grad'"},
      {"zero length unit", replaced(kAsf, "length 0.45", "length 0"), 6, "positive length unit"},
      {"root order dof", replaced(kAsf, "TX TY TZ RX RY RZ", "TX TY TZ RX RY RW"), 11, "got 'RW'"},
      {"root order twice", replaced(kAsf, "TX TY TZ RX RY RZ", "TX TY TZ RX RY RX"), 11,
       "each root dof once"},
      {"root without order", replaced(kAsf, "   order TX TY TZ RX RY RZ\n", ""), 10, "root field 'order'"},
      {"root position short", replaced(kAsf, "position 0 0 0", "position 0 0"), 13,
       "three position values, got end of line"},
      {"root axis order", replaced(kAsf, "   axis XYZ", "   axis XYQ"), 12,
       "axis order such as XYZ, got 'XYQ'"},
      {"no begin", replaced(kAsf, "  begin\n     id 1", "  id 1"), 16,
       "expected 'begin' of a bone, got 'id'"},
      {"bad direction",
       replaced(kAsf, "direction 0 -1 0\n     length 7\n     axis 0 0 20 XYZ\n    dof rx ry",
                "direction 0 -1 x\n     length 7\n     axis 0 0 20 XYZ\n    dof rx ry"),
       19, "expected direction z, got 'x'"},
      {"NaN length",
       replaced(kAsf, "length 7\n     axis 0 0 20 XYZ\n    dof rx ry",
                "length nan\n     axis 0 0 20 XYZ\n    dof rx ry"),
       20, "got 'nan'"},
      {"negative length",
       replaced(kAsf, "length 7\n     axis 0 0 20 XYZ\n    dof rx ry",
                "length -7\n     axis 0 0 20 XYZ\n    dof rx ry"),
       20, "non-negative bone length"},
      {"missing length value",
       replaced(kAsf, "length 7\n     axis 0 0 20 XYZ\n    dof rx ry",
                "length\n     axis 0 0 20 XYZ\n    dof rx ry"),
       20, "expected a bone length, got end of line"},
      {"axis without order", replaced(kAsf, "axis 0 0 20 XYZ\n    dof rx ry", "axis 0 0 20\n    dof rx ry"),
       21, "expected three axis angles and an order such as XYZ, got end of line"},
      {"unknown field", replaced(kAsf, "     id 1\n", "     idx 1\n"), 17, "did you mean 'id'"},
      {"repeated field", replaced(kAsf, "     id 1\n", "     id 1\n     id 1\n"), 18, "second 'id'"},
      {"unknown dof", replaced(kAsf, "dof rx ry rz", "dof rx rq rz"), 22,
       "expected a dof out of rx ry rz tx ty tz, got 'rq'"},
      {"stretch dof", replaced(kAsf, "dof rx ry rz", "dof rx ry rz l"), 22, "bone stretch is not supported"},
      {"repeated dof", replaced(kAsf, "dof rx ry rz", "dof rx ry rx"), 22, "each dof once"},
      {"limits before dof",
       replaced(kAsf, "    dof rx\n    limits (-10.0 170.0)\n", "    limits (-10.0 170.0)\n    dof rx\n"), 33,
       "'dof' before 'limits'"},
      {"too few limits", replaced(kAsf, "           (-60.0 70.0)\n", ""), 25,
       "expected '(' opening the limits of dof rz, got 'end'"},
      {"too many limits", replaced(kAsf, "    limits (-10.0 170.0)", "    limits (-10.0 170.0) (0 1)"), 34,
       "end of line after 1 limit pair (one per dof), got '('"},
      {"limit not a number", replaced(kAsf, "(-70.0 70.0)", "(-70.0 seventy)"), 24,
       "maximum of the limits of dof ry, got 'seventy'"},
      {"limit unclosed", replaced(kAsf, "(-70.0 70.0)", "(-70.0 70.0"), 24,
       "')' closing the limits of dof ry, got end of line"},
      {"limit min above max", replaced(kAsf, "(-70.0 70.0)", "(70.0 -70.0)"), 24,
       "minimum not above the maximum"},
      {"bone without end", replaced(kAsf, "(-60.0 70.0)\n  end\n", "(-60.0 70.0)\n"), 26,
       "expected 'end' of the bone begun at line 16, got 'begin'"},
      {"bone without name", replaced(kAsf, "     name ltibia\n", ""), 34, "field 'name'"},
      {"bone named root", replaced(kAsf, "name ltibia", "name root"), 29, "other than 'root'"},
      {"duplicate bone", replaced(kAsf, "name ltibia", "name lfemur"), 29,
       "'lfemur' again (first at line 16)"},
      {"hierarchy: unknown bone", replaced(kAsf, "lfemur ltibia\n", "lfemur ltibiaa\n"), 39,
       "did you mean 'ltibia'"},
      {"hierarchy: two parents", replaced(kAsf, "root lfemur\n", "root lfemur ltibia\n"), 39,
       "one parent, got 'ltibia' again"},
      {"hierarchy: bone left out", replaced(kAsf, "    lfemur ltibia\n", ""), 27,
       "'ltibia' to hang from 'root'"},
      {"hierarchy: cycle",
       replaced(kAsf, "    root lfemur\n    lfemur ltibia\n", "    ltibia lfemur\n    lfemur ltibia\n"), 16,
       "(a cycle)"},
      {"hierarchy: lone parent", replaced(kAsf, "lfemur ltibia\n", "lfemur\n"), 39,
       "a parent followed by its children"},
      {"hierarchy: no begin", replaced(kAsf, ":hierarchy\n  begin\n", ":hierarchy\n"), 37,
       "'begin' of the hierarchy, got 'root'"},
      {"hierarchy: no end", replaced(kAsf, "    lfemur ltibia\n  end\n", "    lfemur ltibia\n"), 40,
       "'end' of the hierarchy begun at line 37, got end of file"},
      {"no hierarchy", kAsf.substr(0, kAsf.find(":hierarchy")), 36,
       "expected a ':hierarchy' section, got end of file"},
  };
  for (const Case& c : cases) {
    INFO(c.what);
    auto [line, message] = error_of([&] { kg::io::parse_asf(c.text, "bad.asf"); });
    CHECK(line == c.line);
    CHECK_THAT(message, Catch::StartsWith("bad.asf:" + std::to_string(c.line) + ":") &&
                            Catch::Contains(c.message) && Catch::Contains("expected"));
  }
  CHECK_THROWS_WITH(kg::io::read_asf("/nonexistent/x.asf"),
                    Catch::Contains("/nonexistent/x.asf: no such ASF file"));
}

TEST_CASE("amc: malformed inputs fail with file:line and what was expected", "[io][asf][errors]") {
  const AsfSkeleton asf = kg::io::parse_asf(kAsf, "tiny.asf");
  struct Case {
    const char* what;
    std::string text;
    int line;
    const char* message;
  };
  const std::vector<Case> cases{
      {"empty", "", 1, "expected a frame number, got end of file"},
      {"header only", ":FULLY-SPECIFIED\n:DEGREES\n", 3, "expected a frame number, got end of file"},
      {"unknown header", replaced(kAmc, ":DEGREES", ":GRADIANS"), 3, "got ':GRADIANS'"},
      {"two angle units", replaced(kAmc, ":DEGREES", ":DEGREES\n:RADIANS"), 4,
       "one of :DEGREES and :RADIANS"},
      {"bone before a frame number", replaced(kAmc, "1\nroot", "root"), 4,
       "expected a frame number, got 'root'"},
      {"frame number skipped", replaced(kAmc, "2\n", "3\n"), 8, "expected frame number 2, got '3'"},
      {"missing bone", replaced(kAmc, "ltibia 20\n", ""), 7,
       "expected a line for bone 'ltibia' in frame 1 (begun at line 4), got frame number 2"},
      {"missing bone at end", replaced(kAmc, "lfemur 11 0 0\n", ""), 11,
       "bone 'lfemur' in frame 2 (begun at line 8), got end of file"},
      {"unknown bone", replaced(kAmc, "ltibia 20", "ltibiaa 20"), 7, "did you mean 'ltibia'"},
      {"bone twice", replaced(kAmc, "ltibia 20\n", "ltibia 20\nltibia 20\n"), 8,
       "'ltibia' again (first at line 7)"},
      {"too few values", replaced(kAmc, "lfemur 10 0 0", "lfemur 10 0"), 6,
       "expected 3 values for bone 'lfemur' (rx ry rz), got end of line"},
      {"too many values", replaced(kAmc, "ltibia 20", "ltibia 20 0"), 7,
       "end of line after 1 value for bone 'ltibia' (rx), got '0'"},
      {"not a number", replaced(kAmc, "root 0 17 0 0 0 0", "root 0 17 0 0 x 0"), 5,
       "a number for root.ry, got 'x'"},
      {"infinite value", replaced(kAmc, "ltibia 20", "ltibia inf"), 7, "a number for ltibia.rx, got 'inf'"},
      {"frame without bones", kAmc + "3\n", 13, "bone 'root' in frame 3 (begun at line 12), got end of file"},
      // Fuzzing (issue 13): number + 1 overflowed, and the next frame then read 'expected frame number
      // -9223372036854775808'.
      {"frame number at the long long limit", replaced(kAmc, "1\nroot", "9223372036854775807\nroot"), 4,
       "expected a frame number 0..2147483647, got '9223372036854775807'"},
      {"frame number past int", replaced(kAmc, "1\nroot", "2147483648\nroot"), 4,
       "expected a frame number 0..2147483647, got '2147483648'"},
      {"negative frame number", replaced(kAmc, "1\nroot", "-1\nroot"), 4, "a frame number, got '-1'"},
  };
  for (const Case& c : cases) {
    INFO(c.what);
    auto [line, message] = error_of([&] { kg::io::parse_amc(c.text, "bad.amc", asf); });
    CHECK(line == c.line);
    CHECK_THAT(message, Catch::StartsWith("bad.amc:" + std::to_string(c.line)) &&
                            Catch::Contains(c.message) && Catch::Contains("expected"));
  }
  CHECK_THROWS_WITH(kg::io::read_amc("/nonexistent/x.amc", asf), Catch::Contains("no such AMC file"));
}

TEST_CASE("asf/amc: every truncation of the real files fails cleanly or reads a prefix",
          "[io][asf][errors][data]") {
  const fs::path asf_path = kAsfDir / "16.asf", amc_path = kAsfDir / "16_15.amc";
  if (!have({asf_path, amc_path})) return;
  const std::string asf_text = read_file(asf_path), amc_text = read_file(amc_path);
  const AsfSkeleton asf = kg::io::parse_asf(asf_text, "16.asf");

  // ASF: every prefix short of the closing `end` must fail with a place inside the prefix.
  const std::size_t last = asf_text.find_last_not_of(" \t\r\n") + 1;
  int asf_failures = 0;
  for (std::size_t n = 0; n < asf_text.size(); ++n) {
    const std::string_view prefix(asf_text.data(), n);
    try {
      kg::io::parse_asf(prefix, "16.asf");
      if (n < last) FAIL("prefix of " << n << " bytes read without error");
    } catch (const Error& e) {
      ++asf_failures;
      const int lines_in_prefix = static_cast<int>(std::count(prefix.begin(), prefix.end(), '\n')) + 1;
      if (e.where().line < 1 || e.where().line > lines_in_prefix + 1 ||
          std::string(e.what()).find("expected") == std::string::npos)
        FAIL("prefix " << n << ": " << e.what());
    }
  }
  CHECK(asf_failures == static_cast<int>(last));

  // AMC: every prefix of the first 10 kB (12 frames), and the whole file cut every 4999 bytes.
  // A prefix either fails or holds only whole frames: as many as it has frame-number lines.
  constexpr std::size_t kHead = 10000;
  std::vector<std::size_t> cuts;
  for (std::size_t n = 0; n < kHead; ++n) cuts.push_back(n);
  for (std::size_t n = kHead; n < amc_text.size(); n += 4999) cuts.push_back(n);
  cuts.push_back(amc_text.size());
  int amc_failures = 0, amc_reads = 0;
  for (std::size_t n : cuts) {
    const std::string_view prefix(amc_text.data(), n);
    try {
      const Motion m = kg::io::parse_amc(prefix, "16_15.amc", asf);
      ++amc_reads;
      int numbers = 0;
      std::size_t at = 0;
      while (at < prefix.size()) {
        std::size_t end = prefix.find('\n', at);
        if (end == std::string_view::npos) end = prefix.size();
        if (std::isdigit(static_cast<unsigned char>(prefix[at]))) ++numbers;
        at = end + 1;
      }
      if (m.frame_count() != numbers)
        FAIL("prefix " << n << ": " << m.frame_count() << " frames, " << numbers << " numbers");
      m.check();
    } catch (const Error& e) {
      ++amc_failures;
      if (std::string(e.what()).find("16_15.amc:") != 0 ||
          std::string(e.what()).find("expected") == std::string::npos)
        FAIL("prefix " << n << ": " << e.what());
    }
  }
  CHECK(amc_failures > 0);
  CHECK(amc_reads > 0);
}
