// Retiming figures per source frame, one thread, after McCann et al. 2006 fig. 12: a CMU walk
// (16_15.amc on 16.asf, 120 fps, 62 channels) and chains of 10, 100 and 1,000 links of three
// rotation channels each (C10, C100, C1000). Rows so far:
//   KDL RNEA        one plain inverse dynamics call of KDL (ChainIdSolver_RNE on the chains, three
//                   one-DOF segments per link, two of them massless; TreeIdSolver_RNE on the walk's
//                   tree, root channels as six joints from KDL's base), q̇ = q', q̈ = q'';
//   RNEA            our inverse_dynamics, the same numbers (dynamics.hpp);
//   Force           frame_torques: every coefficient of τ(ṗ², p̈, g), the paper's "Force";
//   Force (k)       frame_torques_mass_scale: the same and their change with one segment's mass;
//   Force / KDL     the target: at most 4 (from back-to-back batches of the two);
//   Feasible        build_frame_hull: the hull of feasible timings (GLPK) and the force model's fan
//                   of one frame (hulls.hpp, force_model.hpp), with the frame's coefficients from
//                   frame_torques and its contacts already made (16_15: detect_contacts' two
//                   feet, torque limits ±300 N m; the chains: fixed bases without contact, every
//                   channel limited to 1.5 times its largest |τ| along the clip at the original
//                   timing, the paper's limits "observed" in the motion).
// Later steps (Bake, Obj, NP-Obj, Naive) add rows to `rows` in main(): a row is a name
// and a function timing one case. Times are the median over batches of the mean time per frame,
// each batch running the whole clip as often as needed to last 20 ms.
//
//   bench_retime [NAME]     (only the cases whose name contains NAME)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#ifdef KG_HAVE_KDL
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <kdl/treeidsolver_recursive_newton_euler.hpp>

#include "../tests/support/kdl_body.hpp"
#endif

#include "kg/io/asf_amc.hpp"
#include "kg/retime/contacts.hpp"
#include "kg/retime/dynamics.hpp"
#include "kg/retime/hulls.hpp"
#include "kg/retime/path.hpp"

using namespace kg;
using retime::BodyModel;

namespace {

constexpr double kLink = 0.3;  // metres per chain link

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

volatile double g_sink = 0;  // keeps results observable

// How many passes over the clip make a batch of at least 20 ms (after a warm-up pass).
int passes_for(int frames, const std::function<void(int)>& work) {
  for (int f = 0; f < frames; ++f) work(f);
  const double t0 = now();
  int passes = 0;
  do {
    for (int f = 0; f < frames; ++f) work(f);
    ++passes;
  } while (now() - t0 < 0.02);
  return passes;
}

// Mean seconds per call of work(f) over `passes` passes over the clip.
double batch(int frames, int passes, const std::function<void(int)>& work) {
  const double t0 = now();
  for (int p = 0; p < passes; ++p)
    for (int f = 0; f < frames; ++f) work(f);
  return (now() - t0) / (passes * frames);
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// Median over 9 batches of the mean seconds per call of work(f), f running over every frame.
double seconds_per_frame(int frames, const std::function<void(int)>& work) {
  const int passes = passes_for(frames, work);
  std::vector<double> batches;
  for (int b = 0; b < 9; ++b) batches.push_back(batch(frames, passes, work));
  return median(batches);
}

// Median over 9 pairs of batches, run back to back, of time(a) / time(b): a ratio that holds when
// the machine's load drifts between rows.
double paired_ratio(int frames, const std::function<void(int)>& a, const std::function<void(int)>& b) {
  const int pa = passes_for(frames, a), pb = passes_for(frames, b);
  std::vector<double> ratios;
  for (int i = 0; i < 9; ++i) ratios.push_back(batch(frames, pa, a) / batch(frames, pb, b));
  return median(ratios);
}

// A rod of `mass` kg from the joint's origin to `tip` (joint frame): centre of mass halfway, inertia
// of a cylinder of radius 4 cm.
retime::SegmentInertia rod(double mass, const Eigen::Vector3d& tip) {
  retime::SegmentInertia s;
  s.mass = mass;
  s.com = tip / 2;
  const double l = tip.norm(), r = 0.04;
  const Eigen::Vector3d u = l > 0 ? Eigen::Vector3d(tip / l) : Eigen::Vector3d::UnitY();
  const double along = mass * r * r / 2, across = mass * (3 * r * r + l * l) / 12;
  s.inertia = across * Eigen::Matrix3d::Identity() + (along - across) * u * u.transpose();
  return s;
}

struct Case {
  std::string name;
  BodyModel body;
  motion::Motion clip;
  retime::PathDerivatives d;
  int heavy = 0;  // the segment whose mass the Force (k) row scales
#ifdef KG_HAVE_KDL
  std::vector<std::array<KDL::JntArray, 3>> kdl_frames;  // q, q', q'' in KDL's joint order
  std::function<void(int, KDL::JntArray&)> kdl;          // τ of one frame, KDL's joint order
#endif
};

#ifdef KG_HAVE_KDL
// The clip's q, q', q'' in KDL's joint order (DynamicsTopology's), converted once outside the timing.
void kdl_frames(Case& c) {
  const std::vector<int> order = retime::DynamicsTopology::of(*c.body.skeleton).order;
  const auto n = static_cast<unsigned>(order.size());
  for (int f = 0; f < c.clip.frame_count(); ++f) {
    std::array<KDL::JntArray, 3> a{KDL::JntArray(n), KDL::JntArray(n), KDL::JntArray(n)};
    for (unsigned i = 0; i < n; ++i) {
      a[0](i) = c.clip.values(f, order[i]);
      a[1](i) = c.d.first(f, order[i]);
      a[2](i) = c.d.second(f, order[i]);
    }
    c.kdl_frames.push_back(std::move(a));
  }
}
#endif

// "C10" (built piecewise: g++ 12 warns falsely on "C" + std::to_string(n)).
std::string chain_name(int links) {
  std::string name = std::to_string(links);
  name.insert(0, 1, 'C');
  return name;
}

// A fixed root and `links` joints of X, Y, Z rotation channels hanging 0.3 m apart, 2 kg rods;
// 120 frames at 120 fps of smooth random swinging.
std::unique_ptr<Case> chain_case(int links) {
  auto c = std::make_unique<Case>();
  c->name = chain_name(links);
  auto s = std::make_shared<motion::Skeleton>();
  s->add_joint({.name = "base"});
  for (int i = 1; i <= links; ++i)
    s->add_joint({.name = "link" + std::to_string(i),
                  .parent = i - 1,
                  .offset = i == 1 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(0, -kLink, 0),
                  .channels = {{motion::ChannelKind::Xrotation},
                               {motion::ChannelKind::Yrotation},
                               {motion::ChannelKind::Zrotation}}});
  c->body.skeleton = s;
  c->body.segments.push_back({});
  for (int i = 1; i <= links; ++i) c->body.segments.push_back(rod(2.0, {0, -kLink, 0}));
  c->heavy = links / 2;
  const int frames = 120;
  c->clip = {s, motion::FrameMatrix(frames, s->channel_count()), 120, c->name};
  std::mt19937 rng(links);
  std::uniform_real_distribution<double> freq(0.5, 2), phase(0, 2 * M_PI);
  for (int ch = 0; ch < s->channel_count(); ++ch) {
    const double w = 2 * M_PI * freq(rng), p = phase(rng);
    for (int f = 0; f < frames; ++f) c->clip.values(f, ch) = 0.5 * std::sin(w * f / 120.0 + p);
  }
  c->d = retime::path_derivatives(c->clip);
#ifdef KG_HAVE_KDL
  // Three one-DOF segments per link; the third carries the rod (in its tip frame, 0.3 m down)
  // and the offset to the next link.
  auto chain = std::make_shared<KDL::Chain>();
  const retime::SegmentInertia r = rod(2.0, {0, -kLink, 0});
  const KDL::RigidBodyInertia inertia(
      r.mass, test::kdl(Eigen::Vector3d(r.com - Eigen::Vector3d(0, -kLink, 0))),
      KDL::RotationalInertia(r.inertia(0, 0), r.inertia(1, 1), r.inertia(2, 2), r.inertia(0, 1),
                             r.inertia(0, 2), r.inertia(1, 2)));
  for (int i = 1; i <= links; ++i) {
    chain->addSegment(KDL::Segment(KDL::Joint(KDL::Joint::RotX)));
    chain->addSegment(KDL::Segment(KDL::Joint(KDL::Joint::RotY)));
    chain->addSegment(
        KDL::Segment(KDL::Joint(KDL::Joint::RotZ), KDL::Frame(KDL::Vector(0, -kLink, 0)), inertia));
  }
  auto solver = std::make_shared<KDL::ChainIdSolver_RNE>(*chain, KDL::Vector(0, -9.81, 0));
  auto wrenches = std::make_shared<KDL::Wrenches>(chain->getNrOfSegments(), KDL::Wrench::Zero());
  kdl_frames(*c);
  Case* raw = c.get();
  c->kdl = [raw, chain, solver, wrenches](int f, KDL::JntArray& tau) {
    const auto& a = raw->kdl_frames[static_cast<std::size_t>(f)];
    solver->CartToJnt(a[0], a[1], a[2], *wrenches, tau);
  };
#endif
  return c;
}

// CMU 16_15 on 16.asf: a rod along every bone (to its End Site, or its first child), 10 kg per metre.
std::unique_ptr<Case> walk_case() {
  const std::string asf = std::string(KG_DATA_DIR) + "/cmu/asf_amc/16.asf";
  const std::string amc = std::string(KG_DATA_DIR) + "/cmu/asf_amc/16_15.amc";
  if (!std::filesystem::exists(asf) || !std::filesystem::exists(amc)) {
    std::printf("skipped 16_15: %s or %s not found\n", asf.c_str(), amc.c_str());
    return nullptr;
  }
  auto c = std::make_unique<Case>();
  c->name = "16_15";
  c->clip = io::import_motion(amc, asf, {}).motion;
  const motion::Skeleton& s = *c->clip.skeleton;
  c->body.skeleton = c->clip.skeleton;
  for (int j = 0; j < s.joint_count(); ++j) {
    Eigen::Vector3d tip = Eigen::Vector3d::Zero();
    if (!s.joint(j).end_sites.empty()) tip = s.joint(j).end_sites[0];
    for (int k = j + 1; k < s.joint_count() && tip.isZero(); ++k)
      if (s.joint(k).parent == j) tip = s.joint(k).offset;
    c->body.segments.push_back(rod(10.0 * tip.norm(), tip));
  }
  c->heavy = std::max(0, s.find_joint("lfemur"));
  c->d = retime::path_derivatives(c->clip);
#ifdef KG_HAVE_KDL
  auto k = std::make_shared<test::KdlBody>(test::kdl_body(c->body));
  auto solver = std::make_shared<KDL::TreeIdSolver_RNE>(k->tree, KDL::Vector(0, -9.81, 0));
  auto wrenches = std::make_shared<KDL::WrenchMap>();
  kdl_frames(*c);
  Case* raw = c.get();
  c->kdl = [raw, k, solver, wrenches](int f, KDL::JntArray& tau) {
    const auto& a = raw->kdl_frames[static_cast<std::size_t>(f)];
    solver->CartToJnt(a[0], a[1], a[2], *wrenches, tau);
  };
#endif
  return c;
}

struct Row {
  std::string name;
  // Seconds per frame for a case; nullopt when it does not apply (printed as "-").
  std::function<std::optional<double>(Case&)> time;
};

}  // namespace

int main(int argc, char** argv) {
  const std::string only = argc > 1 ? argv[1] : "";
  std::vector<std::unique_ptr<Case>> cases;
  auto want = [&](const std::string& name) { return only.empty() || name.find(only) != std::string::npos; };
  if (want("16_15"))
    if (auto c = walk_case()) cases.push_back(std::move(c));
  for (int links : {10, 100, 1000})
    if (want(chain_name(links))) cases.push_back(chain_case(links));
  if (cases.empty()) {
    std::printf("no case matches '%s' (cases: 16_15 C10 C100 C1000)\n", only.c_str());
    return 1;
  }
  const Eigen::Vector3d g(0, -9.81, 0);

  std::vector<Row> rows;
  rows.push_back({"KDL RNEA", [](Case& c) -> std::optional<double> {
#ifdef KG_HAVE_KDL
                    KDL::JntArray tau(static_cast<unsigned>(c.clip.skeleton->channel_count()));
                    return seconds_per_frame(c.clip.frame_count(), [&](int f) {
                      c.kdl(f, tau);
                      g_sink = tau(0);
                    });
#else
                    (void)c;
                    return std::nullopt;
#endif
                  }});
  rows.push_back({"RNEA", [&g](Case& c) -> std::optional<double> {
                    retime::DynamicsWorkspace ws;
                    Eigen::VectorXd tau(c.clip.skeleton->channel_count());
                    return seconds_per_frame(c.clip.frame_count(), [&](int f) {
                      retime::inverse_dynamics(c.body, c.clip.values.row(f), c.d.first.row(f),
                                               c.d.second.row(f), g, {}, ws, tau);
                      g_sink = tau[0];
                    });
                  }});
  rows.push_back({"Force", [](Case& c) -> std::optional<double> {
                    retime::DynamicsWorkspace ws;
                    retime::FrameTorques out;
                    return seconds_per_frame(c.clip.frame_count(), [&](int f) {
                      retime::frame_torques(c.body, c.clip, c.d, f, ws, out);
                      g_sink = out.velocity[0];
                    });
                  }});
  rows.push_back({"Force (k)", [](Case& c) -> std::optional<double> {
                    retime::DynamicsWorkspace ws;
                    retime::MassScaleTorques out;
                    return seconds_per_frame(c.clip.frame_count(), [&](int f) {
                      retime::frame_torques_mass_scale(c.body, c.clip, c.d, f, c.heavy, ws, out);
                      g_sink = out.change.velocity[0];
                    });
                  }});

  rows.push_back({"Feasible", [&g](Case& c) -> std::optional<double> {
                    // The body with torque limits, the coefficients and contacts of every frame
                    // (outside the timing).
                    const motion::Skeleton& s = *c.clip.skeleton;
                    const int frames = c.clip.frame_count(), channels = s.channel_count();
                    retime::DynamicsWorkspace ws;
                    std::vector<retime::FrameTorques> torques(static_cast<std::size_t>(frames));
                    for (int f = 0; f < frames; ++f)
                      retime::frame_torques(c.body, c.clip, c.d, f, ws, torques[static_cast<std::size_t>(f)]);
                    BodyModel body = c.body;
                    const bool floating = s.joint(0).channels.size() > 0;
                    body.torque_min = Eigen::VectorXd::Constant(channels, -300.0);
                    body.torque_max = Eigen::VectorXd::Constant(channels, 300.0);
                    if (!floating)
                      for (int ch = 0; ch < channels; ++ch) {
                        double most = 1e-3;
                        for (const retime::FrameTorques& t : torques)
                          most = std::max(most, std::abs(t.at(1, 0, g)[ch]));
                        body.torque_min[ch] = -1.5 * most;
                        body.torque_max[ch] = 1.5 * most;
                      }
                    for (const motion::Joint& j : s.joints())
                      if (j.parent < 0)
                        for (std::size_t i = 0; i < j.channels.size(); ++i)
                          body.torque_min[j.first_channel + static_cast<int>(i)] =
                              body.torque_max[j.first_channel + static_cast<int>(i)] = 0;
                    retime::Contacts contacts;
                    if (floating) {
                      contacts = retime::detect_contacts(c.clip, {});
                    } else {
                      contacts.skeleton = c.clip.skeleton;
                      contacts.frames.resize(static_cast<std::size_t>(frames));
                    }
                    const retime::HullOptions options;
                    return seconds_per_frame(frames, [&](int f) {
                      const retime::FrameHull h =
                          retime::build_frame_hull(body, contacts.frames[static_cast<std::size_t>(f)],
                                                   torques[static_cast<std::size_t>(f)], options);
                      g_sink = h.centre.y();
                    });
                  }});

  std::printf("Per source frame, one thread, microseconds (median of 9 batches)\n%-14s", "");
  for (const auto& c : cases) std::printf("%10s", c->name.c_str());
  std::printf("\n%-14s", "channels");
  for (const auto& c : cases) std::printf("%10d", c->clip.skeleton->channel_count());
  std::printf("\n%-14s", "frames");
  for (const auto& c : cases) std::printf("%10d", c->clip.frame_count());
  std::printf("\n");
  for (const Row& row : rows) {
    std::printf("%-14s", row.name.c_str());
    std::fflush(stdout);
    std::vector<std::optional<double>> times;
    for (const auto& c : cases) {
      times.push_back(row.time(*c));
      if (times.back())
        std::printf("%10.1f", *times.back() * 1e6);
      else
        std::printf("%10s", "-");
      std::fflush(stdout);
    }
    std::printf("\n");
  }
  // The target, from back-to-back batches of frame_torques and KDL (not the rows above,
  // which may have run under different loads).
  std::printf("%-14s", "Force / KDL");
  for (const auto& c : cases) {
#ifdef KG_HAVE_KDL
    retime::DynamicsWorkspace ws;
    retime::FrameTorques out;
    KDL::JntArray tau(static_cast<unsigned>(c->clip.skeleton->channel_count()));
    const double r = paired_ratio(
        c->clip.frame_count(),
        [&](int f) {
          retime::frame_torques(c->body, c->clip, c->d, f, ws, out);
          g_sink = out.velocity[0];
        },
        [&](int f) {
          c->kdl(f, tau);
          g_sink = tau(0);
        });
    std::printf("%10.2f", r);
#else
    std::printf("%10s", "-");
#endif
  }
  std::printf("\n");

#ifdef KG_HAVE_KDL
  // The comparison is of equal work: the same torques, checked on every frame.
  std::printf("largest |τ − τ_KDL| / max|τ_KDL| over all frames:");
  for (const auto& c : cases) {
    const std::vector<int> order = retime::DynamicsTopology::of(*c->body.skeleton).order;
    retime::DynamicsWorkspace ws;
    Eigen::VectorXd tau(c->clip.skeleton->channel_count());
    KDL::JntArray ktau(static_cast<unsigned>(order.size()));
    double worst = 0;
    for (int f = 0; f < c->clip.frame_count(); ++f) {
      retime::inverse_dynamics(c->body, c->clip.values.row(f), c->d.first.row(f), c->d.second.row(f), g, {},
                               ws, tau);
      c->kdl(f, ktau);
      double diff = 0, scale = 0;
      for (std::size_t i = 0; i < order.size(); ++i) {
        diff = std::max(diff, std::abs(tau[order[i]] - ktau(static_cast<unsigned>(i))));
        scale = std::max(scale, std::abs(ktau(static_cast<unsigned>(i))));
      }
      worst = std::max(worst, diff / scale);
    }
    std::printf("  %s %.1e", c->name.c_str(), worst);
  }
  std::printf("\n");
#else
  std::printf("KDL rows skipped: built without KDL (Debian liborocos-kdl-dev)\n");
#endif
  return 0;
}
