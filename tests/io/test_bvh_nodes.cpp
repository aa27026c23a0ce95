// io.import_bvh and io.export_bvh through their specs and a minimal RunContext: ports, params,
// reports, logged notes, atomic writing.
#include <catch2/catch.hpp>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "../support/node_context.hpp"
#include "../support/temp_dir.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/io/bvh.hpp"
#include "kg/io/nodes.hpp"

namespace {

using kg::test::NodeContext;
using kg::test::params_for;

const kg::graph::NodeType& node_type(const std::string& name) {
  static const kg::graph::Registry registry = kg::test::registry_of(kg::bvh_node_types());
  return kg::test::node_type(registry, name);
}

}  // namespace

TEST_CASE("bvh nodes: specs declare ports and params") {
  const auto& imp = node_type("io.import_bvh").spec;
  CHECK(imp.inputs.empty());
  REQUIRE(imp.find_output("motion"));
  CHECK(imp.find_output("motion")->type == "kg.Motion");
  CHECK(imp.find_output("skeleton")->type == "kg.Skeleton");
  REQUIRE(imp.find_param("path"));
  CHECK(imp.find_param("path")->type == kg::graph::ParamType::InputPath);
  CHECK(imp.find_param("path")->required);
  CHECK(imp.find_param("units")->choices.size() == 6);
  CHECK(imp.find_param("up"));
  CHECK(imp.find_param("fps")->type == kg::graph::ParamType::String);  // a rate, 0 or auto

  const auto& exp = node_type("io.export_bvh").spec;
  REQUIRE(exp.find_input("motion"));
  CHECK(exp.find_input("motion")->type == "kg.Motion");
  CHECK(exp.find_input("motion")->required);
  CHECK(exp.outputs.empty());
  CHECK(exp.find_param("path")->type == kg::graph::ParamType::OutputPath);
  CHECK(exp.find_param("path")->required);
  CHECK(exp.find_param("units")->choices == std::vector<std::string>{"source", "m", "cm", "mm", "inch"});
  CHECK(exp.find_param("precision")->min == 1.0);
  CHECK(exp.find_param("precision")->max == 12.0);
  CHECK(std::get<std::int64_t>(exp.find_param("precision")->default_value) == 6);
}

TEST_CASE("bvh nodes: import, report, export atomically, import again") {
  const kg::test::TempDir dir;
  const auto in_path = dir.write(
      "small.bvh",
      "HIERARCHY\nROOT hip\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation "
      "Xrotation "
      "Yrotation\n JOINT knee\n {\n  OFFSET 0 -45 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  End "
      "Site\n"
      "  {\n   OFFSET 0 -45 0\n  }\n }\n End Site\n {\n  OFFSET 0 80 0\n }\n}\nMOTION\nFrames: 3\n"
      "Frame Time: 0.0333333\n0 90 0 0 0 0 10 0 0\n1 90 0 0 0 0 20 0 0\n2 90 0 0 0 0 30 0 0\n");
  const auto& imp = node_type("io.import_bvh");
  auto node = imp.create(params_for(imp.spec, {{"path", in_path.string()}, {"fps", std::string("60")}}));
  NodeContext ctx;
  node->run(ctx);
  const auto& m = ctx.outputs.at("motion").get<kg::motion::Motion>();
  const auto& s = ctx.outputs.at("skeleton").get<kg::motion::Skeleton>();
  CHECK(&s == m.skeleton.get());
  CHECK(m.fps == 60.0);
  CHECK(std::get<std::int64_t>(ctx.figures.at("frames")) == 3);
  CHECK(std::get<std::int64_t>(ctx.figures.at("joints")) == 2);
  CHECK(std::get<std::int64_t>(ctx.figures.at("channels")) == 9);
  CHECK(std::get<double>(ctx.figures.at("fps")) == 60.0);
  CHECK(std::get<double>(ctx.figures.at("seconds")) == Approx(2.0 / 60));
  CHECK(std::get<std::string>(ctx.figures.at("units")) == "cm");
  CHECK(std::get<std::string>(ctx.figures.at("up")) == "y");
  REQUIRE(ctx.logs.size() == 4);  // up, units, fps, trim
  CHECK(ctx.logs[1].find("units auto: standing height 170 file units, taken as cm (1.70 m)") !=
        std::string::npos);
  CHECK(std::get<std::string>(ctx.figures.at("notes")).find("taken as cm") != std::string::npos);

  const auto& exp = node_type("io.export_bvh");
  const auto out_path = dir / "sub" / "out.bvh";
  const NodeContext wctx = kg::test::run_node(
      exp, params_for(exp.spec, {{"path", out_path.string()}, {"units", std::string("m")}}),
      {{"motion", ctx.outputs.at("motion")}});
  CHECK(std::get<std::string>(wctx.figures.at("path")) == out_path.string());
  CHECK(std::get<std::int64_t>(wctx.figures.at("frames")) == 3);
  const std::string text = kg::test::read_file(out_path);
  CHECK(text.find("\t\tOFFSET 0 -0.45 0\n") != std::string::npos);
  CHECK(text.find("Frame Time: 0.0166666667\n") != std::string::npos);
  CHECK(text.find("\n0.02 0.9 0 0 0 0 30 0 0\n") != std::string::npos);
  // Only the target is left behind: the temporary file was renamed over it.
  int files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(out_path.parent_path())) ++files;
  CHECK(files == 1);

  // A malformed file fails the node with file:line.
  dir.write("small.bvh", "HIERARCHY\nROOT hip\n{\n OFFSET 0 0\n");
  try {
    node->run(ctx);
    FAIL("no error");
  } catch (const std::exception& e) {
    INFO(e.what());
    CHECK(std::string(e.what()).find("small.bvh:4:12: expected OFFSET z of joint hip") != std::string::npos);
  }
}
