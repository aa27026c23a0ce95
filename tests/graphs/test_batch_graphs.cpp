// The saved graphs under `kinegraph batch`: every graph that takes an input declares out and stem
// and writes only below ${out}, so it runs under batch unchanged; and a real batch of
// graphs/retarget.yaml over CMU clips writes the same bytes every time (no wall-clock time in
// any output: it stays in the manifest's figures).
#include <filesystem>
#include <map>
#include <sstream>
#include <string>

#include <yaml-cpp/yaml.h>
#include <catch2/catch.hpp>

#include "../support/manifest.hpp"
#include "../support/process.hpp"
#include "kg/graph/sha256.hpp"

namespace {

namespace fs = std::filesystem;
using Catch::Matchers::StartsWith;
using kg::test::kinegraph;
using kg::test::manifest_by_item;
using kg::test::read_file;
using kg::test::Result;
using kg::test::show;
using kg::test::TempDir;

const fs::path kSource = KG_SOURCE_DIR;
const fs::path kData = KG_DATA_DIR;

}  // namespace

TEST_CASE("every graph in graphs/ that takes an input defaults its outputs from out and stem",
          "[graphs][batch]") {
  int checked = 0;
  for (const auto& entry : fs::recursive_directory_iterator(kSource / "graphs")) {
    if (entry.path().extension() != ".yaml") continue;
    const YAML::Node graph = YAML::LoadFile(entry.path().string());
    if (!graph["nodes"]) continue;  // a constraint or target file, not a graph
    const YAML::Node variables = graph["variables"];
    if (!variables || !variables["input"]) continue;
    INFO(entry.path().string());
    ++checked;
    REQUIRE(variables["out"]);
    REQUIRE(variables["stem"]);
    for (const auto& variable : variables) {
      const std::string name = variable.first.as<std::string>();
      const bool setting = name == "output_units" || name == "output_fps";  // not paths
      const bool output = !setting && (name.rfind("output", 0) == 0 || name.rfind("report", 0) == 0 ||
                                       name.rfind("curves", 0) == 0 || name.rfind("forces", 0) == 0);
      if (!output || !variable.second["default"]) continue;
      const std::string value = variable.second["default"].as<std::string>();
      INFO(name << ": " << value);
      if (!value.empty()) CHECK_THAT(value, StartsWith("${out}/${stem}"));
    }
  }
  CHECK(checked >= 8);
}

TEST_CASE(
    "batch of graphs/retarget.yaml over CMU clips: outputs below each item's folder, the same bytes every "
    "run",
    "[graphs][batch]") {
  const fs::path walk = kData / "cmu" / "bvh_motionbuilder" / "16_15.bvh";
  const fs::path run = kData / "cmu" / "bvh_daz" / "09_06.bvh";
  if (!fs::exists(walk) || !fs::exists(run)) {
    WARN("skipped: no motion-capture data in " << kData.string());
    return;
  }
  TempDir dir;
  const std::string graph = (kSource / "graphs" / "retarget.yaml").string();
  auto batch = [&](const fs::path& out) {
    return kinegraph(
        {"batch", graph, "--inputs", walk.string(), run.string(), "--out", out.string(), "--jobs", "2"});
  };
  const Result first = batch(dir / "first");
  const Result second = batch(dir / "second");
  INFO(show(first) << show(second));
  REQUIRE(first.code == 0);
  REQUIRE(second.code == 0);
  const auto a = manifest_by_item(dir / "first" / "manifest.jsonl");
  const auto b = manifest_by_item(dir / "second" / "manifest.jsonl");
  REQUIRE(a.size() == 2);
  for (const auto& [item, record] : a) {
    INFO(item);
    CHECK(record["status"].as<std::string>() == "ok");
    REQUIRE(record["outputs"].size() == 2);  // the clip and its metrics
    for (const YAML::Node& output : record["outputs"]) {
      const std::string path = output["path"].as<std::string>();
      CHECK_THAT(path, StartsWith(item + "/" + record["stem"].as<std::string>()));
      CHECK(read_file(dir / "first" / path) == read_file(dir / "second" / path));
    }
    CHECK(record["figures"]["solve.seconds"].as<double>() > 0);  // the time is a figure, not in a file
    const YAML::Node metrics = YAML::LoadFile(
        (dir / "first" / item / (record["stem"].as<std::string>() + "_metrics.json")).string());
    CHECK(metrics["solve_seconds"].IsNull());
    CHECK(b.at(item)["outputs"][0]["sha256"].as<std::string>() ==
          record["outputs"][0]["sha256"].as<std::string>());
  }
}
