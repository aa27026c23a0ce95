// `kinegraph batch` and `kinegraph merge` through the CLI, on a small graph of the test nodes
// (kg_test_nodes.so: read a number from the input, double it, write it to ${out}/${stem}.txt):
// items in parallel, failures and crashes kept within their item, the manifest, resume with
// content hashes, --force, shards and their merge, the Slurm scripts run as the array would run
// them, Ctrl-C, and bad usage.
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

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
using kg::test::show;
using kg::test::TempDir;

const std::string kTestPlugins = KG_TEST_PLUGIN_DIR;

const char* kDoubleGraph =
    "version: 1\n"
    "doc: Doubles the number in a file.\n"
    "variables:\n"
    "  input: {required: true}\n"
    "  stem: {default: \"doubled\"}\n"
    "  out: {default: \"out\"}\n"
    "  write_seconds: {default: \"0\"}\n"
    "  output: {default: \"${out}/${stem}.txt\"}\n"
    "  extra: {default: \"\", doc: \"a second number file added to the input's (read by the graph)\"}\n"
    "nodes:\n"
    "  read: {type: test.read_number, params: {path: \"${input}\"}}\n"
    "  double: {type: test.add}\n"
    "  early: {type: test.print, params: {path: \"${out}/${stem}.early.txt\"}}\n"
    "  print: {type: test.print, params: {path: \"${output}\", write_seconds: \"${write_seconds}\"}}\n"
    "connections:\n"
    "  - {from: read.value, to: double.a}\n"
    "  - {from: read.value, to: double.b}\n"
    "  - {from: double.sum, to: early.value}\n"
    "  - {from: double.sum, to: print.value}\n";

// The same with ${extra}'s number added: a graph reading a second file.
const char* kExtraGraph =
    "version: 1\n"
    "variables:\n"
    "  input: {required: true}\n"
    "  stem: {default: \"x\"}\n"
    "  out: {default: \"out\"}\n"
    "  extra: {required: true}\n"
    "nodes:\n"
    "  read: {type: test.read_number, params: {path: \"${input}\"}}\n"
    "  extra: {type: test.read_number, params: {path: \"${extra}\"}}\n"
    "  add: {type: test.add}\n"
    "  print: {type: test.print, params: {path: \"${out}/${stem}.txt\"}}\n"
    "connections:\n"
    "  - {from: read.value, to: add.a}\n"
    "  - {from: extra.value, to: add.b}\n"
    "  - {from: add.sum, to: print.value}\n";

struct Setup {
  TempDir dir;
  fs::path graph = dir.write("double.yaml", kDoubleGraph);
  fs::path out = dir / "batch";

  fs::path input(const std::string& name, const std::string& text) { return dir.write("in/" + name, text); }

  Result batch(std::vector<std::string> args) const {
    std::vector<std::string> all{"batch", graph.string(), "--inputs",     (dir / "in" / "*.txt").string(),
                                 "--out", out.string(),   "--plugin-dir", kTestPlugins};
    all.insert(all.end(), args.begin(), args.end());
    return kinegraph(all);
  }
};

// kinegraph ARGS running in the background in a process group of its own (spawn_program),
// stderr to a file; killed with its group if the test ends first.
struct Background {
  pid_t pid = 0;
  fs::path err;

  Background(const std::vector<std::string>& args, fs::path err_file)
      : pid(kg::test::spawn_program(fs::path(KG_BINARY_DIR) / "bin" / "kinegraph", args, {}, "/dev/null",
                                    err_file, true)),
        err(std::move(err_file)) {}
  // The exit code, or 128 + the signal.
  int wait() {
    const int code = kg::test::wait_program(pid);
    pid = 0;
    return code;
  }
  ~Background() {
    if (pid > 0) {
      ::kill(-pid, SIGKILL);
      wait();
    }
  }
};

std::size_t line_count(const fs::path& file) {
  const std::string text = read_file(file);
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

// Files an interrupted item would leave: outputs being written (".NAME.tmp.PID.N") and its log
// (logs/.STEM.log.tmp.PID).
std::vector<fs::path> temporaries(const fs::path& dir, bool logs_too = true) {
  std::vector<fs::path> found;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (!logs_too && entry.path().parent_path().filename() == "logs") continue;
    if (entry.path().filename().string().find(".tmp.") != std::string::npos) found.push_back(entry.path());
  }
  return found;
}

}  // namespace

TEST_CASE("batch runs the graph once per input, in parallel, with a log and a manifest line each",
          "[batch]") {
  Setup s;
  for (int i = 1; i <= 6; ++i) s.input("n" + std::to_string(i) + ".txt", std::to_string(i) + "\n");
  const Result r = s.batch({"--jobs", "2"});
  INFO(show(r));
  REQUIRE(r.code == 0);
  CHECK_THAT(r.err, Contains("[6/6] ok"));
  CHECK_THAT(r.out, Contains("6 ran (6 ok, 0 failed)"));
  const auto records = manifest_by_item(s.out / "manifest.jsonl");
  REQUIRE(records.size() == 6);
  for (int i = 1; i <= 6; ++i) {
    const std::string stem = "n" + std::to_string(i);
    const fs::path output = s.out / stem / (stem + ".txt");
    CHECK(read_file(output) == std::to_string(2 * i) + "\n");
    const YAML::Node& rec = records.at(stem);
    CHECK(rec["status"].as<std::string>() == "ok");
    CHECK(rec["input"].as<std::string>() == (s.dir / "in" / (stem + ".txt")).string());
    REQUIRE(rec["outputs"].size() == 2);
    CHECK(rec["outputs"][0]["path"].as<std::string>() == stem + "/" + stem + ".early.txt");
    CHECK(rec["outputs"][1]["path"].as<std::string>() == stem + "/" + stem + ".txt");
    CHECK(rec["outputs"][1]["sha256"].as<std::string>() == kg::graph::sha256_file(output));
    REQUIRE(rec["reads"].size() == 1);
    CHECK(rec["reads"][0]["path"].as<std::string>() == rec["input"].as<std::string>());
    CHECK(rec["figures"]["double.sum"].as<double>() == 2 * i);
    CHECK(rec["input_sha256"].as<std::string>() == kg::graph::sha256_file(s.dir / "in" / (stem + ".txt")));
    CHECK(rec["wall_seconds"].as<double>() >= rec["graph_seconds"].as<double>());
    CHECK_THAT(read_file(s.out / rec["log"].as<std::string>()), Contains("wrote " + output.string()));
  }
}

TEST_CASE("a malformed input or a crashing node fails its item only, and the batch exits 1", "[batch]") {
  Setup s;
  s.input("a.txt", "1");
  s.input("b.txt", "not a number");
  s.input("c.txt", "abort");
  s.input("d.txt", "4");
  const Result r = s.batch({"--jobs", "2"});
  INFO(show(r));
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Contains("2 item(s) failed"));
  const auto records = manifest_by_item(s.out / "manifest.jsonl");
  REQUIRE(records.size() == 4);
  CHECK(records.at("a")["status"].as<std::string>() == "ok");
  CHECK(records.at("d")["status"].as<std::string>() == "ok");
  CHECK(records.at("b")["status"].as<std::string>() == "failed");
  CHECK_THAT(records.at("b")["message"].as<std::string>(), Contains("expected a number, got 'not a number'"));
  CHECK_THAT(records.at("b")["message"].as<std::string>(), Contains("node read (test.read_number) failed"));
  CHECK(records.at("c")["status"].as<std::string>() == "failed");
  CHECK_THAT(records.at("c")["message"].as<std::string>(), Contains("died of signal 6"));
  CHECK(fs::exists(s.out / "logs" / "c.log"));
  CHECK(read_file(s.out / "d" / "d.txt") == "8\n");
  CHECK(temporaries(s.out).empty());

  SECTION("running it again redoes only the failed items") {
    s.input("b.txt", "2");
    s.input("c.txt", "3");
    const Result again = s.batch({});
    INFO(show(again));
    CHECK(again.code == 0);
    CHECK_THAT(again.out, Contains("2 ran (2 ok, 0 failed), 2 already done"));
    CHECK(read_file(s.out / "c" / "c.txt") == "6\n");
    CHECK(line_count(s.out / "manifest.jsonl") == 4);
  }
}

TEST_CASE("batch resumes: done items are skipped until their input, graph, settings or outputs change",
          "[batch]") {
  Setup s;
  for (int i = 1; i <= 3; ++i) s.input("n" + std::to_string(i) + ".txt", std::to_string(i));
  REQUIRE(s.batch({}).code == 0);

  const Result same = s.batch({});
  INFO(show(same));
  CHECK(same.code == 0);
  CHECK_THAT(same.out, Contains("0 ran (0 ok, 0 failed), 3 already done"));

  s.input("n2.txt", "20");  // a changed input
  Result r = s.batch({});
  CHECK_THAT(r.out, Contains("1 ran (1 ok, 0 failed), 2 already done"));
  CHECK(read_file(s.out / "n2" / "n2.txt") == "40\n");

  fs::remove(s.out / "n3" / "n3.txt");  // a lost output
  r = s.batch({});
  CHECK_THAT(r.out, Contains("1 ran (1 ok, 0 failed), 2 already done"));
  CHECK(fs::exists(s.out / "n3" / "n3.txt"));

  r = s.batch({"--set", "write_seconds=0.001"});  // other settings
  CHECK_THAT(r.out, Contains("3 ran (3 ok, 0 failed), 0 already done"));

  std::ofstream(s.graph, std::ios::app) << "# an edit\n";  // another graph
  r = s.batch({"--set", "write_seconds=0.001"});
  CHECK_THAT(r.out, Contains("3 ran (3 ok, 0 failed), 0 already done"));

  r = s.batch({"--set", "write_seconds=0.001", "--force"});
  CHECK_THAT(r.out, Contains("3 ran (3 ok, 0 failed), 0 already done"));
  CHECK(line_count(s.out / "manifest.jsonl") == 3);  // compacted: one line per item
}

TEST_CASE("resume also checks every other file the graph read, and outputs by content", "[batch]") {
  Setup s;
  s.input("a.txt", "1");
  s.input("b.txt", "2");
  const fs::path graph = s.dir.write("extra.yaml", kExtraGraph);
  const fs::path extra = s.dir.write("extra.txt", "100");
  auto run = [&] {
    return kinegraph({"batch", graph.string(), "--inputs", (s.dir / "in" / "*.txt").string(), "--out",
                      s.out.string(), "--plugin-dir", kTestPlugins, "--set", "extra=" + extra.string()});
  };
  REQUIRE(run().code == 0);
  CHECK(read_file(s.out / "a" / "a.txt") == "101\n");
  const auto records = manifest_by_item(s.out / "manifest.jsonl");
  const YAML::Node reads = records.at("a")["reads"];  // the input and extra.txt, sorted
  REQUIRE(reads.size() == 2);
  CHECK(reads[0]["path"].as<std::string>() == extra.string());
  CHECK(reads[1]["path"].as<std::string>() == (s.dir / "in" / "a.txt").string());

  s.dir.write("extra.txt", "200");  // same --set, other content
  Result r = run();
  CHECK_THAT(r.out, Contains("2 ran (2 ok, 0 failed), 0 already done"));
  CHECK(read_file(s.out / "b" / "b.txt") == "202\n");

  s.dir.write("batch/a/a.txt", "999\n");  // an output edited: same size, other content
  r = run();
  CHECK_THAT(r.out, Contains("1 ran (1 ok, 0 failed), 1 already done"));
  CHECK(read_file(s.out / "a" / "a.txt") == "201\n");
}

TEST_CASE("items writing the same output fail instead of overwriting each other silently", "[batch]") {
  Setup s;
  s.input("a.txt", "1");
  s.input("b.txt", "2");
  const fs::path shared = s.dir / "shared.txt";
  Result r = s.batch({"--jobs", "1", "--set", "output=" + shared.string()});
  INFO(show(r));
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Contains("also writes: the items overwrite each other's outputs"));

  // Two batches of inputs with the same names into one --out.
  Setup t;
  t.input("s1/a.txt", "1");
  t.input("s2/a.txt", "2");
  auto into = [&](const std::string& folder) {
    return kinegraph({"batch", t.graph.string(), "--inputs", (t.dir / "in" / folder / "*.txt").string(),
                      "--out", t.out.string(), "--plugin-dir", kTestPlugins});
  };
  REQUIRE(into("s1").code == 0);
  r = into("s2");
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Contains((t.dir / "in" / "s1" / "a.txt").string() + " also writes"));
  r = into("s1");  // its output was overwritten: it runs again
  CHECK_THAT(r.out, Contains("1 ran"));
}

TEST_CASE(
    "an edited graph fails the items that have not started, and a second batch into the same folder is "
    "refused",
    "[batch]") {
  Setup s;
  for (int i = 0; i < 3; ++i) s.input("n" + std::to_string(i) + ".txt", std::to_string(i));
  Background batch({"batch", s.graph.string(), "--inputs", (s.dir / "in" / "*.txt").string(), "--out",
                    s.out.string(), "--plugin-dir", kTestPlugins, "--jobs", "1", "--set", "write_seconds=1"},
                   s.dir / "stderr.txt");
  REQUIRE(batch.pid > 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (temporaries(s.dir.path(), false).empty() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  REQUIRE(temporaries(s.dir.path(), false).size() == 1);

  const Result second = s.batch({});
  CHECK(second.code == 2);
  CHECK_THAT(second.err, Contains("another batch (pid " + std::to_string(batch.pid)));

  std::ofstream(s.graph, std::ios::app) << "# edited during the batch\n";
  const int code = batch.wait();
  INFO(read_file(batch.err));
  CHECK(code == 1);
  const auto records = manifest_by_item(s.out / "manifest.jsonl");
  REQUIRE(records.size() == 3);
  int edited = 0;
  for (const auto& [item, record] : records) {
    if (record["status"].as<std::string>() == "ok") continue;
    ++edited;
    CHECK_THAT(record["message"].as<std::string>(), Contains("changed after the batch started"));
  }
  CHECK(edited == 2);
}

TEST_CASE("a worker killed outright fails its item only and leaves no temporary file", "[batch]") {
  Setup s;
  s.input("a.txt", "1");
  s.input("b.txt", "2");
  Background batch({"batch", s.graph.string(), "--inputs", (s.dir / "in" / "*.txt").string(), "--out",
                    s.out.string(), "--plugin-dir", kTestPlugins, "--jobs", "1", "--set", "write_seconds=1"},
                   s.dir / "stderr.txt");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (temporaries(s.dir.path(), false).empty() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  const auto pending = temporaries(s.dir.path(), false);
  REQUIRE(pending.size() == 1);
  // ".a.txt.tmp.PID.N": the worker's pid, as the OOM killer or Slurm would kill it.
  const std::string name = pending.front().filename().string();
  const std::string pid_text = name.substr(name.find(".tmp.") + 5);
  ::kill(std::stoi(pid_text.substr(0, pid_text.find('.'))), SIGKILL);
  CHECK(batch.wait() == 1);
  CHECK(temporaries(s.dir.path()).empty());
  const auto records = manifest_by_item(s.out / "manifest.jsonl");
  REQUIRE(records.size() == 2);
  int killed = 0;
  for (const auto& [item, record] : records)
    if (record["status"].as<std::string>() == "failed") {
      ++killed;
      CHECK_THAT(record["message"].as<std::string>(), Contains("died of signal 9"));
    }
  CHECK(killed == 1);
}

TEST_CASE(
    "inputs: a list names files as written, a missing one fails its item, and outputs under --out are no "
    "inputs",
    "[batch]") {
  Setup s;
  s.input("take[1].txt", "1");
  s.input("b.txt", "2");
  const fs::path list = s.dir.write("list.txt", "in/take[1].txt\n# a comment\n\nin/b.txt\nin/gone.txt\n");
  Result r = kinegraph({"batch", s.graph.string(), "--input-list", list.string(), "--out", s.out.string(),
                        "--plugin-dir", kTestPlugins});
  INFO(show(r));
  CHECK(r.code == 1);
  CHECK_THAT(r.out, Contains("3 ran (2 ok, 1 failed)"));
  CHECK_THAT(r.err, Contains("gone.txt"));
  CHECK(read_file(s.out / "take[1]" / "take[1].txt") == "2\n");

  // A literal name with brackets through --inputs too, and options after --inputs end the list.
  r = kinegraph({"batch", s.graph.string(), "--inputs", (s.dir / "in" / "take[1].txt").string(), "-j", "1",
                 "--out", (s.dir / "other").string(), "--plugin-dir", kTestPlugins});
  CHECK(r.code == 0);

  // --out inside the inputs' folder: the outputs of one run are not inputs of the next.
  const fs::path inner = s.dir / "in" / "results";
  for (int run = 0; run < 2; ++run) {
    r = kinegraph({"batch", s.graph.string(), "--inputs", (s.dir / "in" / "**" / "*.txt").string(), "--out",
                   inner.string(), "--plugin-dir", kTestPlugins});
    INFO(show(r));
    CHECK(r.code == 0);
  }
  CHECK_THAT(r.out, Contains("0 ran (0 ok, 0 failed), 2 already done"));
}

TEST_CASE("shards split the items deterministically and merge recovers the whole manifest", "[batch]") {
  Setup s;
  for (int i = 0; i < 5; ++i) s.input("n" + std::to_string(i) + ".txt", std::to_string(i));
  const Result first = s.batch({"--shard", "0/2"});
  const Result second = s.batch({"--shard", "1/2"});
  INFO(show(first) << show(second));
  REQUIRE(first.code == 0);
  REQUIRE(second.code == 0);
  const auto shard0 = manifest_by_item(s.out / "manifest.shard-0-of-2.jsonl");
  const auto shard1 = manifest_by_item(s.out / "manifest.shard-1-of-2.jsonl");
  CHECK(shard0.size() == 3);  // n0 n2 n4
  CHECK(shard1.size() == 2);  // n1 n3
  CHECK(shard0.count("n0") + shard0.count("n2") + shard0.count("n4") == 3);
  CHECK(shard0.at("n2")["shard"].as<std::string>() == "0/2");

  const Result merged = kinegraph({"merge", s.out.string()});
  INFO(show(merged));
  CHECK(merged.code == 0);
  CHECK_THAT(merged.out, Contains("5 item(s)"));
  CHECK(manifest_by_item(s.out / "manifest.jsonl").size() == 5);

  // The shards' work counts as done for an unsharded run over the same folder.
  const Result whole = s.batch({});
  CHECK_THAT(whole.out, Contains("5 already done"));
}

TEST_CASE("merge names the shards that wrote nothing and the inputs no shard recorded", "[batch]") {
  // Issue 14: after shards 0/3 and 1/3 merge said "0 failed" and exited 0 while two inputs never ran.
  Setup s;
  for (int i = 0; i < 8; ++i) s.input("n" + std::to_string(i) + ".txt", std::to_string(i));
  for (const char* shard : {"0/3", "1/3"}) REQUIRE(s.batch({"--shard", shard}).code == 0);
  const Result merged = kinegraph({"merge", s.out.string()});
  INFO(show(merged));
  CHECK(merged.code == 1);
  CHECK_THAT(merged.out,
             Contains("6 ok, 0 failed, 2 of 8 inputs without a record, 1 shard(s) wrote no manifest"));
  CHECK_THAT(merged.err, Contains("no record: " + (s.dir / "in" / "n2.txt").string()));
  CHECK_THAT(merged.err, Contains("no record: " + (s.dir / "in" / "n5.txt").string()));
  CHECK_THAT(merged.err, Contains("no manifest from shard 2/3"));

  // A shard given other inputs than its siblings is refused before it runs.
  s.input("n8.txt", "8");
  const Result other = s.batch({"--shard", "2/3"});
  INFO(show(other));
  CHECK(other.code == 2);
  CHECK_THAT(other.err, Contains("inputs.txt lists other inputs than this shard was given"));
  fs::remove(s.dir / "in" / "n8.txt");
  REQUIRE(s.batch({"--shard", "2/3"}).code == 0);
  const Result whole = kinegraph({"merge", s.out.string()});
  INFO(show(whole));
  CHECK(whole.code == 0);
  CHECK_THAT(whole.out, Contains("8 ok, 0 failed, 0 of 8 inputs without a record"));
}

TEST_CASE(
    "batch with slurm writes an array job and a merge job that, run as Slurm runs them, give the local "
    "outputs",
    "[batch]") {
  Setup s;
  for (int i = 0; i < 5; ++i) s.input("n" + std::to_string(i) + ".txt", std::to_string(10 + i));
  const fs::path script = s.dir / "jobs" / "double.sbatch";
  const Result written = s.batch({"--slurm", script.string(), "--shards", "3", "--sbatch=--partition=short",
                                  "--sbatch", "--time=00:10:00", "--jobs", "2", "--set", "write_seconds=0"});
  INFO(show(written));
  REQUIRE(written.code == 0);
  const std::string array = read_file(script);
  CHECK_THAT(array, Contains("#SBATCH --array=0-2\n"));
  CHECK_THAT(array, Contains("#SBATCH --cpus-per-task=2\n"));
  CHECK_THAT(array, Contains("#SBATCH --partition=short\n"));
  CHECK_THAT(array, Contains("#SBATCH --time=00:10:00\n"));
  CHECK_THAT(array, Contains("--shard \"${SLURM_ARRAY_TASK_ID}/3\""));
  CHECK_THAT(array, Contains("\ncd '" + fs::current_path().string() + "'"));
  CHECK_THAT(array, Contains("--set 'write_seconds=0'"));
  const fs::path merge_script = s.dir / "jobs" / "double.merge.sbatch";
  CHECK_THAT(read_file(merge_script), Contains(" merge '" + s.out.string() + "'"));
  CHECK(line_count(s.out / "inputs.txt") == 5);
  CHECK_FALSE(fs::exists(s.out / "manifest.jsonl"));  // nothing ran

  for (int task = 0; task < 3; ++task) {
    const Result r =
        kg::test::run_program("/bin/bash", {script.string()},
                              {"SLURM_ARRAY_TASK_ID=" + std::to_string(task), "SLURM_CPUS_PER_TASK=1"});
    INFO(show(r));
    REQUIRE(r.code == 0);
  }
  const Result merged = kg::test::run_program("/bin/bash", {merge_script.string()});
  INFO(show(merged));
  REQUIRE(merged.code == 0);
  CHECK_THAT(merged.out, Contains("5 ok, 0 failed, 0 stale, 0 of 5 inputs without a record"));

  // The same batch on this machine alone: byte-identical outputs.
  const fs::path local = s.dir / "local";
  const Result r =
      kinegraph({"batch", s.graph.string(), "--inputs", (s.dir / "in" / "*.txt").string(), "--out",
                 local.string(), "--plugin-dir", kTestPlugins, "--set", "write_seconds=0"});
  REQUIRE(r.code == 0);
  const auto cluster = manifest_by_item(s.out / "manifest.jsonl");
  const auto here = manifest_by_item(local / "manifest.jsonl");
  REQUIRE(cluster.size() == 5);
  for (const auto& [stem, record] : here) {
    for (std::size_t k = 0; k < 2; ++k)
      CHECK(cluster.at(stem)["outputs"][k]["sha256"].as<std::string>() ==
            record["outputs"][k]["sha256"].as<std::string>());
    CHECK(read_file(s.out / stem / (stem + ".txt")) == read_file(local / stem / (stem + ".txt")));
  }

  SECTION("tasks refuse a graph edited after the jobs were written, and merge reports stale records") {
    std::ofstream(s.graph, std::ios::app) << "# edited after submitting\n";
    const Result task = kg::test::run_program("/bin/bash", {script.string()}, {"SLURM_ARRAY_TASK_ID=0"});
    CHECK(task.code == 3);
    CHECK_THAT(task.err, Contains("changed since the Slurm jobs were written"));
    // Written again for the edited graph, one task run: the others' records are stale.
    REQUIRE(s.batch({"--slurm", script.string(), "--shards", "3", "--set", "write_seconds=0"}).code == 0);
    REQUIRE(kg::test::run_program("/bin/bash", {script.string()}, {"SLURM_ARRAY_TASK_ID=0"}).code == 0);
    const Result stale = kinegraph({"merge", s.out.string()});
    CHECK(stale.code == 1);
    CHECK_THAT(stale.out, Contains("2 ok, 0 failed, 3 stale"));
  }

  SECTION("merge reports inputs that no shard recorded") {
    fs::remove(s.out / "manifest.shard-1-of-3.jsonl");
    fs::remove(s.out / "manifest.jsonl");
    const Result partial = kinegraph({"merge", s.out.string()});
    CHECK(partial.code == 1);
    CHECK_THAT(partial.err, Contains("no record: " + (s.dir / "in" / "n1.txt").string()));
  }
}

TEST_CASE("Ctrl-C stops the batch at once, leaves no partial output, and the same command continues",
          "[batch]") {
  Setup s;
  for (int i = 0; i < 4; ++i) s.input("n" + std::to_string(i) + ".txt", std::to_string(i));
  const std::vector<std::string> args{"batch",        s.graph.string(),
                                      "--inputs",     (s.dir / "in" / "*.txt").string(),
                                      "--out",        s.out.string(),
                                      "--plugin-dir", kTestPlugins,
                                      "--jobs",       "2",
                                      "--set",        "write_seconds=3"};

  Background batch(args, s.dir / "stderr.txt");
  REQUIRE(batch.pid > 0);

  // Wait until both workers are inside their 3 s writes, then interrupt the whole group.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (temporaries(s.dir.path(), false).size() < 2 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  REQUIRE(temporaries(s.dir.path(), false).size() == 2);
  ::kill(-batch.pid, SIGINT);
  const int code = batch.wait();
  INFO(read_file(batch.err));
  CHECK(code == 130);
  CHECK_THAT(read_file(batch.err), Contains("interrupted"));
  CHECK(temporaries(s.dir.path()).empty());
  // Nor the finished outputs of the items stopped: an item writes all its outputs or none.
  for (int i = 0; i < 4; ++i)
    CHECK_FALSE(fs::exists(s.out / ("n" + std::to_string(i)) / ("n" + std::to_string(i) + ".early.txt")));
  for (int i = 0; i < 4; ++i)
    CHECK_FALSE(fs::exists(s.out / ("n" + std::to_string(i)) / ("n" + std::to_string(i) + ".txt")));
  CHECK(manifest_by_item(s.out / "manifest.jsonl").empty());

  std::vector<std::string> resume = args;
  resume.back() = "write_seconds=0";
  const Result again = kinegraph(resume);
  INFO(show(again));
  CHECK(again.code == 0);
  CHECK_THAT(again.out, Contains("4 ran (4 ok, 0 failed)"));
}

TEST_CASE("item folders mirror the inputs' folders, so equal names in different folders do not collide",
          "[batch]") {
  Setup s;
  s.input("subject1/walk.txt", "1");
  s.input("subject2/walk.txt", "2");
  s.input("subject2/deeper/run.txt", "3");
  const Result r = kinegraph({"batch", s.graph.string(), "--inputs", (s.dir / "in" / "**" / "*.txt").string(),
                              "--out", s.out.string(), "--plugin-dir", kTestPlugins});
  INFO(show(r));
  REQUIRE(r.code == 0);
  CHECK(read_file(s.out / "subject1" / "walk" / "walk.txt") == "2\n");
  CHECK(read_file(s.out / "subject2" / "walk" / "walk.txt") == "4\n");
  CHECK(read_file(s.out / "subject2" / "deeper" / "run" / "run.txt") == "6\n");
  CHECK(fs::exists(s.out / "logs" / "subject2" / "deeper" / "run.log"));
  CHECK(temporaries(s.out).empty());
}

TEST_CASE("on a terminal, batch redraws one progress bar with counts, rate and ETA", "[batch]") {
  if (!fs::exists("/usr/bin/script")) {
    WARN("skipped: no /usr/bin/script (util-linux) to give batch a terminal");
    return;
  }
  Setup s;
  for (int i = 0; i < 3; ++i) s.input("n" + std::to_string(i) + ".txt", std::to_string(i));
  s.input("bad.txt", "x");
  std::string command = (fs::path(KG_BINARY_DIR) / "bin" / "kinegraph").string();
  for (const std::string& arg :
       {std::string("batch"), s.graph.string(), std::string("--inputs"), (s.dir / "in" / "*.txt").string(),
        std::string("--out"), s.out.string(), std::string("--plugin-dir"), kTestPlugins})
    command += " '" + arg + "'";
  const Result r = kg::test::run_program("/usr/bin/script", {"-qec", command, "/dev/null"}, {"TERM=xterm"});
  INFO(show(r));
  CHECK(r.code == 1);
  CHECK_THAT(r.out, Contains("\r\x1b[K[##############################] 4/4 · 1 failed · "));
  CHECK_THAT(r.out, Contains(" items/s · ETA "));
  CHECK_THAT(r.out, Contains("FAILED bad: "));
  CHECK_THAT(r.out, !Contains("[4/4]"));  // no per-item lines on a terminal
}

TEST_CASE("batch refuses bad usage before running anything", "[batch]") {
  Setup s;
  s.input("a.txt", "1");

  Result r = s.batch({"--set", "stem=x"});
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Contains("batch sets the variable stem for each item itself"));

  r = kinegraph({"batch", s.graph.string(), "--inputs", (s.dir / "none" / "*.bvh").string(), "--out",
                 s.out.string(), "--plugin-dir", kTestPlugins});
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Contains("matches no file"));

  s.input("a.dat", "3");
  r = kinegraph({"batch", s.graph.string(), "--inputs", (s.dir / "in" / "a.*").string(), "--out",
                 s.out.string(), "--plugin-dir", kTestPlugins});
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Contains("differ only in their extension"));

  r = s.batch(
      {"--slurm", (s.dir / "jobs.sbatch").string(), "--set", "bogus=1"});  // checked before writing jobs
  CHECK(r.code == 3);
  CHECK_THAT(r.err, Contains("declares no variable 'bogus'"));
  CHECK_FALSE(fs::exists(s.dir / "jobs.sbatch"));

  r = s.batch({"--shard", "2/2"});
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Contains("--shard expects I/N with 0 <= I < N"));

  r = kinegraph({"batch", s.graph.string(), "--out", s.out.string()});
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Contains("batch needs --inputs"));

  const fs::path no_input =
      s.dir.write("no_input.yaml", "version: 1\nvariables:\n  out: {default: x}\nnodes: {}\n");
  r = kinegraph(
      {"batch", no_input.string(), "--inputs", (s.dir / "in" / "a.txt").string(), "--out", s.out.string()});
  CHECK(r.code == 3);
  CHECK_THAT(r.err, Contains("declares no variable 'input'"));

  const fs::path broken =
      s.dir.write("broken.yaml", std::string(kDoubleGraph) + "  - {from: read.nothing, to: print.value}\n");
  r = kinegraph({"batch", broken.string(), "--inputs", (s.dir / "in" / "a.txt").string(), "--out",
                 s.out.string(), "--plugin-dir", kTestPlugins});
  CHECK(r.code == 3);
  CHECK_THAT(r.err, Contains("broken.yaml:"));
  CHECK_FALSE(fs::exists(s.out / "manifest.jsonl"));
}
