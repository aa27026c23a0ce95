// Retargeting onto another structure through a skeleton map (issue 15): CMU 07_05 (ASF/AMC)
// onto the Unitree G1 and onto the iClone CC rig, the whole solve (adapted figure, per-frame IK
// baseline, spacetime) timed stage by stage, with the joint-limit violation, the ankles'
// distance from the adapted source, and the RMS jerk of the result against the baseline's.
// Footplants on the target's feet are not carried yet, so foot skate and penetration are not
// figures here. One thread (the solvers use none).
//
//   bench_map_retarget [NAME]     (only the cases whose target file contains NAME)
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_timing.hpp"
#include "kg/io/motion_format.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/retarget/constraint_kinds.hpp"
#include "kg/retarget/map_retarget.hpp"
#include "kg/retarget/metrics.hpp"
#include "kg/retarget/skeleton_map.hpp"

namespace fs = std::filesystem;
using namespace kg;
using namespace kg::retarget;
using motion::Motion;

namespace {

Motion load(const fs::path& p) {
  io::ImportOptions o;
  o.trim = "none";
  return io::import_motion(p.string(), "", o).motion;
}

// Mean distance of the target's ankles from the adapted source's, metres.
double ankle_error(const MapRetargetResult& r, const SkeletonMap& map, const Motion& on_target) {
  const motion::Skeleton& tk = *on_target.skeleton;
  const motion::Skeleton& ak = *r.adapted.skeleton;
  std::vector<Eigen::Isometry3d> tw(tk.joint_count()), aw(ak.joint_count());
  double sum = 0;
  for (int f = 0; f < on_target.frame_count(); ++f) {
    motion::forward_kinematics(tk, on_target.values.row(f), tw);
    motion::forward_kinematics(ak, r.adapted.values.row(f), aw);
    for (int side = 0; side < 2; ++side)
      sum += (tw[map.target.chains.legs[side].lower].translation() -
              aw[map.source.chains.legs[side].lower].translation())
                 .norm();
  }
  return sum / (2.0 * on_target.frame_count());
}

// Worst joint-limit excess of a motion (radians or metres).
double limit_excess(const Motion& m) {
  double worst = 0;
  for (const motion::Joint& j : m.skeleton->joints())
    for (std::size_t c = 0; c < j.channels.size(); ++c) {
      const auto col = m.values.col(j.first_channel + static_cast<int>(c));
      worst = std::max({worst, j.channels[c].min - col.minCoeff(), col.maxCoeff() - j.channels[c].max});
    }
  return worst;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string only = argc > 1 ? argv[1] : "";
  const fs::path data = KG_DATA_DIR;
  const fs::path clip_path = data / "cmu/asf_amc/07_05.amc";
  if (!fs::exists(clip_path)) {
    std::printf("skipped: %s not found\n", clip_path.string().c_str());
    return 0;
  }
  const Motion clip = load(clip_path);
  static const ConstraintKindTable table = ConstraintKindTable::builtin();
  const KindFinder kinds = [](const std::string& n) { return table.find(n); };
  for (const char* target_file : {"robots/unitree_g1/g1_29dof.urdf", "cmu/bvh_iclone_cc_rig/007_05.bvh"}) {
    if (!only.empty() && std::string(target_file).find(only) == std::string::npos) continue;
    const fs::path tp = data / target_file;
    if (!fs::exists(tp)) {
      std::printf("skipped: %s not found\n", tp.string().c_str());
      continue;
    }
    const Motion target = load(tp);
    const SkeletonMap map = propose_map(*clip.skeleton, *target.skeleton).map;
    MapRetargetResult r;
    const double seconds =
        bench::best_seconds(3, [&] { r = retarget_onto(clip, map, target.skeleton, kinds); });
    const Motion& out = r.motion();
    const int frames = clip.frame_count();
    std::printf("07_05.amc (%d frames at %g fps) onto %s: %s\n", frames, clip.fps, target_file,
                r.solve.message.c_str());
    std::printf(
        "  whole solve %.3f s = %.0f frames/s (adapt %.3f s, per-frame IK %.3f s, spacetime %.3f s)\n",
        seconds, frames / seconds, r.seconds_adapt, r.seconds_ik, r.seconds_spacetime);
    std::printf("  ankles from the adapted source: IK %.2f mm, spacetime %.2f mm\n",
                1000 * ankle_error(r, map, r.baseline.motion), 1000 * ankle_error(r, map, out));
    std::printf("  RMS jerk: capture %.0f, IK %.0f, spacetime %.0f m/s^3 (ratio %.3f; target <= 0.5)\n",
                rms_joint_jerk(r.adapted), rms_joint_jerk(r.baseline.motion), rms_joint_jerk(out),
                rms_joint_jerk(out) / rms_joint_jerk(r.baseline.motion));
    std::printf("  worst joint-limit excess: IK %.2e, spacetime %.2e (rad or m)\n",
                limit_excess(r.baseline.motion), limit_excess(out));
  }
  return 0;
}
