// Forward kinematics and point Jacobian throughput, one thread, on synthetic 31-joint CMU-like
// skeletons (targets of issue 2: >= 5e6 joint transforms/s and >= 1e6 point Jacobians/s).
// Two layouts: as MotionBuilder writes CMU BVH (every joint ZYX, 96 channels, no axes) and as
// the CMU ASF has it (62 degrees of freedom, 1 to 3 per bone, an `axis` on every bone).
//
//   bench_kinematics [seconds per measurement, default 1]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "kg/motion/kinematics.hpp"
#include "kg/motion/rotations.hpp"

using namespace kg::motion;

namespace {

struct Bone {
  const char* name;
  const char* parent;
  double x, y, z;    // offset, metres
  const char* dofs;  // ASF dof order (rotation axes); BVH layout uses ZYX everywhere
};

// The CMU subject's bones (lengths rounded), parents before children.
const std::vector<Bone> kBones = {
    {"root", "", 0, 0.95, 0, "ZYX"},
    {"lhipjoint", "root", 0, 0, 0, ""},
    {"lfemur", "lhipjoint", 0.09, -0.08, 0.04, "XYZ"},
    {"ltibia", "lfemur", 0, -0.40, 0, "X"},
    {"lfoot", "ltibia", 0, -0.41, 0, "XZ"},
    {"ltoes", "lfoot", 0, -0.03, 0.13, "X"},
    {"rhipjoint", "root", 0, 0, 0, ""},
    {"rfemur", "rhipjoint", -0.09, -0.08, 0.04, "XYZ"},
    {"rtibia", "rfemur", 0, -0.40, 0, "X"},
    {"rfoot", "rtibia", 0, -0.41, 0, "XZ"},
    {"rtoes", "rfoot", 0, -0.03, 0.13, "X"},
    {"lowerback", "root", 0, 0.02, 0, "XYZ"},
    {"upperback", "lowerback", 0, 0.12, 0, "XYZ"},
    {"thorax", "upperback", 0, 0.12, 0, "XYZ"},
    {"lowerneck", "thorax", 0, 0.10, 0, "XYZ"},
    {"upperneck", "lowerneck", 0, 0.09, 0, "XYZ"},
    {"head", "upperneck", 0, 0.09, 0, "XYZ"},
    {"lclavicle", "thorax", 0.03, 0.06, 0, "YZ"},
    {"lhumerus", "lclavicle", 0.17, 0, 0, "XYZ"},
    {"lradius", "lhumerus", 0.28, 0, 0, "X"},
    {"lwrist", "lradius", 0.25, 0, 0, "Y"},
    {"lhand", "lwrist", 0.05, 0, 0, "XZ"},
    {"lfingers", "lhand", 0.04, 0, 0, "X"},
    {"lthumb", "lwrist", 0.03, 0, 0.02, "XZ"},
    {"rclavicle", "thorax", -0.03, 0.06, 0, "YZ"},
    {"rhumerus", "rclavicle", -0.17, 0, 0, "XYZ"},
    {"rradius", "rhumerus", -0.28, 0, 0, "X"},
    {"rwrist", "rradius", -0.25, 0, 0, "Y"},
    {"rhand", "rwrist", -0.05, 0, 0, "XZ"},
    {"rfingers", "rhand", -0.04, 0, 0, "X"},
    {"rthumb", "rwrist", -0.03, 0, 0.02, "XZ"},
};

std::shared_ptr<const Skeleton> make_skeleton(bool asf_layout) {
  auto s = std::make_shared<Skeleton>();
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> tilt(-0.6, 0.6);
  for (const Bone& b : kBones) {
    Joint j;
    j.name = b.name;
    j.parent = b.parent[0] ? s->find_joint(b.parent) : -1;
    j.offset = {b.x, b.y, b.z};
    if (j.parent < 0)
      for (ChannelKind k : {ChannelKind::Xposition, ChannelKind::Yposition, ChannelKind::Zposition})
        j.channels.push_back({k});
    const std::string dofs = asf_layout ? b.dofs : "ZYX";
    for (char c : dofs) j.channels.push_back({static_cast<ChannelKind>(3 + (c - 'X'))});
    if (asf_layout && j.parent >= 0)
      j.axis = euler_to_matrix(parse_rotation_order("ZYX"), Eigen::Vector3d(tilt(rng), tilt(rng), tilt(rng)));
    s->add_joint(std::move(j));
  }
  return s;
}

FrameMatrix random_frames(const Skeleton& s, int frames) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> angle(-1.0, 1.0), pos(-0.5, 0.5);
  FrameMatrix m(frames, s.channel_count());
  for (int f = 0; f < frames; ++f)
    for (int c = 0; c < s.channel_count(); ++c) {
      const auto [j, i] = s.channel_owner(c);
      m(f, c) = is_rotation(s.joint(j).channels[static_cast<std::size_t>(i)].kind) ? angle(rng) : pos(rng);
    }
  return m;
}

// CPU time of this thread: the figures stay meaningful on a machine busy with other work; the
// wall-clock rate is printed beside it.
double thread_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct Stopwatch {
  std::chrono::steady_clock::time_point wall0 = std::chrono::steady_clock::now();
  double cpu0 = thread_seconds();
  double cpu() const { return thread_seconds() - cpu0; }
  double wall() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  }
};

void bench(const char* label, bool asf_layout, double budget) {
  const auto skeleton = make_skeleton(asf_layout);
  const Skeleton& s = *skeleton;
  const int frames = 1000;
  const FrameMatrix values = random_frames(s, frames);
  const auto joints = static_cast<std::size_t>(s.joint_count());
  std::vector<Eigen::Isometry3d> world(joints);
  double checksum = 0;

  // Forward kinematics: every joint of every frame, repeated until the budget is spent.
  long long transforms = 0;
  Stopwatch fk_watch;
  do {
    for (int f = 0; f < frames; ++f) {
      forward_kinematics(s, values.row(f), world);
      checksum += world[joints - 1].translation().x();
    }
    transforms += static_cast<long long>(frames) * s.joint_count();
  } while (fk_watch.cpu() < budget);
  const double fk_cpu = fk_watch.cpu(), fk_wall = fk_watch.wall();

  // Point Jacobians of points on a hand and a toe (all channels' columns written), FK outside
  // the timing. A solver takes Jacobians right after the frame's FK, with the transforms in
  // cache: 64 frames' worth (250 kB) are cycled here, not all 1000.
  const int jac_frames = 64;
  std::vector<std::vector<Eigen::Isometry3d>> worlds(static_cast<std::size_t>(jac_frames),
                                                     std::vector<Eigen::Isometry3d>(joints));
  for (int f = 0; f < jac_frames; ++f)
    forward_kinematics(s, values.row(f), worlds[static_cast<std::size_t>(f)]);
  const int hand = s.find_joint("lhand"), toe = s.find_joint("rtoes");
  const Eigen::Vector3d on_hand(0.05, 0.01, 0.0), on_toe(0.0, -0.02, 0.04);
  Eigen::Matrix<double, 3, Eigen::Dynamic> J(3, s.channel_count());
  long long jacobians = 0;
  Stopwatch jac_watch;
  do {
    for (int f = 0; f < jac_frames; ++f) {
      const auto& w = worlds[static_cast<std::size_t>(f)];
      point_jacobian(s, values.row(f), w, hand, on_hand, J);
      checksum += J(0, 3);
      point_jacobian(s, values.row(f), w, toe, on_toe, J);
      checksum += J(1, 4);
    }
    jacobians += 2LL * jac_frames;
  } while (jac_watch.cpu() < budget);
  const double jac_cpu = jac_watch.cpu(), jac_wall = jac_watch.wall();

  const int chain = static_cast<int>(influencing_channels(s, hand).size());
  std::printf("%s: %d joints, %d channels (hand chain %d channels)\n", label, s.joint_count(),
              s.channel_count(), chain);
  const auto n_fk = static_cast<double>(transforms), n_jac = static_cast<double>(jacobians);
  std::printf(
      "  forward kinematics: %.3g joint transforms/s of CPU time (%.1f ns per joint); wall clock %.3g/s\n",
      n_fk / fk_cpu, 1e9 * fk_cpu / n_fk, n_fk / fk_wall);
  std::printf("  point Jacobians:    %.3g per second of CPU time (%.1f ns each); wall clock %.3g/s\n",
              n_jac / jac_cpu, 1e9 * jac_cpu / n_jac, n_jac / jac_wall);
  std::printf("  (checksum %.6g)\n", checksum);
}

}  // namespace

int main(int argc, char** argv) {
  const double budget = argc > 1 ? std::atof(argv[1]) : 1.0;
  if (!(budget > 0)) {
    std::fprintf(stderr, "usage: bench_kinematics [seconds per measurement > 0]\n");
    return 2;
  }
  std::printf(
      "bench_kinematics: one thread, %.2g s per measurement (targets: FK >= 5e6 joint transforms/s, "
      "point Jacobians >= 1e6/s)\n",
      budget);
  bench("CMU BVH layout (MotionBuilder)", false, budget);
  bench("CMU ASF layout (bone axes)", true, budget);
  return 0;
}
