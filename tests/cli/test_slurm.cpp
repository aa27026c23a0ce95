// `kinegraph batch --slurm --submit` on a real single-node Slurm cluster (slurm_cluster.sh:
// munged, slurmctld and slurmd of Debian's packages, under a temporary folder, on free ports):
// the array over the CMU clips in ../shared/data and its dependent merge job, every output
// checked against the merged manifest and against the same batch run on this machine alone,
// byte for byte. Skips with a message where the cluster cannot start (not root, packages missing)
// or the data is absent; stops only the daemons it started.
#include <unistd.h>

#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include <yaml-cpp/yaml.h>
#include <catch2/catch.hpp>

#include "../support/manifest.hpp"
#include "../support/process.hpp"
#include "kg/graph/sha256.hpp"

namespace {

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using kg::test::kinegraph;
using kg::test::manifest_by_item;
using kg::test::read_file;
using kg::test::Result;
using kg::test::run_program;
using kg::test::show;
using kg::test::TempDir;

const fs::path kClusterScript = fs::path(KG_SOURCE_DIR) / "tests" / "cli" / "slurm_cluster.sh";
const fs::path kData = KG_DATA_DIR;

// The cluster of one test: started in the constructor, stopped in the destructor whatever happens.
class Cluster {
 public:
  explicit Cluster(const fs::path& dir) : dir_(dir) {
    started_ = run_program("/bin/bash", {kClusterScript.string(), "start", dir_.string()});
  }
  ~Cluster() {
    if (started_.code == 0) run_program("/bin/bash", {kClusterScript.string(), "stop", dir_.string()});
  }
  const Result& started() const { return started_; }
  std::string conf() const { return "SLURM_CONF=" + (dir_ / "slurm.conf").string(); }
  Result wait(const std::string& job, int timeout_seconds) const {
    return run_program("/bin/bash",
                       {kClusterScript.string(), "wait", dir_.string(), job, std::to_string(timeout_seconds)},
                       {conf()});
  }

 private:
  fs::path dir_;
  Result started_;
};

}  // namespace

TEST_CASE("batch --slurm --submit on a real Slurm cluster gives the local batch's outputs byte for byte",
          "[batch][slurm]") {
  if (!fs::is_directory(kData / "cmu")) {
    WARN("skipped: no motion-capture data in " << kData.string());
    return;
  }
  TempDir dir;
  const Cluster cluster(dir / "cluster");
  if (cluster.started().code != 0) {
    WARN("skipped: no Slurm cluster could be started here: " << cluster.started().err);
    return;
  }
  const std::string clips = (kData / "cmu" / "**" / "*.bvh").string();
  const std::string graph = (fs::path(KG_SOURCE_DIR) / "graphs" / "convert.yaml").string();
  const fs::path out = dir / "cluster out%1";  // sbatch reads a space and a % in #SBATCH lines its own way
  const Result submitted = kinegraph({"batch", graph, "--inputs", clips, "--out", out.string(), "--slurm",
                                      (dir / "jobs" / "convert.sbatch").string(), "--shards", "4", "--submit",
                                      "--set", "resample=30", "--sbatch=--time=00:10:00"},
                                     {cluster.conf()});
  INFO(show(submitted));
  REQUIRE(submitted.code == 0);
  std::istringstream words(submitted.out.substr(submitted.out.find("submitted array job")));
  std::string skip, array_job, merge_job;
  words >> skip >> skip >> skip >> array_job >> skip >> skip >> skip >> merge_job;
  REQUIRE(!array_job.empty());
  REQUIRE(!merge_job.empty());

  const Result merged = cluster.wait(merge_job, 300);
  const Result tasks = cluster.wait(array_job, 10);
  INFO(show(merged) << show(tasks) << read_file(out / "slurm" / ("merge_" + merge_job + ".out")));
  REQUIRE(tasks.code == 0);
  REQUIRE(merged.code == 0);
  CHECK_THAT(tasks.out, Contains("ArrayTaskId=3"));
  CHECK_THAT(read_file(out / "slurm" / ("merge_" + merge_job + ".out")), Contains("0 of "));

  const auto on_cluster = manifest_by_item(out / "manifest.jsonl");
  REQUIRE(on_cluster.size() >= 8);
  std::set<std::string> shards;
  for (const auto& [stem, record] : on_cluster) {
    INFO(stem);
    CHECK(record["status"].as<std::string>() == "ok");
    shards.insert(record["shard"].as<std::string>());
    const fs::path output = out / record["outputs"][0]["path"].as<std::string>();
    CHECK(kg::graph::sha256_file(output) == record["outputs"][0]["sha256"].as<std::string>());
  }
  CHECK(shards == std::set<std::string>{"0/4", "1/4", "2/4", "3/4"});

  const fs::path local = dir / "local_out";
  const Result here = kinegraph(
      {"batch", graph, "--inputs", clips, "--out", local.string(), "--jobs", "2", "--set", "resample=30"});
  INFO(show(here));
  REQUIRE(here.code == 0);
  const auto on_this_machine = manifest_by_item(local / "manifest.jsonl");
  REQUIRE(on_this_machine.size() == on_cluster.size());
  for (const auto& [stem, record] : on_this_machine) {
    INFO(stem);
    const std::string relative = record["outputs"][0]["path"].as<std::string>();
    CHECK(relative == on_cluster.at(stem)["outputs"][0]["path"].as<std::string>());
    CHECK(read_file(local / relative) == read_file(out / relative));
  }
}
