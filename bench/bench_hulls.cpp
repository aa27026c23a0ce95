// Per frame detail behind the "Feasible" row of bench_retime (McCann et al. 2006 fig. 12: the
// milliseconds per frame to find the feasible region and set up the contact model) on a CMU clip,
// one thread: contact detection, every frame's hull with GLPK (build_hulls), the statuses, LP and
// vertex counts, and the force model's queries; with --frames, one line per frame.
//
// The pipeline is graphs/retime.yaml's: the clip imported (an .amc with its .asf, or a .bvh;
// --source-fps overrides the file's rate, as 16_01.bvh needs: 120), resampled to --fps (0: kept),
// build_body_model's de Leva male table at 70 kg with frame 0 as reference pose, torque limits
// ±limit N m on every actuated channel (default inf: none, as the graph; the root 0), detected
// contacts, path_torques with the derivatives taken through a Gaussian of --smooth seconds
// (default 0.04, the graph's; 0: raw differences, where a millimetre of capture jitter becomes
// metres per second² at 120 Hz and the original timing falls outside most hulls).
//
//   bench_hulls [--clip path.amc [--asf path.asf] | --clip path.bvh] [--source-fps f] [--fps f]
//               [--limit N·m | --limit inf] [--smooth seconds] [--repeat n] [--frames]
//
// e.g. bench_hulls --clip ../shared/data/cmu/bvh_daz/13_13.bvh --fps 30 --frames
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

#include "kg/body/body_build.hpp"
#include "kg/io/asf_amc.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/motion/resample.hpp"
#include "kg/retime/contacts.hpp"
#include "kg/retime/dynamics.hpp"
#include "kg/retime/force_model.hpp"
#include "kg/retime/hulls.hpp"
#include "kg/retime/path.hpp"

using namespace kg;
using namespace kg::retime;
using namespace kg::body;

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  const std::string data = KG_DATA_DIR;
  std::string amc = data + "/cmu/asf_amc/16_15.amc", asf = data + "/cmu/asf_amc/16.asf";
  double limit = INFINITY, source_fps = 0, fps = 0;
  int repeat = 5;
  bool per_frame = false, clip_given = false, asf_given = false;
  double smooth_s = 0.04;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--clip" && i + 1 < argc)
      amc = argv[++i], clip_given = true;
    else if (a == "--asf" && i + 1 < argc)
      asf = argv[++i], asf_given = true;
    else if (a == "--source-fps" && i + 1 < argc)
      source_fps = std::stod(argv[++i]);
    else if (a == "--fps" && i + 1 < argc)
      fps = std::stod(argv[++i]);
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
                   "usage: bench_hulls [--clip x.amc --asf x.asf | --clip x.bvh] [--source-fps f] [--fps f] "
                   "[--limit N|inf] [--smooth s] [--repeat n] [--frames]\n");
      return 2;
    }
  }
  // A clip of one's own: a .bvh needs no skeleton, an .amc's is guessed beside it (import_motion).
  if (clip_given && !asf_given) asf.clear();
  if (!std::filesystem::exists(amc) || (!asf.empty() && !std::filesystem::exists(asf))) {
    std::printf("skipped: %s or %s not found\n", amc.c_str(), asf.c_str());
    return 0;
  }
  io::ImportOptions import;
  import.fps = source_fps;
  motion::Motion walk = io::import_motion(amc, asf, import).motion;
  const double file_fps = walk.fps;
  if (fps > 0) walk = motion::resample(walk, fps);
  const motion::Skeleton& sk = *walk.skeleton;
  const int frames = walk.frame_count(), channels = sk.channel_count();

  body::BodySpec spec;
  if (std::isfinite(limit)) spec.torque_limits = {{".*", {limit}, {}}};
  const Eigen::RowVectorXd reference = walk.values.row(0);
  const BodyModel body = body::build_body_model(walk.skeleton, spec, &reference).body;
  auto t0 = Clock::now();
  const std::vector<FrameTorques> torques =
      retime::path_torques(body, walk, retime::path_derivatives(walk, smooth_s)).frames;
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
      "clip %s: %d frames at %.0f fps (file %.0f fps), %d channels, %d rows per LP (torque limit %g N m), "
      "%.1f kg "
      "(de Leva), derivatives smoothed %g s\n",
      walk.name.c_str(), frames, walk.fps, file_fps, channels, rows, limit, body.total_mass(), smooth_s);
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
    // The centre of mass's vertical acceleration by second differences of the clip's frames: about
    // -9.8 m/s² in true flight, so a flight frame far from it is a contact detected late or early.
    std::vector<double> com(static_cast<std::size_t>(frames));
    for (int f = 0; f < frames; ++f)
      com[static_cast<std::size_t>(f)] = body::body_com(body, walk.values.row(f)).y();
    std::printf(
        "\nframe  status      patches  λ   LPs  vertices  ms      CoM ÿ m/s²  centre            message\n");
    for (int f = 0; f < frames; ++f) {
      const FrameHull& h = hulls.frames[static_cast<std::size_t>(f)];
      const double ydd = f > 0 && f + 1 < frames
                             ? (com[static_cast<std::size_t>(f) + 1] - 2 * com[static_cast<std::size_t>(f)] +
                                com[static_cast<std::size_t>(f) - 1]) *
                                   walk.fps * walk.fps
                             : NAN;
      std::printf("%5d  %-10s  %7zu  %2d  %3d  %8zu  %6.3f  %10.2f  (%6.3f, %6.3f)  %s\n", f,
                  to_string(h.status), contacts.frames[static_cast<std::size_t>(f)].patches().size(),
                  h.column_count(), h.lp_count, h.vertices.size(), frame_ms[static_cast<std::size_t>(f)], ydd,
                  h.centre.x(), h.centre.y(), h.message.c_str());
    }
  }
  return 0;
}
