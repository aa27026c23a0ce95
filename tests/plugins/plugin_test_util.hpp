// Shared by the plugin tests: where the built modules are, a RunContext for running one node by
// hand, a scratch directory, and Motions built in the test.
#pragma once

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "kg/graph/node.hpp"
#include "kg/graph/registry.hpp"
#include "kg/motion/motion.hpp"

namespace kg_test {

namespace fs = std::filesystem;
using namespace kg::graph;

inline fs::path lowpass_library() {
  return fs::path(KG_PLUGIN_DIR) / "kg_lowpass.so";
}
inline fs::path test_nodes_library() {
  return fs::path(KG_TEST_PLUGIN_DIR) / "kg_test_nodes.so";
}
inline fs::path bad_plugin(const std::string& name) {
  return fs::path(KG_TEST_PLUGIN_DIR) / "bad" / ("kg_bad_" + name + ".so");
}

// A fresh directory under the system temp dir, removed with everything in it on destruction.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    path_ = fs::temp_directory_path() /
            ("kg_test_plugins_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& name) const { return path_ / name; }

  void write(const std::string& name, const std::string& text) const {
    std::ofstream(path_ / name, std::ios::binary) << text;
  }

 private:
  fs::path path_;
};

// Runs one node outside any graph: inputs set by the test, outputs and figures collected.
class TestContext final : public RunContext {
 public:
  explicit TestContext(Params params) : params_(std::move(params)) {}

  const std::string& node_id() const override { return id_; }
  const Params& params() const override { return params_; }
  const Value& input_value(const std::string& port) const override {
    static const Value none;
    auto it = inputs.find(port);
    return it == inputs.end() ? none : it->second;
  }
  void set_output(const std::string& port, Value value) override { outputs[port] = std::move(value); }
  void report(const std::string& key, Figure value) override { figures[key] = std::move(value); }
  void log(const std::string& message) override { logs.push_back(message); }

  std::map<std::string, Value> inputs;
  std::map<std::string, Value> outputs;
  std::map<std::string, Figure> figures;
  std::vector<std::string> logs;

 private:
  std::string id_ = "node";
  Params params_;
};

// The spec's defaults with `overrides` on top, as the graph loader would fill them in.
inline Params params_for(const Registry& registry, const std::string& type,
                         const std::map<std::string, ParamValue>& overrides = {}) {
  const NodeType* node_type = registry.find_node(type);
  if (node_type == nullptr) throw std::runtime_error("node type " + type + " not registered");
  Params params;
  for (const ParamSpec& p : node_type->spec.params) {
    if (!p.required) params.set(p.name, p.default_value);
  }
  for (const auto& [name, value] : overrides) params.set(name, value);
  return params;
}

// One root joint "hip" with channels Xposition Yposition Zposition Zrotation Xrotation Yrotation
// (columns 0..5), all zero.
inline kg::motion::Motion blank_motion(int frames, double fps) {
  using kg::motion::ChannelKind;
  auto skeleton = std::make_shared<kg::motion::Skeleton>();
  kg::motion::Joint hip;
  hip.name = "hip";
  for (ChannelKind k : {ChannelKind::Xposition, ChannelKind::Yposition, ChannelKind::Zposition,
                        ChannelKind::Zrotation, ChannelKind::Xrotation, ChannelKind::Yrotation}) {
    hip.channels.push_back({k});
  }
  skeleton->add_joint(hip);
  kg::motion::Motion m;
  m.skeleton = skeleton;
  m.values = kg::motion::FrameMatrix::Zero(frames, skeleton->channel_count());
  m.fps = fps;
  m.name = "test";
  return m;
}

}  // namespace kg_test
