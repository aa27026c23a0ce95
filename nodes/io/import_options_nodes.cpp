// The import options as node params (kg/io/nodes.hpp).
#include "kg/io/nodes.hpp"

#include <cmath>

#include "kg/base/text.hpp"

namespace kg::io {

std::vector<graph::ParamSpec> import_option_params(const std::string& default_units) {
  if (default_units != "auto") metres_per_unit(default_units);  // throws for an unknown unit
  using graph::ParamType;
  return {
      {.name = "units",
       .type = ParamType::Enum,
       .default_value = default_units,
       .doc = "length unit of the file: auto (the file's declaration, else guessed from the standing height, "
              "and said so), m, cm, mm, inch, asf (2.54/45 m, ASF's length 0.45)",
       .choices = {"auto", "m", "cm", "mm", "inch", "asf"}},
      {.name = "up",
       .type = ParamType::Enum,
       .default_value = std::string("auto"),
       .doc = "file axis pointing up: auto (from frame 0's extents, said so), y, z (rotated to +Y)",
       .choices = {"auto", "y", "z"}},
      {.name = "fps",
       .type = ParamType::String,
       .default_value = std::string("0"),
       .doc = "frames per second overriding the file's (files lie); 0 keeps the file's; auto: the file's, "
              "unless the clip's free-fall flights show it off by a whole factor (then the rate they "
              "imply, said so)"},
      {.name = "trim",
       .type = ParamType::String,
       .default_value = std::string("auto"),
       .doc =
           "frames kept: auto (drops calibration frames, a T-pose or A-pose before the motion, and says so), "
           "none, FIRST..LAST or FIRST.. (frame numbers of the file from 0, inclusive)"}};
}

ImportOptions import_options_from(const graph::Params& params) {
  ImportOptions o;
  o.units = params.get<std::string>("units");
  o.up = params.get<std::string>("up");
  const std::string fps = std::string(text::trim(params.get<std::string>("fps")));
  if (fps == "auto") {
    o.fps_from_flights = true;
  } else {
    const auto rate = text::parse_double(fps);
    if (!rate || !(*rate >= 0) || !std::isfinite(*rate))
      throw std::invalid_argument("fps " + text::in_quotes(fps) +
                                  ": expected auto, 0 (the file's) or a rate > 0 (frames per second)");
    o.fps = *rate;
  }
  o.trim = params.get<std::string>("trim");
  o.validate();  // node factories call this: a bad setting fails when the graph loads
  return o;
}

}  // namespace kg::io
