// `kinegraph batch` and `kinegraph merge` through the CLI, on a small graph of the test nodes
// (kg_test_nodes.so: read a number from the input, double it, write it to ${out}/${stem}.txt):
// items in parallel, failures and crashes kept within their item, the manifest, resume with
// content hashes, --force, shards and their merge, the Slurm scripts run as the array would run
// them, Ctrl-C, and bad usage.
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
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
    "nodes:\n"
    "  read: {type: test.read_number, params: {path: \"${input}\"}}\n"
    "  double: {type: test.add}\n"
    "  print: {type: test.print, params: {path: \"${out}/${stem}.txt\", write_seconds: \"${write_seconds}\"}}\n"
    "connections:\n"
    "  - {from: read.value, to: double.a}\n"
    "  - {from: read.value, to: double.b}\n"
    "  - {from: double.sum, to: print.value}\n";

struct Setup {
  TempDir dir;
  fs::path graph = dir.write("double.yaml", kDoubleGraph);
  fs::path out = dir / "batch";

  fs::path input(const std::string& name, const std::string& text) { return dir.write("in/" + name, text); }

  Result batch(std::vector<std::string> args) const {
    std::vector<std::string> all{"batch", graph.string(), "--inputs", (dir / "in" / "*.txt").string(), "--out",
                                 out.string(), "--plugin-dir", kTestPlugins};
    all.insert(all.end(), args.begin(), args.end());
    return kinegraph(all);
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

TEST_CASE("batch runs the graph once per input, in parallel, with a log and a manifest line each", "[batch]") {
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
    CHECK(rec["outputs"].size() == 1);
    CHECK(rec["outputs"][0]["path"].as<std::string>() == stem + "/" + stem + ".txt");
    CHECK(rec["outputs"][0]["sha256"].as<std::string>() == kg::graph::sha256_file(output));
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

TEST_CASE("batch resumes: done items are skipped until their input, graph, settings or outputs change", "[batch]") {
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

TEST_CASE("batch with slurm writes an array job and a merge job that, run as Slurm runs them, give the local "
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
  CHECK_THAT(array, Contains("--set 'write_seconds=0'"));
  const fs::path merge_script = s.dir / "jobs" / "double.merge.sbatch";
  CHECK_THAT(read_file(merge_script), Contains(" merge '" + s.out.string() + "'"));
  CHECK(line_count(s.out / "inputs.txt") == 5);
  CHECK_FALSE(fs::exists(s.out / "manifest.jsonl"));  // nothing ran

  for (int task = 0; task < 3; ++task) {
    const Result r = kg::test::run_program("/bin/bash", {script.string()},
                                           {"SLURM_ARRAY_TASK_ID=" + std::to_string(task), "SLURM_CPUS_PER_TASK=1"});
    INFO(show(r));
    REQUIRE(r.code == 0);
  }
  const Result merged = kg::test::run_program("/bin/bash", {merge_script.string()});
  INFO(show(merged));
  REQUIRE(merged.code == 0);
  CHECK_THAT(merged.out, Contains("5 ok, 0 failed, 0 of 5 inputs without a record"));

  // The same batch on this machine alone: byte-identical outputs.
  const fs::path local = s.dir / "local";
  const Result r = kinegraph({"batch", s.graph.string(), "--inputs", (s.dir / "in" / "*.txt").string(), "--out",
                              local.string(), "--plugin-dir", kTestPlugins, "--set", "write_seconds=0"});
  REQUIRE(r.code == 0);
  const auto cluster = manifest_by_item(s.out / "manifest.jsonl");
  const auto here = manifest_by_item(local / "manifest.jsonl");
  REQUIRE(cluster.size() == 5);
  for (const auto& [stem, record] : here) {
    CHECK(cluster.at(stem)["outputs"][0]["sha256"].as<std::string>() ==
          record["outputs"][0]["sha256"].as<std::string>());
    CHECK(read_file(s.out / stem / (stem + ".txt")) == read_file(local / stem / (stem + ".txt")));
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
  const std::vector<std::string> args{"batch", s.graph.string(), "--inputs", (s.dir / "in" / "*.txt").string(),
                                      "--out", s.out.string(), "--plugin-dir", kTestPlugins, "--jobs", "2",
                                      "--set", "write_seconds=3"};

  // In a process group of its own, as a shell runs a job: the terminal's SIGINT reaches all of it.
  std::vector<std::string> argv_text{(fs::path(KG_BINARY_DIR) / "bin" / "kinegraph").string()};
  argv_text.insert(argv_text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_text) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
  posix_spawnattr_setpgroup(&attributes, 0);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const std::string err_file = (s.dir / "stderr.txt").string();
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  REQUIRE(posix_spawn(&pid, argv[0], &actions, &attributes, argv.data(), environ) == 0);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);

  // Wait until both workers are inside their 3 s writes, then interrupt the whole group.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (temporaries(s.dir.path(), false).size() < 2 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  REQUIRE(temporaries(s.dir.path(), false).size() == 2);
  ::kill(-pid, SIGINT);
  int status = 0;
  ::waitpid(pid, &status, 0);
  INFO(read_file(err_file));
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 130);
  CHECK_THAT(read_file(err_file), Contains("interrupted"));
  CHECK(temporaries(s.dir.path()).empty());
  for (int i = 0; i < 4; ++i) CHECK_FALSE(fs::exists(s.out / ("n" + std::to_string(i)) / ("n" + std::to_string(i) + ".txt")));
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
  for (const std::string& arg : {std::string("batch"), s.graph.string(), std::string("--inputs"),
                                 (s.dir / "in" / "*.txt").string(), std::string("--out"), s.out.string(),
                                 std::string("--plugin-dir"), kTestPlugins})
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

  r = kinegraph({"batch", s.graph.string(), "--inputs", (s.dir / "none" / "*.bvh").string(), "--out", s.out.string(),
                 "--plugin-dir", kTestPlugins});
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Contains("matches no file"));

  s.input("a.dat", "3");
  r = kinegraph({"batch", s.graph.string(), "--inputs", (s.dir / "in" / "a.*").string(), "--out", s.out.string(),
                 "--plugin-dir", kTestPlugins});
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Contains("differ only in their extension"));

  r = s.batch({"--shard", "2/2"});
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Contains("--shard expects I/N with 0 <= I < N"));

  r = kinegraph({"batch", s.graph.string(), "--out", s.out.string()});
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Contains("batch needs --inputs"));

  const fs::path no_input = s.dir.write("no_input.yaml", "version: 1\nvariables:\n  out: {default: x}\nnodes: {}\n");
  r = kinegraph({"batch", no_input.string(), "--inputs", (s.dir / "in" / "a.txt").string(), "--out", s.out.string()});
  CHECK(r.code == 3);
  CHECK_THAT(r.err, Contains("declares no variable 'input'"));

  const fs::path broken = s.dir.write("broken.yaml", std::string(kDoubleGraph) + "  - {from: read.nothing, to: print.value}\n");
  r = kinegraph({"batch", broken.string(), "--inputs", (s.dir / "in" / "a.txt").string(), "--out", s.out.string(),
                 "--plugin-dir", kTestPlugins});
  CHECK(r.code == 3);
  CHECK_THAT(r.err, Contains("broken.yaml:"));
  CHECK_FALSE(fs::exists(s.out / "manifest.jsonl"));
}
