// The BVH writer: text built in one buffer with std::to_chars (fixed decimals, trailing zeros
// dropped), so that reading and writing again reproduces the text exactly.
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "kg/base/option_check.hpp"
#include "kg/io/bvh.hpp"
#include "kg/motion/rotations.hpp"

namespace kg::io {
namespace {

using motion::ChannelKind;
using motion::Joint;
using motion::Skeleton;

// `value` with `precision` decimals, trailing zeros and a bare point dropped, "-0" written "0".
void append_number(std::string& out, double value, int precision) {
  char buf[400];  // the largest finite double in fixed notation with 12 decimals fits
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, value, std::chars_format::fixed, precision);
  if (ec != std::errc()) throw std::invalid_argument("BVH writer: cannot format a value");
  char* e = end;
  while (e > buf && e[-1] == '0') --e;
  if (e > buf && e[-1] == '.') --e;
  if (e - buf == 2 && buf[0] == '-' && buf[1] == '0') {
    out += '0';
    return;
  }
  out.append(buf, e);
}

bool is_identity(const Eigen::Matrix3d& m) {
  return (m - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-12;
}

Eigen::Matrix3d axis_rotation(int axis, double angle) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::Unit(axis)).toRotationMatrix();
}

// Angles (a, b, c) with r = R_i(a) R_j(b) R_k(c), i, j, k distinct axes; b in [-pi/2, pi/2].
std::array<double, 3> euler_angles(const Eigen::Matrix3d& r, int i, int j, int k) {
  // +1 when (i, j, k) is a cyclic permutation of (x, y, z).
  const double s = ((j - i + 3) % 3 == 1) ? 1.0 : -1.0;
  // cos b from the other entries of the row: asin loses half the digits near +-90 degrees.
  const double cb = std::hypot(r(i, i), r(i, j));
  const double b = std::atan2(s * r(i, k), cb);
  double a, c;
  if (cb > 1e-12) {
    a = std::atan2(-s * r(j, k), r(k, k));
    c = std::atan2(-s * r(i, j), r(i, i));
  } else {  // gimbal lock: only a + c (or a - c) is defined; put it all in a
    a = std::atan2(s * r(k, j), r(j, j));
    c = 0;
  }
  return {a, b, c};
}

// The solution of the same rotation closest to `previous`, each angle unwrapped by 2 pi.
std::array<double, 3> closest_euler(std::array<double, 3> e, const std::array<double, 3>& previous) {
  auto unwrap = [&](std::array<double, 3> v) {
    for (int n = 0; n < 3; ++n) v[n] = motion::nearest_angle(v[n], previous[n]);
    return v;
  };
  const std::array<double, 3> first = unwrap(e);
  const std::array<double, 3> second =
      unwrap({e[0] + std::numbers::pi, std::numbers::pi - e[1], e[2] + std::numbers::pi});
  auto distance = [&](const std::array<double, 3>& v) {
    return std::abs(v[0] - previous[0]) + std::abs(v[1] - previous[1]) + std::abs(v[2] - previous[2]);
  };
  return distance(second) < distance(first) ? second : first;
}

// What one joint writes: its channels and where each value comes from.
struct WrittenJoint {
  std::vector<ChannelKind> channels;
  // Written as read: source column per written channel. Otherwise (converted) position channels
  // first, each from its source column or, when the joint has none for that axis, -1 for the
  // OFFSET component it stands in for; then the three rotation channels computed per frame.
  std::vector<int> source;
  bool converted = false;
  std::array<int, 3> order{};  // converted joints: axes of the written rotations
};

// Three distinct rotation axes, and no or three distinct position axes: what every tool reads.
bool has_standard_layout(const Joint& joint) {
  std::array<int, 2> count{0, 0};
  std::array<std::array<bool, 3>, 2> seen{};
  for (const motion::Channel& c : joint.channels) {
    const int rotation = motion::is_rotation(c.kind) ? 1 : 0, axis = motion::axis_index(c.kind);
    if (seen[rotation][axis]) return false;
    seen[rotation][axis] = true;
    ++count[rotation];
  }
  return count[1] == 3 && (count[0] == 0 || count[0] == 3);
}

WrittenJoint plan_joint(const Joint& joint, bool exact) {
  WrittenJoint w;
  if (is_identity(joint.axis) && (exact || has_standard_layout(joint))) {
    for (std::size_t c = 0; c < joint.channels.size(); ++c) {
      w.channels.push_back(joint.channels[c].kind);
      w.source.push_back(joint.first_channel + static_cast<int>(c));
    }
    return w;
  }
  w.converted = true;
  std::vector<int> axes;
  std::array<int, 3> position_column{-1, -1, -1};
  bool any_position = false;
  for (std::size_t c = 0; c < joint.channels.size(); ++c) {
    const ChannelKind kind = joint.channels[c].kind;
    const int a = motion::axis_index(kind);
    if (motion::is_rotation(kind)) {
      if (std::find(axes.begin(), axes.end(), a) == axes.end()) axes.push_back(a);
    } else if (exact) {
      w.channels.push_back(kind);
      w.source.push_back(joint.first_channel + static_cast<int>(c));
    } else {
      position_column[static_cast<std::size_t>(a)] = joint.first_channel + static_cast<int>(c);
      any_position = true;
    }
  }
  if (any_position) {
    for (int a = 0; a < 3; ++a) {
      w.channels.push_back(static_cast<ChannelKind>(static_cast<int>(ChannelKind::Xposition) + a));
      w.source.push_back(position_column[static_cast<std::size_t>(a)]);
    }
  }
  for (int a = 0; a < 3; ++a)
    if (std::find(axes.begin(), axes.end(), a) == axes.end()) axes.push_back(a);
  for (int n = 0; n < 3; ++n) {
    w.order[n] = axes[n];
    w.channels.push_back(static_cast<ChannelKind>(static_cast<int>(ChannelKind::Xrotation) + axes[n]));
  }
  return w;
}

class Writer {
 public:
  Writer(const motion::Motion& m, double metres_per_unit, int precision, bool exact)
      : m_(m), s_(*m.skeleton), mpu_(metres_per_unit), precision_(precision), exact_(exact) {}

  std::string write() {
    const int n = s_.joint_count();
    children_.assign(static_cast<std::size_t>(n), {});
    std::vector<int> roots;
    for (int j = 0; j < n; ++j) {
      const int p = s_.joint(j).parent;
      (p < 0 ? roots : children_[static_cast<std::size_t>(p)]).push_back(j);
    }
    plans_.reserve(static_cast<std::size_t>(n));
    for (int j = 0; j < n; ++j) plans_.push_back(plan_joint(s_.joint(j), exact_));

    out_.reserve(static_cast<std::size_t>(m_.frame_count()) * static_cast<std::size_t>(s_.channel_count()) *
                     10 +
                 static_cast<std::size_t>(n) * 160 + 256);
    out_ += "HIERARCHY\n";
    for (int r : roots) write_joint(r, 0);
    out_ += "MOTION\nFrames: ";
    out_ += std::to_string(m_.frame_count());
    out_ += "\nFrame Time: ";
    char buf[64];
    auto [end, ec] = std::to_chars(buf, buf + sizeof buf, 1.0 / m_.fps, std::chars_format::general, 9);
    out_.append(buf, end);
    out_ += '\n';
    write_frames();
    return std::move(out_);
  }

 private:
  void indent(int depth) { out_.append(static_cast<std::size_t>(depth), '\t'); }

  void write_offset(const Eigen::Vector3d& o, int depth) {
    indent(depth);
    out_ += "OFFSET";
    for (int i = 0; i < 3; ++i) {
      out_ += ' ';
      append_number(out_, o[i] / mpu_, precision_);
    }
    out_ += '\n';
  }

  void write_joint(int j, int depth) {
    const Joint& joint = s_.joint(j);
    const WrittenJoint& plan = plans_[static_cast<std::size_t>(j)];
    order_.push_back(j);
    indent(depth);
    out_ += joint.parent < 0 ? "ROOT " : "JOINT ";
    out_ += joint.name;
    out_ += '\n';
    indent(depth);
    out_ += "{\n";
    write_offset(joint.offset, depth + 1);
    indent(depth + 1);
    out_ += "CHANNELS ";
    out_ += std::to_string(plan.channels.size());
    for (ChannelKind k : plan.channels) {
      out_ += ' ';
      out_ += motion::to_string(k);
    }
    out_ += '\n';
    for (int c : children_[static_cast<std::size_t>(j)]) write_joint(c, depth + 1);
    for (const Eigen::Vector3d& tip : joint.end_sites) {
      indent(depth + 1);
      out_ += "End Site\n";
      indent(depth + 1);
      out_ += "{\n";
      write_offset(tip, depth + 2);
      indent(depth + 1);
      out_ += "}\n";
    }
    indent(depth);
    out_ += "}\n";
  }

  void write_frames() {
    const double to_degrees = 180.0 / std::numbers::pi;
    std::vector<std::array<double, 3>> previous(static_cast<std::size_t>(s_.joint_count()), {0, 0, 0});
    for (int f = 0; f < m_.frame_count(); ++f) {
      const auto row = m_.values.row(f);
      bool first_value = true;
      auto put = [&](double v) {
        if (!first_value) out_ += ' ';
        first_value = false;
        append_number(out_, v, precision_);
      };
      for (int j : order_) {
        const WrittenJoint& plan = plans_[static_cast<std::size_t>(j)];
        const Joint& joint = s_.joint(j);
        for (std::size_t c = 0; c < plan.source.size(); ++c) {
          if (plan.source[c] < 0) {  // a position channel standing in for its OFFSET component
            put(joint.offset[motion::axis_index(plan.channels[c])] / mpu_);
            continue;
          }
          const double v = row(plan.source[c]);
          put(motion::is_rotation(plan.channels[c]) ? v * to_degrees : v / mpu_);
        }
        if (!plan.converted) continue;
        Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
        for (std::size_t c = 0; c < joint.channels.size(); ++c)
          if (motion::is_rotation(joint.channels[c].kind))
            r = r * axis_rotation(motion::axis_index(joint.channels[c].kind),
                                  row(joint.first_channel + static_cast<int>(c)));
        r = joint.axis * r * joint.axis.transpose();
        std::array<double, 3>& prev = previous[static_cast<std::size_t>(j)];
        prev = closest_euler(euler_angles(r, plan.order[0], plan.order[1], plan.order[2]), prev);
        for (double a : prev) put(a * to_degrees);
      }
      out_ += '\n';
    }
  }

  const motion::Motion& m_;
  const Skeleton& s_;
  double mpu_;
  int precision_;
  bool exact_;
  std::vector<std::vector<int>> children_;
  std::vector<WrittenJoint> plans_;
  std::vector<int> order_;  // joints depth first, as written
  std::string out_;
};

}  // namespace

void BvhWriteOptions::validate() const {
  using options::require;
  const char* o = "BvhWriteOptions";
  require(units == "source" || known_unit(units), o, "units", units, "source, m, cm, mm, inch or asf");
  require(precision >= 1 && precision <= 12, o, "precision", precision,
          "1 to 12 digits after the decimal point");
}

std::string write_bvh_string(const motion::Motion& motion, const BvhWriteOptions& options) {
  options.validate();
  if (!motion.skeleton) throw std::invalid_argument("BVH writer: motion has no skeleton");
  motion.check();
  if (motion.skeleton->joint_count() == 0)
    throw std::invalid_argument("BVH writer: the skeleton has no joint");
  if (motion.skeleton->channel_count() == 0 && motion.frame_count() > 0)
    throw std::invalid_argument("BVH writer: frames of a skeleton without channels cannot be written");
  const double mpu =
      options.units == "source" ? motion.skeleton->source_unit_metres : metres_per_unit(options.units);
  if (!(mpu > 0) || !std::isfinite(mpu))
    throw std::invalid_argument("BVH writer: bad unit (" + std::to_string(mpu) + " m per unit)");
  return Writer(motion, mpu, options.precision, options.exact).write();
}

void write_bvh(std::ostream& os, const motion::Motion& motion, const BvhWriteOptions& options) {
  const std::string text = write_bvh_string(motion, options);
  os.write(text.data(), static_cast<std::streamsize>(text.size()));
  if (!os) throw std::runtime_error("BVH writer: the stream failed");
}

}  // namespace kg::io
