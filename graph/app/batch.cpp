#include "batch.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "kg/base/atomic_file.hpp"
#include "kg/base/error.hpp"
#include "kg/graph/executor.hpp"
#include "kg/graph/file_patterns.hpp"
#include "kg/graph/manifest.hpp"
#include "kg/graph/sha256.hpp"
#include "kg/graph/yaml_io.hpp"
#include "slurm.hpp"

namespace kg::app {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// ---- the items ------------------------------------------------------------------------------

struct Item {
  fs::path input;            // absolute
  std::string stem;          // the input's file name without extension
  fs::path name;             // its folders below the inputs' common folder, then the stem
  std::string input_sha256;  // filled when a previous record had to be checked
};

bool valid_utf8(const std::string& text) {
  for (std::size_t i = 0; i < text.size();) {
    const auto c = static_cast<unsigned char>(text[i]);
    const int extra = c < 0x80 ? 0 : (c >> 5) == 0x6 ? 1 : (c >> 4) == 0xe ? 2 : (c >> 3) == 0x1e ? 3 : -1;
    if (extra < 0 || i + extra + 1 > text.size()) return false;
    for (int k = 1; k <= extra; ++k)
      if ((static_cast<unsigned char>(text[i + k]) >> 6) != 0x2) return false;
    i += 1 + extra;
  }
  return true;
}

// The batch's inputs, sorted and each once: files matching --inputs, and the paths of
// --input-list taken as written (relative to the list's folder), which need not exist yet: a
// missing one fails its own item. Files inside DIR are left out (earlier outputs).
std::vector<fs::path> inputs_of(const Options& o, const fs::path& dir) {
  std::vector<fs::path> inputs;
  try {
    if (!o.inputs.empty()) inputs = graph::expand_file_patterns(o.inputs);
  } catch (const std::invalid_argument& e) {
    throw Failure{kExitUsage, e.what()};
  }
  if (!o.input_list.empty()) {
    std::ifstream in(o.input_list);
    if (!in) throw Failure{kExitUsage, "--input-list " + o.input_list.string() + ": cannot open it"};
    const fs::path base = fs::absolute(o.input_list).parent_path();
    std::string line;
    while (std::getline(in, line)) {
      const auto first = line.find_first_not_of(" \t\r");
      if (first == std::string::npos || line[first] == '#') continue;
      line = line.substr(first, line.find_last_not_of(" \t\r") + 1 - first);
      inputs.push_back((fs::path(line).is_absolute() ? fs::path(line) : base / line).lexically_normal());
    }
  }
  if (inputs.empty())
    throw Failure{kExitUsage, "no inputs: --input-list " + o.input_list.string() + " lists none"};
  std::sort(inputs.begin(), inputs.end());
  inputs.erase(std::unique(inputs.begin(), inputs.end()), inputs.end());
  std::vector<fs::path> kept;
  for (const fs::path& input : inputs) {
    const fs::path inside = input.lexically_relative(dir);
    if (!dir.empty() && !inside.empty() && *inside.begin() != "..") continue;
    if (!valid_utf8(input.string())) {
      throw Failure{kExitUsage,
                    "input " + input.string() +
                        ": its name is not UTF-8, which the JSON manifest cannot record: rename it"};
    }
    kept.push_back(input);
  }
  if (kept.empty())
    throw Failure{kExitUsage, "no input left: every file given is inside --out " + dir.string()};
  return kept;
}

fs::path common_folder(const std::vector<fs::path>& inputs) {
  if (inputs.empty()) return {};
  fs::path common = inputs.front().parent_path();
  for (const fs::path& input : inputs) {
    while (!common.empty() && common != common.root_path()) {
      const fs::path relative = input.parent_path().lexically_relative(common);
      if (!relative.empty() && *relative.begin() != "..") break;
      common = common.parent_path();
    }
  }
  return common;
}

// Item folders and logs mirror the inputs' folders below their common folder, so that
// walk.bvh of subject01/ and of subject02/ each have their own (subject01/walk, subject02/walk);
// inputs of one folder differing only in extension would share one and are refused.
std::vector<Item> items_of(const std::vector<fs::path>& inputs) {
  const fs::path common = common_folder(inputs);
  std::vector<Item> items;
  std::map<fs::path, fs::path> by_name;
  for (const fs::path& input : inputs) {
    const std::string stem = input.stem().string();
    const fs::path name = input.parent_path().lexically_relative(common) / stem;
    const auto [it, fresh] = by_name.emplace(name.lexically_normal(), input);
    if (!fresh) {
      throw Failure{kExitUsage,
                    "inputs " + it->second.string() + " and " + input.string() + " differ only in " +
                        "their extension, so their outputs and logs would collide: batch them separately"};
    }
    items.push_back({input, stem, name.lexically_normal(), {}});
  }
  return items;
}

std::vector<Item> shard_of(std::vector<Item> items, const std::optional<Shard>& shard) {
  if (!shard) return items;
  std::vector<Item> mine;
  for (std::size_t i = static_cast<std::size_t>(shard->index); i < items.size(); i += shard->count)
    mine.push_back(std::move(items[i]));
  return mine;
}

std::string shard_text(const std::optional<Shard>& shard) {
  return shard ? std::to_string(shard->index) + "/" + std::to_string(shard->count) : "";
}

fs::path manifest_path(const fs::path& dir, const std::optional<Shard>& shard) {
  if (!shard) return dir / "manifest.jsonl";
  return dir / ("manifest.shard-" + std::to_string(shard->index) + "-of-" + std::to_string(shard->count) +
                ".jsonl");
}

// Every record in DIR's manifests (the batch's own and its shards'), in file name order.
std::vector<graph::ManifestRecord> read_manifests(const fs::path& dir) {
  std::vector<fs::path> files;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind("manifest", 0) == 0 && it->path().extension() == ".jsonl") files.push_back(it->path());
  }
  std::sort(files.begin(), files.end());
  std::vector<graph::ManifestRecord> records;
  std::vector<std::string> problems;
  for (const fs::path& file : files) {
    std::vector<graph::ManifestRecord> more = graph::read_manifest(file, problems);
    records.insert(records.end(), std::make_move_iterator(more.begin()), std::make_move_iterator(more.end()));
  }
  for (const std::string& problem : problems) warn(problem);
  return records;
}

// The shards DIR's manifests name (manifest.shard-K-of-N.jsonl) that wrote none: "1/3" for a
// shard 1 of 3 whose siblings ran but which did not.
std::vector<std::string> shards_without_manifest(const fs::path& dir) {
  std::map<int, std::set<int>> ran;  // count -> indices with a manifest
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    int index = -1, count = 0, used = 0;
    const std::string name = it->path().filename().string();
    if (std::sscanf(name.c_str(), "manifest.shard-%d-of-%d.jsonl%n", &index, &count, &used) == 2 &&
        used == static_cast<int>(name.size()) && index >= 0 && index < count)
      ran[count].insert(index);
  }
  std::vector<std::string> missing;
  for (const auto& [count, indices] : ran)
    for (int k = 0; k < count; ++k)
      if (!indices.count(k)) missing.push_back(std::to_string(k) + "/" + std::to_string(count));
  return missing;
}

// A shard writes every input of its batch to DIR/inputs.txt (as --slurm does), so that merge can
// name the inputs no shard recorded; shards given other inputs than that list are refused.
void record_batch_inputs(const fs::path& list, const std::vector<Item>& all) {
  std::string text;
  for (const Item& item : all) text += item.input.string() + '\n';
  std::error_code ec;
  if (fs::exists(list, ec)) {
    if (kg::read_input_file(list, "input list") == text) return;
    throw Failure{kExitUsage, list.string() +
                                  " lists other inputs than this shard was given: every shard of a batch "
                                  "takes the same inputs (use another --out, or remove that file to start "
                                  "the batch anew)"};
  }
  kg::write_file_atomically(list, [&](std::ostream& os) { os << text; });
}

std::string relative_to(const fs::path& path, const fs::path& dir) {
  const fs::path relative = path.lexically_relative(dir);
  if (!relative.empty() && *relative.begin() != "..") return relative.generic_string();
  return path.string();
}

// ---- what every item shares ------------------------------------------------------------------

struct Batch {
  explicit Batch(const Options& options) : o(options) {}
  const Options& o;
  fs::path graph;  // absolute
  fs::path dir;    // absolute
  bool declares_stem = false, declares_out = false;
  std::string graph_sha256, settings_sha256;
  std::string host_name;
  std::string shard;

  std::map<std::string, std::string> variables(const Item& item) const {
    std::map<std::string, std::string> sets = o.sets;
    sets["input"] = item.input.string();
    if (declares_stem) sets["stem"] = item.stem;
    if (declares_out) sets["out"] = (dir / item.name).string();
    return sets;
  }
  fs::path log(const Item& item) const { return dir / "logs" / (item.name.string() + ".log"); }
  // Beside the log, named after the process writing it: renamed over the log when the item ends.
  fs::path partial_log(const Item& item, pid_t pid) const {
    return log(item).parent_path() / ("." + item.stem + ".log.tmp." + std::to_string(pid));
  }
};

// An item done before counts as done when nothing it depends on changed (the graph, the
// settings, and every file it read: the input, a skeleton, a target, ...) and its outputs are
// still there with their recorded content.
bool still_done(const graph::ManifestRecord& r, Item& item, const Batch& b) {
  if (!r.ok() || r.graph_sha256 != b.graph_sha256 || r.settings_sha256 != b.settings_sha256) return false;
  auto unchanged = [&](const graph::ManifestFile& file) {
    if (file.path == r.input) return true;  // compared by input_sha256 below, not hashed twice
    const fs::path path = fs::path(file.path).is_absolute() ? fs::path(file.path) : b.dir / file.path;
    std::error_code ec;
    if (fs::file_size(path, ec) != file.bytes || ec) return false;
    try {
      return graph::sha256_file(path) == file.sha256;
    } catch (const std::exception&) {
      return false;
    }
  };
  try {
    item.input_sha256 = graph::sha256_file(item.input);
  } catch (const std::exception&) {
    return false;
  }
  return r.input_sha256 == item.input_sha256 && std::all_of(r.reads.begin(), r.reads.end(), unchanged) &&
         std::all_of(r.outputs.begin(), r.outputs.end(), unchanged);
}

// ---- one item, in its own process ----------------------------------------------------------------

// What stops a batch and its items: Ctrl-C, kill and scancel, a closed terminal.
constexpr int kStopSignals[] = {SIGINT, SIGTERM, SIGHUP};

// For the signal handler: the item's partial log, removed with the partial outputs.
char g_partial_log[4096];

extern "C" void item_interrupted(int sig) {
  kg::remove_pending_temporaries();
  kg::remove_written_files();
  if (g_partial_log[0]) ::unlink(g_partial_log);
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

bool write_all(int fd, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

[[noreturn]] void run_item(Host& host, const Batch& b, const Item& item, int result_fd) {
  const Clock::time_point start = Clock::now();
  const fs::path partial = b.partial_log(item, ::getpid());
  std::error_code ec;
  fs::create_directories(partial.parent_path(), ec);
  std::snprintf(g_partial_log, sizeof g_partial_log, "%s", partial.c_str());
  struct sigaction action {};
  action.sa_handler = item_interrupted;
  ::sigemptyset(&action.sa_mask);
  for (int sig : kStopSignals) ::sigaction(sig, &action, nullptr);

  const int log_fd = ::open(partial.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log_fd >= 0) {
    ::dup2(log_fd, STDOUT_FILENO);
    ::dup2(log_fd, STDERR_FILENO);
    ::close(log_fd);
  }
  const int null_fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  if (null_fd >= 0) ::dup2(null_fd, STDIN_FILENO);

  graph::ManifestRecord r;
  r.input = item.input.string();
  r.stem = item.stem;
  r.item = item.name.generic_string();
  r.log = relative_to(b.log(item), b.dir);
  r.graph_sha256 = b.graph_sha256;
  r.settings_sha256 = b.settings_sha256;
  r.host = b.host_name;
  r.shard = b.shard;
  try {
    r.input_sha256 = item.input_sha256.empty() ? graph::sha256_file(item.input) : item.input_sha256;
    const std::map<std::string, std::string> sets = b.variables(item);
    std::cerr << "kinegraph batch: " << b.graph.string() << " on " << r.input << '\n';
    if (graph::sha256_file(b.graph) != b.graph_sha256) {
      throw Failure{kExitGraphInvalid, b.graph.string() +
                                           " changed after the batch started (edited?), so this item "
                                           "would run another graph: run the batch again"};
    }
    for (const auto& [name, value] : sets) std::cerr << "  " << name << " = " << value << '\n';
    const graph::Graph g = load_graph(host, b.graph, sets);
    graph::RunOptions options;
    options.reproducible = true;
    options.keep_outputs =
        false;  // the sinks have written the files: free each value after its last consumer
    options.on_log = [](const std::string& node, const std::string& message) {
      std::cerr << node << ": " << message << '\n';
    };
    const graph::RunResult result = graph::run_graph(g, host.registry, options);
    r.graph_seconds = result.wall_seconds;
    for (const graph::NodeRun& n : result.nodes) {
      for (const auto& [key, figure] : n.figures) r.figures.emplace_back(n.id + "." + key, figure);
    }
    const std::vector<std::string> failures = node_failures(g, result);
    for (const std::string& failure : failures) {
      std::cerr << failure << '\n';
      r.message += (r.message.empty() ? "" : "; ") + failure;
    }
    if (!result.ok && failures.empty()) r.message = "nodes were skipped";
    r.status = result.ok ? "ok" : "failed";
  } catch (const Failure& f) {
    r.status = "failed";
    r.message = f.message;
  } catch (const std::exception& e) {
    r.status = "failed";
    r.message = e.what();
  }
  auto record_file = [&](const fs::path& file, std::vector<graph::ManifestFile>& files) {
    graph::ManifestFile entry;
    entry.path = relative_to(fs::absolute(file).lexically_normal(), b.dir);
    for (const graph::ManifestFile& known : files)
      if (known.path == entry.path) return;  // written twice
    try {
      // The input was hashed before the run.
      entry.sha256 =
          entry.path == r.input && !r.input_sha256.empty() ? r.input_sha256 : graph::sha256_file(file);
      entry.bytes = fs::file_size(file);
    } catch (const std::exception& e) {
      r.status = "failed";
      r.message += std::string(r.message.empty() ? "" : "; ") + e.what();
    }
    files.push_back(std::move(entry));
  };
  for (const fs::path& written : kg::written_files()) record_file(written, r.outputs);
  for (const fs::path& read : kg::input_files_read())
    if (read != b.graph) record_file(read, r.reads);
  r.wall_seconds = since(start);
  r.finished_at = graph::utc_timestamp();
  std::cerr << "kinegraph batch: " << r.status << " in " << seconds(r.wall_seconds)
            << (r.message.empty() ? "" : ": " + r.message) << '\n';
  std::cout.flush();
  std::cerr.flush();
  // Done: a stop signal from now on would remove outputs the record below vouches for.
  sigset_t stop_signals;
  ::sigemptyset(&stop_signals);
  for (int sig : kStopSignals) ::sigaddset(&stop_signals, sig);
  ::sigprocmask(SIG_BLOCK, &stop_signals, nullptr);
  fs::rename(partial, b.log(item), ec);
  g_partial_log[0] = 0;
  const bool sent = write_all(result_fd, graph::manifest_line(r) + "\n");
  ::_exit(sent ? 0 : 1);
}

// ---- the parent: scheduling, progress, signals ----------------------------------------------------

// The flag is what counts; the pipe only wakes poll().
volatile sig_atomic_t g_interrupted = 0;
int g_signal_pipe[2] = {-1, -1};

extern "C" void batch_interrupted(int sig) {
  g_interrupted = 1;
  const unsigned char byte = static_cast<unsigned char>(sig);
  [[maybe_unused]] const ssize_t n = ::write(g_signal_pipe[1], &byte, 1);
}

std::string clock_text(double s) {
  const long total = std::lround(std::max(0.0, s));
  std::ostringstream os;
  if (total >= 3600)
    os << total / 3600 << ':' << std::setw(2) << std::setfill('0') << (total / 60) % 60;
  else
    os << total / 60;
  os << ':' << std::setw(2) << std::setfill('0') << total % 60;
  return os.str();
}

// Done/failed counts, rate and ETA: a redrawn bar on a terminal, one line per item otherwise.
class Progress {
 public:
  Progress(std::size_t total, bool terminal) : total_(total), terminal_(terminal), start_(Clock::now()) {}

  void item_done(const graph::ManifestRecord& r, const fs::path& dir) {
    ++done_;
    failed_ += !r.ok();
    if (!terminal_) {
      std::cerr << "[" << done_ << "/" << total_ << "] " << (r.ok() ? "ok" : "FAILED") << ' ' << r.item
                << " (" << seconds(r.wall_seconds) << ")"
                << (r.ok() ? "" : ": " + r.message + " (log: " + (dir / r.log).string() + ")") << " · "
                << failed_ << " failed · " << rate_text() << '\n';
      return;
    }
    if (!r.ok()) {
      std::cerr << "\r\x1b[K"
                << "FAILED " << r.item << ": " << r.message << " (log: " << (dir / r.log).string() << ")\n";
    }
    draw();
  }

  void tick() {
    if (terminal_ && since(last_draw_) > 0.2) draw();
  }

  void finish() {
    if (terminal_ && drawn_) std::cerr << "\r\x1b[K" << std::flush;
  }

 private:
  std::string rate_text() const {
    const double elapsed = since(start_);
    const double rate = elapsed > 0 ? done_ / elapsed : 0;
    std::ostringstream os;
    os << std::fixed << std::setprecision(rate < 10 ? 2 : 1) << rate << " items/s · ETA ";
    os << (done_ > 0 ? clock_text((total_ - done_) / rate) : std::string("?"));
    return os.str();
  }

  void draw() {
    constexpr int kWidth = 30;
    const int filled = total_ ? static_cast<int>(kWidth * done_ / total_) : kWidth;
    std::cerr << "\r\x1b[K[" << std::string(filled, '#') << std::string(kWidth - filled, '.') << "] " << done_
              << '/' << total_ << " · " << failed_ << " failed · " << rate_text() << std::flush;
    drawn_ = true;
    last_draw_ = Clock::now();
  }

  std::size_t total_, done_ = 0, failed_ = 0;
  bool terminal_, drawn_ = false;
  Clock::time_point start_, last_draw_ = Clock::now();
};

struct Running {
  pid_t pid;
  int fd;
  const Item* item;
  std::string output;
};

std::string signal_name(int sig) {
  const char* text = ::strsignal(sig);
  return "signal " + std::to_string(sig) + (text ? std::string(" (") + text + ")" : "");
}

int cores_available() {
  cpu_set_t set;
  if (::sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
  return static_cast<int>(std::max(1L, ::sysconf(_SC_NPROCESSORS_ONLN)));
}

struct Outcome {
  std::vector<graph::ManifestRecord> records;
  std::size_t interrupted = 0;
  bool stopped = false;
};

// Removes what a worker that died by a signal (SIGKILL from the OOM killer or Slurm) left in its
// item's folder: the temporaries of its writes in progress, named ".NAME.tmp.PID.N".
void sweep_temporaries(const fs::path& folder, pid_t pid) {
  const std::string mark = ".tmp." + std::to_string(pid) + ".";
  std::error_code ec;
  for (fs::recursive_directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.front() == '.' && name.find(mark) != std::string::npos) fs::remove(it->path(), ec);
  }
}

// Outputs already claimed, by path as recorded: two items writing one file would overwrite
// each other (a --set output=... common to all, or two batches' items sharing a folder).
using Claims = std::map<std::string, std::string>;  // output path -> input

// The batch's handlers of kStopSignals, and the pipe through which they wake poll(), for as long
// as it lives; the handlers found before are put back when it ends.
class StopSignals {
 public:
  StopSignals() {
    g_interrupted = 0;
    if (::pipe2(g_signal_pipe, O_CLOEXEC | O_NONBLOCK) != 0)
      throw Failure{kExitNodeFailed, std::string("cannot create a pipe: ") + std::strerror(errno)};
    struct sigaction action {};
    action.sa_handler = batch_interrupted;
    ::sigemptyset(&action.sa_mask);
    for (std::size_t i = 0; i < std::size(kStopSignals); ++i)
      ::sigaction(kStopSignals[i], &action, &previous_[i]);
    ::sigemptyset(&set_);
    for (int sig : kStopSignals) ::sigaddset(&set_, sig);
  }
  ~StopSignals() {
    for (std::size_t i = 0; i < std::size(kStopSignals); ++i)
      ::sigaction(kStopSignals[i], &previous_[i], nullptr);
    ::close(g_signal_pipe[0]);
    ::close(g_signal_pipe[1]);
  }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  // Blocked around fork, so that a new item never runs with the batch's handlers.
  const sigset_t& set() const { return set_; }

 private:
  struct sigaction previous_[std::size(kStopSignals)];
  sigset_t set_;
};

bool stderr_is_terminal() {
  const char* term = std::getenv("TERM");
  return ::isatty(STDERR_FILENO) && term && std::string(term) != "dumb";
}

// The items to do, up to `jobs` processes at once: each forked to run_item, its manifest line read
// back through a pipe, and recorded as it ends (the manifest, the progress, the outputs claimed).
class Workers {
 public:
  Workers(Host& host, const Batch& b, const std::vector<Item*>& todo, int jobs, int manifest_fd,
          Claims& claims, const StopSignals& signals)
      : host_(host),
        b_(b),
        todo_(todo),
        jobs_(jobs),
        manifest_fd_(manifest_fd),
        claims_(claims),
        signals_(signals),
        progress_(todo.size(), stderr_is_terminal()) {}

  Outcome run() {
    try {
      std::vector<pollfd> polled;
      while (true) {
        if (g_interrupted) stop();
        start_items();
        if (running_.empty()) break;
        const int ready = wait(polled);
        if (g_interrupted) stop();
        collect(polled, ready);
        progress_.tick();
      }
    } catch (...) {
      // Leave no worker behind: stop them, and keep the records of those that had finished.
      progress_.finish();
      abandon();
      throw;
    }
    progress_.finish();
    return std::move(outcome_);
  }

 private:
  void start_items() {
    while (!outcome_.stopped && running_.size() < static_cast<std::size_t>(jobs_) && next_ < todo_.size()) {
      start(*todo_[next_]);
      ++next_;
    }
  }

  // Forks the process of one item; it writes its manifest line into a pipe of its own.
  void start(const Item& item) {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0)
      throw Failure{kExitNodeFailed, std::string("cannot create a pipe: ") + std::strerror(errno)};
    std::cout.flush();
    std::cerr.flush();
    sigset_t unblocked;
    ::sigprocmask(SIG_BLOCK, &signals_.set(), &unblocked);
    const pid_t pid = ::fork();
    if (pid < 0) {
      const int error = errno;
      ::sigprocmask(SIG_SETMASK, &unblocked, nullptr);
      ::close(fds[0]);
      ::close(fds[1]);
      throw Failure{kExitNodeFailed, std::string("cannot start a process: ") + std::strerror(error)};
    }
    if (pid == 0) {
      for (int sig : kStopSignals) ::signal(sig, SIG_DFL);
      ::sigprocmask(SIG_SETMASK, &unblocked, nullptr);
      ::close(fds[0]);
      ::close(g_signal_pipe[0]);
      ::close(g_signal_pipe[1]);
      if (manifest_fd_ >= 0) ::close(manifest_fd_);
      for (const Running& other : running_) ::close(other.fd);
      kg::forget_files_of_parent_process();  // the shard's inputs.txt is no item's output
      run_item(host_, b_, item, fds[1]);
    }
    ::sigprocmask(SIG_SETMASK, &unblocked, nullptr);
    ::close(fds[1]);
    running_.push_back({pid, fds[0], &item, {}});
  }

  // Up to 200 ms for a worker's output or a stop signal. `polled`: the signal pipe, then one per
  // running worker. Returns how many are ready.
  int wait(std::vector<pollfd>& polled) {
    polled.clear();
    polled.push_back({g_signal_pipe[0], POLLIN, 0});
    for (const Running& r : running_) polled.push_back({r.fd, POLLIN, 0});
    const int ready = ::poll(polled.data(), polled.size(), 200);
    if (ready < 0 && errno != EINTR)
      throw Failure{kExitNodeFailed, std::string("poll: ") + std::strerror(errno)};
    if (ready > 0 && (polled[0].revents & POLLIN)) {
      unsigned char sig[16];
      while (::read(g_signal_pipe[0], sig, sizeof sig) > 0) {
      }
    }
    return ready;
  }

  // Reads what the ready workers wrote; one whose pipe closed has ended: reaped and recorded.
  void collect(const std::vector<pollfd>& polled, int ready) {
    for (std::size_t i = running_.size(); ready > 0 && i-- > 0;) {
      if (!(polled[i + 1].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      char buffer[4096];
      const ssize_t n = ::read(running_[i].fd, buffer, sizeof buffer);
      if (n > 0) {
        running_[i].output.append(buffer, static_cast<std::size_t>(n));
        continue;
      }
      if (n < 0 && errno == EINTR) continue;
      ::close(running_[i].fd);
      int status = 0;
      while (::waitpid(running_[i].pid, &status, 0) < 0 && errno == EINTR) {
      }
      finish(running_[i], status);
      running_.erase(running_.begin() + static_cast<std::ptrdiff_t>(i));
    }
  }

  void finish(const Running& r, int status) {
    std::optional<graph::ManifestRecord> record = record_of(r, status);
    if (!record) {
      ++outcome_.interrupted;
      return;
    }
    refuse_claimed_outputs(*record);
    if (manifest_fd_ >= 0 && !write_all(manifest_fd_, graph::manifest_line(*record) + "\n"))
      warn("cannot append to the manifest: " + std::string(std::strerror(errno)));
    progress_.item_done(*record, b_.dir);
    outcome_.records.push_back(std::move(*record));
  }

  // The line the worker wrote, or a failed record saying how it ended; none when it was stopped
  // from outside (Ctrl-C reaches the whole process group, Slurm's scancel every process of the
  // job): not the item's fault, so the next run does it again.
  std::optional<graph::ManifestRecord> record_of(const Running& r, int status) const {
    graph::ManifestRecord record;
    bool have = false;
    if (!r.output.empty() && r.output.back() == '\n') {
      try {
        record = graph::parse_manifest_line(r.output);
        have = true;
      } catch (const std::exception& e) {
        record.message = std::string("its report could not be read: ") + e.what();
      }
    }
    if (have) return record;
    const fs::path partial = b_.partial_log(*r.item, r.pid);
    std::error_code ec;
    if (WIFSIGNALED(status)) sweep_temporaries(b_.dir / r.item->name, r.pid);
    if (WIFSIGNALED(status) && std::find(std::begin(kStopSignals), std::end(kStopSignals),
                                         WTERMSIG(status)) != std::end(kStopSignals)) {
      fs::remove(partial, ec);
      return std::nullopt;
    }
    record.input = r.item->input.string();
    record.stem = r.item->stem;
    record.item = r.item->name.generic_string();
    record.status = "failed";
    if (record.message.empty()) {
      record.message = WIFSIGNALED(status) ? "its process died of " + signal_name(WTERMSIG(status))
                                           : "its process exited with code " +
                                                 std::to_string(WEXITSTATUS(status)) + " before reporting";
    }
    record.log = relative_to(b_.log(*r.item), b_.dir);
    record.graph_sha256 = b_.graph_sha256;
    record.settings_sha256 = b_.settings_sha256;
    record.host = b_.host_name;
    record.shard = b_.shard;
    record.finished_at = graph::utc_timestamp();
    if (fs::exists(partial, ec)) fs::rename(partial, b_.log(*r.item), ec);
    return record;
  }

  // An output another item of the batch also wrote fails this one.
  void refuse_claimed_outputs(graph::ManifestRecord& record) {
    for (const graph::ManifestFile& output : record.outputs) {
      const auto [claim, fresh] = claims_.emplace(output.path, record.input);
      if (fresh || claim->second == record.input) continue;
      record.status = "failed";
      record.message += std::string(record.message.empty() ? "" : "; ") + "it wrote " + output.path +
                        ", which " + claim->second +
                        " also writes: the items overwrite each other's outputs (give each its " +
                        "own ${out}, or this batch another --out)";
    }
  }

  // Ctrl-C or SIGTERM: no more items start, and the running ones are stopped.
  void stop() {
    if (outcome_.stopped) return;
    outcome_.stopped = true;
    progress_.finish();
    std::cerr << "kinegraph: batch: interrupted; stopping " << running_.size()
              << " running item(s) and removing their partial outputs\n";
    for (const Running& r : running_) ::kill(r.pid, SIGTERM);
  }

  void abandon() {
    for (Running& r : running_) {
      ::kill(r.pid, SIGTERM);
      ::close(r.fd);
      int status = 0;
      while (::waitpid(r.pid, &status, 0) < 0 && errno == EINTR) {
      }
      sweep_temporaries(b_.dir / r.item->name, r.pid);
    }
  }

  Host& host_;
  const Batch& b_;
  const std::vector<Item*>& todo_;
  int jobs_;
  int manifest_fd_;  // -1: none
  Claims& claims_;
  const StopSignals& signals_;
  Progress progress_;
  std::vector<Running> running_;
  std::size_t next_ = 0;  // the next of todo_ to start
  Outcome outcome_;
};

Outcome run_items(Host& host, const Batch& b, const std::vector<Item*>& todo, int jobs, int manifest_fd,
                  Claims& claims) {
  const StopSignals signals;
  return Workers(host, b, todo, jobs, manifest_fd, claims, signals).run();
}

// One line per item: this batch's items in order, then any other record the folder holds.
void compact_manifest(const fs::path& file, const std::vector<graph::ManifestRecord>& records,
                      const std::vector<Item>& items, bool keep_others) {
  const std::vector<graph::ManifestRecord> latest = graph::latest_records(records);
  std::map<std::string, const graph::ManifestRecord*> by_input;
  for (const graph::ManifestRecord& r : latest) by_input[r.input] = &r;
  kg::write_file_atomically(file, [&](std::ostream& os) {
    std::set<std::string> written;
    for (const Item& item : items) {
      const auto it = by_input.find(item.input.string());
      if (it == by_input.end()) continue;
      os << graph::manifest_line(*it->second) << '\n';
      written.insert(it->first);
    }
    if (!keep_others) return;
    for (const auto& [input, record] : by_input)
      if (!written.count(input)) os << graph::manifest_line(*record) << '\n';
  });
}

// One process writes a manifest at a time: a second batch into the same DIR (or shard) would
// append to a file the first one replaces when it compacts, losing records.
class ManifestLock {
 public:
  ManifestLock(const fs::path& manifest, const std::string& host) {
    const fs::path file = manifest.parent_path() / ("." + manifest.filename().string() + ".lock");
    fd_ = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw Failure{kExitUsage, file.string() + ": cannot open it: " + std::strerror(errno)};
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      char holder[256] = {};
      [[maybe_unused]] const ssize_t n = ::pread(fd_, holder, sizeof holder - 1, 0);
      ::close(fd_);
      throw Failure{kExitUsage, "another batch (" + std::string(holder) + ") is writing " +
                                    manifest.string() + ": wait for it, or give this one another --out"};
    }
    const std::string me = "pid " + std::to_string(::getpid()) + " on " + host;
    if (::ftruncate(fd_, 0) == 0) write_all(fd_, me);
  }
  ~ManifestLock() { ::close(fd_); }
  ManifestLock(const ManifestLock&) = delete;
  ManifestLock& operator=(const ManifestLock&) = delete;

 private:
  int fd_ = -1;
};

// For appending one line per record. A file edited by hand may lack its last newline: one is
// added first, so the next record starts a line of its own.
int open_for_appending(const fs::path& manifest) {
  const int fd = ::open(manifest.c_str(), O_RDWR | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) throw Failure{kExitUsage, manifest.string() + ": cannot open it: " + std::strerror(errno)};
  const off_t size = ::lseek(fd, 0, SEEK_END);
  char last = '\n';
  if (size > 0 && ::pread(fd, &last, 1, size - 1) == 1 && last != '\n') write_all(fd, "\n");
  return fd;
}

std::string this_host() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0) return "";
  return name;
}

}  // namespace

int batch(Host& host, const Options& o, const char* argv0) {
  const Clock::time_point start = Clock::now();
  Batch b(o);
  b.graph = fs::absolute(o.graph).lexically_normal();
  b.dir = fs::absolute(o.out).lexically_normal();
  b.shard = shard_text(o.shard);
  b.host_name = this_host();

  std::error_code ec;
  if (!fs::is_regular_file(b.graph, ec))
    throw Failure{kExitGraphInvalid, o.graph.string() + ": no such graph file"};
  std::vector<graph::Variable> declared;
  try {
    declared = graph::read_graph_variables(b.graph);
  } catch (const std::exception& e) {
    throw Failure{kExitGraphInvalid, e.what()};
  }
  auto declares = [&](const std::string& name) {
    return std::any_of(declared.begin(), declared.end(),
                       [&](const graph::Variable& v) { return v.name == name; });
  };
  if (!declares("input")) {
    throw Failure{kExitGraphInvalid,
                  o.graph.string() +
                      ": declares no variable 'input', so it cannot run once per input file "
                      "(batch gives each item the variables input, stem and out)"};
  }
  b.declares_stem = declares("stem");
  b.declares_out = declares("out");

  const std::vector<Item> all = items_of(inputs_of(o, b.dir));
  if (!b.declares_out && all.size() > 1) {
    throw Failure{kExitGraphInvalid,
                  o.graph.string() +
                      ": declares no variable 'out', so every item would write the same outputs; "
                      "declare it and default the outputs from it (output: ${out}/${stem}.bvh)"};
  }
  // The whole graph is checked once, on the first item, before anything runs or is submitted.
  load_graph(host, b.graph, b.variables(all.front()));
  b.graph_sha256 = graph::sha256_file(b.graph);
  std::vector<std::pair<std::string, std::string>> settings(o.sets.begin(), o.sets.end());
  b.settings_sha256 = graph::settings_sha256(settings);
  const fs::path identity_file = b.dir / "batch.json";

  if (!o.slurm.empty()) {
    std::vector<fs::path> inputs;
    for (const Item& item : all) inputs.push_back(item.input);
    fs::create_directories(b.dir, ec);
    graph::write_batch_identity(identity_file, {b.graph.string(), b.graph_sha256, b.settings_sha256});
    return write_slurm_jobs(o, b.graph, b.dir, inputs, executable_path(argv0));
  }
  // An array task of jobs written by --slurm runs the batch they were written for, or nothing.
  if (o.shard && !o.input_list.empty() &&
      fs::absolute(o.input_list).lexically_normal() == b.dir / "inputs.txt" &&
      fs::exists(identity_file, ec)) {
    graph::BatchIdentity expected;
    try {
      expected = graph::read_batch_identity(identity_file);
    } catch (const std::exception& e) {
      throw Failure{kExitUsage, e.what()};
    }
    if (expected.graph_sha256 != b.graph_sha256 || expected.settings_sha256 != b.settings_sha256) {
      throw Failure{kExitGraphInvalid, o.graph.string() +
                                           " or the --set values changed since the Slurm jobs were "
                                           "written (" +
                                           identity_file.string() + "): write and submit them again"};
    }
  }

  std::vector<Item> items = shard_of(all, o.shard);
  fs::create_directories(b.dir / "logs", ec);
  if (ec) throw Failure{kExitUsage, "--out " + o.out.string() + ": cannot create it: " + ec.message()};
  const fs::path manifest = manifest_path(b.dir, o.shard);
  const ManifestLock lock(manifest, b.host_name);
  if (o.shard) record_batch_inputs(b.dir / "inputs.txt", all);

  std::vector<graph::ManifestRecord> records = read_manifests(b.dir);
  const std::vector<graph::ManifestRecord> latest = graph::latest_records(records);
  std::map<std::string, const graph::ManifestRecord*> previous;
  for (const graph::ManifestRecord& r : latest) previous[r.input] = &r;

  std::vector<Item*> todo;
  for (Item& item : items) {
    const auto it = previous.find(item.input.string());
    if (o.force || it == previous.end() || !still_done(*it->second, item, b)) todo.push_back(&item);
  }
  // The outputs of items not run now stay theirs.
  std::set<std::string> running_now;
  for (const Item* item : todo) running_now.insert(item->input.string());
  Claims claims;
  for (const graph::ManifestRecord& r : latest) {
    if (!r.ok() || running_now.count(r.input)) continue;
    for (const graph::ManifestFile& output : r.outputs) claims.emplace(output.path, r.input);
  }
  // Largest inputs first: the items still running when the others are done are then short ones,
  // which keeps every worker busy to the end (longest-processing-time-first scheduling).
  std::map<const Item*, std::uintmax_t> sizes;
  for (const Item* item : todo) sizes[item] = fs::file_size(item->input, ec);
  std::stable_sort(todo.begin(), todo.end(),
                   [&](const Item* a, const Item* b) { return sizes[a] > sizes[b]; });
  const int jobs = o.jobs_given ? o.jobs : cores_available();
  const std::size_t skipped = items.size() - todo.size();
  std::cerr << "kinegraph: batch: " << items.size() << " item(s)" << (o.shard ? " in shard " + b.shard : "")
            << ", " << skipped << " already done, " << todo.size() << " to run";
  if (!todo.empty()) std::cerr << " on " << std::min<std::size_t>(jobs, todo.size()) << " worker(s)";
  std::cerr << "; output in " << b.dir.string() << '\n';

  const int manifest_fd = open_for_appending(manifest);
  Outcome outcome;
  try {
    outcome = run_items(host, b, todo, jobs, manifest_fd, claims);
  } catch (...) {
    ::close(manifest_fd);
    throw;
  }
  ::close(manifest_fd);
  records.insert(records.end(), outcome.records.begin(), outcome.records.end());
  compact_manifest(manifest, records, items, !o.shard);

  std::size_t failed = 0;
  for (const graph::ManifestRecord& r : outcome.records) failed += !r.ok();
  const double wall = since(start);
  std::cout << "kinegraph: batch: " << outcome.records.size() << " ran (" << outcome.records.size() - failed
            << " ok, " << failed << " failed), " << skipped << " already done";
  if (outcome.records.size() < todo.size())
    std::cout << ", " << todo.size() - outcome.records.size() << " not run";
  std::cout << " in " << seconds(wall) << "; manifest " << manifest.string() << '\n';
  if (failed) {
    std::cerr << "kinegraph: batch: " << failed << " item(s) failed:\n";
    for (const graph::ManifestRecord& r : outcome.records)
      if (!r.ok())
        std::cerr << "  " << r.input << ": " << r.message << " (log: " << (b.dir / r.log).string() << ")\n";
  }
  if (outcome.stopped) {
    std::cerr << "kinegraph: batch: interrupted; the same command continues where this one stopped\n";
    return kExitInterrupted;
  }
  if (outcome.interrupted) {
    std::cerr << "kinegraph: batch: " << outcome.interrupted
              << " item(s) were stopped by a signal from outside; the same command runs them again\n";
    return kExitNodeFailed;
  }
  return failed ? kExitNodeFailed : kExitOk;
}

int merge(const Options& o) {
  const fs::path dir = fs::absolute(o.out).lexically_normal();
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw Failure{kExitUsage, "merge: " + o.out.string() + ": no such folder"};
  const fs::path manifest = dir / "manifest.jsonl";
  const ManifestLock lock(manifest, this_host());
  const std::vector<graph::ManifestRecord> records = read_manifests(dir);
  std::vector<Item> expected;
  if (fs::exists(dir / "inputs.txt", ec)) {
    Options listed;
    listed.input_list = dir / "inputs.txt";
    expected = items_of(inputs_of(listed, {}));
  }
  std::optional<graph::BatchIdentity> identity;
  if (fs::exists(dir / "batch.json", ec)) {
    try {
      identity = graph::read_batch_identity(dir / "batch.json");
    } catch (const std::exception& e) {
      throw Failure{kExitUsage, std::string("merge: ") + e.what()};
    }
  }
  const std::vector<graph::ManifestRecord> latest = graph::latest_records(records);
  if (latest.empty() && expected.empty())
    throw Failure{kExitUsage, "merge: " + dir.string() + " holds no manifest"};
  compact_manifest(manifest, records, expected, true);

  std::set<std::string> recorded;
  std::size_t ok = 0;
  std::vector<const graph::ManifestRecord*> failed, stale;
  for (const graph::ManifestRecord& r : latest) {
    recorded.insert(r.input);
    if (identity &&
        (r.graph_sha256 != identity->graph_sha256 || r.settings_sha256 != identity->settings_sha256)) {
      stale.push_back(&r);
    } else if (r.ok()) {
      ++ok;
    } else {
      failed.push_back(&r);
    }
  }
  std::vector<std::string> missing;
  for (const Item& item : expected)
    if (!recorded.count(item.input.string())) missing.push_back(item.input.string());
  const std::vector<std::string> silent_shards = shards_without_manifest(dir);
  std::cout << "kinegraph: merge: " << latest.size() << " item(s) in " << manifest.string() << ": " << ok
            << " ok, " << failed.size() << " failed";
  if (identity) std::cout << ", " << stale.size() << " stale";
  if (!expected.empty())
    std::cout << ", " << missing.size() << " of " << expected.size() << " inputs without a record";
  if (!silent_shards.empty()) std::cout << ", " << silent_shards.size() << " shard(s) wrote no manifest";
  std::cout << '\n';
  for (const graph::ManifestRecord* r : failed)
    std::cerr << "  failed: " << r->input << ": " << r->message << " (log: " << (dir / r->log).string()
              << ")\n";
  for (const graph::ManifestRecord* r : stale)
    std::cerr << "  stale (another graph or settings than " << dir.string() << "/batch.json): " << r->input
              << '\n';
  for (const std::string& input : missing) std::cerr << "  no record: " << input << '\n';
  for (const std::string& shard : silent_shards)
    std::cerr << "  no manifest from shard " << shard << " (run it: kinegraph batch ... --shard " << shard
              << ")\n";
  return failed.empty() && missing.empty() && stale.empty() && silent_shards.empty() ? kExitOk
                                                                                     : kExitNodeFailed;
}

}  // namespace kg::app
