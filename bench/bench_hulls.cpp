// Per frame detail behind the "Feasible" row of bench_retime (McCann et al. 2006 fig. 12: the
// milliseconds per frame to find the feasible region and set up the contact model) on a CMU clip,
// one thread: contact detection, every frame's hull with GLPK (build_hulls), the statuses, LP and
// vertex counts, and the force model's queries.
//
// The body: build_body_model's de Leva male table at 70 kg, torque limits ±limit N m on every
// actuated rotation channel (the root 0). The coefficients: path_torques (the inverse dynamics)
// on the clip, its channels first smoothed by a Gaussian of --smooth seconds (default 0: none;
// captured markers jitter by a millimetre or so, which second differences at 120 Hz turn into
// metres per second², so the original timing falls outside most hulls unsmoothed).
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
#include "kg/motion/rotations.hpp"
#include "kg/retime/body_build.hpp"
#include "kg/retime/contacts.hpp"
#include "kg/retime/dynamics.hpp"
#include "kg/retime/force_model.hpp"
#include "kg/retime/hulls.hpp"
#include "kg/retime/path.hpp"

using namespace kg;
using namespace kg::retime;

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// The clip with every channel smoothed by a Gaussian of sigma_s seconds (rotation channels
// unwrapped first, so a turn through ±180 degrees is not averaged away).
motion::Motion smoothed(const motion::Motion& m, double sigma_s) {
  if (!(sigma_s > 0)) return m;
  const motion::Skeleton& sk = *m.skeleton;
  motion::Motion out = m;
  motion::FrameMatrix q = m.values;
  for (int c = 0; c < sk.channel_count(); ++c) {
    const auto [joint, index] = sk.channel_owner(c);
    if (motion::is_rotation(sk.joint(joint).channels[static_cast<std::size_t>(index)].kind))
      for (int f = 1; f < m.frame_count(); ++f) q(f, c) = motion::nearest_angle(q(f, c), q(f - 1, c));
  }
  const double sigma = sigma_s * m.fps;
  const int half = static_cast<int>(std::ceil(3 * sigma)), frames = m.frame_count();
  for (int f = 0; f < frames; ++f) {
    Eigen::RowVectorXd sum = Eigen::RowVectorXd::Zero(sk.channel_count());
    double weight = 0;
    for (int k = -half; k <= half; ++k) {
      const double w = std::exp(-0.5 * k * k / (sigma * sigma));
      sum += w * q.row(std::clamp(f + k, 0, frames - 1));
      weight += w;
    }
    out.values.row(f) = sum / weight;
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
  double smooth_s = 0;
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

  retime::BodySpec spec;
  spec.torque_limits = {{".*", {limit}, {}}};
  const BodyModel body = retime::build_body_model(walk.skeleton, spec).body;
  const motion::Motion clip = smoothed(walk, smooth_s);
  auto t0 = Clock::now();
  const std::vector<FrameTorques> torques =
      retime::path_torques(body, clip, retime::path_derivatives(clip)).frames;
  const double force_ms = ms_since(t0) / frames;

  t0 = Clock::now();
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
      "clip %s: %d frames at %.0f fps, %d channels, %d rows per LP (torque limit %g N m), %.1f kg (de "
      "Leva), channels smoothed %g s\n",
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
  std::printf("Force (path_torques, for reference): %.3f ms per frame\n", force_ms);
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
