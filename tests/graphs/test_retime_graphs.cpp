// The retiming pipelines run end to end through the kinegraph CLI, as a user runs them:
// graphs/retime.yaml on captured jumps, walks and runs; the paper's experiments in
// graphs/retime/ (McCann, Pollard & Srinivasa 2006 §4); the retiming branch of graphs/demo.yaml;
// physics known exactly, on a rigid figure's hop whose flight is exactly ballistic (it must play
// at source speed, or at ṗ² = g'/g under another gravity); and bad input, each refused with a
// non-zero exit, a message saying what is wrong and no output written.
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <catch2/catch.hpp>

#include "../support/process.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/io/bvh.hpp"
#include "kg/motion/resample.hpp"
#include "kg/synth/synthesize.hpp"

namespace {

namespace fs = std::filesystem;
using kg::test::kinegraph;
using kg::test::Result;
using kg::test::show;
using kg::test::TempDir;

const fs::path kSource = KG_SOURCE_DIR;
const fs::path kData = KG_DATA_DIR;
const fs::path kRetime = kSource / "graphs/retime.yaml";
const fs::path kChecked = kSource / "tests/graphs/data/retime_checked.yaml";
constexpr double kFps = 30;  // every retiming graph works at 30 Hz by default, and writes at the input's rate

Result run_graph(const fs::path& graph, const std::vector<std::string>& sets) {
  std::vector<std::string> args{"run", graph.string()};
  for (const std::string& s : sets) args.insert(args.end(), {"--set", s});
  return kinegraph(args);
}

// Frames of a retiming of `duration` seconds written at kFps (retime.retime's count).
int output_frames(double duration, double fps = kFps) {
  return static_cast<int>(std::floor(duration * fps + 1e-9)) + 1;
}

// The still figure the synthesizer draws, standing (the first frame of its jump), as a motion of
// `frames` frames at 120 Hz; `root` sets the root's position (metres, world) at each frame.
template <class Root>
fs::path write_rigid_clip(const TempDir& dir, const std::string& name, int frames, Root root) {
  const kg::synth::Synthesis jump = kg::synth::synthesize_jump({});
  const kg::motion::Motion& source = jump.motion;
  const kg::motion::Joint& hips = source.skeleton->joint(0);
  int position[3] = {-1, -1, -1};
  for (std::size_t k = 0; k < hips.channels.size(); ++k)
    if (!kg::motion::is_rotation(hips.channels[k].kind))
      position[kg::motion::axis_index(hips.channels[k].kind)] = hips.first_channel + static_cast<int>(k);
  REQUIRE((position[0] >= 0 && position[1] >= 0 && position[2] >= 0));
  kg::motion::Motion clip{source.skeleton, kg::motion::FrameMatrix(frames, source.values.cols()), 120.0,
                          name};
  for (int f = 0; f < frames; ++f) {
    clip.values.row(f) = source.values.row(0);
    const Eigen::Vector3d p =
        root(f / clip.fps, Eigen::Vector3d(source.values(0, position[0]), source.values(0, position[1]),
                                           source.values(0, position[2])));
    for (int a = 0; a < 3; ++a) clip.values(f, position[a]) = p[a];
  }
  return dir.write(name + ".bvh", kg::io::write_bvh_string(clip, {.units = "m", .precision = 9}));
}

// A rigid hop: the figure stands still for 1 s, leaves the floor straight up at v = √(2 g h)
// (h = 0.3 m), flies exactly ballistically (the whole body as one: y = y0 + v t - g t²/2) for
// 2 v / g = 0.495 s, lands where it left and stands 1 s more. Its only non-physical instants are
// the takeoff and landing (a velocity step: an impulse the floor gives).
constexpr double kHopStand = 1.0, kHopHeight = 0.3, kG = 9.81;
const double kHopV = std::sqrt(2 * kG * kHopHeight), kHopFlight = 2 * kHopV / kG;

// It lasts a whole number of 30 Hz frames, so the working copy of the retiming graphs lasts as
// long as it does; `extra` 120 Hz frames more make a clip that outlasts its copy.
fs::path write_hop(const TempDir& dir, int extra = 0) {
  const int frames = 4 * static_cast<int>(std::ceil((2 * kHopStand + kHopFlight) * 30)) + 1 + extra;
  return write_rigid_clip(dir, "hop", frames, [](double t, Eigen::Vector3d p) {
    const double s = t - kHopStand;
    if (s > 0 && s < kHopFlight) p.y() += kHopV * s - 0.5 * kG * s * s;
    return p;
  });
}

// One source frame of retime.retime's `forces` JSON.
struct ForceFrame {
  int frame = 0;
  std::string status;
  Eigen::Vector2d point{0, 0};   // the hull's first vertex (p̈, ṗ²): a flight frame's only one
  Eigen::Vector2d timing{0, 0};  // (p̈, ṗ²) played
  double output_time = 0;        // s
};

std::vector<ForceFrame> read_forces(const fs::path& path) {
  const YAML::Node root = YAML::LoadFile(path.string());
  std::vector<ForceFrame> out;
  for (const YAML::Node& f : root["frames"]) {
    ForceFrame ff;
    ff.frame = f["frame"].as<int>();
    ff.status = f["status"].as<std::string>();
    ff.point = {f["hull"][0].as<double>(), f["hull"][1].as<double>()};
    ff.timing = {f["timing"][0].as<double>(), f["timing"][1].as<double>()};
    ff.output_time = f["output_time"].as<double>();
    out.push_back(ff);
  }
  return out;
}

// retime.retime's `curves` CSV: t, p, ṗ, p̈ per output frame.
std::vector<std::array<double, 4>> read_curves(const fs::path& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  REQUIRE(line == "t,p,pdot,pddot");
  std::vector<std::array<double, 4>> rows;
  while (std::getline(in, line)) {
    std::array<double, 4> r{};
    char comma = 0;
    std::istringstream s(line);
    s >> r[0] >> comma >> r[1] >> comma >> r[2] >> comma >> r[3];
    REQUIRE(s);
    rows.push_back(r);
  }
  return rows;
}

// The report of retime.retime: sane in any case; returns it.
YAML::Node check_report(const fs::path& path, double duration_scale, double source_duration) {
  const YAML::Node r = YAML::LoadFile(path.string());
  CHECK(r["converged"].as<bool>());
  CHECK(r["source_duration"].as<double>() == Approx(source_duration).margin(1e-9));
  CHECK(r["duration"].as<double>() == Approx(duration_scale * source_duration).margin(1e-9));
  const double inside = r["share_inside"].as<double>(), at_point = r["share_at_point"].as<double>();
  CHECK((inside >= 0 && inside <= 1));
  CHECK((at_point >= 0 && at_point <= 1));
  CHECK(r["objective_feasibility"].as<double>() >= 0);
  CHECK(r["objective_torque"].as<double>() >= 0);
  CHECK(r["frames_feasible"].as<int>() + r["frames_flight"].as<int>() + r["frames_infeasible"].as<int>() ==
        std::lround(source_duration * kFps) + 1);
  CHECK_FALSE(r["message"].as<std::string>().empty());
  return r;
}

// The retimed clip: at `fps` (the input's rate, output_fps' default), the frames its duration
// gives, the source's skeleton. A clip `tail` source seconds longer than its 30 Hz working copy
// plays that tail at the warp's end speed (exactly: the test "a clip that outlasts ..."); here
// the bound is an end played at a quarter of source speed or faster.
void check_retimed_clip(const fs::path& path, double duration, int joints, double fps, double tail = 0) {
  const kg::motion::Motion m = kg::io::read_bvh(path).motion;
  CHECK(m.fps == Approx(fps));
  if (tail == 0) {
    CHECK(m.frame_count() == output_frames(duration, fps));
  } else {
    CHECK(m.frame_count() >= output_frames(duration, fps));
    CHECK(m.frame_count() <= output_frames(duration + tail / 0.25, fps));
  }
  CHECK(m.skeleton->joint_count() == joints);
}

// The source clip as the graphs see it at kFps: its duration and joint count; and its own rate.
struct Source {
  double duration = 0;
  int joints = 0;
  double rate = 0;
  double tail = 0;  // seconds of the clip past its working copy's last frame
};
Source source_at_30(const fs::path& clip, double fps = 0) {
  const kg::io::ImportedMotion in = kg::io::import_motion(clip.string(), "", {.fps = fps});
  const int frames = kg::motion::resampled_frame_count(in.motion.frame_count(), in.motion.fps, kFps);
  return {(frames - 1) / kFps, in.motion.skeleton->joint_count(), in.motion.fps,
          in.motion.duration() - (frames - 1) / kFps};
}

// A graph variable's default (graphs document theirs at the top).
std::string default_of(const fs::path& graph, const std::string& variable) {
  return YAML::LoadFile(graph.string())["variables"][variable]["default"].as<std::string>();
}

// The line of `err` saying which node failed and why ("" when none did).
std::string failure_line(const std::string& err) {
  std::istringstream in(err);
  for (std::string line; std::getline(in, line);)
    if (line.find(") failed: ") != std::string::npos) return line;
  return "";
}

// Flight frames of a retiming, without the first and last (their central differences straddle
// takeoff or landing): the source seconds they span and the output seconds they play in.
struct Flight {
  int frames = 0;
  double source = 0, output = 0;
};
Flight interior_flight(const std::vector<ForceFrame>& forces) {
  std::vector<const ForceFrame*> flight;
  for (const ForceFrame& f : forces)
    if (f.status == "flight") flight.push_back(&f);
  if (flight.size() < 3) return {};
  const ForceFrame& a = *flight[1];
  const ForceFrame& b = *flight[flight.size() - 2];
  return {static_cast<int>(flight.size()) - 2, (b.frame - a.frame) / kFps, b.output_time - a.output_time};
}

}  // namespace

TEST_CASE("graphs/retime.yaml retimes a captured jump, walk and run to half their duration",
          "[graphs][retime][data]") {
  struct Clip {
    fs::path path;
    double fps;   // 16_01.bvh says 30 fps and is 120
    bool flight;  // a jump and a run leave the floor; a walk always has a foot down
    bool jump;    // its flight is held at source speed: the paper's fig. 1
  };
  // 13_11 starts with a T-pose frame (Daz), dropped by trim: auto.
  const std::vector<Clip> clips{{kData / "cmu/bvh_cmu_names/16_01.bvh", 120, true, true},
                                {kData / "cmu/bvh_daz/13_11.bvh", 0, true, true},
                                {kData / "cmu/asf_amc/16_15.amc", 0, false, false},
                                {kData / "cmu/bvh_daz/02_03.bvh", 0, true, false}};
  TempDir out;
  int ran = 0;
  for (const Clip& clip : clips) {
    if (!fs::exists(clip.path)) {
      WARN("skipped: " << clip.path << " not found");
      continue;
    }
    ++ran;
    const fs::path output = out / "retimed.bvh", report = out / "report.json", forces = out / "forces.json";
    fs::remove(output);
    fs::remove(report);
    const Result r = run_graph(
        kRetime, {"input=" + clip.path.string(), "source_fps=" + std::to_string(clip.fps),
                  "output=" + output.string(), "report=" + report.string(), "forces=" + forces.string()});
    INFO(clip.path << "\n" << show(r));
    REQUIRE(r.code == 0);
    const Source source = source_at_30(clip.path, clip.fps);
    const YAML::Node rep = check_report(report, 0.5, source.duration);
    check_retimed_clip(output, 0.5 * source.duration, source.joints, source.rate, source.tail);
    CHECK(rep["output_frames"].as<int>() == output_frames(0.5 * source.duration));  // at the working rate
    if (clip.flight)
      CHECK(rep["frames_flight"].as<int>() > 0);
    else
      CHECK(rep["frames_flight"].as<int>() == 0);
    if (clip.jump) {
      // The flight plays at source speed exactly, so it shows the gravity the capture shows (at
      // 1.55x and 1.19x before flights were held: 23.7 and 13.8 m/s²).
      CHECK(rep["flights"].as<std::string>() == "hold");
      CHECK(rep["mode"].as<std::string>() == "match");
      CHECK(rep["flights_held"].as<int>() >= 1);
      const Flight flight = interior_flight(read_forces(forces));
      REQUIRE(flight.frames > 5);
      CHECK(flight.output == Approx(flight.source).epsilon(1e-6));
    }
  }
  if (ran == 0) WARN("skipped: no clip of this test in " << kData);
}

TEST_CASE("a run whose flights cannot all be held says so, and the duration it names holds them all",
          "[graphs][retime][data]") {
  const fs::path clip = kData / "cmu/bvh_daz/09_06.bvh";
  if (!fs::exists(clip)) {
    WARN("skipped: " << clip << " not found");
    return;
  }
  TempDir out;
  const fs::path output = out / "retimed.bvh", report = out / "report.json";
  const Result half = run_graph(kRetime, {"input=" + clip.string(), "duration_scale=0.5",
                                          "output=" + output.string(), "report=" + report.string()});
  INFO(show(half));
  REQUIRE(half.code == 0);
  const YAML::Node rep = YAML::LoadFile(report.string());
  const int found = rep["flights_found"].as<int>();
  CHECK(found >= 3);  // a stride's flight after each stance
  REQUIRE(rep["flights_held"].as<int>() < found);
  CHECK_THAT(rep["message"].as<std::string>(), Catch::StartsWith("Not ballistic: "));
  const double holding = rep["duration_holding_flights"].as<double>();
  CHECK(holding > rep["duration"].as<double>());
  CHECK(holding <= rep["source_duration"].as<double>());
  // Asked for that duration, every flight is held.
  const Result longer =
      run_graph(kRetime, {"input=" + clip.string(), "duration=" + std::to_string(holding + 0.001),
                          "output=" + output.string(), "report=" + report.string()});
  INFO(show(longer));
  REQUIRE(longer.code == 0);
  const YAML::Node held = YAML::LoadFile(report.string());
  CHECK(held["flights_held"].as<int>() == found);
  CHECK_FALSE(held["duration_holding_flights"]);
}

TEST_CASE(
    "a rigid hop retimed to half its duration: the flight plays at source speed, the stands take the rest",
    "[graphs][retime]") {
  // The hop is exactly physical, so in flight (no contact) the only timing its dynamics allow is
  // the source's: ṗ = 1, p̈ = 0 (the flight hulls are that point); the standing figure can play at
  // any speed, so the halving must come from the stands. Raw derivatives (smoothing 0): the clip
  // has no capture noise, and a Gaussian would spread the takeoff's impulse into the flight.
  TempDir dir;
  const fs::path hop = write_hop(dir);
  const Result r = run_graph(
      kRetime, {"input=" + hop.string(), "smoothing=0", "output=" + (dir / "out.bvh").string(),
                "report=" + (dir / "report.json").string(), "forces=" + (dir / "forces.json").string(),
                "curves=" + (dir / "curves.csv").string()});
  INFO(show(r));
  REQUIRE(r.code == 0);
  // Nothing edited: the reference hulls are the hulls, built once.
  CHECK_THAT(r.err, Catch::Contains("hulls: same_as: reference"));
  const Source source = source_at_30(hop);
  const YAML::Node rep = check_report(dir / "report.json", 0.5, source.duration);
  check_retimed_clip(dir / "out.bvh", 0.5 * source.duration, source.joints, source.rate);
  CHECK(rep["feasible"].as<bool>());  // every output frame with contact inside its hull

  const std::vector<ForceFrame> forces = read_forces(dir / "forces.json");
  int ballistic = 0;
  double pdot2_min = 1e9, pdot2_max = 0, pddot_max = 0;
  for (const ForceFrame& f : forces) {
    if (f.status != "flight" || (f.point - Eigen::Vector2d(0, 1)).norm() > 1e-6) continue;
    ++ballistic;
    pdot2_min = std::min(pdot2_min, f.timing.y());
    pdot2_max = std::max(pdot2_max, f.timing.y());
    pddot_max = std::max(pddot_max, std::abs(f.timing.x()));
  }
  INFO("flight frames at (0, 1): " << ballistic << "; played at ṗ² in [" << pdot2_min << ", " << pdot2_max
                                   << "], |p̈| <= " << pddot_max);
  CHECK(ballistic >= static_cast<int>(kHopFlight * kFps) - 3);  // all but the frames at takeoff and landing
  // Held (flights: hold): exactly the source's timing, not near it.
  CHECK(pdot2_min == Approx(1).epsilon(1e-6));
  CHECK(pdot2_max == Approx(1).epsilon(1e-6));
  CHECK(pddot_max < 1e-4);
  CHECK(rep["flights_held"].as<int>() == 1);
  const Flight flight = interior_flight(forces);
  REQUIRE(flight.frames > 5);
  CHECK(flight.output == Approx(flight.source).epsilon(1e-6));

  // The stands took the speed-up: the mean speed outside the flight is well over 1.
  const auto curves = read_curves(dir / "curves.csv");
  REQUIRE(static_cast<int>(curves.size()) == output_frames(0.5 * source.duration, source.rate));
  CHECK(curves.front()[1] == Approx(0).margin(1e-9));
  CHECK(curves.back()[1] == Approx(source.duration).margin(1e-6));
  const double stand_output = 0.5 * source.duration - flight.output;
  const double stand_source = source.duration - flight.source;
  CHECK(stand_source / stand_output > 1.5);
  bool increasing = true;
  for (std::size_t k = 1; k < curves.size(); ++k) increasing = increasing && curves[k][1] > curves[k - 1][1];
  CHECK(increasing);
}

TEST_CASE("the report counts the frames written at the output fps, not at the hulls' 30 Hz",
          "[graphs][retime]") {
  TempDir dir;
  const fs::path hop = write_hop(dir);
  const Source source = source_at_30(hop);
  for (const double fps : {24.0, 60.0}) {
    const fs::path output = dir / "out.bvh", report = dir / "report.json", curves = dir / "curves.csv";
    const Result r = run_graph(
        kChecked, {"input=" + hop.string(), "output_fps=" + std::to_string(fps), "output=" + output.string(),
                   "report=" + report.string(), "curves=" + curves.string()});
    INFO(fps << " fps\n" << show(r));
    REQUIRE(r.code == 0);
    const kg::motion::Motion m = kg::io::read_bvh(output).motion;
    CHECK(m.fps == Approx(fps));
    const int written = static_cast<int>(std::floor(0.5 * source.duration * fps + 1e-9)) + 1;
    CHECK(m.frame_count() == written);
    CHECK(static_cast<int>(read_curves(curves).size()) == written);
    const YAML::Node rep = YAML::LoadFile(report.string());
    CHECK(rep["fps"].as<double>() == Approx(fps));
    CHECK(rep["output_frames"].as<int>() == written);
    CHECK_FALSE(rep["failed"].as<bool>());
  }
}

TEST_CASE("graphs/retime.yaml takes a body file in `body`", "[graphs][retime]") {
  TempDir dir;
  const fs::path hop = write_hop(dir);
  const fs::path body = dir.write("light.yaml", "version: 1\nmass: 55\n");
  const Result r =
      run_graph(kRetime, {"input=" + hop.string(), "body=" + body.string(),
                          "output=" + (dir / "out.bvh").string(), "report=" + (dir / "r.json").string()});
  INFO(show(r));
  REQUIRE(r.code == 0);
  CHECK_THAT(r.err, Catch::Contains("body file " + body.string() + " sets mass = 55 kg"));
  // A .urdf for a motion that is not on that robot is refused, naming both.
  const fs::path g1 = fs::path(KG_DATA_DIR) / "robots" / "unitree_g1" / "g1_29dof.urdf";
  if (!fs::exists(g1)) {
    WARN("skipped: " << g1.string() << " not found (the robot lives in ../shared/data)");
    return;
  }
  const Result robot = run_graph(
      kRetime, {"input=" + hop.string(), "body=" + g1.string(), "output=" + (dir / "robot.bvh").string()});
  INFO(show(robot));
  CHECK(robot.code != 0);
  CHECK_THAT(robot.err, Catch::Contains("not its tree"));
  CHECK_FALSE(fs::exists(dir / "robot.bvh"));
}

TEST_CASE("a clip that outlasts its 30 Hz working copy is played to its last frame", "[graphs][retime]") {
  // 2 frames at 120 Hz past the copy's last frame (1/60 s): the warp ends there, and its end speed
  // plays the rest (before, 13_13.bvh retimed at duration_scale 1 lost 2 of its 435 frames).
  TempDir dir;
  const fs::path hop = write_hop(dir, 2);
  const kg::motion::Motion source = kg::io::read_bvh(hop).motion;
  const fs::path output = dir / "out.bvh", curves = dir / "curves.csv";
  const Result r = run_graph(
      kRetime, {"input=" + hop.string(), "trim=none", "duration_scale=1", "output=" + output.string(),
                "report=" + (dir / "r.json").string(), "curves=" + curves.string()});
  INFO(show(r));
  REQUIRE(r.code == 0);
  const kg::motion::Motion m = kg::io::read_bvh(output).motion;
  const auto rows = read_curves(curves);
  REQUIRE(static_cast<int>(rows.size()) == m.frame_count());
  const Source copy = source_at_30(hop);
  REQUIRE(source.duration() - copy.duration == Approx(2 / 120.0));
  // The last frame written plays within one frame of the clip's end, and none plays past it.
  const auto& last = rows.back();
  CHECK(last[0] > copy.duration);
  CHECK(last[1] <= source.duration() + 1e-9);
  CHECK(source.duration() - last[1] < last[2] / m.fps + 1e-9);
  CHECK(m.frame_count() >= source.frame_count() - 1);
  // Past the warp's end, the end speed: p'' = 0 and p' constant.
  CHECK(last[3] == 0);
  CHECK(last[2] == Approx(rows[rows.size() - 2][2]));
}

TEST_CASE("graphs/retime/gravity.yaml on the rigid hop: the flight plays at ṗ² = g'/g under each gravity",
          "[graphs][retime]") {
  // Under gravity g' the hop's ballistic path (made under g) is physical again played at
  // ṗ = √(g'/g): its flight lasts √(g/g') times as long. Fig. 9: lower gravity, a longer flight.
  TempDir dir;
  const fs::path hop = write_hop(dir);
  const fs::path graph = kSource / "graphs/retime/gravity.yaml";
  const Result r = run_graph(
      graph, {"input=" + hop.string(), "smoothing=0", "gravity_low=4.9", "gravity_high=19.6",
              "output_low=" + (dir / "low.bvh").string(), "output_high=" + (dir / "high.bvh").string(),
              "report_low=" + (dir / "low.json").string(), "report_high=" + (dir / "high.json").string(),
              "curves_low=", "curves_high=", "forces_low=" + (dir / "low_forces.json").string(),
              "forces_high=" + (dir / "high_forces.json").string()});
  INFO(show(r));
  REQUIRE(r.code == 0);
  const Source source = source_at_30(hop);
  for (const std::string side : {"low", "high"}) {
    check_report(dir / (side + ".json"), 1, source.duration);
    check_retimed_clip(dir / (side + ".bvh"), source.duration, source.joints, source.rate);
  }
  const Flight low = interior_flight(read_forces(dir / "low_forces.json"));
  const Flight high = interior_flight(read_forces(dir / "high_forces.json"));
  REQUIRE(low.frames > 5);
  REQUIRE(high.frames > 5);
  INFO("flight: source " << low.source << " s; low gravity " << low.output << " s (physics "
                         << low.source * std::sqrt(kG / 4.9) << "), high " << high.output << " s (physics "
                         << high.source * std::sqrt(kG / 19.6) << ")");
  CHECK(low.output == Approx(low.source * std::sqrt(kG / 4.9)).epsilon(0.1));
  CHECK(high.output == Approx(high.source * std::sqrt(kG / 19.6)).epsilon(0.1));
}

TEST_CASE("graphs/demo.yaml retimes its synthesized jump to half its duration", "[graphs][retime]") {
  TempDir out;
  const Result r =
      kinegraph({"run", (kSource / "graphs/demo.yaml").string(), "--set", "out=" + out.path().string()});
  INFO(show(r));
  REQUIRE(r.code == 0);
  const kg::motion::Motion jump = kg::io::read_bvh(out / "jump_30hz.bvh").motion;
  const double duration = (jump.frame_count() - 1) / kFps;  // the file's Frame Time has 9 digits
  check_report(out / "jump_retimed_report.json", 0.5, duration);
  check_retimed_clip(out / "jump_retimed.bvh", 0.5 * duration, jump.skeleton->joint_count(), kFps);
  CHECK(static_cast<int>(read_curves(out / "jump_retimed_curves.csv").size()) ==
        output_frames(0.5 * duration));

  // The contacts see the synthesized flight: the hulls' flight frames are those between the
  // synthesizer's takeoff and landing, within a frame.
  const kg::synth::Synthesis synth = kg::synth::synthesize_jump({});
  const std::vector<ForceFrame> forces = read_forces(out / "jump_retimed_forces.json");
  REQUIRE(static_cast<int>(forces.size()) == jump.frame_count());
  int first = -1, last = -1, count = 0;
  for (const ForceFrame& f : forces)
    if (f.status == "flight") {
      if (first < 0) first = f.frame;
      last = f.frame, ++count;
    }
  INFO("flight frames " << first << " to " << last << "; synthesized takeoff " << synth.flight_start * kFps
                        << ", landing " << synth.flight_end * kFps);
  CHECK(count == last - first + 1);
  CHECK(first >= std::floor(synth.flight_start * kFps));
  CHECK(first <= std::ceil(synth.flight_start * kFps) + 1);
  CHECK(last <= std::ceil(synth.flight_end * kFps));
  CHECK(last >= std::floor(synth.flight_end * kFps) - 1);

  // Its centre of mass flies ballistically, so its flight frames' least-squares points are the
  // source timing (0, 1), but for the frames where the shift fades in and out; and the flight,
  // weighted above the ground phases, plays at its own speed.
  int at_source = 0;
  for (const ForceFrame& f : forces)
    if (f.status == "flight") at_source += (f.point - Eigen::Vector2d(0, 1)).norm() < 0.15;
  INFO("flight frames whose point is within 0.15 of (0, 1): " << at_source << " of " << count);
  CHECK(at_source >= count - 4);
  const Flight flight = interior_flight(forces);
  INFO("flight: source " << flight.source << " s, output " << flight.output << " s");
  CHECK(flight.output > 0.9 * flight.source);
  CHECK(flight.output < 1.1 * flight.source);
}

TEST_CASE("every graph in graphs/retime/ validates", "[graphs][retime]") {
  int graphs = 0;
  for (const auto& entry : fs::directory_iterator(kSource / "graphs/retime")) {
    if (entry.path().extension() != ".yaml") continue;
    ++graphs;
    std::vector<std::string> args{"validate", entry.path().string()};
    for (const auto& variable : YAML::LoadFile(entry.path().string())["variables"]) {
      if (!variable.second["required"] || !variable.second["required"].as<bool>()) continue;
      const std::string name = variable.first.as<std::string>();
      const std::string value =
          name.rfind("pin_", 0) == 0 ? "1" : (kSource / "tests/graphs/data/two_joints.bvh").string();
      args.insert(args.end(), {"--set", name + "=" + value});
    }
    const Result r = kinegraph(args);
    INFO(entry.path() << "\n" << show(r));
    CHECK(r.code == 0);
  }
  CHECK(graphs == 5);
}

TEST_CASE("the graphs of graphs/retime/ reproduce the paper's experiments on the nearest CMU clips",
          "[graphs][retime][data]") {
  const fs::path jump = kData / "cmu/bvh_cmu_names/16_01.bvh", walk = kData / "cmu/asf_amc/16_15.amc";
  if (!fs::exists(jump) || !fs::exists(walk)) {
    WARN("skipped: " << jump << " or " << walk << " not found");
    return;
  }
  const Source jump_source = source_at_30(jump, 120), walk_source = source_at_30(walk);
  TempDir out;
  // Each graph with its clip and the variables that name its outputs (BVH, then report).
  struct Case {
    std::string graph;
    fs::path clip;
    std::vector<std::string> sets;
    std::vector<std::pair<std::string, std::string>> outputs;  // BVH variable, report variable
  };
  const std::vector<Case> cases{
      {"jump_half", jump, {"source_fps=120"}, {{"output", "report"}}},
      {"jump_pin", jump, {"source_fps=120", "pin_source=1.25", "pin_output=1.0"}, {{"output", "report"}}},
      {"gravity", jump, {"source_fps=120"}, {{"output_low", "report_low"}, {"output_high", "report_high"}}},
      {"walk_sideways_gravity", walk, {}, {{"output", "report"}}},
      {"heavy_femur", walk, {}, {{"output", "report"}}}};
  std::map<std::string, fs::path> files;  // variable@graph -> file
  for (const Case& c : cases) {
    const fs::path graph = kSource / "graphs/retime" / (c.graph + ".yaml");
    std::vector<std::string> sets = c.sets;
    sets.push_back("input=" + c.clip.string());
    // Every output variable (output*, report*, curves*, forces*) into the temp folder.
    for (const auto& variable : YAML::LoadFile(graph.string())["variables"]) {
      const std::string name = variable.first.as<std::string>();
      if (name == "output_units" || name == "output_fps") continue;  // settings, not files
      for (const std::string kind : {"output", "report", "curves", "forces"})
        if (name.rfind(kind, 0) == 0) {
          const std::string ext = kind == "output" ? ".bvh" : kind == "curves" ? ".csv" : ".json";
          files[name + "@" + c.graph] = out / (c.graph + "_" + name + ext);
          sets.push_back(name + "=" + files[name + "@" + c.graph].string());
        }
    }
    const Result r = run_graph(graph, sets);
    INFO(graph << "\n" << show(r));
    REQUIRE(r.code == 0);
    const Source& source = c.clip == jump ? jump_source : walk_source;
    const double scale = std::stod(default_of(graph, "duration_scale"));
    for (const auto& [bvh, report] : c.outputs) {
      check_report(files[report + "@" + c.graph], scale, source.duration);
      check_retimed_clip(files[bvh + "@" + c.graph], scale * source.duration, source.joints, source.rate,
                         source.tail);
    }
  }

  // fig. 1: half the duration is a little shorter than any feasible timing of 16_01 (about 0.54
  // of it); the flight, weighted above the ground phases, keeps close to its source speed (a
  // uniform halving would play it in half the time).
  const Flight half = interior_flight(read_forces(files["forces@jump_half"]));
  INFO("jump_half flight: source " << half.source << " s, output " << half.output << " s");
  REQUIRE(half.frames >= 8);
  CHECK(half.output > 0.9 * half.source);
  CHECK(half.output < 1.1 * half.source);

  // fig. 8: the pinned moment plays when asked (output 1.0 s; curves at the rate written).
  const auto pinned = read_curves(files["curves@jump_pin"]);
  const std::size_t at_one_second = static_cast<std::size_t>(std::lround(jump_source.rate));
  REQUIRE(pinned.size() > at_one_second);
  CHECK(pinned[at_one_second][0] == Approx(1.0));
  CHECK(pinned[at_one_second][1] == Approx(1.25).margin(1e-6));

  // fig. 9: lower gravity, a longer flight; higher gravity, a shorter one.
  const Flight low = interior_flight(read_forces(files["forces_low@gravity"]));
  const Flight high = interior_flight(read_forces(files["forces_high@gravity"]));
  INFO("flight: source " << low.source << " s, low gravity " << low.output << " s, high " << high.output
                         << " s");
  REQUIRE(low.frames > 3);
  CHECK(low.output > 1.1 * low.source);
  CHECK(high.output < 0.9 * high.source);

  // fig. 11: the heavy thigh changes the timing (against the same graph with the mass unchanged).
  const Result same =
      run_graph(kSource / "graphs/retime/heavy_femur.yaml",
                {"input=" + walk.string(), "mass_scale=1", "output=" + (out / "same.bvh").string(),
                 "report=" + (out / "same.json").string(), "curves=" + (out / "same.csv").string()});
  INFO(show(same));
  REQUIRE(same.code == 0);
  const auto heavy = read_curves(files["curves@heavy_femur"]), unchanged = read_curves(out / "same.csv");
  REQUIRE(heavy.size() == unchanged.size());
  double moved = 0;
  for (std::size_t k = 0; k < heavy.size(); ++k)
    moved = std::max(moved, std::abs(heavy[k][1] - unchanged[k][1]));
  INFO("largest change of p(t): " << moved << " s");
  CHECK(moved > 0.02);
}

TEST_CASE("retiming graphs on bad input: a non-zero exit, what is wrong, and nothing written",
          "[graphs][retime]") {
  TempDir dir;
  const fs::path hop = write_hop(dir);
  const fs::path output = dir / "out.bvh", report = dir / "report.json", curves = dir / "curves.csv";
  auto nothing_written = [&] {
    CHECK_FALSE(fs::exists(output));
    CHECK_FALSE(fs::exists(report));
    CHECK_FALSE(fs::exists(curves));
  };

  SECTION("a clip that never touches the floor (graphs/retime.yaml)") {
    // The rigid figure sliding along +Z at 3 m/s: its feet are never slow enough to be planted.
    const fs::path glide = write_rigid_clip(dir, "glide", 240, [](double t, Eigen::Vector3d p) {
      p.z() += 3.0 * t;
      return p;
    });
    const Result r = run_graph(
        kRetime, {"input=" + glide.string(), "output=" + output.string(), "report=" + report.string()});
    INFO(show(r));
    CHECK(r.code == 1);
    CHECK_THAT(failure_line(r.err), Catch::Contains("(retime.hulls) failed") &&
                                        Catch::Contains("no frame of the clip touches anything") &&
                                        Catch::Contains("retime.contacts"));
    nothing_written();
  }

  SECTION("contradictory pins: a later source moment pinned earlier") {
    const Result r =
        run_graph(kSource / "graphs/retime/jump_pin.yaml",
                  {"input=" + hop.string(), "pin_source=1.0, 1.5", "pin_output=1.2, 0.8",
                   "output=" + output.string(), "report=" + report.string(), "curves=" + curves.string()});
    INFO(show(r));
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Catch::Contains("node retime (retime.retime) failed") &&
                          Catch::Contains("contradictory pins") &&
                          Catch::Contains("source 1.5 s at output 0.8 s"));
    nothing_written();
  }

  SECTION("pins in unequal numbers: refused when the graph loads") {
    const Result r =
        run_graph(kSource / "graphs/retime/jump_pin.yaml",
                  {"input=" + hop.string(), "pin_source=1.0, 1.5", "pin_output=0.8",
                   "output=" + output.string(), "report=" + report.string(), "curves=" + curves.string()});
    INFO(show(r));
    CHECK(r.code == 3);
    CHECK_THAT(r.err, Catch::Contains("jump_pin.yaml:") &&
                          Catch::Contains("pin_source has 2 times and pin_output 1"));
    nothing_written();
  }

  SECTION("a pin at infinity: refused when the graph loads") {
    const Result r =
        run_graph(kSource / "graphs/retime/jump_pin.yaml",
                  {"input=" + hop.string(), "pin_source=.inf", "pin_output=0.8", "output=" + output.string(),
                   "report=" + report.string(), "curves=" + curves.string()});
    INFO(show(r));
    CHECK(r.code == 3);
    CHECK_THAT(r.err,
               Catch::Contains("jump_pin.yaml:") &&
                   Catch::Contains("pin 0: pin_source inf s, pin_output 0.8 s (expected finite seconds)"));
    nothing_written();
  }

  SECTION("a knot spacing too fine for the duration: at load when the duration is given, else when it runs") {
    Result r = run_graph(kChecked, {"input=" + hop.string(), "duration=100000", "knot_spacing=0.001",
                                    "output=" + output.string(), "report=" + report.string()});
    INFO(show(r));
    CHECK(r.code == 3);
    CHECK_THAT(r.err, Catch::Contains("retime_checked.yaml:") &&
                          Catch::Contains("knot_spacing 0.001 s cuts the 100000 s duration into more than "
                                          "4096 segments (expected knot_spacing >= 24.4141 s)"));
    nothing_written();
    r = run_graph(kChecked, {"input=" + hop.string(), "duration_scale=1000", "knot_spacing=0.001",
                             "output=" + output.string(), "report=" + report.string()});
    INFO(show(r));
    CHECK(r.code == 1);
    CHECK_THAT(failure_line(r.err), Catch::Contains("node retime (retime.retime) failed") &&
                                        Catch::Contains("RetimeOptions.knot_spacing = 0.001: expected >= "
                                                        "duration / 4096 (") &&
                                        Catch::Contains("segments, at most 4096 are solved"));
    nothing_written();
  }

  SECTION("a pin outside the output") {
    const Result r =
        run_graph(kSource / "graphs/retime/jump_pin.yaml",
                  {"input=" + hop.string(), "pin_source=1.2", "pin_output=9", "output=" + output.string(),
                   "report=" + report.string(), "curves=" + curves.string()});
    INFO(show(r));
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Catch::Contains("pin (source 1.2 s at output 9 s): output time outside"));
    nothing_written();
  }

  SECTION("strict: a duration no feasible timing reaches fails; one that is reached passes") {
    // The hop's stands can be played fast, its flight cannot: half its duration fits, 0.3 does not.
    Result r = run_graph(kChecked, {"input=" + hop.string(), "duration_scale=0.5", "strict=true",
                                    "output=" + output.string(), "report=" + report.string()});
    INFO(show(r));
    REQUIRE(r.code == 0);
    CHECK(fs::exists(output));
    fs::remove(output);
    fs::remove(report);
    r = run_graph(kChecked, {"input=" + hop.string(), "duration_scale=0.3", "strict=true",
                             "output=" + output.string(), "report=" + report.string()});
    INFO(show(r));
    CHECK(r.code == 1);
    const std::string failure = failure_line(r.err);
    CHECK_THAT(failure, Catch::Contains("node retime (retime.retime) failed") &&
                            Catch::Contains("output frames inside their hulls") &&
                            Catch::Contains("shorter than any feasible playback"));
    CHECK_FALSE(fs::exists(output));
    // The shortest feasible playback: no shorter than the flight at source speed plus the stands
    // at the hulls' box (ṗ² <= 16, ṗ <= 4), and no longer than the half that was feasible.
    const std::string key = "the shortest lasts ";
    const std::size_t at = failure.find(key);
    REQUIRE(at != std::string::npos);
    const double shortest = std::stod(failure.substr(at + key.size()));
    const Source source = source_at_30(hop);
    INFO("shortest " << shortest << " s");
    CHECK(shortest >= kHopFlight + 2 * kHopStand / 4 - 2 / kFps);
    CHECK(shortest <= 0.5 * source.duration);
    // The report is written all the same, saying why: infeasible, the shortest feasible duration,
    // no frame written.
    REQUIRE(fs::exists(report));
    const YAML::Node rep = YAML::LoadFile(report.string());
    CHECK(rep["failed"].as<bool>());
    CHECK_FALSE(rep["feasible"].as<bool>());
    CHECK(rep["output_frames"].as<int>() == 0);
    CHECK(rep["duration"].as<double>() == Approx(0.3 * source.duration).margin(1e-9));
    REQUIRE(rep["shortest_duration"]);
    CHECK(rep["shortest_duration"].as<double>() == Approx(shortest).margin(5e-4));
    CHECK_THAT(rep["message"].as<std::string>(), Catch::Contains("shorter than any feasible playback"));
  }

  SECTION("strict failure writes the report but neither curves nor motion") {
    const Result r = run_graph(
        kChecked, {"input=" + hop.string(), "duration_scale=0.3", "strict=true", "output=" + output.string(),
                   "report=" + report.string(), "curves=" + curves.string()});
    INFO(show(r));
    CHECK(r.code == 1);
    CHECK(fs::exists(report));
    CHECK_FALSE(fs::exists(output));
    CHECK_FALSE(fs::exists(curves));
  }

  SECTION(
      "strict on a captured walk at half its duration: the message gives the shortest feasible duration") {
    const fs::path walk = kData / "cmu/asf_amc/16_15.amc";
    if (!fs::exists(walk)) {
      WARN("skipped: " << walk << " not found");
      return;
    }
    // Without strict: written, and the report has the shortest feasible duration.
    Result r = run_graph(kChecked, {"input=" + walk.string(), "smoothing=0.04", "output=" + output.string(),
                                    "report=" + report.string()});
    INFO(show(r));
    REQUIRE(r.code == 0);
    const YAML::Node rep = YAML::LoadFile(report.string());
    REQUIRE(rep["shortest_duration"]);
    const double shortest = rep["shortest_duration"].as<double>();
    CHECK(shortest > rep["duration"].as<double>());
    CHECK_FALSE(rep["feasible"].as<bool>());
    fs::remove(output);
    fs::remove(report);
    r = run_graph(kChecked, {"input=" + walk.string(), "smoothing=0.04", "strict=true",
                             "output=" + output.string(), "report=" + report.string()});
    INFO(show(r));
    CHECK(r.code == 1);
    std::ostringstream seconds;
    seconds.setf(std::ios::fixed);
    seconds.precision(3);
    seconds << shortest;
    CHECK_THAT(r.err, Catch::Contains("shorter than any feasible playback") &&
                          Catch::Contains("the shortest lasts " + seconds.str() + " s"));
    CHECK_FALSE(fs::exists(output));
    const YAML::Node failed = YAML::LoadFile(report.string());
    CHECK(failed["failed"].as<bool>());
    CHECK_FALSE(failed["feasible"].as<bool>());
    CHECK(failed["shortest_duration"].as<double>() == Approx(shortest).margin(1e-9));
  }

  SECTION("a body file with a massless or negative segment: file, line and what was expected") {
    for (const auto& [text, where, expected] : std::vector<std::array<std::string, 3>>{
             {"version: 1\nsegments:\n  LeftUpLeg: {mass: 0}\n",
              "body.yaml:3:", "mass: expected a number > 0, got 0"},
             {"version: 1\nsegments:\n  LeftUpLeg: {mass: -8}\n",
              "body.yaml:3:", "mass: expected a number > 0, got -8"},
             {"version: 1\nsegments:\n  LeftUpLeg: {mass_scale: -2}\n",
              "body.yaml:3:", "mass_scale: expected a number > 0, got -2"},
             {"version: 1\nmass: -70\n", "body.yaml:2:", "mass: expected a number >= 0, got -70"}}) {
      const fs::path body = dir.write("body.yaml", text);
      const Result r = run_graph(kChecked, {"input=" + hop.string(), "body=" + body.string(),
                                            "output=" + output.string(), "report=" + report.string()});
      INFO(text << "\n" << show(r));
      CHECK(r.code == 1);
      CHECK_THAT(r.err, Catch::Contains("node body (retime.body_model) failed") && Catch::Contains(where) &&
                            Catch::Contains(expected));
      nothing_written();
    }
  }

  SECTION("a segment the skeleton does not have") {
    // heavy_femur.yaml's default segment is CMU's lfemur; the synthesized figure's is LeftUpLeg.
    const Result r = run_graph(kSource / "graphs/retime/heavy_femur.yaml",
                               {"input=" + hop.string(), "output=" + output.string(),
                                "report=" + report.string(), "curves=" + curves.string()});
    INFO(show(r));
    CHECK(r.code == 1);
    CHECK_THAT(r.err, Catch::Contains("segment 'lfemur': no such joint"));
    nothing_written();
  }
}
