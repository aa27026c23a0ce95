#include <catch2/catch.hpp>

#include <map>

#include "../support/node_context.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/graph/registry.hpp"
#include "kg/motion/nodes.hpp"
#include "kg/motion/resample.hpp"
#include "motion_test_util.hpp"

using namespace kg;
using kg::motion::test::channels_of;
using kg::test::NodeContext;
using K = motion::ChannelKind;

namespace {

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

// motion.resample, registered as the CLI's module registers it.
const graph::NodeType& resample_type() {
  static const graph::Registry registry = kg::test::registry_of(motion_node_types());
  return kg::test::node_type(registry, "motion.resample");
}

}  // namespace

TEST_CASE("motion.resample declares its signature", "[nodes]") {
  // Registers through the same registry API as plugins.
  const graph::Registry registry = kg::test::registry_of(motion_node_types());
  REQUIRE(registry.find_node("motion.resample") != nullptr);
  const graph::NodeSpec& spec = registry.find_node("motion.resample")->spec;
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
}

TEST_CASE("motion.resample runs through a RunContext and reports its figures", "[nodes]") {
  const graph::NodeType& t = resample_type();
  const graph::Params params({{"fps", 30.0}});
  const auto node = t.create(params);
  NodeContext ctx(params);
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
  NodeContext again(params);
  again.inputs["motion"] = graph::Value::make(clip(31, 30.0));
  node->run(again);
  CHECK(again.outputs["motion"].get<motion::Motion>().frame_count() == 31);
}

TEST_CASE("motion.resample with fps 0 passes the clip through unchanged", "[nodes]") {
  const graph::NodeType& t = resample_type();
  const graph::Params params({{"fps", 0.0}});
  const motion::Motion in = clip(17, 120.0);
  const NodeContext ctx = kg::test::run_node(t, params, {{"motion", graph::Value::make(in)}});
  const auto& out = ctx.outputs.at("motion").get<motion::Motion>();
  CHECK(out.fps == 120.0);
  CHECK(out.values == in.values);
}

TEST_CASE("motion.resample fails clearly on bad params and inputs", "[nodes]") {
  const graph::NodeType& t = resample_type();
  CHECK_THROWS_WITH(t.create(graph::Params({{"fps", -0.5}})), Catch::Contains("expected a frame rate > 0"));
  CHECK_THROWS_WITH(t.create(graph::Params({{"fps", -5.0}})), Catch::Contains("fps -5"));
  const graph::Params params({{"fps", 30.0}});
  const auto node = t.create(params);
  NodeContext wrong_type(params);
  wrong_type.inputs["motion"] = graph::Value::make(1.5);
  CHECK_THROWS_WITH(node->run(wrong_type), Catch::Contains("kg.Motion"));
  NodeContext bad_clip(params);
  motion::Motion nan_clip = clip(10, 120.0);
  nan_clip.values(3, 4) = std::nan("");
  bad_clip.inputs["motion"] = graph::Value::make(nan_clip);
  CHECK_THROWS_WITH(node->run(bad_clip), Catch::Contains("frame 3, channel root.Xrotation is nan"));
  CHECK(bad_clip.outputs.empty());
}

TEST_CASE("motion.frame_range keeps a range of frames, frame_range refuses ranges outside the clip",
          "[nodes]") {
  const graph::Registry registry = kg::test::registry_of(motion_node_types());
  const motion::Motion m = clip(10, 120);
  auto run = [&](std::int64_t first, std::int64_t last) {
    return kg::test::run_node(
        registry, "motion.frame_range",
        kg::test::params_for(registry, "motion.frame_range", {{"first", first}, {"last", last}}),
        {{"motion", graph::Value::make(m)}});
  };
  const NodeContext without_first = run(1, -1);
  const motion::Motion& out = without_first.outputs.at("motion").get<motion::Motion>();
  REQUIRE(out.frame_count() == 9);
  CHECK(out.values.row(0) == m.values.row(1));
  CHECK(out.values.row(8) == m.values.row(9));
  CHECK(out.fps == 120);
  CHECK(out.skeleton == m.skeleton);
  CHECK(std::get<std::int64_t>(without_first.figures.at("frames_out")) == 9);
  const motion::Motion middle = motion::frame_range(m, 3, 5);
  REQUIRE(middle.frame_count() == 3);
  CHECK(middle.values.row(2) == m.values.row(5));
  CHECK(motion::frame_range(m, 9, 9).frame_count() == 1);
  CHECK_THROWS_WITH(motion::frame_range(m, 4, 10),
                    Catch::Contains("of its 10") && Catch::Contains("0 <= first <= last < 10"));
  CHECK_THROWS_WITH(motion::frame_range(m, 6, 5), Catch::Contains("frames 6 to 5"));
  CHECK_THROWS(motion::frame_range(m, -1, 5));
  CHECK_THROWS_WITH(run(12, -1), Catch::Contains("of its 10"));
  CHECK_THROWS_WITH(
      kg::test::node_type(registry, "motion.frame_range")
          .create(kg::test::params_for(registry, "motion.frame_range",
                                       {{"first", std::int64_t{5}}, {"last", std::int64_t{2}}})),
      Catch::Contains("last 2 before first 5"));
}
