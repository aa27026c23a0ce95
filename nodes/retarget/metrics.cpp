// Metrics of a retargeted motion (metrics.hpp).
#include "kg/retarget/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <span>
#include <stdexcept>
#include <tuple>

#include "kg/base/json.hpp"
#include "kg/motion/filters.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/motion/rotations.hpp"

namespace kg::retarget {
namespace {

using motion::Motion;
constexpr double kPi = std::numbers::pi;

// A rotation channel's curve made continuous (motion::unwrap_angles); with `start_near_zero`, moved
// by whole turns so that it starts within pi of 0.
Eigen::VectorXd unwrapped(Eigen::VectorXd x, bool start_near_zero = false) {
  motion::unwrap_angles(std::span<double>(x.data(), static_cast<std::size_t>(x.size())));
  if (start_near_zero && x.size() > 0) {
    const double turn = motion::nearest_angle(x(0), 0) - x(0);
    if (turn != 0) x.array() += turn;
  }
  return x;
}

void check_same_layout(const Motion& a, const Motion& b, const char* what) {
  if (a.frame_count() != b.frame_count() || a.values.cols() != b.values.cols())
    throw std::invalid_argument(std::string("metrics: the result (") + std::to_string(a.frame_count()) +
                                " frames x " + std::to_string(a.values.cols()) + " channels) and the " +
                                what + " (" + std::to_string(b.frame_count()) + " x " +
                                std::to_string(b.values.cols()) + ") differ in shape");
  for (int c = 0; c < a.values.cols(); ++c) {
    const bool ra =
        motion::is_rotation(a.skeleton->joint(a.skeleton->channel_owner(c).first)
                                .channels[static_cast<std::size_t>(a.skeleton->channel_owner(c).second)]
                                .kind);
    const bool rb =
        motion::is_rotation(b.skeleton->joint(b.skeleton->channel_owner(c).first)
                                .channels[static_cast<std::size_t>(b.skeleton->channel_owner(c).second)]
                                .kind);
    if (ra != rb)
      throw std::invalid_argument(std::string("metrics: channel ") + std::to_string(c) + " is a " +
                                  (ra ? "rotation" : "position") + " in the result but not in the " + what);
  }
}

bool channel_is_rotation(const motion::Skeleton& s, int c) {
  const auto [joint, index] = s.channel_owner(c);
  return motion::is_rotation(s.joint(joint).channels[static_cast<std::size_t>(index)].kind);
}

// Sum of squared third differences of `x` (times fps^3).
double jerk_sum_squares(const Eigen::VectorXd& x, double fps) {
  const double scale = fps * fps * fps;
  double sum = 0;
  for (Eigen::Index f = 0; f + 3 < x.size(); ++f) {
    const double j = (x(f + 3) - 3 * x(f + 2) + 3 * x(f + 1) - x(f)) * scale;
    sum += j * j;
  }
  return sum;
}

JerkFigures jerk_of(const Motion& shape, const std::function<Eigen::VectorXd(int)>& channel) {
  JerkFigures out;
  const int frames = shape.frame_count();
  out.samples = std::max(0, frames - 3);
  double sum_t = 0, sum_r = 0;
  for (int c = 0; c < shape.values.cols(); ++c) {
    const bool rotation = channel_is_rotation(*shape.skeleton, c);
    const double s = jerk_sum_squares(channel(c), shape.fps);
    if (rotation) {
      ++out.rotation_channels;
      sum_r += s;
    } else {
      ++out.translation_channels;
      sum_t += s;
    }
  }
  if (out.samples > 0) {
    if (out.translation_channels > 0)
      out.translation = std::sqrt(sum_t / (out.samples * out.translation_channels));
    if (out.rotation_channels > 0) out.rotation = std::sqrt(sum_r / (out.samples * out.rotation_channels));
  }
  return out;
}

// The displacement of channel c: result - reference, rotations unwrapped over time from within pi
// of 0.
Eigen::VectorXd displacement(const Motion& result, const Motion& reference, int c) {
  Eigen::VectorXd d = result.values.col(c) - reference.values.col(c);
  if (channel_is_rotation(*result.skeleton, c)) d = unwrapped(d, true);
  return d;
}

}  // namespace

// ---- foot skate ----
std::vector<PlantSkate> find_plants(const ConstraintSet& set) {
  // Point identity -> frame -> (offset at that frame, the constraints naming it there), in order
  // of first appearance.
  using Key = std::tuple<int, double, double, double>;
  struct AtFrame {
    Eigen::Vector3d local;
    std::vector<std::size_t> constraints;  // indices into set.constraints, ascending
  };
  std::map<Key, std::size_t> index;
  std::vector<std::pair<PointRef, std::map<int, AtFrame>>> points;
  for (std::size_t ci = 0; ci < set.constraints.size(); ++ci) {
    const Constraint& c = set.constraints[ci];
    const bool position = c.kind == "position", same_place = c.kind == "same_place";
    if (c.soft || (!position && !same_place)) continue;  // a soft feature that stays put is no plant
    if (std::any_of(c.points.begin(), c.points.end(), [](const PointRef& p) { return p.character != 0; }))
      continue;
    // A target that moves on the floor is not a plant (a height that changes is: a morphing foot).
    if (position) {
      auto horizontal = [&](const Sample& s) {
        const std::vector<double>& p = s.params.empty() ? c.params : s.params;
        return std::pair(p.size() > 0 ? p[0] : 0.0, p.size() > 2 ? p[2] : 0.0);
      };
      if (std::any_of(c.samples.begin(), c.samples.end(),
                      [&](const Sample& s) { return horizontal(s) != horizontal(c.samples.front()); }))
        continue;
    }
    for (std::size_t i = 0; i < c.points.size(); ++i) {
      const PointRef& p = c.points[i];
      const Key key{p.joint, p.local.x(), p.local.y(), p.local.z()};
      auto [it, added] = index.try_emplace(key, points.size());
      if (added) points.push_back({p, {}});
      std::map<int, AtFrame>& frames = points[it->second].second;
      for (const Sample& s : c.samples) {
        if (i >= s.frames.size()) continue;
        AtFrame& at = frames.try_emplace(s.frames[i], AtFrame{point_at(c, s, i).local, {}}).first->second;
        if (at.constraints.empty() || at.constraints.back() != ci) at.constraints.push_back(ci);
      }
    }
  }
  // A run of consecutive frames is one plant while each frame shares a constraint with the one
  // before: two plants of one foot that touch at a coarse rate stay two.
  const auto share = [](const AtFrame& a, const AtFrame& b) {
    return std::find_first_of(a.constraints.begin(), a.constraints.end(), b.constraints.begin(),
                              b.constraints.end()) != a.constraints.end();
  };
  std::vector<PlantSkate> plants;
  for (const auto& [point, frames] : points) {
    auto it = frames.begin();
    while (it != frames.end()) {
      PlantSkate plant;
      plant.point = point;
      plant.label = set.constraints[it->second.constraints.front()].label;
      plant.first_frame = plant.last_frame = plant.worst_frame = it->first;
      plant.locals = {it->second.local};
      for (auto previous = it++;
           it != frames.end() && it->first == plant.last_frame + 1 && share(previous->second, it->second);
           previous = it++) {
        plant.last_frame = it->first;
        plant.locals.push_back(it->second.local);
      }
      plants.push_back(plant);
    }
  }
  return plants;
}

SkateSummary foot_skate(const ConstraintSet& set, const PoseCache& poses) {
  SkateSummary out;
  out.plants = find_plants(set);
  for (PlantSkate& plant : out.plants) {
    auto at = [&](int f) {
      PointRef p = plant.point;
      p.local = plant.locals[static_cast<std::size_t>(f - plant.first_frame)];
      return poses.point(p, f);
    };
    const Eigen::Vector3d start = at(plant.first_frame);
    for (int f = plant.first_frame + 1; f <= plant.last_frame; ++f) {
      const Eigen::Vector3d p = at(f);
      const double travel = std::hypot(p.x() - start.x(), p.z() - start.z());
      if (travel > plant.travel) {
        plant.travel = travel;
        plant.worst_frame = f;
      }
    }
    out.worst = std::max(out.worst, plant.travel);
    out.mean += plant.travel;
  }
  if (!out.plants.empty()) out.mean /= static_cast<double>(out.plants.size());
  return out;
}

// ---- jerk ----
double rms_joint_jerk(const Motion& motion) {
  const Eigen::MatrixXd p = motion::joint_world_positions(motion);
  const Eigen::Index n = p.rows() - 3;
  if (n < 1) return 0;
  const Eigen::MatrixXd j =
      (p.bottomRows(n) - 3 * p.middleRows(2, n) + 3 * p.middleRows(1, n) - p.topRows(n)) *
      std::pow(motion.fps, 3);
  return std::sqrt(j.squaredNorm() / static_cast<double>(j.size()));
}

JerkFigures rms_jerk(const Motion& motion) {
  motion.check();
  return jerk_of(motion, [&](int c) -> Eigen::VectorXd {
    if (channel_is_rotation(*motion.skeleton, c)) return unwrapped(motion.values.col(c));
    return motion.values.col(c);
  });
}

JerkFigures rms_jerk_of_displacement(const Motion& result, const Motion& reference) {
  result.check();
  reference.check();
  check_same_layout(result, reference, "reference");
  return jerk_of(result, [&](int c) { return displacement(result, reference, c); });
}

// ---- energy ----
double key_cutoff_hz(double fps, int frames_per_key) {
  if (!(fps > 0) || frames_per_key < 1)
    throw std::invalid_argument("key_cutoff_hz: fps must be > 0 and frames_per_key >= 1");
  return fps / (2.0 * frames_per_key);
}

namespace {
// Orthonormal DCT-II of the columns of `x` (N x channels), by blocks of rows of the basis so
// memory stays O(block N) for long clips.
Eigen::MatrixXd dct2(const Eigen::MatrixXd& x) {
  const Eigen::Index n = x.rows();
  Eigen::MatrixXd out(n, x.cols());
  const Eigen::Index block = 256;
  Eigen::MatrixXd basis;
  for (Eigen::Index m0 = 0; m0 < n; m0 += block) {
    const Eigen::Index rows = std::min(block, n - m0);
    basis.resize(rows, n);
    for (Eigen::Index m = 0; m < rows; ++m) {
      const double scale = std::sqrt((m0 + m == 0 ? 1.0 : 2.0) / static_cast<double>(n));
      for (Eigen::Index k = 0; k < n; ++k)
        basis(m, k) = scale * std::cos(kPi * static_cast<double>(m0 + m) * (2.0 * k + 1) / (2.0 * n));
    }
    out.middleRows(m0, rows).noalias() = basis * x;
  }
  return out;
}

// Adds one DCT column's energy to `band`.
void add_energy(BandEnergy& band, const Eigen::Ref<const Eigen::VectorXd>& coefficients, double fps,
                double cutoff) {
  const Eigen::Index n = coefficients.size();
  for (Eigen::Index m = 0; m < n; ++m) {
    const double e = coefficients(m) * coefficients(m);
    band.total += e;
    if (m * fps / (2.0 * n) > cutoff) band.above += e;
  }
  ++band.channels;
}

void finish(BandEnergy& band) {
  band.fraction = band.total > 0 ? band.above / band.total : 0.0;
}
}  // namespace

BandEnergy energy_above(const Eigen::Ref<const Eigen::VectorXd>& signal, double fps, double cutoff_hz) {
  BandEnergy band;
  const Eigen::MatrixXd x = signal;
  const Eigen::MatrixXd coefficients = dct2(x);
  add_energy(band, coefficients.col(0), fps, cutoff_hz);
  finish(band);
  return band;
}

AddedEnergy energy_above_cutoff(const Motion& result, const Motion& reference,
                                const std::vector<int>& frames_per_key, double keys_fps) {
  result.check();
  reference.check();
  check_same_layout(result, reference, "reference");
  const int channels = static_cast<int>(result.values.cols());
  if (frames_per_key.size() != 1 && static_cast<int>(frames_per_key.size()) != channels)
    throw std::invalid_argument("metrics: key spacing has " + std::to_string(frames_per_key.size()) +
                                " entries, expected 1 or the motion's " + std::to_string(channels) +
                                " channels");
  Eigen::MatrixXd d(result.frame_count(), channels);
  for (int c = 0; c < channels; ++c) d.col(c) = displacement(result, reference, c);
  const Eigen::MatrixXd coefficients = dct2(d);
  AddedEnergy out;
  out.min_cutoff_hz = std::numeric_limits<double>::infinity();
  out.max_cutoff_hz = 0;
  for (int c = 0; c < channels; ++c) {
    const int k =
        frames_per_key.size() == 1 ? frames_per_key[0] : frames_per_key[static_cast<std::size_t>(c)];
    const double cutoff = key_cutoff_hz(keys_fps > 0 ? keys_fps : result.fps, k);
    out.min_cutoff_hz = std::min(out.min_cutoff_hz, cutoff);
    out.max_cutoff_hz = std::max(out.max_cutoff_hz, cutoff);
    add_energy(channel_is_rotation(*result.skeleton, c) ? out.rotation : out.translation, coefficients.col(c),
               result.fps, cutoff);
  }
  if (channels == 0) out.min_cutoff_hz = 0;
  finish(out.translation);
  finish(out.rotation);
  return out;
}

// ---- everything ----
RetargetMetrics compute_metrics(const MetricsInputs& in) {
  if (!in.result || !in.constraints || !in.kinds)
    throw std::invalid_argument("metrics: a result motion, constraints and their kinds are required");
  const Motion& result = *in.result;
  result.check();
  if (in.constraints->character_count() > 2)
    throw std::invalid_argument("metrics: the constraints name " +
                                std::to_string(in.constraints->character_count()) +
                                " characters; at most two are measured");
  if (in.constraints->character_count() > 1 && !in.result2)
    for (const Constraint& c : in.constraints->constraints)
      if (std::any_of(c.points.begin(), c.points.end(), [](const PointRef& p) { return p.character == 1; }) ||
          std::any_of(c.channels.begin(), c.channels.end(),
                      [](const ChannelRef& p) { return p.character == 1; }))
        throw std::invalid_argument("metrics: constraint '" + c.label +
                                    "' names character 1; give the second character's result (motion2)");
  if (in.result2) {
    in.result2->check();
    if (in.result2->frame_count() != result.frame_count() ||
        std::abs(in.result2->fps - result.fps) > 1e-9 * result.fps)
      throw std::invalid_argument(
          "metrics: the second character has " + std::to_string(in.result2->frame_count()) + " frames at " +
          std::to_string(in.result2->fps) + " Hz, the first " + std::to_string(result.frame_count()) +
          " at " + std::to_string(result.fps) + " Hz");
  }
  check_constraints(*in.constraints, *in.kinds);

  RetargetMetrics out;
  out.motion_name = result.name;
  out.frames = result.frame_count();
  out.fps = result.fps;
  PoseCache::SkeletonAt skeleton_at;
  if (in.target && in.target->morphing()) {
    const Target* target = in.target;
    const double fps = result.fps;
    skeleton_at = [target, fps](int frame) { return target->skeleton_at(frame / fps); };
  }
  std::vector<Motion> characters{result};
  if (in.result2) characters.push_back(*in.result2);
  const std::vector<PoseCache::SkeletonAt> skeletons_at{skeleton_at, {}};
  const PoseCache poses(characters, std::span(skeletons_at).first(characters.size()));
  const ViolationSummary summary = summarize_violations(*in.constraints, *in.kinds, poses, in.tolerance);
  for (const KindViolation& kv : summary.kinds) {
    KindMetrics km{kv, false};
    if (kv.kind != "orientation") {
      for (const Constraint& c : in.constraints->constraints)
        if (c.kind == kv.kind && !c.points.empty()) km.in_metres = true;
    }
    if (km.in_metres) out.worst_violation_metres = std::max(out.worst_violation_metres, kv.worst);
    out.kinds.push_back(km);
  }
  out.skate = foot_skate(*in.constraints, poses);
  if (in.initial) {
    check_same_layout(result, *in.initial, "initial");
    std::vector<Motion> initial{*in.initial};
    if (in.result2) initial.push_back(*in.result2);
    const PoseCache initial_poses(initial, std::span(skeletons_at).first(initial.size()));
    out.initial_skate = foot_skate(*in.constraints, initial_poses);
  }
  out.jerk = rms_jerk(result);
  if (in.source) {
    out.source_jerk = rms_jerk(*in.source);
    out.displacement_jerk = rms_jerk_of_displacement(result, *in.source);
  }
  const Motion* reference = in.initial ? in.initial : in.source;
  if (reference) {
    out.energy_reference = in.initial ? "initial" : "source";
    out.energy = energy_above_cutoff(
        result, *reference, in.frames_per_key.empty() ? std::vector<int>{4} : in.frames_per_key, in.keys_fps);
  }
  out.solve_seconds = in.solve_seconds;
  return out;
}

namespace {
void write_jerk(kg::JsonWriter& w, const JerkFigures& j) {
  w.begin_object();
  w.field("translation_m_per_s3", j.translation);
  w.field("rotation_rad_per_s3", j.rotation);
  w.field("translation_channels", j.translation_channels);
  w.field("rotation_channels", j.rotation_channels);
  w.end_object();
}
void write_band(kg::JsonWriter& w, const BandEnergy& b) {
  w.begin_object();
  w.field("fraction", b.fraction);
  w.field("above", b.above);
  w.field("total", b.total);
  w.field("channels", b.channels);
  w.end_object();
}

// "violation": the worst violation and each kind's figures.
void write_violations(kg::JsonWriter& w, const RetargetMetrics& m) {
  w.key("violation");
  w.begin_object();
  w.field("worst_cm", 100 * m.worst_violation_metres);
  w.key("kinds");
  w.begin_array();
  for (const KindMetrics& k : m.kinds) {
    const double scale = k.in_metres ? 100.0 : 1.0;
    w.begin_object();
    w.field("kind", k.violation.kind);
    w.field("unit", k.in_metres ? "cm" : "native");
    w.field("worst", scale * k.violation.worst);
    w.field("mean", scale * k.violation.mean);
    w.field("rows", k.violation.rows);
    w.field("counted_rows", k.violation.counted_rows);
    w.field("violated_rows", k.violation.violated_rows);
    w.field("worst_label", k.violation.worst_label);
    w.field("worst_frame", k.violation.worst_frame);
    w.end_object();
  }
  w.end_array();
  w.end_object();
}

// "foot_skate_cm": the plants' travel.
void write_skate(kg::JsonWriter& w, const RetargetMetrics& m) {
  w.key("foot_skate_cm");
  w.begin_object();
  w.field("worst", 100 * m.skate.worst);
  w.field("mean", 100 * m.skate.mean);
  w.field("plants_count", m.skate.plants.size());
  if (m.initial_skate) {
    w.field("initial_worst", 100 * m.initial_skate->worst);
    w.field("initial_mean", 100 * m.initial_skate->mean);
  }
  w.key("plants");
  w.begin_array();
  for (const PlantSkate& p : m.skate.plants) {
    w.begin_object();
    w.field("label", p.label);
    w.field("joint", p.point.joint);
    w.field("first_frame", p.first_frame);
    w.field("last_frame", p.last_frame);
    w.field("travel", 100 * p.travel);
    w.field("worst_frame", p.worst_frame);
    w.end_object();
  }
  w.end_array();
  w.end_object();
}

// "jerk": of the result, the source, their difference and the displacement.
void write_jerks(kg::JsonWriter& w, const RetargetMetrics& m) {
  w.key("jerk");
  w.begin_object();
  w.key("result");
  write_jerk(w, m.jerk);
  w.key("source");
  if (m.source_jerk)
    write_jerk(w, *m.source_jerk);
  else
    w.null();
  w.key("increase");
  if (m.source_jerk) {
    w.begin_object();
    w.field("translation_m_per_s3", m.jerk.translation - m.source_jerk->translation);
    w.field("rotation_rad_per_s3", m.jerk.rotation - m.source_jerk->rotation);
    w.end_object();
  } else {
    w.null();
  }
  w.key("displacement");
  if (m.displacement_jerk)
    write_jerk(w, *m.displacement_jerk);
  else
    w.null();
  w.end_object();
}

// "energy_above_cutoff": the pyramid's band energy above the key spacing's cutoff, or null.
void write_energy(kg::JsonWriter& w, const RetargetMetrics& m) {
  w.key("energy_above_cutoff");
  if (m.energy) {
    w.begin_object();
    w.field("reference", m.energy_reference);
    w.field("cutoff_hz_min", m.energy->min_cutoff_hz);
    w.field("cutoff_hz_max", m.energy->max_cutoff_hz);
    w.key("translation");
    write_band(w, m.energy->translation);
    w.key("rotation");
    write_band(w, m.energy->rotation);
    w.end_object();
  } else {
    w.null();
  }
}

}  // namespace

Report metrics_report(const RetargetMetrics& m) {
  Report report;
  kg::JsonWriter w(report);
  w.begin_object();
  w.field("version", 1);
  w.field("motion", m.motion_name);
  w.field("frames", m.frames);
  w.field("fps", m.fps);
  write_violations(w, m);
  write_skate(w, m);
  write_jerks(w, m);
  write_energy(w, m);
  w.field("solve_seconds", m.solve_seconds);
  w.end_object();
  return report;
}

void write_metrics_json(std::ostream& os, const RetargetMetrics& m) {
  metrics_report(m).write(os);
  os << '\n';
}

}  // namespace kg::retarget
