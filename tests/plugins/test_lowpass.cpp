// filter.lowpass, loaded at run time from KG_PLUGIN_DIR (the plugin is never linked into a test),
// run on Motions built here: exact constants, the Butterworth magnitude response (bilinear
// transform with prewarping, squared by forward-backward), zero phase, edges, unwrapping, errors.
#include <cmath>
#include <functional>
#include <numbers>

#include <catch2/catch.hpp>

#include "kg/graph/executor.hpp"
#include "kg/graph/plugin_loader.hpp"
#include "kg/graph/yaml_io.hpp"
#include "kg/motion/nodes.hpp"
#include "plugin_test_util.hpp"

using namespace kg_test;
using Catch::Matchers::Contains;
using kg::motion::Motion;

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kFps = 120.0;

struct Lowpass {
  Registry registry;
  PluginLoader loader{registry};
  Lowpass() { loader.load_file(lowpass_library()); }

  Motion run(const Motion& in, const std::map<std::string, ParamValue>& overrides = {},
             std::map<std::string, Figure>* figures = nullptr) const {
    const NodeContext ctx =
        kg::test::run_node(registry, "filter.lowpass", params_for(registry, "filter.lowpass", overrides),
                           {{"motion", Value::make(in)}});
    if (figures) *figures = ctx.figures;
    return ctx.outputs.at("motion").get<Motion>();
  }
};

// Least-squares fit of a sin(2 pi f t) + b cos(2 pi f t) + c over frames [first, last).
struct Fit {
  double amplitude, phase;  // phase: radians, a sin(wt + phase)
};
Fit fit_sine(const Motion& m, int column, double hz, int first, int last) {
  Eigen::MatrixXd a(last - first, 3);
  Eigen::VectorXd y(last - first);
  for (int f = first; f < last; ++f) {
    const double t = f / m.fps;
    a.row(f - first) << std::sin(2 * kPi * hz * t), std::cos(2 * kPi * hz * t), 1.0;
    y(f - first) = m.values(f, column);
  }
  const Eigen::Vector3d x = a.colPivHouseholderQr().solve(y);
  return {std::hypot(x(0), x(1)), std::atan2(x(1), x(0))};
}

// One-way Butterworth magnitude of the prewarped bilinear design, squared by filtfilt.
double butterworth_filtfilt_gain(double hz, double cutoff_hz, int order) {
  const double ratio = std::tan(kPi * hz / kFps) / std::tan(kPi * cutoff_hz / kFps);
  return 1 / (1 + std::pow(ratio, 2 * order));
}

Motion sines(int frames, std::initializer_list<std::pair<double, double>> hz_amplitude) {
  Motion m = blank_motion(frames, kFps);
  for (int f = 0; f < frames; ++f) {
    double v = 0;
    for (auto [hz, amplitude] : hz_amplitude) v += amplitude * std::sin(2 * kPi * hz * f / kFps);
    for (int c = 0; c < 6; ++c) m.values(f, c) = v;
  }
  return m;
}

double max_abs_difference(const Motion& a, const Motion& b, int column) {
  return (a.values.col(column) - b.values.col(column)).cwiseAbs().maxCoeff();
}

}  // namespace

TEST_CASE("filter.lowpass declares its signature", "[lowpass]") {
  Lowpass lp;
  const NodeType* type = lp.registry.find_node("filter.lowpass");
  REQUIRE(type != nullptr);
  CHECK(lp.registry.node_origin("filter.lowpass") == fs::canonical(lowpass_library()).string());
  REQUIRE(type->spec.inputs.size() == 1);
  CHECK(type->spec.inputs[0].name == "motion");
  CHECK(type->spec.inputs[0].type == "kg.Motion");
  REQUIRE(type->spec.outputs.size() == 1);
  CHECK(type->spec.outputs[0].type == "kg.Motion");
  const ParamSpec* method = type->spec.find_param("method");
  REQUIRE(method != nullptr);
  CHECK(method->choices == std::vector<std::string>{"butterworth", "gaussian"});
  CHECK(std::get<std::string>(method->default_value) == "butterworth");
  CHECK(std::get<double>(type->spec.find_param("cutoff_hz")->default_value) == 6.0);
  CHECK(std::get<std::int64_t>(type->spec.find_param("order")->default_value) == 2);
  CHECK(type->spec.find_param("channels")->choices ==
        std::vector<std::string>{"all", "rotations", "positions"});
  CHECK(lp.loader.loaded().at(0).id == "kg.lowpass");
}

TEST_CASE("constants stay exactly constant", "[lowpass]") {
  Lowpass lp;
  Motion in = blank_motion(300, kFps);
  const double constants[6] = {0.1, 1.7, -2.3, 3.1, -0.5, 123.456};
  for (int c = 0; c < 6; ++c) in.values.col(c).setConstant(constants[c]);
  for (auto overrides : std::vector<std::map<std::string, ParamValue>>{
           {},
           {{"order", std::int64_t{4}}},
           {{"cutoff_hz", 0.5}},
           {{"method", std::string("gaussian")}},
           {{"method", std::string("gaussian")}, {"sigma_frames", 7.5}}}) {
    const Motion out = lp.run(in, overrides);
    CHECK(out.values == in.values);  // bit for bit
    CHECK(out.fps == in.fps);
    CHECK(out.skeleton == in.skeleton);
  }
}

TEST_CASE("Butterworth: the prewarped design's magnitude, squared by forward-backward", "[lowpass]") {
  Lowpass lp;
  for (int order : {2, 4}) {
    for (double hz : {1.0, 6.0, 12.0, 20.0}) {
      const Motion out =
          lp.run(sines(1200, {{hz, 1.0}}), {{"order", std::int64_t{order}}, {"cutoff_hz", 6.0}});
      const Fit fit = fit_sine(out, 0, hz, 200, 1000);  // away from the ends
      CAPTURE(order, hz, fit.amplitude, fit.phase);
      CHECK(fit.amplitude == Approx(butterworth_filtfilt_gain(hz, 6.0, order)).margin(2e-4));
      if (hz < 20) CHECK(std::abs(fit.phase) < 1e-3);  // zero phase
    }
  }
  // At the cutoff both orders pass exactly half the amplitude.
  CHECK(butterworth_filtfilt_gain(6.0, 6.0, 4) == Approx(0.5));
}

TEST_CASE("1 Hz + 20 Hz at 120 fps: the 20 Hz part goes, the 1 Hz part stays in phase", "[lowpass]") {
  Lowpass lp;
  const int frames = 480;
  const Motion in = sines(frames, {{1.0, 1.0}, {20.0, 0.5}});
  const Motion clean = sines(frames, {{1.0, 1.0}});
  const double sigma_seconds = std::sqrt(std::log(2.0) / 2) / (kPi * 6.0);
  struct Case {
    const char* name;
    std::map<std::string, ParamValue> params;
    std::function<double(double)> gain;  // the method's amplitude response at a frequency
    double max_error;                    // against the clean 1 Hz sine, frames [edge, frames - edge)
  };
  // Odd reflection keeps the first and last frames as they are, 20 Hz noise included (as
  // scipy's filtfilt does); that noise has faded `edge` frames (0.5 s) into the clip.
  const int edge = 60;
  const Case cases[] = {
      {"butterworth order 2", {}, [](double hz) { return butterworth_filtfilt_gain(hz, 6.0, 2); }, 4e-3},
      {"butterworth order 4",
       {{"order", std::int64_t{4}}},
       [](double hz) { return butterworth_filtfilt_gain(hz, 6.0, 4); },
       2e-4},
      {"gaussian from cutoff",
       {{"method", std::string("gaussian")}},
       [&](double hz) { return std::exp(-2 * kPi * kPi * sigma_seconds * sigma_seconds * hz * hz); },
       2.5e-2},
  };
  for (const Case& c : cases) {
    SECTION(c.name) {
      std::map<std::string, Figure> figures;
      const Motion out = lp.run(in, c.params, &figures);
      for (int column : {0, 3}) {  // a position and a rotation channel
        const Fit slow = fit_sine(out, column, 1.0, edge, frames - edge);
        const Fit fast = fit_sine(out, column, 20.0, edge, frames - edge);
        const double lag_seconds = -slow.phase / (2 * kPi);
        double interior_error = 0;
        for (int f = edge; f < frames - edge; ++f) {
          interior_error =
              std::max(interior_error, std::abs(out.values(f, column) - clean.values(f, column)));
        }
        CAPTURE(column, slow.amplitude, lag_seconds, fast.amplitude, interior_error);
        CHECK(slow.amplitude == Approx(c.gain(1.0)).margin(1e-4));
        CHECK(slow.amplitude > 0.98);
        CHECK(std::abs(lag_seconds) < 1e-5);  // 1/800 of a frame
        CHECK(fast.amplitude == Approx(0.5 * c.gain(20.0)).margin(1e-4));
        CHECK(fast.amplitude < 3e-3);  // from 0.5
        CHECK(interior_error < c.max_error);
        CHECK(out.values(0, column) == Approx(in.values(0, column)).margin(1e-9));
        CHECK(out.values(frames - 1, column) == Approx(in.values(frames - 1, column)).margin(1e-9));
      }
      CHECK(std::get<std::int64_t>(figures.at("channels_filtered")) == 6);
    }
  }
}

TEST_CASE("the ends: a straight line stays straight up to the first and last frame", "[lowpass]") {
  Lowpass lp;
  Motion in = blank_motion(240, kFps);
  for (int f = 0; f < 240; ++f) in.values.row(f).setConstant(0.3 + 2.0 * f / kFps);
  for (auto overrides : std::vector<std::map<std::string, ParamValue>>{
           {}, {{"order", std::int64_t{4}}}, {{"method", std::string("gaussian")}}}) {
    const Motion out = lp.run(in, overrides);
    for (int c = 0; c < 6; ++c) CHECK(max_abs_difference(out, in, c) < 1e-6);
  }
}

TEST_CASE("rotation channels are unwrapped before filtering and keep their branch", "[lowpass]") {
  Lowpass lp;
  Motion in = blank_motion(360, kFps);
  for (int f = 0; f < 360; ++f) {
    const double angle = -3.0 + 5.0 * f / kFps;             // crosses +pi near frame 147
    const double wrapped = std::remainder(angle, 2 * kPi);  // in [-pi, pi]
    for (int c = 0; c < 6; ++c) in.values(f, c) = wrapped;
  }
  for (auto method : {"butterworth", "gaussian"}) {
    const Motion out = lp.run(in, {{"method", std::string(method)}});
    CAPTURE(method);
    for (int c = 3; c < 6; ++c) CHECK(max_abs_difference(out, in, c) < 1e-6);
    // Position channels are not angles: their jump is smoothed away like any other step.
    CHECK(max_abs_difference(out, in, 0) > 1.0);
  }
}

TEST_CASE("channels: only the selected kind is touched", "[lowpass]") {
  Lowpass lp;
  const Motion in = sines(240, {{1.0, 1.0}, {20.0, 0.5}});
  const Motion rotations = lp.run(in, {{"channels", std::string("rotations")}});
  const Motion positions = lp.run(in, {{"channels", std::string("positions")}});
  for (int c = 0; c < 3; ++c) {
    CHECK(rotations.values.col(c) == in.values.col(c));
    CHECK(max_abs_difference(positions, in, c) > 0.3);
  }
  for (int c = 3; c < 6; ++c) {
    CHECK(positions.values.col(c) == in.values.col(c));
    CHECK(max_abs_difference(rotations, in, c) > 0.3);
  }
}

TEST_CASE("gaussian: sigma from the cutoff or given in frames", "[lowpass]") {
  Lowpass lp;
  std::map<std::string, Figure> figures;
  const Motion at_cutoff = lp.run(sines(1200, {{6.0, 1.0}}), {{"method", std::string("gaussian")}}, &figures);
  // sigma = fps sqrt(ln 2 / 2) / (pi cutoff): half amplitude at the cutoff, like Butterworth.
  CHECK(std::get<double>(figures.at("sigma_frames")) ==
        Approx(120 * std::sqrt(std::log(2.0) / 2) / (kPi * 6)));
  CHECK(fit_sine(at_cutoff, 0, 6.0, 200, 1000).amplitude == Approx(0.5).margin(2e-3));

  lp.run(sines(100, {{1.0, 1.0}}), {{"method", std::string("gaussian")}, {"sigma_frames", 2.0}}, &figures);
  CHECK(std::get<double>(figures.at("sigma_frames")) == 2.0);
  // A wider kernel removes more: sigma 2 frames keeps more of 12 Hz than sigma 6 frames.
  const Motion narrow =
      lp.run(sines(1200, {{12.0, 1.0}}), {{"method", std::string("gaussian")}, {"sigma_frames", 2.0}});
  const Motion wide =
      lp.run(sines(1200, {{12.0, 1.0}}), {{"method", std::string("gaussian")}, {"sigma_frames", 6.0}});
  CHECK(fit_sine(narrow, 0, 12.0, 200, 1000).amplitude > 10 * fit_sine(wide, 0, 12.0, 200, 1000).amplitude);
}

TEST_CASE("short clips are handled", "[lowpass]") {
  Lowpass lp;
  for (int frames : {0, 1, 2, 3, 5}) {
    Motion in = blank_motion(frames, kFps);
    for (int f = 0; f < frames; ++f) in.values.row(f).setConstant(0.25 * f);
    for (auto method : {"butterworth", "gaussian"}) {
      const Motion out = lp.run(in, {{"method", std::string(method)}});
      CAPTURE(frames, method);
      REQUIRE(out.frame_count() == frames);
      if (frames > 0) CHECK(max_abs_difference(out, in, 0) < 1e-9);  // a line stays a line
    }
  }
}

TEST_CASE("errors: cutoff at or above Nyquist, bad param combinations, bad motions", "[lowpass]") {
  Lowpass lp;
  const Motion in = sines(100, {{1.0, 1.0}});
  for (double cutoff : {60.0, 75.0}) {
    for (auto method : {"butterworth", "gaussian"}) {
      CAPTURE(cutoff, method);
      CHECK_THROWS_WITH(lp.run(in, {{"cutoff_hz", cutoff}, {"method", std::string(method)}}),
                        Contains("must be below the Nyquist frequency 60") && Contains("120"));
    }
  }
  CHECK_NOTHROW(lp.run(in, {{"cutoff_hz", 59.0}}));

  auto create = [&](const std::map<std::string, ParamValue>& overrides) {
    return lp.registry.create_node("filter.lowpass", params_for(lp.registry, "filter.lowpass", overrides));
  };
  CHECK_THROWS_WITH(create({{"order", std::int64_t{3}}}), Contains("order must be 2 or 4, got 3"));
  CHECK_THROWS_WITH(create({{"cutoff_hz", 0.0}}), Contains("cutoff_hz must be greater than 0"));
  CHECK_THROWS_WITH(create({{"sigma_frames", 3.0}}),
                    Contains("sigma_frames applies to method gaussian only"));

  Motion broken = in;
  broken.values.conservativeResize(100, 4);
  CHECK_THROWS_WITH(lp.run(broken), Contains("4 channels per frame but its skeleton declares 6"));
}

TEST_CASE("filter.lowpass in a graph, run by the executor", "[lowpass]") {
  Lowpass lp;
  const Motion source = sines(480, {{1.0, 1.0}, {20.0, 0.5}});
  class Source final : public Node {
   public:
    explicit Source(Motion m) : motion_(std::move(m)) {}
    void run(RunContext& ctx) const override { ctx.output("motion", motion_); }

   private:
    Motion motion_;
  };
  lp.registry.add_node(
      {{"test.motion_source", 1, "A fixed clip.", {}, {{"motion", "kg.Motion", true, "the clip"}}, {}},
       [source](const Params&) { return std::make_unique<Source>(source); }});

  const std::string text =
      "version: 1\n"
      "nodes:\n"
      "  src: {type: test.motion_source}\n"
      "  smooth: {type: filter.lowpass, params: {cutoff_hz: 5, order: 4}}\n"
      "connections:\n"
      "  - {from: src.motion, to: smooth.motion}\n";
  const Graph graph = load_graph_from_string(text, "lowpass.yaml", lp.registry);
  const RunResult result = run_graph(graph, lp.registry);
  REQUIRE(result.ok);
  const Motion& out = result.outputs.at("smooth.motion").get<Motion>();
  CHECK(fit_sine(out, 0, 20.0, 60, 420).amplitude < 1e-4);
  CHECK(fit_sine(out, 0, 1.0, 60, 420).amplitude == Approx(1.0).margin(0.01));
  CHECK(std::get<std::int64_t>(result.nodes.at(1).figures.at(0).second) == 6);  // channels_filtered

  SECTION("the spec's ranges and choices are checked when the graph loads") {
    auto load = [&](const std::string& params) {
      return load_graph_from_string(
          "version: 1\nnodes:\n  src: {type: test.motion_source}\n"
          "  smooth: {type: filter.lowpass, params: " +
              params + "}\nconnections:\n  - {from: src.motion, to: smooth.motion}\n",
          "bad.yaml", lp.registry);
    };
    CHECK_THROWS_WITH(load("{method: median}"), Contains("bad.yaml:4") && Contains("median"));
    CHECK_THROWS_WITH(load("{cutoff_hz: -1}"), Contains("bad.yaml:4") && Contains("cutoff_hz"));
    CHECK_THROWS_WITH(load("{order: 3}"), Contains("bad.yaml:4") && Contains("order must be 2 or 4"));
  }
}
