#include <catch2/catch.hpp>

#include <map>

#include "kg/builtin_nodes.hpp"
#include "kg/graph/registry.hpp"
#include "kg/motion/resample.hpp"
#include "motion_test_util.hpp"

using namespace kg;
using kg::motion::test::channels_of;
using K = motion::ChannelKind;

namespace {

// The least a node needs to run: inputs in, outputs and figures out.
class TestContext final : public graph::RunContext {
 public:
  explicit TestContext(graph::Params params) : params_(std::move(params)) {}
  const std::string& node_id() const override { return id_; }
  const graph::Params& params() const override { return params_; }
  const graph::Value& input_value(const std::string& port) const override {
    auto it = inputs.find(port);
    return it == inputs.end() ? empty_ : it->second;
  }
  void set_output(const std::string& port, graph::Value value) override { outputs[port] = std::move(value); }
  void report(const std::string& key, graph::Figure value) override { figures[key] = std::move(value); }
  void log(const std::string& message) override { logs.push_back(message); }

  std::map<std::string, graph::Value> inputs, outputs;
  std::map<std::string, graph::Figure> figures;
  std::vector<std::string> logs;

 private:
  std::string id_ = "resample";
  graph::Params params_;
  graph::Value empty_;
};

motion::Motion clip(int frames, double fps) {
  auto s = std::make_shared<motion::Skeleton>();
  motion::Joint root;
  root.name = "root";
  root.channels =
      channels_of({K::Xposition, K::Yposition, K::Zposition, K::Zrotation, K::Xrotation, K::Yrotation});
  s->add_joint(root);
  motion::Motion m{s, motion::FrameMatrix(frames, 6), fps, "clip"};
  for (int f = 0; f < frames; ++f)
    for (int c = 0; c < 6; ++c) m.values(f, c) = 0.1 * f + 0.01 * c;
  return m;
}

const graph::NodeType& resample_type(const std::vector<graph::NodeType>& types) {
  for (const graph::NodeType& t : types)
    if (t.spec.type == "motion.resample") return t;
  FAIL("motion.resample is not among motion_node_types()");
  throw;  // unreachable
}

}  // namespace

TEST_CASE("motion.resample declares its signature", "[nodes]") {
  const auto types = motion_node_types();
  const graph::NodeType& t = resample_type(types);
  const graph::NodeSpec& spec = t.spec;
  CHECK(spec.version == 1);
  CHECK_FALSE(spec.doc.empty());
  REQUIRE(spec.inputs.size() == 1);
  CHECK(spec.inputs[0].name == "motion");
  CHECK(spec.inputs[0].type == "kg.Motion");
  CHECK(spec.inputs[0].required);
  REQUIRE(spec.outputs.size() == 1);
  CHECK(spec.outputs[0].name == "motion");
  CHECK(spec.outputs[0].type == "kg.Motion");
  const graph::ParamSpec* fps = spec.find_param("fps");
  REQUIRE(fps != nullptr);
  CHECK(fps->type == graph::ParamType::Float);
  CHECK(fps->required);
  REQUIRE(fps->min.has_value());
  CHECK(*fps->min == 0);  // 0 keeps the clip as it is
  // Registers through the same registry API as plugins.
  graph::Registry registry;
  for (const graph::NodeType& nt : types) registry.add_node(nt);
  CHECK(registry.find_node("motion.resample") != nullptr);
}

TEST_CASE("motion.resample runs through a RunContext and reports its figures", "[nodes]") {
  const graph::NodeType& t = resample_type(motion_node_types());
  const graph::Params params({{"fps", 30.0}});
  const auto node = t.create(params);
  TestContext ctx(params);
  const motion::Motion in = clip(241, 120.0);
  ctx.inputs["motion"] = graph::Value::make(in);
  node->run(ctx);
  REQUIRE(ctx.outputs.count("motion") == 1);
  const auto& out = ctx.outputs["motion"].get<motion::Motion>();
  CHECK(out.frame_count() == 61);
  CHECK(out.fps == 30.0);
  CHECK((out.values - motion::resample(in, 30.0).values).isZero(0));
  CHECK(std::get<std::int64_t>(ctx.figures.at("frames_in")) == 241);
  CHECK(std::get<std::int64_t>(ctx.figures.at("frames_out")) == 61);
  CHECK(std::get<double>(ctx.figures.at("fps_in")) == 120.0);
  CHECK(std::get<double>(ctx.figures.at("fps_out")) == 30.0);
  CHECK(std::get<double>(ctx.figures.at("duration_s")) == Approx(2.0));

  // The node keeps no per-run state: a second run on other data is independent.
  TestContext again(params);
  again.inputs["motion"] = graph::Value::make(clip(31, 30.0));
  node->run(again);
  CHECK(again.outputs["motion"].get<motion::Motion>().frame_count() == 31);
}

TEST_CASE("motion.resample with fps 0 passes the clip through unchanged", "[nodes]") {
  const graph::NodeType& t = resample_type(motion_node_types());
  const graph::Params params({{"fps", 0.0}});
  const auto node = t.create(params);
  TestContext ctx(params);
  const motion::Motion in = clip(17, 120.0);
  ctx.inputs["motion"] = graph::Value::make(in);
  node->run(ctx);
  const auto& out = ctx.outputs["motion"].get<motion::Motion>();
  CHECK(out.fps == 120.0);
  CHECK(out.values == in.values);
}

TEST_CASE("motion.resample fails clearly on bad params and inputs", "[nodes]") {
  const graph::NodeType& t = resample_type(motion_node_types());
  CHECK_THROWS_WITH(t.create(graph::Params({{"fps", -0.5}})), Catch::Contains("expected a frame rate > 0"));
  CHECK_THROWS_WITH(t.create(graph::Params({{"fps", -5.0}})), Catch::Contains("fps -5"));
  const graph::Params params({{"fps", 30.0}});
  const auto node = t.create(params);
  TestContext wrong_type(params);
  wrong_type.inputs["motion"] = graph::Value::make(1.5);
  CHECK_THROWS_WITH(node->run(wrong_type), Catch::Contains("kg.Motion"));
  TestContext bad_clip(params);
  motion::Motion nan_clip = clip(10, 120.0);
  nan_clip.values(3, 4) = std::nan("");
  bad_clip.inputs["motion"] = graph::Value::make(nan_clip);
  CHECK_THROWS_WITH(node->run(bad_clip), Catch::Contains("frame 3, channel root.Xrotation is nan"));
  CHECK(bad_clip.outputs.empty());
}
