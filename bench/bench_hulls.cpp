// The "Feasible" figure of McCann et al. 2006 fig. 12 (milliseconds per frame to find the feasible
// region and set up the contact model) on a CMU walk, one thread: contact detection, every
// frame's hull with GLPK (build_hulls), and the force model's queries.
//
// Until the inverse dynamics lands (branch dyn), the torque coefficients come from a stand-in
// that is exact for its own body: point masses at the segments' midpoints (de Leva's male mass
// fractions of 70 kg), τ = Σ m_i J_iᵀ (x_i'' ṗ² + x_i' p̈ − g), with x_i', x_i'' the points'
// path derivatives by central differences of their paths smoothed by a Gaussian of --smooth
// seconds (default 0.04). Torque limits: 0 on the root, ±limit elsewhere (default 300).
//
//   bench_hulls [--clip path.amc --asf path.asf] [--limit N·m | --limit inf] [--smooth seconds]
//               [--repeat n] [--frames]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "kg/io/asf_amc.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/retime/contacts.hpp"
#include "kg/retime/force_model.hpp"
#include "kg/retime/hulls.hpp"

using namespace kg;
using namespace kg::retime;

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// de Leva (1996) male mass fractions (% of body mass) by CMU ASF bone, split where a table segment
// spans several bones.
double mass_percent(const std::string& bone) {
  const std::string b =
      bone.size() > 1 && (bone[0] == 'l' || bone[0] == 'r') && bone != "lowerback" && bone != "lowerneck"
          ? bone.substr(1)
          : bone;
  if (b == "lowerback" || b == "upperback" || b == "thorax") return 43.46 / 3;
  if (b == "lowerneck" || b == "upperneck" || b == "head") return 6.94 / 3;
  if (b == "humerus") return 2.71;
  if (b == "radius") return 1.62;
  if (b == "hand") return 0.61;
  if (b == "femur") return 14.16;
  if (b == "tibia") return 4.33;
  if (b == "foot") return 1.37 * 0.8;
  if (b == "toes") return 1.37 * 0.2;
  return 0;
}

struct PointMass {
  int joint;
  Eigen::Vector3d local;
  double mass;
};

std::vector<PointMass> point_masses(const motion::Skeleton& sk, double body_mass) {
  std::vector<PointMass> out;
  for (int j = 0; j < sk.joint_count(); ++j) {
    const double m = mass_percent(sk.joint(j).name) / 100 * body_mass;
    if (m <= 0) continue;
    Eigen::Vector3d tip = Eigen::Vector3d::Zero();
    for (int c = 0; c < sk.joint_count(); ++c)
      if (sk.joint(c).parent == j) {
        tip = sk.joint(c).offset;
        break;
      }
    if (tip.isZero() && !sk.joint(j).end_sites.empty()) tip = sk.joint(j).end_sites.front();
    out.push_back({j, 0.5 * tip, m});
  }
  return out;
}

// The stand-in inverse dynamics along the clip's path (see the header comment).
std::vector<FrameTorques> point_mass_torques(const motion::Motion& m, const std::vector<PointMass>& masses,
                                             double sigma_s) {
  const motion::Skeleton& sk = *m.skeleton;
  const int frames = m.frame_count(), channels = sk.channel_count();
  const double h = 1.0 / m.fps;
  std::vector<std::vector<Eigen::Vector3d>> x(static_cast<std::size_t>(frames));
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(sk.joint_count()));
  for (int f = 0; f < frames; ++f) {
    motion::forward_kinematics(sk, m.values.row(f), world);
    for (const PointMass& p : masses)
      x[static_cast<std::size_t>(f)].push_back(world[static_cast<std::size_t>(p.joint)] * p.local);
  }
  // Captured markers jitter by a millimetre or so, which second differences at 120 Hz turn into
  // metres per second²: smooth the points' paths (Gaussian, sigma_s) before differencing.
  if (sigma_s > 0) {
    const double sigma = sigma_s * m.fps;
    const int half = static_cast<int>(std::ceil(3 * sigma));
    std::vector<std::vector<Eigen::Vector3d>> smooth = x;
    for (int f = 0; f < frames; ++f)
      for (std::size_t i = 0; i < masses.size(); ++i) {
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        double weight = 0;
        for (int k = -half; k <= half; ++k) {
          const int g = std::clamp(f + k, 0, frames - 1);
          const double w = std::exp(-0.5 * k * k / (sigma * sigma));
          sum += w * x[static_cast<std::size_t>(g)][i];
          weight += w;
        }
        smooth[static_cast<std::size_t>(f)][i] = sum / weight;
      }
    x = std::move(smooth);
  }
  std::vector<FrameTorques> out(static_cast<std::size_t>(frames));
  Eigen::Matrix<double, 3, Eigen::Dynamic> J(3, channels);
  for (int f = 0; f < frames; ++f) {
    const int a = std::clamp(f, 1, frames - 2);
    motion::forward_kinematics(sk, m.values.row(f), world);
    FrameTorques& t = out[static_cast<std::size_t>(f)];
    t.velocity = Eigen::VectorXd::Zero(channels);
    t.acceleration = Eigen::VectorXd::Zero(channels);
    t.gravity = Eigen::Matrix<double, Eigen::Dynamic, 3>::Zero(channels, 3);
    for (std::size_t i = 0; i < masses.size(); ++i) {
      const auto& xm = x[static_cast<std::size_t>(a - 1)][i];
      const auto& x0 = x[static_cast<std::size_t>(a)][i];
      const auto& xp = x[static_cast<std::size_t>(a + 1)][i];
      const Eigen::Vector3d d1 = (xp - xm) / (2 * h), d2 = (xp - 2 * x0 + xm) / (h * h);
      motion::point_jacobian(sk, m.values.row(f), world, masses[i].joint, masses[i].local, J);
      t.velocity.noalias() += masses[i].mass * J.transpose() * d2;
      t.acceleration.noalias() += masses[i].mass * J.transpose() * d1;
      t.gravity.noalias() -= masses[i].mass * J.transpose();
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string data = KG_DATA_DIR;
  std::string amc = data + "/cmu/asf_amc/16_15.amc", asf = data + "/cmu/asf_amc/16.asf";
  double limit = 300;
  int repeat = 5;
  bool per_frame = false;
  double smooth_s = 0.04;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--clip" && i + 1 < argc)
      amc = argv[++i];
    else if (a == "--asf" && i + 1 < argc)
      asf = argv[++i];
    else if (a == "--limit" && i + 1 < argc)
      limit = std::strcmp(argv[++i], "inf") == 0 ? INFINITY : std::stod(argv[i]);
    else if (a == "--repeat" && i + 1 < argc)
      repeat = std::max(1, std::stoi(argv[++i]));
    else if (a == "--frames")
      per_frame = true;
    else if (a == "--smooth" && i + 1 < argc)
      smooth_s = std::stod(argv[++i]);
    else {
      std::fprintf(stderr,
                   "usage: bench_hulls [--clip x.amc --asf x.asf] [--limit N|inf] [--smooth s] [--repeat n] "
                   "[--frames]\n");
      return 2;
    }
  }
  if (!std::filesystem::exists(amc) || !std::filesystem::exists(asf)) {
    std::printf("skipped: %s or %s not found\n", amc.c_str(), asf.c_str());
    return 0;
  }
  const motion::Motion walk = io::import_asf_amc(asf, amc, {}).motion;
  const motion::Skeleton& sk = *walk.skeleton;
  const int frames = walk.frame_count(), channels = sk.channel_count();

  BodyModel body;
  body.skeleton = walk.skeleton;
  body.segments.resize(static_cast<std::size_t>(sk.joint_count()));
  body.segment_class.resize(static_cast<std::size_t>(sk.joint_count()));
  const std::vector<PointMass> masses = point_masses(sk, 70.0);
  for (const PointMass& p : masses) {
    body.segments[static_cast<std::size_t>(p.joint)].mass = p.mass;
    body.segments[static_cast<std::size_t>(p.joint)].com = p.local;
  }
  body.torque_min = Eigen::VectorXd::Constant(channels, -limit);
  body.torque_max = Eigen::VectorXd::Constant(channels, limit);
  for (const motion::Joint& j : sk.joints())
    if (j.parent < 0)
      for (std::size_t c = 0; c < j.channels.size(); ++c)
        body.torque_min[j.first_channel + static_cast<int>(c)] =
            body.torque_max[j.first_channel + static_cast<int>(c)] = 0;

  const std::vector<FrameTorques> torques = point_mass_torques(walk, masses, smooth_s);

  auto t0 = Clock::now();
  Contacts contacts;
  for (int r = 0; r < repeat; ++r) contacts = detect_contacts(walk, {});
  const double contacts_ms = ms_since(t0) / repeat;

  Hulls hulls;
  double best = INFINITY;
  for (int r = 0; r < repeat; ++r) {
    t0 = Clock::now();
    hulls = build_hulls(body, contacts, torques, {});
    best = std::min(best, ms_since(t0));
  }
  // Per frame, for the distribution (each call builds its own buffers: a little slower).
  std::vector<double> frame_ms(static_cast<std::size_t>(frames));
  for (int f = 0; f < frames; ++f) {
    t0 = Clock::now();
    const FrameHull h = build_frame_hull(body, contacts.frames[static_cast<std::size_t>(f)],
                                         torques[static_cast<std::size_t>(f)], {});
    frame_ms[static_cast<std::size_t>(f)] = ms_since(t0);
  }

  int lps = 0, max_lps = 0, vertices = 0, on_box = 0, columns = 0, max_columns = 0, outside = 0, feasible = 0;
  double lp_ms_feasible = 0;
  for (int f = 0; f < frames; ++f) {
    const FrameHull& h = hulls.frames[static_cast<std::size_t>(f)];
    lps += h.lp_count;
    max_lps = std::max(max_lps, h.lp_count);
    columns += h.column_count();
    max_columns = std::max(max_columns, h.column_count());
    if (h.status != HullStatus::Feasible) continue;
    ++feasible;
    lp_ms_feasible += frame_ms[static_cast<std::size_t>(f)];
    vertices += static_cast<int>(h.vertices.size());
    for (std::uint8_t b : h.on_box) on_box += b ? 1 : 0;
    outside += h.centre_is_original ? 0 : 1;
  }
  int rows = 0;
  for (int c = 0; c < channels; ++c)
    rows += std::isfinite(body.torque_min[c]) || std::isfinite(body.torque_max[c]) ? 1 : 0;
  std::vector<double> sorted = frame_ms;
  std::sort(sorted.begin(), sorted.end());

  std::printf(
      "clip %s: %d frames at %.0f fps, %d channels, %d rows per LP (torque limit %g), %.1f kg of point "
      "masses, "
      "paths smoothed %g s\n",
      walk.name.c_str(), frames, walk.fps, channels, rows, limit, body.total_mass(), smooth_s);
  std::printf("contacts: %zu patches, λ columns per frame mean %.1f, max %d\n", contacts.patches.size(),
              static_cast<double>(columns) / frames, max_columns);
  std::printf(
      "frames: %d feasible, %d flight, %d infeasible; (0, 1) outside the hull in %d feasible frames\n",
      hulls.count(HullStatus::Feasible), hulls.count(HullStatus::Flight), hulls.count(HullStatus::Infeasible),
      outside);
  std::printf(
      "LPs per frame: mean %.1f, max %d; vertices per feasible hull: mean %.1f; %d vertices on the box\n",
      static_cast<double>(lps) / frames, max_lps, feasible ? static_cast<double>(vertices) / feasible : 0.0,
      on_box);
  std::printf("Contacts (detection, Jacobians): %.3f ms per frame\n", contacts_ms / frames);
  std::printf("Feasible (build_hulls, best of %d): %.3f ms per frame (%.1f ms for the clip)\n", repeat,
              best / frames, best);
  std::printf(
      "  per frame alone: median %.3f ms, 90th percentile %.3f ms, max %.3f ms; feasible frames mean %.3f "
      "ms\n",
      sorted[sorted.size() / 2], sorted[sorted.size() * 9 / 10], sorted.back(),
      feasible ? lp_ms_feasible / feasible : 0.0);

  // The force model's queries along a random walk in the plane (the retimer's access pattern).
  std::mt19937 rng(1);
  std::normal_distribution<double> step(0, 0.05);
  Eigen::VectorXd lambda;
  SectorTorques st;
  const int queries = 200000;
  double sink = 0;
  t0 = Clock::now();
  for (int q = 0; q < queries; ++q) {
    const FrameHull& h = hulls.frames[static_cast<std::size_t>((q / 100) % frames)];
    static int hint = 0;
    static Eigen::Vector2d x(0, 1);
    if (q % 100 == 0) x = {0, 1}, hint = 0;
    x += Eigen::Vector2d(step(rng), step(rng));
    lambda_at(h, x, hint, lambda);
    const HullPoint c = closest_point(h, x, hint);
    sink += c.distance_squared + (lambda.size() ? lambda[0] : 0);
  }
  const double query_ns = ms_since(t0) * 1e6 / queries;
  t0 = Clock::now();
  for (int f = 0; f < frames; ++f) {
    const FrameHull& h = hulls.frames[static_cast<std::size_t>(f)];
    for (int s = 0; s < static_cast<int>(h.sectors.size()); ++s) {
      sector_torques(h, s, torques[static_cast<std::size_t>(f)], hulls.gravity, st);
      sink += st.t0[0];
    }
  }
  const double sector_ms = ms_since(t0) / frames;
  std::printf(
      "force model: λ + closest point %.0f ns per query (random walk, hints); all sectors' τ coefficients "
      "%.3f ms per frame%s\n",
      query_ns, sector_ms, sink == 12345.678 ? " " : "");

  if (per_frame) {
    std::printf("\nframe  status      patches  λ   LPs  vertices  ms      centre            message\n");
    for (int f = 0; f < frames; ++f) {
      const FrameHull& h = hulls.frames[static_cast<std::size_t>(f)];
      std::printf("%5d  %-10s  %7zu  %2d  %3d  %8zu  %6.3f  (%6.3f, %6.3f)  %s\n", f, to_string(h.status),
                  contacts.frames[static_cast<std::size_t>(f)].patches().size(), h.column_count(), h.lp_count,
                  h.vertices.size(), frame_ms[static_cast<std::size_t>(f)], h.centre.x(), h.centre.y(),
                  h.message.c_str());
    }
  }
  return 0;
}
