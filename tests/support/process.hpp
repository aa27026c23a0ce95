// Test support: running a program with its output captured.
//
//   const Result r = run_program(kinegraph, {"run", graph.string()}, {"KINEGRAPH_PLUGIN_PATH=..."});
//   INFO(show(r));  // exit code, stdout and stderr in a failure message
#pragma once

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "temp_dir.hpp"

extern char** environ;

namespace kg::test {

namespace fs = std::filesystem;

struct Result {
  int code = -1;
  std::string out, err;
};

// Starts `program args...` with stdin from /dev/null and stdout and stderr to the files named;
// the environment is ours without KINEGRAPH_PLUGIN_PATH, plus `env` ("NAME=value"). With
// `own_group` the program leads a process group of its own, as a shell runs a job, so that
// kill(-pid, SIGINT) reaches it and its children as a terminal's Ctrl-C would. Returns the pid,
// or minus the error of posix_spawn.
inline pid_t spawn_program(const fs::path& program, const std::vector<std::string>& args,
                           const std::vector<std::string>& env, const fs::path& out_file,
                           const fs::path& err_file, bool own_group = false) {
  std::vector<std::string> env_strings;
  for (char** e = environ; *e != nullptr; ++e) {
    if (std::string(*e).rfind("KINEGRAPH_PLUGIN_PATH=", 0) != 0) env_strings.emplace_back(*e);
  }
  for (const std::string& e : env) env_strings.push_back(e);
  std::vector<char*> envp;
  for (std::string& e : env_strings) envp.push_back(e.data());
  envp.push_back(nullptr);

  std::vector<std::string> arg_strings{program.string()};
  arg_strings.insert(arg_strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : arg_strings) argv.push_back(a.data());
  argv.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  if (own_group) {
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
    posix_spawnattr_setpgroup(&attributes, 0);
  }
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0], &actions, &attributes, argv.data(), envp.data());
  posix_spawnattr_destroy(&attributes);
  posix_spawn_file_actions_destroy(&actions);
  return spawned == 0 ? pid : -spawned;
}

// The exit code of a program spawn_program started, or 128 + the signal that ended it.
inline int wait_program(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// Runs `program args...` as spawn_program starts it, with stdout and stderr captured.
inline Result run_program(const fs::path& program, const std::vector<std::string>& args,
                          const std::vector<std::string>& env = {}) {
  static std::atomic<int> counter{0};
  const fs::path base = fs::temp_directory_path() /
                        ("kg_cli_out_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  const fs::path out_file = base.string() + ".out", err_file = base.string() + ".err";
  Result r;
  const pid_t pid = spawn_program(program, args, env, out_file, err_file);
  if (pid < 0) {
    r.err = "posix_spawn failed: " + std::string(std::strerror(-pid));
    return r;
  }
  r.code = wait_program(pid);
  r.out = read_file(out_file);
  r.err = read_file(err_file);
  fs::remove(out_file);
  fs::remove(err_file);
  return r;
}

// The shell-like line, for failure messages.
inline std::string show(const Result& r) {
  return "exit " + std::to_string(r.code) + "\nstdout:\n" + r.out + "\nstderr:\n" + r.err;
}

// Runs the built kinegraph CLI (KG_BINARY_DIR/bin/kinegraph), as run_program does.
inline Result kinegraph(const std::vector<std::string>& args, const std::vector<std::string>& env = {}) {
  return run_program(fs::path(KG_BINARY_DIR) / "bin" / "kinegraph", args, env);
}

}  // namespace kg::test
