// Shared by the plugin tests: where the built modules are, and Motions built in the test. Running
// one node by hand and scratch directories: tests/support.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "../support/node_context.hpp"
#include "../support/temp_dir.hpp"
#include "kg/graph/node.hpp"
#include "kg/graph/registry.hpp"
#include "kg/motion/motion.hpp"

namespace kg_test {

namespace fs = std::filesystem;
using namespace kg;
using namespace kg::graph;
using kg::test::NodeContext;
using kg::test::params_for;
using kg::test::TempDir;

inline fs::path lowpass_library() {
  return fs::path(KG_PLUGIN_DIR) / "kg_lowpass.so";
}
inline fs::path test_nodes_library() {
  return fs::path(KG_TEST_PLUGIN_DIR) / "kg_test_nodes.so";
}
inline fs::path bad_plugin(const std::string& name) {
  return fs::path(KG_TEST_PLUGIN_DIR) / "bad" / ("kg_bad_" + name + ".so");
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
