// graphs/ladder.yaml (Gleicher 1998 7.2) run end to end through the kinegraph CLI: a synthesized
// ladder climb retargeted to a character of 0.6 times the size with the ladder plugin's rung and
// rail constraints. The result is read back from its BVH and every hold is measured with the
// plugin's own kinds (loaded here as the CLI loads them); the constraint file the graph reads
// is checked against the synthesizer's holds, so the two cannot drift apart unnoticed.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <catch2/catch.hpp>

#include "../support/process.hpp"
#include "kg/graph/plugin_loader.hpp"
#include "kg/graph/registry.hpp"
#include "kg/io/bvh.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/retarget/nodes.hpp"  // kg.ConstraintKind
#include "kg/synth/synthesize.hpp"

namespace {

namespace fs = std::filesystem;
using kg::test::Result;
using kg::test::show;
using kg::test::TempDir;

const fs::path kSource = KG_SOURCE_DIR;
const fs::path kGraph = kSource / "graphs/ladder.yaml";
const fs::path kConstraints = kSource / "graphs/ladder/climb_constraints.yaml";

using kg::test::kinegraph;

// The climb graphs/ladder.yaml synthesizes (its `climb` node's params), and the margin its rung
// constraints keep a foot from either rail.
kg::synth::ClimbOptions graph_climb() {
  return {.rungs = 4,
          .rung_spacing = 0.30,
          .rail_half_width = 0.22,
          .ladder_distance = 0.50,
          .stature = 1.75,
          .fps = 30};
}
constexpr double kRungMargin = 0.05;

std::string number(double v) {
  std::ostringstream s;
  s.precision(15);
  s << (std::abs(v) < 1e-15 ? 0.0 : v);
  return s.str();
}

// The constraint file for `climb`: per hold, a ladder.rung (feet, the sole under the ball) or a
// ladder.rail (hands, the middle of the grip) over the hold's frames.
std::string constraints_yaml(const kg::synth::Synthesis& climb) {
  const kg::motion::Skeleton& sk = *climb.motion.skeleton;
  std::ostringstream y;
  y << "version: 1\n"
       "doc: >\n"
       "  The holds of the climb graphs/ladder.yaml synthesizes (motion.synthesize kind climb, steps 4,\n"
       "  rung_spacing 0.30, rail_half_width 0.22, ladder_distance 0.50, stature 1.75, fps 30): each foot\n"
       "  hold a ladder.rung on the sole under the ball (margin 0.05 m from the rails), each hand hold a\n"
       "  ladder.rail on the middle of the grip. Frames at 30 fps, metres, world +Y up, the ladder in the\n"
       "  plane z = 0.5. Written from the synthesizer's holds; tests/graphs/test_ladder_graph.cpp checks\n"
       "  they still agree and prints this file anew when they do not.\n"
       "constraints:\n";
  for (const kg::synth::Hold& h : climb.holds) {
    y << "  - kind: " << (h.hand ? "ladder.rail" : "ladder.rung") << "\n";
    y << "    label: \"" << h.name() << "\"\n";
    y << "    points: [{joint: " << sk.joint(h.joint).name << ", offset: [" << number(h.local.x()) << ", "
      << number(h.local.y()) << ", " << number(h.local.z()) << "]}]\n";
    y << "    params: [";
    for (int i = 0; i < 3; ++i) y << number(h.segment_a[i]) << ", ";
    for (int i = 0; i < 3; ++i) y << number(h.segment_b[i]) << (i < 2 ? ", " : "");
    if (!h.hand) y << ", " << number(kRungMargin);
    y << "]\n";
    y << "    frames: [" << h.first_frame << ", " << h.last_frame << "]\n";
  }
  return y.str();
}

std::vector<double> numbers(const YAML::Node& n) {
  std::vector<double> v;
  for (const YAML::Node& x : n) v.push_back(x.as<double>());
  return v;
}

// The ladder plugin's kinds, loaded from the build's plugin folder as the CLI finds them.
struct LadderKinds {
  kg::graph::Registry registry;
  kg::graph::PluginLoader loader{registry};
  LadderKinds() { loader.load_file(fs::path(KG_PLUGIN_DIR) / "kg_ladder.so"); }
  std::shared_ptr<const kg::retarget::ConstraintKind> kind(const std::string& name) const {
    auto found = registry.find<kg::retarget::ConstraintKind>(name);
    REQUIRE(found != nullptr);
    return found;
  }
};

}  // namespace

TEST_CASE("graphs/ladder/climb_constraints.yaml holds the holds of the climb graphs/ladder.yaml makes",
          "[graphs][ladder]") {
  // The graph synthesizes exactly the climb the file was written for.
  const YAML::Node params = YAML::LoadFile(kGraph.string())["nodes"]["climb"]["params"];
  const kg::synth::ClimbOptions o = graph_climb();
  CHECK(params["kind"].as<std::string>() == "climb");
  CHECK(params["steps"].as<int>() == o.rungs);
  CHECK(params["rung_spacing"].as<double>() == o.rung_spacing);
  CHECK(params["rail_half_width"].as<double>() == o.rail_half_width);
  CHECK(params["ladder_distance"].as<double>() == o.ladder_distance);
  CHECK(params["stature"].as<double>() == o.stature);
  CHECK(params["fps"].as<double>() == o.fps);

  const std::string expected_text = constraints_yaml(kg::synth::synthesize_climb(o));
  INFO("expected graphs/ladder/climb_constraints.yaml:\n" << expected_text);
  const YAML::Node expected = YAML::Load(expected_text)["constraints"];
  const YAML::Node actual = YAML::LoadFile(kConstraints.string())["constraints"];
  REQUIRE(actual.IsSequence());
  REQUIRE(actual.size() == expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const YAML::Node e = expected[i], a = actual[i];
    CAPTURE(i, e["label"].as<std::string>());
    CHECK(a["kind"].as<std::string>() == e["kind"].as<std::string>());
    CHECK(a["label"].as<std::string>() == e["label"].as<std::string>());
    CHECK(a["points"][0]["joint"].as<std::string>() == e["points"][0]["joint"].as<std::string>());
    CHECK(numbers(a["frames"]) == numbers(e["frames"]));
    const std::vector<double> ao = numbers(a["points"][0]["offset"]), eo = numbers(e["points"][0]["offset"]);
    const std::vector<double> ap = numbers(a["params"]), ep = numbers(e["params"]);
    REQUIRE(ao.size() == eo.size());
    REQUIRE(ap.size() == ep.size());
    for (std::size_t k = 0; k < eo.size(); ++k) CHECK(ao[k] == Approx(eo[k]).margin(1e-12));
    for (std::size_t k = 0; k < ep.size(); ++k) CHECK(ap[k] == Approx(ep[k]).margin(1e-12));
  }
}

TEST_CASE("graphs/ladder.yaml retargets the climb: hands on the rails, feet on the rungs, converged",
          "[graphs][ladder]") {
  TempDir out;
  const double scale = 0.6;
  const fs::path output = out / "ladder_small.bvh", metrics_file = out / "metrics.json";
  const fs::path climb_file = out / "climb.bvh", run_report = out / "run.json";
  const Result r = kinegraph({"run", kGraph.string(), "--set", "output=" + output.string(), "--set",
                              "report=" + metrics_file.string(), "--set", "climb=" + climb_file.string(),
                              "--set", "constraints=" + kConstraints.string(), "--set",
                              "scale=" + number(scale), "--report", run_report.string()});
  INFO(show(r));
  REQUIRE(r.code == 0);

  // The synthesized climb as the graph wrote it, and the retargeted one: same frames, a figure
  // 0.6 times the size.
  const kg::synth::Synthesis climb = kg::synth::synthesize_climb(graph_climb());
  const kg::motion::Motion source = kg::io::read_bvh(climb_file).motion;
  const kg::motion::Motion small = kg::io::read_bvh(output).motion;
  CHECK(source.fps == Approx(30));
  CHECK(small.fps == Approx(30));
  REQUIRE(source.frame_count() == climb.motion.frame_count());
  REQUIRE(small.frame_count() == climb.motion.frame_count());
  CHECK(small.skeleton->rest_height() == Approx(scale * source.skeleton->rest_height()).epsilon(1e-6));

  // Every hold measured on the result with the plugin's kinds: within 1 mm of its rung's or rail's
  // line (the two equality rows) and not past its ends by more (the two inequality rows).
  const LadderKinds kinds;
  const auto rung = kinds.kind("ladder.rung"), rail = kinds.kind("ladder.rail");
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(small.skeleton->joint_count()));
  double worst_off_line = 0, worst_past_end = 0, moved = 0;
  int frames_checked = 0;
  for (const kg::synth::Hold& h : climb.holds) {
    const std::string joint_name = climb.motion.skeleton->joint(h.joint).name;
    const int joint = small.skeleton->find_joint(joint_name);
    REQUIRE(joint >= 0);
    kg::retarget::Constraint c;
    c.kind = h.hand ? "ladder.rail" : "ladder.rung";
    c.label = h.name();
    c.points = {{.character = 0, .joint = joint, .local = scale * h.local}};
    c.params = {h.segment_a.x(), h.segment_a.y(), h.segment_a.z(),
                h.segment_b.x(), h.segment_b.y(), h.segment_b.z()};
    if (!h.hand) c.params.push_back(kRungMargin);
    c.samples = {{.frames = {h.first_frame}}};
    const kg::retarget::ConstraintKind& kind = h.hand ? *rail : *rung;
    REQUIRE_NOTHROW(kind.check(c));
    for (int f = h.first_frame; f <= h.last_frame; ++f, ++frames_checked) {
      kg::motion::forward_kinematics(*small.skeleton, small.values.row(f), world);
      const Eigen::Vector3d p[1] = {world[std::size_t(joint)] * c.points[0].local};
      Eigen::VectorXd residual = Eigen::VectorXd::Zero(4);
      Eigen::MatrixXd d_points = Eigen::MatrixXd::Zero(4, 3), d_values = Eigen::MatrixXd::Zero(4, 0);
      kind.evaluate(c, c.params, p, {}, residual, d_points, d_values);
      worst_off_line = std::max(worst_off_line, residual.head<2>().norm());
      worst_past_end = std::max({worst_past_end, -residual(2), -residual(3)});
      moved = std::max(moved, (p[0] - h.world).norm());
    }
  }
  INFO(frames_checked << " hold frames; worst distance from a rung or rail " << worst_off_line * 1000
                      << " mm, past an end " << worst_past_end * 1000 << " mm; a hold moved up to " << moved
                      << " m along its rung or rail");
  CHECK(frames_checked > 3 * small.frame_count());
  CHECK(worst_off_line <= 1e-3);
  CHECK(worst_past_end <= 1e-3);
  // The small figure cannot hold where the large one did: some hold slid along its rung or rail.
  CHECK(moved > 0.01);

  // The solve converged, and the metrics say the same: every constraint within 1 mm.
  const YAML::Node report = YAML::LoadFile(run_report.string());
  bool found_solve = false;
  for (const YAML::Node& node : report["nodes"]) {
    if (node["id"].as<std::string>() != "solve") continue;
    found_solve = true;
    CHECK(node["figures"]["converged"].as<bool>());
    INFO(node["figures"]["message"].as<std::string>());
    CHECK(node["figures"]["worst_violation_mm"].as<double>() <= 1.0);
  }
  CHECK(found_solve);
  const YAML::Node metrics = YAML::LoadFile(metrics_file.string());
  CHECK(metrics["violation"]["worst_cm"].as<double>() <= 0.1);
  std::vector<std::string> measured;
  for (const YAML::Node& k : metrics["violation"]["kinds"]) {
    measured.push_back(k["kind"].as<std::string>());
    CHECK(k["worst"].as<double>() <= 0.1);
  }
  CHECK(std::find(measured.begin(), measured.end(), "ladder.rung") != measured.end());
  CHECK(std::find(measured.begin(), measured.end(), "ladder.rail") != measured.end());
}
