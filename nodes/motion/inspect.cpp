#include "kg/motion/inspect.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "kg/base/option_check.hpp"
#include "kg/base/text.hpp"
#include "kg/motion/filters.hpp"
#include "kg/motion/kinematics.hpp"

namespace kg::motion {
namespace {

std::string g3(double x) {
  return text::significant(x, 3);
}

std::string frames_text(int first, int last) {
  return first == last ? "frame " + std::to_string(first)
                       : "frames " + std::to_string(first) + ".." + std::to_string(last);
}

// The height (world Y) at every frame of the joint that carries the clip's translation: of the
// joints with position channels, the one whose height varies most (an exporter's static Root
// above the hips does not). The pelvis stays within centimetres of the centre of mass in flight,
// where the mean of the joints does not: arms swung up raise it (CMU 13_13's jump: 7.4 m/s² from
// the mean of the joints, 9.5 from the hips).
std::vector<double> pelvis_heights(const Eigen::MatrixXd& world, const Skeleton& skeleton,
                                   std::string& name) {
  int best = 0;
  double best_range = -1;
  for (int j = 0; j < skeleton.joint_count(); ++j) {
    bool positioned = false;
    for (const Channel& c : skeleton.joint(j).channels) positioned = positioned || !is_rotation(c.kind);
    if (!positioned) continue;
    const double range = world.col(3 * j + 1).maxCoeff() - world.col(3 * j + 1).minCoeff();
    if (range > best_range) best = j, best_range = range;
  }
  name = skeleton.joint(best).name;
  std::vector<double> y(static_cast<std::size_t>(world.rows()));
  for (Eigen::Index f = 0; f < world.rows(); ++f) y[static_cast<std::size_t>(f)] = world(f, 3 * best + 1);
  return y;
}

struct Parabola {
  double gravity = 0;  // m/s²: -2 c
  double rise = 0;     // m: g T² / 8 over the span's T, the apex above its ends' level (rate-free)
  double rms = 0;      // m: the fit's residual
};

// The least-squares y = a + b t + c t² through y[first..last] at t = (f - first) / fps.
Parabola fit_parabola(const std::vector<double>& y, int first, int last, double fps) {
  const int n = last - first + 1;
  Eigen::MatrixXd A(n, 3);
  Eigen::VectorXd b(n);
  for (int k = 0; k < n; ++k) {
    const double t = k / fps;
    A.row(k) << 1, t, t * t;
    b[k] = y[static_cast<std::size_t>(first + k)];
  }
  const Eigen::Vector3d x = A.colPivHouseholderQr().solve(b);
  const double g = -2 * x[2], T = (n - 1) / fps;
  return {g, g * T * T / 8, std::sqrt((A * x - b).squaredNorm() / n)};
}

// Runs of frames with every foot point off the floor: above its clip-wide rest height (the
// floor_percentile of its heights) by more than a plant's leave threshold. Heights only, so that
// the runs are the same at any frame rate: plants and their rest window are per second, and a
// header that lies about the rate would find plants in mid-air.
std::vector<std::pair<int, int>> airborne_runs(const FootplantDetection& d, const FootplantOptions& o,
                                               int frames) {
  const double lift = o.height_threshold * o.hysteresis;
  auto airborne = [&](int f) {
    for (const PlantPoint& p : d.points)
      if (p.heights[static_cast<std::size_t>(f)] - p.rest_height <= lift) return false;
    return true;
  };
  std::vector<std::pair<int, int>> runs;
  for (int f = 0; f < frames;) {
    if (!airborne(f)) {
      ++f;
      continue;
    }
    int last = f;
    while (last + 1 < frames && airborne(last + 1)) ++last;
    if (last > f) runs.push_back({f, last});
    f = last + 1;
  }
  return runs;
}

// The rate the flights' gravity implies: source_fps and the evidence.
void check_rate(MotionInspection& out) {
  double weighted = 0, weight = 0;
  for (const FlightSpan& f : out.flights)
    if (f.gravity && f.weighs_rate) {
      weighted += *f.gravity * (f.last - f.first);
      weight += f.last - f.first;
    }
  out.source_fps = out.header_fps;
  if (weight == 0) {
    out.rate_evidence =
        "rate " + g3(out.header_fps) +
        " fps as read: no flight to weigh it against gravity (a free fall whose pelvis rises " +
        g3(100 * kMinFlightRise) + " cm or more, a parabola within " + g3(100 * kMaxFlightResidual) +
        "% of that)";
    return;
  }
  const double g = weighted / weight;
  const std::string shown = "the flights' pelvis (" + out.pelvis + ") falls at " + g3(g) + " m/s^2 at " +
                            g3(out.header_fps) + " fps";
  if (!(g > 0)) {
    out.rate_evidence =
        shown + ", not downwards: the rate is not checked (contacts misread, or no free flight)";
    return;
  }
  const double factor = std::sqrt(kEarthGravity / g);
  double best = 1;
  for (const double c : kRateFactors)
    if (std::abs(std::log(factor / c)) < std::abs(std::log(factor / best))) best = c;
  if (std::abs(factor / best - 1) > kRateTolerance) {
    out.rate_evidence =
        shown + ": no whole factor of the rate gives " + g3(kEarthGravity) + " m/s^2 (it would take " +
        g3(factor) + "x), so " + g3(out.header_fps) +
        " fps is kept; the flights may be no free fall (a wire, a trampoline, misread contacts)";
    return;
  }
  if (best == 1) {
    out.rate_evidence = shown + ", Earth's within the tolerance (a rate factor within " +
                        g3(100 * kRateTolerance) + "% of 1): the rate is confirmed";
    return;
  }
  out.source_fps = out.header_fps * best;
  out.rate_evidence = shown + ": at " + g3(out.source_fps) + " fps (" + g3(best) + "x) they fall at " +
                      g3(g * best * best) + " m/s^2, Earth's gravity, so the clip's true rate is " +
                      g3(out.source_fps) + " fps, not the " + g3(out.header_fps) + " it states";
  out.fixes.push_back("--set source_fps=" + g3(out.source_fps));
}

void find_pops(const Eigen::MatrixXd& world, const Skeleton& skeleton, double fps, int offset,
               const InspectOptions& o, MotionInspection& out) {
  const Eigen::Index frames = world.rows(), joints = world.cols() / 3;
  if (frames < 3) return;
  std::vector<std::vector<double>> acceleration(static_cast<std::size_t>(joints));
  for (Eigen::Index j = 0; j < joints; ++j) {
    auto& a = acceleration[static_cast<std::size_t>(j)];
    a.resize(static_cast<std::size_t>(frames - 2));
    for (Eigen::Index f = 1; f + 1 < frames; ++f)
      a[static_cast<std::size_t>(f - 1)] = (world.block<1, 3>(f + 1, 3 * j) -
                                            2 * world.block<1, 3>(f, 3 * j) + world.block<1, 3>(f - 1, 3 * j))
                                               .norm() *
                                           fps * fps;
  }
  std::vector<double> typical_of(static_cast<std::size_t>(joints));
  for (Eigen::Index j = 0; j < joints; ++j)
    typical_of[static_cast<std::size_t>(j)] = percentile(acceleration[static_cast<std::size_t>(j)], 0.95);
  for (Eigen::Index f = 1; f + 1 < frames; ++f) {
    double worst_ratio = 0;
    Pop pop;
    for (Eigen::Index j = 0; j < joints; ++j) {
      const double typical = typical_of[static_cast<std::size_t>(j)];
      const double x = acceleration[static_cast<std::size_t>(j)][static_cast<std::size_t>(f - 1)];
      if (x <= o.pop_floor || x <= o.pop_ratio * typical) continue;
      const double ratio = typical > 0 ? x / typical : x;
      if (ratio > worst_ratio) {
        worst_ratio = ratio;
        pop = {static_cast<int>(f) + offset, skeleton.joint(static_cast<int>(j)).name, x};
      }
    }
    if (worst_ratio > 0) out.pops.push_back(pop);
  }
}

void summarise(MotionInspection& out, const Motion& motion) {
  auto& s = out.summary;
  int roots = 0;
  for (const JointSummary& j : out.joints) roots += j.parent < 0;
  s.push_back(out.clip + ": " + std::to_string(out.joints.size()) + " joints (" + std::to_string(roots) +
              (roots == 1 ? " root" : " roots") + "), " + std::to_string(motion.skeleton->channel_count()) +
              " channels; " + std::to_string(out.frames) + " frames at " + g3(out.header_fps) + " fps (" +
              g3((out.frames - 1) / out.source_fps) + " s at the rate believed, " + g3(out.source_fps) +
              " fps)");
  s.push_back("up: " + out.up + " (file axis); length unit: " + g3(out.unit_metres) + " m per file unit");
  s.push_back("rate: " + out.rate_evidence);
  s.push_back("calibration: " + out.calibration.evidence);
  s.push_back("floor: " + g3(out.floor) + " m");
  for (const PointPlants& p : out.plants)
    s.push_back("plants of " + p.point + ": " + std::to_string(p.spans.size()) +
                (p.spans.empty() ? std::string() : ", worst skate " + g3(100 * p.worst_skate) + " cm"));
  for (const std::string& note : out.plant_notes) s.push_back("plants: " + note);
  for (const FlightSpan& f : out.flights)
    s.push_back("flight " + frames_text(f.first, f.last) + ": " + g3(f.seconds) + " s" +
                (f.gravity ? ", gravity " + g3(*f.gravity) + " m/s^2 at " + g3(out.source_fps) + " fps"
                           : std::string(" (too short to weigh)")));
  if (out.flights.empty()) s.push_back("flights: none (a foot is on the floor at every frame)");
  if (out.penetration > 0.01)
    s.push_back("floor penetration: " + out.penetration_point + " " + g3(100 * out.penetration) +
                " cm below the floor at frame " + std::to_string(out.penetration_frame));
  else
    s.push_back("floor penetration: none over 1 cm");
  if (out.pops.empty()) {
    s.push_back("pops: none");
  } else {
    std::string list;
    for (std::size_t i = 0; i < out.pops.size() && i < 5; ++i)
      list += (i ? ", " : "") + std::to_string(out.pops[i].frame) + " (" + out.pops[i].joint + " " +
              g3(out.pops[i].acceleration) + " m/s^2)";
    s.push_back("pops: " + std::to_string(out.pops.size()) +
                " frames where a joint's velocity jumps: " + list + (out.pops.size() > 5 ? ", ..." : ""));
  }
  s.push_back(out.fixes.empty() ? "fixes: none needed" : "fixes: " + text::join(out.fixes, " "));
}

}  // namespace

void InspectOptions::validate() const {
  using options::require;
  const char* o = "InspectOptions";
  plants.validate();
  require(options::positive(pop_ratio), o, "pop_ratio", pop_ratio, "> 0 and finite");
  require(options::non_negative(pop_floor), o, "pop_floor", pop_floor, ">= 0 and finite");
  require(min_flight_frames >= 3, o, "min_flight_frames", min_flight_frames, ">= 3 (a parabola)");
}

MotionInspection inspect_motion(const Motion& motion, const InspectOptions& options) {
  options.validate();
  motion.check();
  if (motion.frame_count() < 3)
    throw std::invalid_argument("inspect: the clip has " + std::to_string(motion.frame_count()) +
                                " frames (expected at least 3)");
  MotionInspection out;
  out.clip = motion.name;
  const Skeleton& skeleton = *motion.skeleton;
  for (int j = 0; j < skeleton.joint_count(); ++j) {
    const Joint& joint = skeleton.joint(j);
    JointSummary s{joint.name, joint.parent, {}, joint.parent < 0 ? 0.0 : joint.offset.norm()};
    for (const Channel& c : joint.channels) s.channels.push_back(to_string(c.kind));
    out.joints.push_back(std::move(s));
  }
  out.frames = motion.frame_count();
  out.header_fps = motion.fps;
  out.unit_metres = skeleton.source_unit_metres;
  const Eigen::Matrix3d z_up = (Eigen::Matrix3d() << 1, 0, 0, 0, 0, 1, 0, -1, 0).finished();
  out.up = skeleton.file_to_world.isIdentity(1e-9)       ? "y"
           : skeleton.file_to_world.isApprox(z_up, 1e-9) ? "z"
                                                         : "custom";

  out.calibration = detect_calibration_frames(motion);
  for (int f = 0; f < out.calibration.frames; ++f) out.calibration_frames.push_back(f);
  const int offset = out.calibration.frames;
  if (offset > 0) out.fixes.push_back("--set trim=" + std::to_string(offset) + "..");
  const Motion analysed = offset > 0 ? frame_range(motion, offset) : motion;

  // Flights first, from heights alone (the same at any rate): they tell the rate, at which the
  // plants (thresholds per second, rest levels over a window of seconds) are then found.
  const FootplantDetection at_header = detect_footplants(analysed, options.plants);
  const Eigen::MatrixXd world = joint_world_positions(analysed);
  const std::vector<double> centre = pelvis_heights(world, skeleton, out.pelvis);
  for (const auto& [first, last] : airborne_runs(at_header, options.plants, analysed.frame_count())) {
    FlightSpan f{first + offset, last + offset, 0, std::nullopt};
    if (last - first + 1 >= options.min_flight_frames) {
      const Parabola p = fit_parabola(centre, first, last, motion.fps);
      f.gravity = p.gravity;
      f.rise = p.rise;
      f.weighs_rate = p.rise >= kMinFlightRise && p.rms <= kMaxFlightResidual * p.rise;
    }
    out.flights.push_back(f);
  }
  check_rate(out);
  Motion at_rate = analysed;
  at_rate.fps = out.source_fps;
  const FootplantDetection plants =
      out.source_fps == out.header_fps ? at_header : detect_footplants(at_rate, options.plants);

  out.floor = plants.floor;
  out.plant_notes = plants.notes;
  out.plant_notes.insert(out.plant_notes.end(), plants.warnings.begin(), plants.warnings.end());
  std::vector<char> planted(static_cast<std::size_t>(analysed.frame_count()), 0);
  for (std::size_t i = 0; i < plants.points.size(); ++i) {
    PointPlants p{plants.points[i].name, {}, 0};
    for (const Footplant& plant : plants.plants)
      if (plant.point == static_cast<int>(i)) {
        p.spans.push_back({plant.first_frame + offset, plant.last_frame + offset});
        p.worst_skate = std::max(p.worst_skate, plant.skate);
        for (int f = plant.first_frame; f <= plant.last_frame; ++f) planted[static_cast<std::size_t>(f)] = 1;
      }
    out.plants.push_back(std::move(p));
    const std::vector<double>& h = plants.points[i].heights;
    for (std::size_t f = 0; f < h.size(); ++f)
      if (plants.floor - h[f] > out.penetration) {
        out.penetration = plants.floor - h[f];
        out.penetration_frame = static_cast<int>(f) + offset;
        out.penetration_point = plants.points[i].name;
      }
  }
  // Flights are what is off the floor and planted nowhere at the rate believed (a walk's feet
  // both lift above their clip-wide low on a drifting floor, but one stays planted).
  std::erase_if(out.flights, [&](const FlightSpan& f) {
    for (int k = f.first; k <= f.last; ++k)
      if (planted[static_cast<std::size_t>(k - offset)]) return true;
    return false;
  });
  const double factor = out.source_fps / out.header_fps;
  for (FlightSpan& f : out.flights) {
    f.seconds = (f.last - f.first) / out.source_fps;
    if (f.gravity) *f.gravity *= factor * factor;  // accelerations scale with the rate squared
  }
  find_pops(world, skeleton, out.source_fps, offset, options, out);
  summarise(out, motion);
  return out;
}

RateCheck rate_from_flights(const Motion& motion, const InspectOptions& options) {
  const MotionInspection i = inspect_motion(motion, options);
  return {i.source_fps, i.rate_evidence};
}

void write_inspection_json(JsonWriter& w, const MotionInspection& i, const std::string& units) {
  w.begin_object();
  w.field("clip", i.clip);
  w.key("joints");
  w.begin_array();
  for (const JointSummary& j : i.joints) {
    w.begin_object();
    w.field("name", j.name);
    w.field("parent", j.parent);
    w.key("channels");
    w.begin_array();
    for (const std::string& c : j.channels) w.value(c);
    w.end_array();
    w.field("rest_length_m", j.rest_length);
    w.end_object();
  }
  w.end_array();
  w.field("frames", i.frames);
  w.field("header_fps", i.header_fps);
  w.field("source_fps", i.source_fps);
  w.field("duration_s", (i.frames - 1) / i.source_fps);
  w.field("rate_evidence", i.rate_evidence);
  w.field("up", i.up);
  w.field("units", units);
  w.key("calibration_frames");
  w.begin_array();
  for (const int f : i.calibration_frames) w.value(f);
  w.end_array();
  w.field("calibration_evidence", i.calibration.evidence);
  w.field("floor_m", i.floor);
  w.key("plants");
  w.begin_array();
  for (const PointPlants& p : i.plants) {
    w.begin_object();
    w.field("point", p.point);
    w.field("count", static_cast<int>(p.spans.size()));
    w.field("worst_skate_m", p.worst_skate);
    w.key("spans");
    w.begin_array();
    for (const auto& [first, last] : p.spans) w.value(std::vector<double>{double(first), double(last)});
    w.end_array();
    w.end_object();
  }
  w.end_array();
  w.key("plant_notes");
  w.begin_array();
  for (const std::string& n : i.plant_notes) w.value(n);
  w.end_array();
  w.key("flights");
  w.begin_array();
  for (const FlightSpan& f : i.flights) {
    w.begin_object();
    w.field("first", f.first);
    w.field("last", f.last);
    w.field("seconds", f.seconds);
    w.field("gravity", f.gravity);
    w.field("rise_m", f.rise);
    w.field("weighs_rate", f.weighs_rate);
    w.end_object();
  }
  w.end_array();
  w.key("penetration");
  w.begin_object();
  w.field("depth_m", i.penetration);
  w.field("frame", i.penetration_frame);
  w.field("point", i.penetration_point);
  w.end_object();
  w.key("pops");
  w.begin_array();
  for (const Pop& p : i.pops) {
    w.begin_object();
    w.field("frame", p.frame);
    w.field("joint", p.joint);
    w.field("acceleration", p.acceleration);
    w.end_object();
  }
  w.end_array();
  w.key("fixes");
  w.begin_array();
  for (const std::string& f : i.fixes) w.value(f);
  w.end_array();
  w.key("summary");
  w.begin_array();
  for (const std::string& s : i.summary) w.value(s);
  w.end_array();
  w.end_object();
}

}  // namespace kg::motion
