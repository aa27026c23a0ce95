#include "kg/motion/resample.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "kg/motion/rotations.hpp"

namespace kg::motion {

namespace {

// Times within this many frames of a frame time are that frame (rounding of k * fps / new_fps).
constexpr double kFrameSnap = 1e-9;

struct Bracket {
  int f0 = 0, f1 = 0;
  double u = 0;
};

// The frames around position s (in frames, not seconds) and the fraction between them.
Bracket locate(int frames, double s) {
  const double last = frames - 1;
  s = std::clamp(s, 0.0, last);
  Bracket b;
  double f = std::floor(s);
  double u = s - f;
  if (u < kFrameSnap) {
    u = 0;
  } else if (u > 1 - kFrameSnap) {
    f += 1;
    u = 0;
  }
  b.f0 = static_cast<int>(std::min(f, last));
  b.f1 = std::min(b.f0 + 1, frames - 1);
  b.u = b.f0 == b.f1 ? 0.0 : u;
  return b;
}

void check_size(const Skeleton& skeleton, Eigen::Index size, const char* what) {
  if (size != skeleton.channel_count())
    throw std::invalid_argument(std::string("interpolate_frames: ") + what + " has " + std::to_string(size) +
                                " values, skeleton has " + std::to_string(skeleton.channel_count()) +
                                " channels");
}

double frames_position(const Motion& motion, double time) {
  if (!motion.skeleton) throw std::invalid_argument("pose_at: motion '" + motion.name + "' has no skeleton");
  if (motion.frame_count() == 0)
    throw std::invalid_argument("pose_at: motion '" + motion.name + "' has no frames");
  if (!std::isfinite(time)) throw std::invalid_argument("pose_at: time is not finite");
  return time * motion.fps;
}

}  // namespace

void interpolate_frames(const Skeleton& skeleton, FrameRef a, FrameRef b, double u, FrameRef reference,
                        Eigen::Ref<Eigen::RowVectorXd> out) {
  check_size(skeleton, a.size(), "a");
  check_size(skeleton, b.size(), "b");
  check_size(skeleton, reference.size(), "reference");
  check_size(skeleton, out.size(), "out");
  if (!std::isfinite(u)) throw std::invalid_argument("interpolate_frames: fraction u is not finite");
  const double* pa = a.data();
  const double* pb = b.data();
  const double* pr = reference.data();
  double* po = out.data();
  const bool at_a = u <= 0, at_b = u >= 1;
  const double* source = at_a ? pa : pb;

  for (const Joint& jt : skeleton.joints()) {
    const int first = jt.first_channel;
    const int n = static_cast<int>(jt.channels.size());
    RotationOrder order;
    std::array<int, 3> rot{};  // frame indices of the rotation channels
    Eigen::Vector3d ref = Eigen::Vector3d::Zero();
    for (int c = 0; c < n; ++c) {
      const ChannelKind kind = jt.channels[static_cast<std::size_t>(c)].kind;
      const int i = first + c;
      if (is_rotation(kind)) {
        if (order.count == 3)  // add_joint refuses these; a joint edited through joint_mut may not
          throw std::invalid_argument("interpolate_frames: joint '" + jt.name +
                                      "' has more than 3 rotation channels");
        // Read before any write: out may alias reference.
        ref[order.count] = pr[i];
        rot[static_cast<std::size_t>(order.count)] = i;
        order.axes[static_cast<std::size_t>(order.count++)] = axis_index(kind);
      }
    }
    for (int c = 0; c < n; ++c) {
      const int i = first + c;
      if (!is_rotation(jt.channels[static_cast<std::size_t>(c)].kind))
        po[i] = (at_a || at_b) ? source[i] : (1 - u) * pa[i] + u * pb[i];
    }
    if (order.count == 0) continue;

    if (at_a || at_b) {
      for (int r = 0; r < order.count; ++r) po[rot[r]] = nearest_angle(source[rot[r]], ref[r]);
    } else if (order.count == 3) {
      const Eigen::Vector3d ea(pa[rot[0]], pa[rot[1]], pa[rot[2]]);
      const Eigen::Vector3d eb(pb[rot[0]], pb[rot[1]], pb[rot[2]]);
      const Eigen::Quaterniond q =
          slerp_shortest(euler_to_quaternion(order, ea), euler_to_quaternion(order, eb), u);
      // The Euler solution the input itself would take here: where a joint passes gimbal lock,
      // an exporter may switch solutions between two frames, and a displacement added to these
      // angles (retarget.at_rate) means something only on the input's solution.
      Eigen::Vector3d own;
      for (int r = 0; r < 3; ++r) own[r] = ea[r] + u * std::remainder(eb[r] - ea[r], 2 * std::numbers::pi);
      const Eigen::Vector3d e = quaternion_to_euler(q, order, own);
      for (int r = 0; r < 3; ++r) po[rot[r]] = nearest_angle(e[r], ref[r]);
    } else {
      for (int r = 0; r < order.count; ++r) {
        const double x0 = pa[rot[r]];
        const double step = std::remainder(pb[rot[r]] - x0, 2 * std::numbers::pi);
        po[rot[r]] = nearest_angle(x0 + u * step, ref[r]);
      }
    }
  }
}

void pose_at(const Motion& motion, double time, FrameRef reference, Eigen::Ref<Eigen::RowVectorXd> out) {
  const Bracket br = locate(motion.frame_count(), frames_position(motion, time));
  interpolate_frames(*motion.skeleton, motion.values.row(br.f0), motion.values.row(br.f1), br.u, reference,
                     out);
}

void pose_at(const Motion& motion, double time, Eigen::Ref<Eigen::RowVectorXd> out) {
  const Bracket br = locate(motion.frame_count(), frames_position(motion, time));
  const int nearer = br.u <= 0.5 ? br.f0 : br.f1;
  interpolate_frames(*motion.skeleton, motion.values.row(br.f0), motion.values.row(br.f1), br.u,
                     motion.values.row(nearer), out);
}

Eigen::RowVectorXd pose_at(const Motion& motion, double time) {
  Eigen::RowVectorXd out(motion.values.cols());
  pose_at(motion, time, out);
  return out;
}

int resampled_frame_count(int frames, double fps, double new_fps) {
  if (!(fps > 0) || !std::isfinite(fps) || !(new_fps > 0) || !std::isfinite(new_fps)) {
    std::ostringstream s;
    s << "resample: frame rates " << fps << " -> " << new_fps << " (expected finite numbers > 0)";
    throw std::invalid_argument(s.str());
  }
  if (frames <= 0) return 0;
  const double n = std::floor(static_cast<double>(frames - 1) * new_fps / fps + kFrameSnap) + 1;
  if (n > std::numeric_limits<int>::max()) {
    std::ostringstream s;
    s << "resample: " << frames << " frames at " << fps << " fps would become " << std::fixed
      << std::setprecision(0) << n << std::defaultfloat << std::setprecision(6) << " frames at " << new_fps
      << " fps";
    throw std::invalid_argument(s.str());
  }
  return static_cast<int>(n);
}

Motion resample(const Motion& motion, double new_fps) {
  motion.check();
  if (motion.frame_count() == 0)
    throw std::invalid_argument("resample: motion '" + motion.name + "' has no frames");
  const int n_out = resampled_frame_count(motion.frame_count(), motion.fps, new_fps);
  const Eigen::Index channels = motion.values.cols();
  if (static_cast<double>(n_out) * static_cast<double>(channels) > 2147483648.0) {
    std::ostringstream s;
    s << "resample: motion '" << motion.name << "' at " << new_fps << " fps would hold " << n_out
      << " frames x " << channels << " channels (more than 2^31 values)";
    throw std::invalid_argument(s.str());
  }

  Motion out;
  out.skeleton = motion.skeleton;
  out.fps = new_fps;
  out.name = motion.name;
  out.values.resize(n_out, channels);
  const Skeleton& skeleton = *motion.skeleton;
  out.values.row(0) = motion.values.row(0);
  for (int k = 1; k < n_out; ++k) {
    // k * fps / new_fps in this order is exact whenever the true position is an integer that
    // the product represents (120 -> 30, 120 -> 50, 30 -> 120 ...).
    const Bracket br = locate(motion.frame_count(), static_cast<double>(k) * motion.fps / new_fps);
    interpolate_frames(skeleton, motion.values.row(br.f0), motion.values.row(br.f1), br.u,
                       out.values.row(k - 1), out.values.row(k));
  }
  return out;
}

}  // namespace kg::motion
