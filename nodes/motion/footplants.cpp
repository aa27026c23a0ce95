// Footplant detection (footplants.hpp).
#include "kg/motion/footplants.hpp"

#include "kg/base/option_check.hpp"
#include "kg/motion/filters.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <span>
#include <sstream>
#include <stdexcept>

#include "kg/base/error.hpp"
#include "kg/base/text.hpp"
#include "kg/motion/kinematics.hpp"

namespace kg::motion {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Lower-case, without a namespace prefix ("mixamorig:"), a "CC_Base_" prefix, '_', '-' and ' ',
// so that LeftFoot, l_foot, Foot_L, CC_Base_L_Foot and lFoot compare alike.
std::string normalised(const std::string& name) {
  std::string n = name.substr(name.find_last_of(':') == std::string::npos ? 0 : name.find_last_of(':') + 1);
  std::string out;
  for (char ch : n) {
    if (ch == '_' || ch == '-' || ch == ' ') continue;
    out += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  }
  if (out.rfind("ccbase", 0) == 0) out = out.substr(6);
  return out;
}

// Whether a normalised name is `side` + `part` or `part` + `side` for a side spelling and part.
bool matches(const std::string& n, std::span<const char* const> sides, std::span<const char* const> parts) {
  for (const char* s : sides)
    for (const char* p : parts)
      if (n == std::string(s) + p || n == std::string(p) + s) return true;
  return false;
}

int find_by_role(const Skeleton& sk, bool left, bool toe) {
  static constexpr const char* kLeft[] = {"left", "l"};
  static constexpr const char* kRight[] = {"right", "r"};
  static constexpr const char* kToe[] = {"toebase", "toes", "toe", "toejoint", "ball"};
  static constexpr const char* kFoot[] = {"foot", "ankle"};
  const std::span<const char* const> sides =
      left ? std::span<const char* const>(kLeft) : std::span<const char* const>(kRight);
  const std::span<const char* const> parts =
      toe ? std::span<const char* const>(kToe) : std::span<const char* const>(kFoot);
  for (int j = 0; j < sk.joint_count(); ++j)
    if (matches(normalised(sk.joint(j).name), sides, parts)) return j;
  return -1;
}

std::vector<PlantPoint> auto_points(const Skeleton& sk, int character, std::vector<std::string>& notes) {
  std::vector<PlantPoint> out;
  for (bool left : {true, false}) {
    const int foot = find_by_role(sk, left, false);
    const int toe = find_by_role(sk, left, true);
    if (foot >= 0) out.push_back(find_point(sk, sk.joint(foot).name, character));
    if (toe >= 0)
      out.push_back(
          find_point(sk, sk.joint(toe).name + (sk.joint(toe).end_sites.empty() ? "" : "/end"), character));
    else if (foot >= 0 && !sk.joint(foot).end_sites.empty())
      out.push_back(find_point(sk, sk.joint(foot).name + "/end", character));
  }
  if (out.empty())
    throw std::invalid_argument(
        "footplants: no foot joint found by name (tried LeftFoot/RightFoot, lfoot/rfoot, l_foot, Foot_L, "
        "LeftAnkle, ...); name the points");
  std::string list;
  for (const PlantPoint& p : out) list += (list.empty() ? "" : ", ") + p.name;
  notes.push_back("points (auto): " + list);
  return out;
}

}  // namespace

PlantPoint find_point(const Skeleton& sk, const std::string& spec, int character, const std::string& who) {
  std::string joint = spec;
  bool end = false, has_offset = false;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  if (spec.size() > 4 && spec.compare(spec.size() - 4, 4, "/end") == 0) {
    joint = spec.substr(0, spec.size() - 4);
    end = true;
  } else if (const auto open = spec.find('['); open != std::string::npos) {
    // "LeftFoot[0 -0.07 -0.05]": a point in the joint's frame (a heel), metres.
    std::istringstream in(spec.substr(open + 1));
    char close = 0;
    if (spec.back() != ']' || !(in >> offset.x() >> offset.y() >> offset.z() >> close) || close != ']' ||
        !offset.allFinite())
      throw std::invalid_argument(who + ": point '" + spec +
                                  "': expected Joint[x y z] (metres, in the joint's frame)");
    joint = spec.substr(0, open);
    has_offset = true;
  }
  const int j = sk.find_joint(joint);
  if (j < 0) {
    std::string msg = who + ": unknown joint " + text::in_quotes(joint);
    const std::string near = nearest_joint_name(sk, joint);
    if (!near.empty()) msg += " (nearest: " + text::in_quotes(near) + ")";
    throw std::invalid_argument(msg);
  }
  PlantPoint p;
  p.name = spec;
  p.point.character = character;
  p.point.joint = j;
  if (end) {
    if (sk.joint(j).end_sites.empty())
      throw std::invalid_argument(who + ": joint " + text::in_quotes(joint) + " has no End Site (" +
                                  text::in_quotes(spec) + ")");
    p.point.local = sk.joint(j).end_sites.front();
  }
  if (has_offset) p.point.local = offset;
  return p;
}

std::vector<Eigen::Vector3d> point_positions(const Motion& m, const std::vector<PlantPoint>& points) {
  const Skeleton& sk = *m.skeleton;
  std::vector<Eigen::Vector3d> out(static_cast<std::size_t>(m.frame_count()) * points.size());
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(sk.joint_count()));
  for (int f = 0; f < m.frame_count(); ++f) {
    forward_kinematics(sk, m.values.row(f), world);
    for (std::size_t i = 0; i < points.size(); ++i)
      out[static_cast<std::size_t>(f) * points.size() + i] =
          world[static_cast<std::size_t>(points[i].point.joint)] * points[i].point.local;
  }
  return out;
}

namespace {

// The body's pace where it runs: the horizontal speed (m/s, over +-0.1 s) of the mean of its
// joints' positions (whatever joint carries the translation; joints that never move, as a static
// root at the origin, left out) at the frames where its Froude number v^2 / (g h) passes
// run_froude (h: that centre's median height above the floor), else 0.
struct BodyPace {
  std::vector<double> pace;  // per frame; 0 where the body walks or stands
  double centre_height = 0;  // m above the floor
  int running_frames = 0;
  double fastest = 0;  // m/s
};

BodyPace running_pace(const Motion& m, double floor, double run_froude) {
  const int frames = m.frame_count();
  const Eigen::MatrixXd world = joint_world_positions(m);  // frames x 3 joints
  const Eigen::Index joints = world.cols() / 3;
  std::vector<Eigen::Index> moving;
  for (Eigen::Index j = 0; j < joints; ++j) {
    const auto xyz = world.middleCols(3 * j, 3);
    if (frames > 0 && (xyz.colwise().maxCoeff() - xyz.colwise().minCoeff()).maxCoeff() > 1e-6)
      moving.push_back(j);
  }
  std::vector<Eigen::Vector3d> centre(static_cast<std::size_t>(frames), Eigen::Vector3d::Zero());
  std::vector<double> heights(static_cast<std::size_t>(frames));
  for (int f = 0; f < frames; ++f) {
    Eigen::Vector3d& c = centre[static_cast<std::size_t>(f)];
    for (const Eigen::Index j : moving) c += world.row(f).segment<3>(3 * j).transpose();
    c /= static_cast<double>(std::max<std::size_t>(1, moving.size()));
    heights[static_cast<std::size_t>(f)] = c.y() - floor;
  }
  BodyPace out;
  out.pace.assign(static_cast<std::size_t>(frames), 0.0);
  if (frames < 2) return out;
  out.centre_height = percentile(heights, 0.5);
  if (!(out.centre_height > 0)) return out;
  const double running_speed = std::sqrt(run_froude * kEarthGravity * out.centre_height);
  const int k = std::max(1, static_cast<int>(std::lround(0.1 * m.fps)));
  for (int f = 0; f < frames; ++f) {
    const int a = std::max(0, f - k), b = std::min(frames - 1, f + k);
    const Eigen::Vector3d dv = centre[static_cast<std::size_t>(b)] - centre[static_cast<std::size_t>(a)];
    const double v = std::hypot(dv.x(), dv.z()) * m.fps / (b - a);
    if (v <= running_speed) continue;
    out.pace[static_cast<std::size_t>(f)] = v;
    ++out.running_frames;
    out.fastest = std::max(out.fastest, v);
  }
  return out;
}

}  // namespace

int FootplantDetection::count(int point) const {
  return static_cast<int>(
      std::count_if(plants.begin(), plants.end(), [&](const Footplant& p) { return p.point == point; }));
}

void FootplantOptions::validate() const {
  using options::require;
  const char* o = "FootplantOptions";
  require(options::positive(height_threshold), o, "height_threshold", height_threshold,
          "> 0 and finite (metres)");
  require(options::positive(speed_threshold), o, "speed_threshold", speed_threshold, "> 0 and finite (m/s)");
  require(options::non_negative(speed_relative) && speed_relative < 1, o, "speed_relative", speed_relative,
          "in [0, 1)");
  require(options::non_negative(body_relative) && body_relative < 1, o, "body_relative", body_relative,
          "in [0, 1)");
  require(options::positive(run_froude), o, "run_froude", run_froude, "> 0 and finite");
  require(hysteresis >= 1 && std::isfinite(hysteresis), o, "hysteresis", hysteresis,
          ">= 1 and finite (leave thresholds = enter thresholds x hysteresis)");
  require(options::non_negative(min_duration_s), o, "min_duration_s", min_duration_s,
          ">= 0 and finite (seconds)");
  require(min_duration_frames >= 1, o, "min_duration_frames", min_duration_frames, ">= 1");
  require(!std::isinf(floor), o, "floor", floor, "a finite height (metres), or NaN: estimated");
  require(floor_percentile >= 0 && floor_percentile <= 0.5, o, "floor_percentile", floor_percentile,
          "in [0, 0.5]");
  require(options::non_negative(trim_distance), o, "trim_distance", trim_distance,
          ">= 0 and finite (metres; 0: no trimming)");
  require(options::non_negative(bridge_s), o, "bridge_s", bridge_s, ">= 0 and finite (seconds; 0: none)");
  require(options::non_negative(bridge_distance), o, "bridge_distance", bridge_distance,
          ">= 0 and finite (metres)");
  require(options::non_negative(rest_window_s), o, "rest_window_s", rest_window_s,
          ">= 0 and finite (seconds)");
  require(character >= 0, o, "character", character, ">= 0");
}

FootplantDetection detect_footplants(const Motion& m, const FootplantOptions& o) {
  if (!m.skeleton) throw std::invalid_argument("footplants: the motion has no skeleton");
  o.validate();
  const Skeleton& sk = *m.skeleton;
  FootplantDetection d;
  if (o.points.empty())
    d.points = auto_points(sk, o.character, d.notes);
  else
    for (const std::string& name : o.points) d.points.push_back(find_point(sk, name, o.character));

  const int frames = m.frame_count();
  const std::size_t np = d.points.size();
  const std::vector<Eigen::Vector3d> pos = point_positions(m, d.points);
  auto at = [&](int f, std::size_t i) -> const Eigen::Vector3d& {
    return pos[static_cast<std::size_t>(f) * np + i];
  };

  std::vector<std::vector<double>> heights(np);
  for (std::size_t i = 0; i < np; ++i) {
    heights[i].resize(static_cast<std::size_t>(frames));
    for (int f = 0; f < frames; ++f) heights[i][static_cast<std::size_t>(f)] = at(f, i).y();
  }
  std::vector<double> rest(np, 0.0);
  const bool rest_on_floor = o.rest_on_floor && !std::isnan(o.floor);
  for (std::size_t i = 0; i < np; ++i)
    rest[i] = rest_on_floor ? o.floor : percentile(heights[i], o.floor_percentile);
  if (std::isnan(o.floor)) {
    d.floor = np == 0 || frames == 0 ? 0.0 : *std::min_element(rest.begin(), rest.end());
    std::ostringstream note;
    note << "floor (estimated, " << o.floor_percentile * 100
         << "th percentile of the lowest point): " << d.floor << " m";
    d.notes.push_back(note.str());
    d.floor_estimated = true;
  } else {
    d.floor = o.floor;
  }
  for (std::size_t i = 0; i < np; ++i) {
    d.points[i].rest_height = rest[i];
    d.points[i].heights = heights[i];
    d.points[i].rest_levels.assign(static_cast<std::size_t>(frames), rest[i]);
  }
  if (frames < 2) return d;

  const int k = std::max(1, static_cast<int>(std::lround(m.fps / 60.0)));
  const int half_window = static_cast<int>(std::lround(o.rest_window_s * m.fps / 2));
  const int min_frames =
      std::max(o.min_duration_frames, static_cast<int>(std::ceil(o.min_duration_s * m.fps - 1e-9)));
  const BodyPace running = running_pace(m, d.floor, o.run_froude);
  if (running.running_frames > 0)
    d.notes.push_back("the body runs at " + std::to_string(running.running_frames) + " of " +
                      std::to_string(frames) + " frames (up to " + text::significant(running.fastest, 3) +
                      " m/s: Froude number v^2/(g h) above run_froude " + text::significant(o.run_froude, 3) +
                      ", h = " + text::significant(running.centre_height, 3) +
                      " m, the height of its joints' mean above the floor)");
  const std::vector<double> body =
      o.body_relative > 0 && running.running_frames > 0 ? running.pace : std::vector<double>{};
  // Per point: its runs of min_frames or more within height_threshold of its rest level, and the
  // warning it would get, said only if no point of its foot is planted during such a run.
  std::vector<std::vector<std::pair<int, int>>> low_runs(np);
  std::vector<std::string> would_warn(np);
  for (std::size_t i = 0; i < np; ++i) {
    const std::size_t plants_before = d.plants.size();
    int bridged = 0, longest_bridge = 0;
    double widest_bridge = 0;
    auto speed = [&](int f) {
      const int a = std::max(0, f - k), b = std::min(frames - 1, f + k);
      const Eigen::Vector3d dv = at(b, i) - at(a, i);
      return std::hypot(dv.x(), dv.z()) * m.fps / (b - a);
    };
    auto close = [&](int first, int last) {
      if (o.trim_distance > 0 && last > first) {
        // Trim the ends that stray from the span's (component-wise) median position: the roll
        // into and out of a plant, which the thresholds admit late or release late.
        Eigen::Vector3d median;
        std::vector<double> axis(static_cast<std::size_t>(last - first + 1));
        for (int a = 0; a < 3; ++a) {
          for (int f = first; f <= last; ++f) axis[static_cast<std::size_t>(f - first)] = at(f, i)[a];
          median[a] = percentile(axis, 0.5);
        }
        // Where the body moves fast (a run), a point slower than body_relative x its pace covers
        // that much over the shortest plant while still in stance: only the roll beyond is trimmed.
        double reach = o.trim_distance;
        if (!body.empty()) {
          std::vector<double> paces(body.begin() + first, body.begin() + last + 1);
          reach = std::max(reach, o.body_relative * percentile(paces, 0.5) * o.min_duration_s);
        }
        while (first < last && (at(first, i) - median).norm() > reach) ++first;
        while (last > first && (at(last, i) - median).norm() > reach) --last;
      }
      if (last - first + 1 < min_frames) return;
      // A lift shorter than bridge_s, back to where the point left the floor, is the capture's
      // jitter, not a step: the plant goes on.
      if (d.plants.size() > plants_before) {
        Footplant& previous = d.plants.back();
        const int gap = first - previous.last_frame - 1;
        const Eigen::Vector3d moved = at(first, i) - at(previous.last_frame, i);
        if (gap * 1.0 < o.bridge_s * m.fps && std::hypot(moved.x(), moved.z()) <= o.bridge_distance) {
          ++bridged;
          longest_bridge = std::max(longest_bridge, gap);
          widest_bridge = std::max(widest_bridge, std::hypot(moved.x(), moved.z()));
          first = previous.first_frame;
          d.plants.pop_back();
        }
      }
      Footplant p;
      p.point = static_cast<int>(i);
      p.first_frame = first;
      p.last_frame = last;
      p.mean.setZero();
      for (int f = first; f <= last; ++f) {
        p.mean += at(f, i);
        const Eigen::Vector3d dv = at(f, i) - at(first, i);
        p.skate = std::max(p.skate, std::hypot(dv.x(), dv.z()));
      }
      p.mean /= static_cast<double>(last - first + 1);
      d.plants.push_back(p);
    };
    // The rest level: the point's own low percentile, or its lowest height within the window
    // around each frame (floors that slope or drift between steps).
    std::vector<double> base(static_cast<std::size_t>(frames), d.points[i].rest_height);
    if (half_window > 0 && !rest_on_floor)
      for (int f = 0; f < frames; ++f) {
        double low = kInf;
        for (int g = std::max(0, f - half_window); g <= std::min(frames - 1, f + half_window); ++g)
          low = std::min(low, heights[i][static_cast<std::size_t>(g)]);
        base[static_cast<std::size_t>(f)] = low;
      }
    d.points[i].rest_levels = base;
    // The entering speed: speed_threshold, or a share of the point's own fast speed when that is
    // more (a run's stance rolls at 0.1 to 1.3 m/s at 30 Hz; a walk's stays under 0.15).
    std::vector<double> speeds(static_cast<std::size_t>(frames));
    for (int f = 0; f < frames; ++f) speeds[static_cast<std::size_t>(f)] = speed(f);
    const double fast = percentile(speeds, 0.9);
    const double enter_speed = std::max(o.speed_threshold, o.speed_relative * fast);
    if (enter_speed > o.speed_threshold)
      d.notes.push_back(d.points[i].name + ": speed threshold " + text::significant(enter_speed, 3) +
                        " m/s (" + text::significant(100 * o.speed_relative, 3) +
                        "% of its 90th-percentile speed, " + text::significant(fast, 3) +
                        " m/s: more than speed_threshold " + text::significant(o.speed_threshold, 3) + ")");
    int low_run = 0, longest_low_run = 0;  // consecutive frames within height_threshold
    std::vector<double> low_speeds;        // the point's speed at those frames
    bool in = false;
    int start = 0;
    int by_body = 0;  // frames kept in a span only by the body's pace
    double by_body_speed = 0, by_body_pace = 0;
    for (int f = 0; f < frames; ++f) {
      const double h = at(f, i).y() - base[static_cast<std::size_t>(f)], v = speed(f);
      const double pace = body.empty() ? 0.0 : body[static_cast<std::size_t>(f)];
      const double threshold = std::max(enter_speed, o.body_relative * pace);
      low_run = h <= o.height_threshold ? low_run + 1 : 0;
      if (low_run == min_frames) low_runs[i].push_back({f - min_frames + 1, f});
      if (low_run > min_frames) low_runs[i].back().second = f;
      longest_low_run = std::max(longest_low_run, low_run);
      if (h <= o.height_threshold) low_speeds.push_back(v);
      if (!in) {
        if (h <= o.height_threshold && v <= threshold) {
          in = true;
          start = f;
        }
      } else if (h > o.height_threshold * o.hysteresis || v > threshold * o.hysteresis) {
        in = false;
        close(start, f - 1);
      }
      if (in && v > enter_speed * (f == start ? 1 : o.hysteresis)) {
        ++by_body;
        by_body_speed = std::max(by_body_speed, v);
        by_body_pace = std::max(by_body_pace, pace);
      }
    }
    if (by_body > 0)
      d.notes.push_back(d.points[i].name + ": " + std::to_string(by_body) + " frame" +
                        (by_body == 1 ? "" : "s") + " on the floor at up to " +
                        text::significant(by_body_speed, 3) + " m/s, slower than " +
                        text::significant(100 * o.body_relative, 3) + "% of the body's pace (up to " +
                        text::significant(by_body_pace, 3) + " m/s; body_relative), kept in stance");
    if (in) close(start, frames - 1);
    if (bridged > 0)
      d.notes.push_back(d.points[i].name + ": " + std::to_string(bridged) + " lift" +
                        (bridged == 1 ? "" : "s") + " of at most " + std::to_string(longest_bridge) +
                        " frame" + (longest_bridge == 1 ? "" : "s") + " (" +
                        text::significant(longest_bridge / m.fps, 3) + " s) inside a plant, back within " +
                        text::significant(100 * widest_bridge, 3) +
                        " cm of where it left, bridged (bridge_s " + text::significant(o.bridge_s, 3) +
                        " s, bridge_distance " + text::significant(100 * o.bridge_distance, 3) + " cm)");
    if (d.plants.size() == plants_before && longest_low_run >= min_frames) {
      std::ostringstream w;
      w << d.points[i].name << " gets no plant although it stays within " << o.height_threshold * 100
        << " cm of its rest level for " << longest_low_run << " frames ("
        << text::significant(longest_low_run / m.fps, 3) << " s at " << text::significant(m.fps, 4)
        << " fps): its horizontal speed there is "
        << text::significant(*std::min_element(low_speeds.begin(), low_speeds.end()), 3) << " to "
        << text::significant(*std::max_element(low_speeds.begin(), low_speeds.end()), 3) << " m/s (median "
        << text::significant(percentile(low_speeds, 0.5), 3) << "), and a plant needs " << min_frames
        << " frames below its speed threshold " << text::significant(enter_speed, 3)
        << " m/s (a run, or a noisy capture?); raise speed_threshold, or give the plants in a constraint "
           "file";
      would_warn[i] = w.str();
    }
  }
  // A point rolling on the floor while another point of its foot is planted (a run's ankle over
  // its planted toe) needs no plant of its own: its foot has one.
  auto same_foot = [&](std::size_t a, std::size_t b) {
    auto above = [&](int joint, int ancestor) {
      for (int j = joint; j >= 0; j = sk.joint(j).parent)
        if (j == ancestor) return true;
      return false;
    };
    const int ja = d.points[a].point.joint, jb = d.points[b].point.joint;
    return above(ja, jb) || above(jb, ja);
  };
  for (std::size_t i = 0; i < np; ++i) {
    if (would_warn[i].empty()) continue;
    bool unsupported = false;
    for (const auto& [first, last] : low_runs[i]) {
      bool planted = false;
      for (const Footplant& p : d.plants)
        planted = planted || (same_foot(i, static_cast<std::size_t>(p.point)) && p.first_frame <= last &&
                              p.last_frame >= first);
      unsupported = unsupported || !planted;
    }
    if (unsupported) d.warnings.push_back(would_warn[i]);
  }
  return d;
}

std::vector<std::string> split_names(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const auto a = item.find_first_not_of(" \t");
    const auto b = item.find_last_not_of(" \t");
    if (a != std::string::npos) out.push_back(item.substr(a, b - a + 1));
  }
  return out;
}

double parse_floor(const std::string& text) {
  if (text == "auto" || text.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !std::isfinite(v))
    throw std::invalid_argument("floor " + text::in_quotes(text) + ": expected 'auto' or a height in metres");
  return v;
}

}  // namespace kg::motion
