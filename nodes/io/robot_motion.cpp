// Robot motions as CSV and JSON (robot_motion.hpp).
#include "kg/io/robot_motion.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string_view>
#include <unordered_map>

#include "kg/base/error.hpp"
#include "kg/base/json.hpp"
#include "kg/base/text.hpp"
#include "kg/io/import_options.hpp"
#include "kg/io/urdf.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/motion/rotations.hpp"

namespace kg::io {

namespace {

void require_robot_shape(const motion::Motion& motion) {
  const motion::Skeleton& s = *motion.skeleton;
  const std::string who = motion.name.empty() ? std::string("the motion") : text::excerpt(motion.name);
  if (s.joint_count() == 0) throw std::invalid_argument(who + " has no joints: not a robot motion");
  const motion::Joint& root = s.joint(0);
  int positions = 0, rotations = 0;
  for (const motion::Channel& c : root.channels) (motion::is_rotation(c.kind) ? rotations : positions) += 1;
  if (positions != 3 || rotations != 3)
    throw std::invalid_argument(who + ": a robot motion's root " + text::excerpt(root.name) +
                                " has 3 position and 3 rotation channels (a floating base); it has " +
                                std::to_string(positions) + " and " + std::to_string(rotations));
  for (int j = 1; j < s.joint_count(); ++j) {
    if (s.joint(j).parent < 0)
      throw std::invalid_argument(who + ": a robot motion has one root; " + text::excerpt(s.joint(j).name) +
                                  " is a second");
    if (s.joint(j).channels.size() > 1)
      throw std::invalid_argument(who +
                                  ": a robot motion has at most one channel per joint (a URDF target's "
                                  "skeleton); joint " +
                                  text::excerpt(s.joint(j).name) + " has " +
                                  std::to_string(s.joint(j).channels.size()));
  }
}

}  // namespace

RobotTrajectory robot_trajectory(const motion::Motion& motion) {
  motion.check();
  require_robot_shape(motion);
  const motion::Skeleton& s = *motion.skeleton;
  RobotTrajectory out;
  out.fps = motion.fps;
  std::vector<int> joints;
  for (int j = 1; j < s.joint_count(); ++j)
    if (!s.joint(j).channels.empty()) {
      joints.push_back(j);
      out.joint_names.push_back(s.joint(j).name);
    }
  const int frames = motion.frame_count();
  out.root_pos.resize(frames, 3);
  out.root_rot.resize(frames, 4);
  out.dof_pos.resize(frames, static_cast<Eigen::Index>(joints.size()));
  const Eigen::Matrix3d to_z_up = z_up_to_y_up().transpose() * s.file_to_world;
  Eigen::Quaterniond previous(1, 0, 0, 0);
  for (int f = 0; f < frames; ++f) {
    const auto row = motion.values.row(f);
    const Eigen::Isometry3d base = motion::local_transform(s, 0, row);
    out.root_pos.row(f) = (to_z_up * base.translation()).transpose();
    Eigen::Quaterniond q(to_z_up * base.linear());
    q.normalize();
    if ((f == 0 && q.w() < 0) || (f > 0 && q.dot(previous) < 0)) q.coeffs() = -q.coeffs();
    previous = q;
    out.root_rot.row(f) << q.x(), q.y(), q.z(), q.w();
    for (std::size_t i = 0; i < joints.size(); ++i) {
      const motion::Joint& j = s.joint(joints[i]);
      const double v = row[j.first_channel];
      double value = v;
      if (!motion::is_rotation(j.channels[0].kind)) {
        const int k = motion::axis_index(j.channels[0].kind);
        value = (j.axis(k, 0) < 0 ? -1.0 : 1.0) * (v - j.offset[k]);
      }
      out.dof_pos(f, static_cast<Eigen::Index>(i)) = value + 0.0;  // no -0 written
    }
  }
  return out;
}

void write_robot_csv(std::ostream& os, const RobotTrajectory& t, int precision) {
  os << "time,root_x,root_y,root_z,root_qx,root_qy,root_qz,root_qw";
  for (const std::string& name : t.joint_names) os << ',' << name;
  os << '\n';
  char buf[64];
  auto put = [&](double x) {
    std::snprintf(buf, sizeof buf, "%.*f", precision, x);
    os << ',' << buf;
  };
  for (Eigen::Index f = 0; f < t.root_pos.rows(); ++f) {
    std::snprintf(buf, sizeof buf, "%.*f", precision, static_cast<double>(f) / t.fps);
    os << buf;
    for (int k = 0; k < 3; ++k) put(t.root_pos(f, k));
    for (int k = 0; k < 4; ++k) put(t.root_rot(f, k));
    for (Eigen::Index k = 0; k < t.dof_pos.cols(); ++k) put(t.dof_pos(f, k));
    os << '\n';
  }
}

void write_robot_json(std::ostream& os, const RobotTrajectory& t) {
  JsonWriter w(os, 0);
  auto rows = [&](const Eigen::MatrixXd& m) {
    w.begin_array();
    for (Eigen::Index f = 0; f < m.rows(); ++f) {
      w.begin_array();
      for (Eigen::Index k = 0; k < m.cols(); ++k) w.value(m(f, k));
      w.end_array();
    }
    w.end_array();
  };
  w.begin_object();
  w.key("fps");
  w.value(t.fps);
  w.key("joint_names");
  w.begin_array();
  for (const std::string& n : t.joint_names) w.value(n);
  w.end_array();
  w.key("root_pos");
  rows(t.root_pos);
  w.key("root_rot");
  rows(t.root_rot);
  w.key("dof_pos");
  rows(t.dof_pos);
  w.end_object();
  os << '\n';
}

namespace {

std::vector<std::string_view> split_commas(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    out.push_back(
        text::trim(line.substr(start, comma == std::string_view::npos ? line.npos : comma - start)));
    if (comma == std::string_view::npos) return out;
    start = comma + 1;
  }
}

// The rate of `steps` frame steps spanning `span` seconds, the times printed with `decimals`
// digits after the point. As for a BVH header's frame time (motion::rate_of_printed_frame_time),
// printed times put span/steps a little off the capture's rate (30.0001 for a 5-frame clip at 6
// digits), and resampled to its own rate such a clip would lose its last frame: when an integer
// rate n or an NTSC rate n * 1000/1001 gives a span within the printing's error (a unit of the
// last digit, half at each end) and that error fixes the rate to 1e-4 of itself, that rate.
double rate_of_printed_times(double span, int steps, int decimals) {
  const double raw = steps / span;
  const double error = std::pow(10.0, -decimals);
  if (error / span > 1e-4) return raw;  // too few digits for the times to fix the rate
  for (const double rate : {std::round(raw), std::round(raw * 1.001) * 1000.0 / 1001.0})
    if (rate > 0 && std::abs(span - steps / rate) <= error) return rate;
  return raw;
}

}  // namespace

motion::Motion parse_robot_csv(const std::string& text, const std::string& path, const Robot& robot,
                               double fps) {
  const motion::Skeleton& s = *robot.skeleton;
  const char* kBase[] = {"time", "root_x", "root_y", "root_z", "root_qx", "root_qy", "root_qz", "root_qw"};
  std::vector<std::string_view> lines;
  for (std::size_t start = 0; start < text.size();) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string_view line(text.data() + start, end - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    lines.push_back(line);
    start = end + 1;
  }
  while (!lines.empty() && text::trim(lines.back()).empty()) lines.pop_back();
  if (lines.empty()) throw kg::Error("empty robot CSV: expected a header row time,root_x,...", {path, 1});
  const std::vector<std::string_view> header = split_commas(lines[0]);
  for (std::size_t k = 0; k < 8; ++k)
    if (header.size() <= k || header[k] != kBase[k])
      throw kg::Error("robot CSV header: expected column " + std::to_string(k + 1) + " to be " + kBase[k] +
                          ", got " + (header.size() <= k ? std::string("nothing") : text::excerpt(header[k])),
                      {path, 1});
  // Column -> dof.
  std::vector<int> dof_of_column(header.size(), -1);
  std::vector<int> column_of_dof(robot.dofs.size(), -1);
  for (std::size_t c = 8; c < header.size(); ++c) {
    const std::string name(header[c]);
    const int d = robot.find_dof(name);
    if (d < 0) {
      std::vector<std::string> names;
      for (const RobotDof& dof : robot.dofs) names.push_back(dof.name);
      const std::string near = kg::nearest_name(name, names);
      throw kg::Error("robot CSV column " + std::to_string(c + 1) + ": " + text::excerpt(name) +
                          " is no moving joint of " + text::shown_path(robot.path) +
                          (near.empty() ? std::string() : " (did you mean " + text::excerpt(near) + "?)"),
                      {path, 1});
    }
    if (column_of_dof[static_cast<std::size_t>(d)] >= 0)
      throw kg::Error("robot CSV column " + std::to_string(c + 1) + ": " + text::excerpt(name) + " twice",
                      {path, 1});
    column_of_dof[static_cast<std::size_t>(d)] = static_cast<int>(c);
    dof_of_column[c] = d;
  }
  for (std::size_t d = 0; d < robot.dofs.size(); ++d)
    if (column_of_dof[d] < 0)
      throw kg::Error("robot CSV header: no column for joint " + text::excerpt(robot.dofs[d].name) + " of " +
                          text::shown_path(robot.path),
                      {path, 1});

  const int frames = static_cast<int>(lines.size()) - 1;
  if (frames < 1) throw kg::Error("robot CSV: no frame rows after the header", {path, 1});
  motion::Motion m{robot.skeleton, motion::FrameMatrix::Zero(frames, s.channel_count()), 30.0,
                   std::filesystem::path(path).stem().string()};
  std::vector<double> times(static_cast<std::size_t>(frames));
  int time_decimals = 0;
  Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(s.channel_count());
  for (int f = 0; f < frames; ++f) {
    const int line = f + 2;
    const std::vector<std::string_view> cells = split_commas(lines[static_cast<std::size_t>(f) + 1]);
    if (cells.size() != header.size())
      throw kg::Error("robot CSV row: expected " + std::to_string(header.size()) +
                          " values as the header, got " + std::to_string(cells.size()),
                      {path, line});
    std::vector<double> v(cells.size());
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const auto x = text::parse_double(cells[c]);
      if (!x || !std::isfinite(*x))
        throw kg::Error("robot CSV column " + std::to_string(c + 1) + " (" + text::excerpt(header[c]) +
                            "): expected a finite number, got " + text::excerpt(cells[c]),
                        {path, line});
      v[c] = *x;
    }
    times[static_cast<std::size_t>(f)] = v[0];
    if (const std::size_t dot = cells[0].find('.'); dot != std::string_view::npos)
      time_decimals = std::max(time_decimals, static_cast<int>(cells[0].size() - dot - 1));
    row.setZero();
    Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (!(q.norm() > 1e-9))
      throw kg::Error("robot CSV: the base quaternion root_qx..root_qw is zero", {path, line});
    q.normalize();
    for (std::size_t c = 8; c < cells.size(); ++c) {
      const RobotDof& d = robot.dofs[static_cast<std::size_t>(dof_of_column[c])];
      row[d.channel] = d.offset + d.sign * v[c];
    }
    const motion::Joint& root = s.joint(0);
    const Eigen::Vector3d p(v[1], v[2], v[3]);
    // The previous frame's angles first, so that the base's Euler angles stay continuous.
    if (f > 0)
      row.segment(root.first_channel, static_cast<Eigen::Index>(root.channels.size())) =
          m.values.row(f - 1).segment(root.first_channel, static_cast<Eigen::Index>(root.channels.size()));
    for (std::size_t k = 0; k < root.channels.size(); ++k)
      if (!motion::is_rotation(root.channels[k].kind))
        row[root.first_channel + static_cast<int>(k)] = p[motion::axis_index(root.channels[k].kind)];
    motion::set_joint_rotation(s, 0, q.toRotationMatrix(), row);
    m.values.row(f) = row;
  }
  if (fps > 0) {
    m.fps = fps;
  } else if (frames >= 2) {
    const double step = (times.back() - times.front()) / (frames - 1);
    if (!(step > 0))
      throw kg::Error("robot CSV: the time column must rise; it goes from " +
                          text::significant(times.front()) + " to " + text::significant(times.back()),
                      {path, frames + 1});
    for (int f = 1; f < frames; ++f) {
      const double expected = times.front() + f * step;
      if (std::abs(times[static_cast<std::size_t>(f)] - expected) > 0.01 * step)
        throw kg::Error("robot CSV: times must be evenly spaced (" + text::significant(step) +
                            " s apart); this row's is " +
                            text::significant(times[static_cast<std::size_t>(f)]) + ", expected " +
                            text::significant(expected) + " (set source_fps to override)",
                        {path, f + 2});
    }
    m.fps = rate_of_printed_times(times.back() - times.front(), frames - 1, time_decimals);
  }
  return m;
}

}  // namespace kg::io
