// retime.contacts: a thin adapter over contacts.hpp (detected feet, or a contact file).
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <sstream>

#include "kg/builtin_nodes.hpp"
#include "kg/retime/contacts.hpp"
#include "kg/retime/nodes.hpp"

namespace kg {

namespace {

using graph::Node;
using graph::NodeSpec;
using graph::NodeType;
using graph::Params;
using graph::ParamSpec;
using graph::ParamType;
using graph::RunContext;

class ContactsNode final : public Node {
 public:
  explicit ContactsNode(const Params& p) : path_(p.get<std::string>("path")) {
    options_.feet = motion::split_names(p.get<std::string>("feet"));
    options_.heel_ratio = p.get<double>("heel_ratio");
    options_.width_ratio = p.get<double>("width_ratio");
    options_.plants.height_threshold = p.get<double>("height_threshold");
    options_.plants.speed_threshold = p.get<double>("speed_threshold");
    options_.plants.hysteresis = p.get<double>("hysteresis");
    options_.plants.min_duration_s = p.get<double>("min_duration_s");
    options_.plants.bridge_s = p.get<double>("bridge_s");
    options_.plants.bridge_distance = p.get<double>("bridge_distance");
    options_.plants.body_relative = p.get<double>("body_relative");
    options_.plants.run_froude = p.get<double>("run_froude");
    options_.plants.rest_window_s = p.get<double>("rest_window_s");
    options_.plants.floor = motion::parse_floor(p.get<std::string>("floor"));
    options_.support_acceleration = p.get<double>("support_acceleration");
    options_.validate();  // a bad setting fails when the graph loads
  }

  void run(RunContext& ctx) const override {
    const motion::Motion& m = ctx.input<motion::Motion>("motion");
    retime::Contacts c =
        path_.empty() ? retime::detect_contacts(m, options_) : retime::read_contacts_file(path_, m);
    for (const std::string& note : c.notes) ctx.log(note);
    std::int64_t flight = 0, single = 0, multiple = 0, points = 0;
    for (const retime::ContactFrame& f : c.frames) {
      const std::size_t n = f.patches().size();
      (n == 0 ? flight : n == 1 ? single : multiple) += 1;
      points += static_cast<std::int64_t>(f.points.size());
    }
    ctx.report("source", c.source);
    ctx.report("patches", static_cast<std::int64_t>(c.patches.size()));
    ctx.report("frames_without_contact", flight);
    ctx.report("frames_one_patch", single);
    ctx.report("frames_more_patches", multiple);
    ctx.report("touching_vertices", points);
    if (flight > 0 && path_.empty())
      ctx.log(std::to_string(flight) + " frames without contact (flight, or plants the detection missed)");
    ctx.output("contacts", std::move(c));
  }

 private:
  std::string path_;
  retime::FootContactOptions options_;
};

NodeType contacts_type() {
  const retime::FootContactOptions d;
  NodeSpec spec{
      .type = "retime.contacts",
      .version = 1,
      .doc =
          "Contacts with the floor for retiming (McCann et al. 2006 §3.2): per frame the touching vertices "
          "of "
          "polygonal patches fixed on segments, with their world positions and Jacobians. Detected (path "
          "empty): per foot a heel-to-toe-tip rectangle (kg/retime/contacts.hpp says how it is sized), its "
          "heel pair touching while the heel is planted, its tip pair while the toe tip is (near the floor "
          "and slow, as retarget.footplants detects; or near the floor at a frame the root is held up "
          "without other "
          "contact: a landing's impact). Or read from a contact file (YAML version 1: patches "
          "on named joints, vertices in the joint's frame, frame or time ranges).",
      .inputs = {{"motion", "kg.Motion", true, "the clip (its poses place the vertices)"}},
      .outputs = {{"contacts", "kg.Contacts", true,
                   "patches and per-frame touching vertices (metres, world)"}},
      .params = {
          ParamSpec{.name = "path",
                    .type = ParamType::InputPath,
                    .default_value = std::string(),
                    .doc = "a contact file (YAML); empty: detect the feet"},
          ParamSpec{.name = "feet",
                    .type = ParamType::String,
                    .default_value = std::string(),
                    .doc =
                        "comma-separated foot joints (the ankle's segment: lfoot, LeftFoot); empty: found by "
                        "common names"},
          ParamSpec{.name = "heel_ratio",
                    .type = ParamType::Float,
                    .default_value = d.heel_ratio,
                    .doc = "heel behind the ankle, as a fraction of the ankle-to-toe-tip distance",
                    .min = 0.0,
                    .max = 2.0},
          ParamSpec{.name = "width_ratio",
                    .type = ParamType::Float,
                    .default_value = d.width_ratio,
                    .doc = "foot width as a fraction of its length (Winter: 0.36)",
                    .min = 1e-3,
                    .max = 2.0},
          ParamSpec{.name = "height_threshold",
                    .type = ParamType::Float,
                    .default_value = d.plants.height_threshold,
                    .doc = "m above the point's rest level to touch",
                    .min = 1e-6,
                    .max = 10.0},
          ParamSpec{.name = "speed_threshold",
                    .type = ParamType::Float,
                    .default_value = d.plants.speed_threshold,
                    .doc = "m/s horizontal speed to touch",
                    .min = 1e-6,
                    .max = 100.0},
          ParamSpec{.name = "hysteresis",
                    .type = ParamType::Float,
                    .default_value = d.plants.hysteresis,
                    .doc = "leave thresholds = touch thresholds x this",
                    .min = 1.0,
                    .max = 10.0},
          ParamSpec{.name = "min_duration_s",
                    .type = ParamType::Float,
                    .default_value = d.plants.min_duration_s,
                    .doc = "shorter touches are dropped, seconds",
                    .min = 0.0,
                    .max = 10.0},
          ParamSpec{.name = "body_relative",
                    .type = ParamType::Float,
                    .default_value = d.plants.body_relative,
                    .doc = "where the body runs, a point slower than this share of its pace may touch (a "
                           "run's stance foot rolls at up to 1.5 m/s; 0: none)",
                    .min = 0.0,
                    .max = 0.99},
          ParamSpec{
              .name = "run_froude",
              .type = ParamType::Float,
              .default_value = d.plants.run_froude,
              .doc = "the body runs where v^2 / (g h) of its pace passes this (0.5: the walk-run transition)",
              .min = 0.01,
              .max = 100.0},
          ParamSpec{.name = "bridge_s",
                    .type = ParamType::Float,
                    .default_value = d.plants.bridge_s,
                    .doc = "a lift shorter than this (seconds) between two touches of a point, back within "
                           "bridge_distance of where it left, is jitter: one touch (0: none)",
                    .min = 0.0,
                    .max = 1.0},
          ParamSpec{
              .name = "bridge_distance",
              .type = ParamType::Float,
              .default_value = d.plants.bridge_distance,
              .doc = "metres, horizontal: how far from where it left a point may come back for bridge_s",
              .min = 0.0,
              .max = 1.0},
          ParamSpec{
              .name = "rest_window_s",
              .type = ParamType::Float,
              .default_value = d.plants.rest_window_s,
              .doc = "s: a point's rest level is its lowest height within this window (0: the whole clip)",
              .min = 0.0,
              .max = 100.0},
          ParamSpec{.name = "support_acceleration",
                    .type = ParamType::Float,
                    .default_value = d.support_acceleration,
                    .doc =
                        "m/s²: at frames without plants whose root accelerates upward more than this above "
                        "free fall, feet within the leave height touch however fast they move (a landing's "
                        "impact, a takeoff's last push), from a plant outwards: a clip never planted stays "
                        "so; 0: off",
                    .min = 0.0,
                    .max = 100.0},
          ParamSpec{
              .name = "floor",
              .type = ParamType::String,
              .default_value = std::string("auto"),
              .doc = "floor height in metres (the soles touch within height_threshold of it; rest_window_s "
                     "is then unused), or 'auto' (each sole point's own lowest heights: captured floors "
                     "slope and drift)"},
      }};
  return {spec, [](const Params& p) { return std::make_unique<ContactsNode>(p); }};
}

}  // namespace

std::vector<graph::NodeType> retime_contact_node_types() {
  return {contacts_type()};
}

}  // namespace kg
