#include "slurm.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>

#include "host.hpp"
#include "kg/base/atomic_file.hpp"

namespace kg::app {
namespace {

namespace fs = std::filesystem;

// A word for bash, single-quoted.
std::string quoted(const std::string& word) {
  std::string q = "'";
  for (char c : word) {
    if (c == '\'')
      q += "'\\''";
    else
      q += c;
  }
  return q + "'";
}

// A value of an #SBATCH line, which sbatch reads like a shell word in double quotes. In a file
// name % starts a pattern (%A the array job, %a the task), so `folder`'s own are doubled and
// `pattern` follows it.
std::string directive(const std::string& value, const fs::path& folder = {},
                      const std::string& pattern = "") {
  const std::string literal = folder.empty() ? value : folder.string();
  if (literal.find_first_of("\"\\\n") != std::string::npos) {
    throw Failure{kExitUsage, "--slurm: '" + literal +
                                  "' has a quote, backslash or line break, which an #SBATCH "
                                  "line cannot hold: use another --out or graph name"};
  }
  if (folder.empty()) return "\"" + value + "\"";
  std::string q = "\"";
  for (char c : literal) {
    if (c == '%') q += '%';
    q += c;
  }
  return q + "/" + pattern + "\"";
}

void write_script(const fs::path& file, const std::string& text) {
  kg::write_file_atomically(file, [&](std::ostream& os) { os << text; });
  fs::permissions(file, fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec,
                  fs::perm_options::add);
}

// sbatch's job id from its --parsable output ("123" or "123;cluster").
std::string submit(const std::string& command) {
  std::FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) throw Failure{kExitNodeFailed, "cannot run sbatch"};
  std::string output;
  std::array<char, 256> buffer;
  while (std::fgets(buffer.data(), buffer.size(), pipe)) output += buffer.data();
  const int status = ::pclose(pipe);
  std::string id = output.substr(0, output.find_first_of(";\n"));
  const bool numeric =
      !id.empty() && std::all_of(id.begin(), id.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (status != 0 || !numeric) throw Failure{kExitNodeFailed, "`" + command + "` failed: " + output};
  return id;
}

}  // namespace

fs::path merge_script_path(const fs::path& script) {
  return script.parent_path() / (script.stem().string() + ".merge" + script.extension().string());
}

int write_slurm_jobs(const Options& o, const fs::path& graph, const fs::path& dir,
                     const std::vector<fs::path>& inputs, const fs::path& executable) {
  const int shards = std::max<int>(
      1, std::min<int>(static_cast<int>(inputs.size()),
                       o.shards ? o.shards : std::min<int>(100, (static_cast<int>(inputs.size()) + 7) / 8)));
  const int jobs = o.jobs_given ? o.jobs : 1;
  const fs::path script = fs::absolute(o.slurm).lexically_normal();
  const fs::path merge = merge_script_path(script);
  const fs::path list = dir / "inputs.txt";
  const fs::path logs = dir / "slurm";
  std::error_code ec;
  fs::create_directories(logs, ec);
  if (ec) throw Failure{kExitUsage, "--out " + dir.string() + ": cannot create it: " + ec.message()};

  kg::write_file_atomically(list, [&](std::ostream& os) {
    for (const fs::path& input : inputs) os << input.string() << '\n';
  });

  const std::string name = "kinegraph-" + graph.stem().string();
  std::ostringstream head;
  for (const std::string& option : o.sbatch_options) head << "#SBATCH " << option << '\n';

  std::ostringstream array;
  array << "#!/bin/bash\n"
        << "# Written by `kinegraph batch --slurm`: " << inputs.size() << " inputs of " << graph.string()
        << " in " << shards << " shards, one array task each.\n"
        << "# Submit: jid=$(sbatch --parsable " << quoted(script.string())
        << ") && sbatch --dependency=afterany:$jid " << quoted(merge.string()) << "\n"
        << "#SBATCH --job-name=" << directive(name) << "\n"
        << "#SBATCH --array=0-" << shards - 1 << "\n"
        << "#SBATCH --cpus-per-task=" << jobs << "\n"
        << "#SBATCH --output=" << directive("", logs, "%A_%a.out") << "\n"
        << head.str() << "set -euo pipefail\n"
        << "cd " << quoted(fs::current_path().string())
        << "  # where the batch was written: relative paths hold\n"
        << "exec " << quoted(executable.string()) << " batch " << quoted(graph.string()) << " --input-list "
        << quoted(list.string()) << " --out " << quoted(dir.string()) << " --shard \"${SLURM_ARRAY_TASK_ID}/"
        << shards << "\" --jobs \"${SLURM_CPUS_PER_TASK:-" << jobs << "}\"";
  for (const auto& [key, value] : o.sets) array << " --set " << quoted(key + "=" + value);
  for (const fs::path& plugins : o.plugin_dirs)
    array << " --plugin-dir " << quoted(fs::absolute(plugins).string());
  if (o.force) array << " --force";
  array << '\n';
  write_script(script, array.str());

  std::ostringstream merger;
  merger << "#!/bin/bash\n"
         << "# Written by `kinegraph batch --slurm`: merges the shard manifests of " << dir.string()
         << " once the array job has ended.\n"
         << "#SBATCH --job-name=" << directive(name + "-merge") << "\n"
         << "#SBATCH --output=" << directive("", logs, "merge_%j.out") << "\n"
         << head.str() << "set -euo pipefail\n"
         << "exec " << quoted(executable.string()) << " merge " << quoted(dir.string()) << '\n';
  write_script(merge, merger.str());

  std::cout << "kinegraph: batch: wrote " << script.string() << " (" << shards << " array tasks over "
            << inputs.size() << " inputs) and " << merge.string() << '\n';
  if (!o.submit) {
    std::cout << "submit with: jid=$(sbatch --parsable " << quoted(script.string())
              << ") && sbatch --dependency=afterany:$jid " << quoted(merge.string()) << '\n';
    return kExitOk;
  }
  const std::string array_id = submit("sbatch --parsable " + quoted(script.string()));
  const std::string merge_id =
      submit("sbatch --parsable --dependency=afterany:" + array_id + " " + quoted(merge.string()));
  std::cout << "submitted array job " << array_id << " and merge job " << merge_id << '\n'
            << "the merged manifest will be " << (dir / "manifest.jsonl").string() << '\n';
  return kExitOk;
}

}  // namespace kg::app
