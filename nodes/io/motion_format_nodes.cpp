// The motion formats as registry extensions (kg/io/nodes.hpp).
#include "kg/io/nodes.hpp"

namespace kg::io {

std::vector<graph::Extension> builtin_motion_format_extensions() {
  std::vector<graph::Extension> out;
  for (std::shared_ptr<const MotionFormat>& format : builtin_motion_formats()) {
    std::string name = format->name, doc = format->doc;
    out.push_back(graph::Extension::make<MotionFormat>(std::move(name), std::move(format), std::move(doc)));
  }
  return out;
}

MotionFormats motion_formats_in(const graph::Registry& registry) {
  MotionFormats formats;
  for (const std::string& name : registry.names<MotionFormat>())
    formats.push_back(registry.find<MotionFormat>(name));
  return formats;
}

}  // namespace kg::io
