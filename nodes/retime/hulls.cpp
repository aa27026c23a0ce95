// Feasible timings per frame (hulls.hpp): GLPK LPs for the hull's vertices and centre, a bounded
// least squares for frames without a hull.
#include "kg/retime/hulls.hpp"
#include "kg/base/option_check.hpp"

#include <glpk.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include <Eigen/Cholesky>

#include "kg/numerics/bounded_least_squares.hpp"

#include "kg/base/text.hpp"
#include "kg/retime/force_model.hpp"

namespace kg::retime {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A point of the (p̈, ṗ²) plane for messages.
std::string point_text(const Eigen::Vector2d& x) {
  return "(" + text::significant(x.x(), 4) + ", " + text::significant(x.y(), 4) + ")";
}

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

std::vector<bool> root_channels(const motion::Skeleton& sk) {
  std::vector<bool> root(static_cast<std::size_t>(sk.channel_count()), false);
  for (const motion::Joint& j : sk.joints())
    if (j.parent < 0)
      for (std::size_t i = 0; i < j.channels.size(); ++i)
        root[static_cast<std::size_t>(j.first_channel) + i] = true;
  return root;
}

void check_sizes(const body::BodyModel& body, const FrameTorques& t) {
  if (!body.skeleton) throw std::invalid_argument("hulls: the body model has no skeleton");
  const Eigen::Index c = body.skeleton->channel_count();
  if (body.torque_min.size() != c || body.torque_max.size() != c)
    throw std::invalid_argument(
        "hulls: the body's torque limits have " + std::to_string(body.torque_min.size()) + " and " +
        std::to_string(body.torque_max.size()) + " entries for " + std::to_string(c) + " channels");
  if (t.velocity.size() != c || t.acceleration.size() != c || t.gravity.rows() != c)
    throw std::invalid_argument("hulls: the torque coefficients have " + std::to_string(t.velocity.size()) +
                                " channels, the body " + std::to_string(c));
  if (!body.gravity.allFinite()) throw std::invalid_argument("hulls: the body's gravity is not finite");
}

// One frame's rows: lo <= acceleration·p̈ + velocity·ṗ² − N λ <= hi, the gravity term moved into
// the bounds. The root's rows are equalities; channels without any finite limit have no row.
struct Rows {
  std::vector<int> channel;
  std::vector<double> lo, hi;
  std::vector<bool> root;
  int root_count = 0;
};

void make_rows(const body::BodyModel& body, const std::vector<bool>& root, const FrameTorques& t,
               Rows& rows) {
  rows.channel.clear();
  rows.lo.clear();
  rows.hi.clear();
  rows.root.clear();
  rows.root_count = 0;
  const Eigen::Index channels = t.velocity.size();
  for (Eigen::Index c = 0; c < channels; ++c) {
    const double gravity_term = t.gravity.row(c).dot(body.gravity);
    const bool is_root = root[static_cast<std::size_t>(c)];
    const double lo = is_root ? 0.0 : body.torque_min[c], hi = is_root ? 0.0 : body.torque_max[c];
    if (std::isnan(lo) || std::isnan(hi) || lo > hi)
      throw std::invalid_argument("hulls: torque limits of channel " + std::to_string(c) +
                                  " are not an interval");
    if (!is_root && lo == -kInf && hi == kInf) continue;
    rows.channel.push_back(static_cast<int>(c));
    rows.lo.push_back(lo - gravity_term);
    rows.hi.push_back(hi - gravity_term);
    rows.root.push_back(is_root);
    rows.root_count += is_root ? 1 : 0;
  }
}

// ---- the LP ---------------------------------------------------------------------------------

struct Vertex {
  Eigen::Vector2d x;
  Eigen::VectorXd lambda;
};

// Buffers shared by the frames of a clip.
struct Workspace {
  Rows rows;
  std::vector<int> ia, ja;
  std::vector<double> ar;
  Eigen::VectorXd lambda;  // the last LP's λ
  glp_smcp parm{};
  int terminal = GLP_ON;
  Workspace() {
    terminal = glp_term_out(GLP_OFF);  // glp_scale_prob and glp_adv_basis print otherwise
    glp_init_smcp(&parm);
    parm.msg_lev = GLP_MSG_OFF;
    parm.presolve = GLP_OFF;
    parm.meth = GLP_PRIMAL;
  }
  ~Workspace() { glp_term_out(terminal); }
  Workspace(const Workspace&) = delete;
  Workspace& operator=(const Workspace&) = delete;
};

class FrameLp {
 public:
  // Columns: 1 p̈, 2 ṗ², 3.. λ.
  FrameLp(const Rows& rows, const FrameTorques& t, const Eigen::MatrixXd& N, const HullOptions& o,
          Workspace& w)
      : lp_(glp_create_prob()), w_(w), columns_(static_cast<int>(N.cols())) {
    const int m = static_cast<int>(rows.channel.size());
    if (m > 0) glp_add_rows(lp_, m);
    glp_add_cols(lp_, 2 + columns_);
    for (int i = 0; i < m; ++i) {
      const double lo = rows.lo[static_cast<std::size_t>(i)], hi = rows.hi[static_cast<std::size_t>(i)];
      const int type = lo == hi ? GLP_FX : lo == -kInf ? GLP_UP : hi == kInf ? GLP_LO : GLP_DB;
      glp_set_row_bnds(lp_, i + 1, type, lo == -kInf ? 0.0 : lo, hi == kInf ? 0.0 : hi);
    }
    glp_set_col_bnds(lp_, 1, GLP_DB, -o.pddot_max, o.pddot_max);
    glp_set_col_bnds(lp_, 2, GLP_DB, 0.0, o.pdot2_max);
    for (int j = 0; j < columns_; ++j) glp_set_col_bnds(lp_, 3 + j, GLP_LO, 0.0, 0.0);
    w.ia.assign(1, 0);
    w.ja.assign(1, 0);
    w.ar.assign(1, 0.0);
    auto put = [&](int row, int col, double v) {
      if (v == 0) return;
      w.ia.push_back(row);
      w.ja.push_back(col);
      w.ar.push_back(v);
    };
    for (int i = 0; i < m; ++i) {
      const int c = rows.channel[static_cast<std::size_t>(i)];
      put(i + 1, 1, t.acceleration[c]);
      put(i + 1, 2, t.velocity[c]);
      for (int j = 0; j < columns_; ++j) put(i + 1, 3 + j, -N(c, j));
    }
    glp_load_matrix(lp_, static_cast<int>(w.ia.size()) - 1, w.ia.data(), w.ja.data(), w.ar.data());
    glp_scale_prob(lp_, GLP_SF_AUTO);
    glp_adv_basis(lp_, 0);
    w.lambda.resize(columns_);
  }
  ~FrameLp() { glp_delete_prob(lp_); }
  FrameLp(const FrameLp&) = delete;
  FrameLp& operator=(const FrameLp&) = delete;

  enum class Result { Optimal, Empty, Failed };

  // Maximises d·(p̈, ṗ²); the point and λ are read with point() and w.lambda.
  Result maximise(const Eigen::Vector2d& d) {
    glp_set_obj_dir(lp_, GLP_MAX);
    glp_set_obj_coef(lp_, 1, d.x());
    glp_set_obj_coef(lp_, 2, d.y());
    return run();
  }

  // Minimises the summed L1 norms of the patches' forces, Σ_p |F_px| + |F_py| + |F_pz| with F_p =
  // Σ_{j in p} λ_j b_j, with (p̈, ṗ²) fixed at x. Adds two columns (|F_px|, |F_pz| bounds) and four
  // rows per patch to the LP, so call it last; the basis stays valid (new rows basic).
  Result minimise_patch_forces_at(const Eigen::Vector2d& x, const Eigen::Matrix3Xd& directions,
                                  const std::vector<int>& column_patch) {
    std::vector<int> patches;
    for (int p : column_patch)
      if (std::find(patches.begin(), patches.end(), p) == patches.end()) patches.push_back(p);
    const int np = static_cast<int>(patches.size());
    glp_set_obj_dir(lp_, GLP_MIN);
    glp_set_obj_coef(lp_, 1, 0.0);
    glp_set_obj_coef(lp_, 2, 0.0);
    glp_set_col_bnds(lp_, 1, GLP_FX, x.x(), x.x());
    glp_set_col_bnds(lp_, 2, GLP_FX, x.y(), x.y());
    for (int j = 0; j < columns_; ++j) glp_set_obj_coef(lp_, 3 + j, directions(1, j));  // Σ F_py
    if (np > 0) {
      const int first_col = glp_add_cols(lp_, 2 * np);
      const int first_row = glp_add_rows(lp_, 4 * np);
      std::vector<int> index(1);
      std::vector<double> value(1);
      for (int q = 0; q < np; ++q)
        for (int axis = 0; axis < 2; ++axis) {
          const int t = first_col + 2 * q + axis;
          glp_set_col_bnds(lp_, t, GLP_LO, 0.0, 0.0);
          glp_set_obj_coef(lp_, t, 1.0);
          for (int sign = 0; sign < 2; ++sign) {  // t − F ≥ 0 and t + F ≥ 0
            index.assign(1, 0);
            value.assign(1, 0.0);
            index.push_back(t);
            value.push_back(1.0);
            for (int j = 0; j < columns_; ++j) {
              const double b = directions(axis == 0 ? 0 : 2, j);
              if (column_patch[static_cast<std::size_t>(j)] != patches[static_cast<std::size_t>(q)] || b == 0)
                continue;
              index.push_back(3 + j);
              value.push_back(sign == 0 ? -b : b);
            }
            const int row = first_row + 4 * q + 2 * axis + sign;
            glp_set_row_bnds(lp_, row, GLP_LO, 0.0, 0.0);
            glp_set_mat_row(lp_, row, static_cast<int>(index.size()) - 1, index.data(), value.data());
          }
        }
    }
    return run();
  }

  Eigen::Vector2d point() const { return {glp_get_col_prim(lp_, 1), glp_get_col_prim(lp_, 2)}; }
  int solved() const { return solved_; }
  int last_code() const { return code_; }

 private:
  Result run() {
    for (int attempt = 0; attempt < 2; ++attempt) {
      ++solved_;
      code_ = glp_simplex(lp_, &w_.parm);
      const int status = glp_get_status(lp_);
      if (code_ == 0 && status == GLP_OPT) {
        for (int j = 0; j < columns_; ++j) w_.lambda[j] = std::max(0.0, glp_get_col_prim(lp_, 3 + j));
        return Result::Optimal;
      }
      if (code_ == 0 && status == GLP_NOFEAS) return Result::Empty;
      glp_adv_basis(lp_, 0);  // a numerical failure: once more from a fresh basis
    }
    return Result::Failed;
  }

  glp_prob* lp_;
  Workspace& w_;
  int columns_;
  int solved_ = 0;
  int code_ = 0;
};

std::uint8_t box_bits(const Eigen::Vector2d& x, const HullOptions& o) {
  const double eps = 1e-7 * std::max(o.pddot_max, o.pdot2_max);
  std::uint8_t bits = 0;
  if (x.x() <= -o.pddot_max + eps) bits |= kBoxPddotMin;
  if (x.x() >= o.pddot_max - eps) bits |= kBoxPddotMax;
  if (x.y() >= o.pdot2_max - eps) bits |= kBoxPdot2Max;
  return bits;
}

void append_message(FrameHull& h, const std::string& note) {
  h.message += (h.message.empty() ? "" : "; ") + note;
}

// λ at x inside (or on) a convex polygon by interpolation between its vertices' (a fan from
// vertex 0): the fallback when the centre LP fails numerically.
Eigen::VectorXd interpolate_on_polygon(const std::vector<Vertex>& v, const Eigen::Vector2d& x) {
  const std::size_t n = v.size();
  if (n == 1) return v[0].lambda;
  if (n == 2) {
    const Eigen::Vector2d e = v[1].x - v[0].x;
    const double t = std::clamp((x - v[0].x).dot(e) / e.squaredNorm(), 0.0, 1.0);
    return (1 - t) * v[0].lambda + t * v[1].lambda;
  }
  for (std::size_t i = 1; i + 1 < n; ++i) {
    Eigen::Matrix2d basis;
    basis << v[i].x - v[0].x, v[i + 1].x - v[0].x;
    const Eigen::Vector2d ab = basis.inverse() * (x - v[0].x);
    if ((ab.minCoeff() >= -1e-9 && ab.sum() <= 1 + 1e-9) || i + 2 == n)
      return (1 - ab.sum()) * v[0].lambda + ab.x() * v[i].lambda + ab.y() * v[i + 1].lambda;
  }
  return v[0].lambda;
}

// Drops repeated vertices and those not strictly convex (collinear within rounding).
void clean_polygon(std::vector<Vertex>& v, double eps) {
  bool changed = true;
  while (changed && v.size() > 1) {
    changed = false;
    for (std::size_t i = 0; i < v.size() && v.size() > 1; ++i) {
      const std::size_t next = (i + 1) % v.size();
      if ((v[next].x - v[i].x).norm() <= eps) {
        v.erase(v.begin() + static_cast<std::ptrdiff_t>(next));
        changed = true;
        break;
      }
    }
    if (changed || v.size() < 3) continue;
    for (std::size_t i = 0; i < v.size(); ++i) {
      const Vertex& a = v[(i + v.size() - 1) % v.size()];
      const Vertex& b = v[(i + 1) % v.size()];
      const Eigen::Vector2d e1 = v[i].x - a.x, e2 = b.x - v[i].x;
      // Between its neighbours (collinear or dented by rounding), not the end of a segment.
      if (cross(e1, e2) <= eps * (e1.norm() + e2.norm()) && e1.dot(e2) > 0) {
        v.erase(v.begin() + static_cast<std::ptrdiff_t>(i));
        changed = true;
        break;
      }
    }
  }
}

// The single least-squares point of a frame without a hull (hulls.hpp), as its hull.
void least_squares_hull(const body::BodyModel& body, const FrameTorques& t, const Rows& rows,
                        const Eigen::MatrixXd& N, bool flight, const HullOptions& o, FrameHull& h) {
  const Eigen::Index k = flight ? 0 : N.cols();
  numerics::BoundedLsProblem p;
  std::vector<std::size_t> used;
  for (std::size_t i = 0; i < rows.channel.size(); ++i)
    if (!flight || rows.root[i]) used.push_back(i);
  const Eigen::Index m = static_cast<Eigen::Index>(used.size());
  p.G.resize(m, 2 + k);
  p.e.resize(m);
  p.lo.resize(m);
  p.hi.resize(m);
  for (Eigen::Index r = 0; r < m; ++r) {
    const std::size_t i = used[static_cast<std::size_t>(r)];
    const int c = rows.channel[i];
    p.G(r, 0) = t.acceleration[c];
    p.G(r, 1) = t.velocity[c];
    if (k > 0) p.G.row(r).tail(k) = -N.row(c);
    // Rows hold τ − gravity·g within [lo, hi]: e = 0.
    p.e[r] = 0;
    p.lo[r] = rows.lo[i];
    p.hi[r] = rows.hi[i];
  }
  p.xlo.setZero(2 + k);
  p.xhi.setConstant(2 + k, kInf);
  p.xlo[0] = -o.pddot_max;
  p.xhi[0] = o.pddot_max;
  p.xhi[1] = o.pdot2_max;
  p.ref.setZero(2 + k);
  p.ref[1] = 1;
  double scale = 1;
  for (Eigen::Index j = 0; j < p.G.cols(); ++j) scale = std::max(scale, p.G.col(j).squaredNorm());
  p.reg.setConstant(2 + k, 1e-9 * scale);
  const numerics::BoundedLsResult r = numerics::bounded_least_squares(p);
  const Eigen::Vector2d x = r.x.head<2>();
  h.vertices = {x};
  h.lambda = {r.x.tail(k)};
  h.on_box = {box_bits(x, o)};
  h.centre = x;
  h.centre_lambda = r.x.tail(k);
  h.centre_is_original = (x - Eigen::Vector2d(0, 1)).norm() <= 1e-9;
  h.residual = r.residual;
  (void)body;
  std::string why = flight
                        ? "flight: no contact; the least-squares point of the root's rows"
                        : "infeasible: no timing and contact forces meet every row; the least-squares point "
                          "of every row (bounded-variable least squares)";
  why += " is " + point_text(x) + ", residual " + text::significant(r.residual, 4);
  if (!r.converged) why += " (least squares stopped at its iteration limit)";
  append_message(h, why);
}

FrameHull frame_hull(const body::BodyModel& body, const std::vector<bool>& root, const ContactFrame& contact,
                     const FrameTorques& t, const HullOptions& o, Workspace& w) {
  check_sizes(body, t);
  FrameHull h;
  const int channels = body.skeleton->channel_count();
  contact_generalised_forces(contact, channels, body.friction, h.N);
  const Eigen::Index k = h.N.cols();
  const Eigen::Matrix<double, 3, 4> P = friction_basis(body.friction);
  h.force_directions.resize(3, k);
  h.points.resize(3, k);
  h.column_patch.resize(static_cast<std::size_t>(k));
  for (std::size_t i = 0; i < contact.points.size(); ++i)
    for (int b = 0; b < 4; ++b) {
      const Eigen::Index j = 4 * static_cast<Eigen::Index>(i) + b;
      h.force_directions.col(j) = P.col(b);
      h.points.col(j) = contact.points[i].world;
      h.column_patch[static_cast<std::size_t>(j)] = contact.points[i].patch;
    }
  make_rows(body, root, t, w.rows);

  // A floating base without contact flies: its root's rows pin the timing (ballistic). A fixed
  // base (a root without channels) has no such rows and keeps the LP: its torque limits alone.
  if (contact.points.empty() && w.rows.root_count > 0) {
    h.status = HullStatus::Flight;
    least_squares_hull(body, t, w.rows, h.N, true, o, h);
    build_fan(h);
    return h;
  }

  FrameLp lp(w.rows, t, h.N, o, w);
  std::vector<Vertex> sweep;
  bool empty = false, failed = false;
  for (int i = 0; i < o.initial_directions && !empty; ++i) {
    const double angle = -std::numbers::pi / 2 + 2 * std::numbers::pi * i / o.initial_directions;
    const FrameLp::Result r = lp.maximise({std::cos(angle), std::sin(angle)});
    if (r == FrameLp::Result::Empty) empty = true;
    if (r == FrameLp::Result::Failed) failed = true;
    if (r == FrameLp::Result::Optimal) sweep.push_back({lp.point(), w.lambda});
  }
  if (empty || sweep.empty()) {
    h.status = HullStatus::Infeasible;
    if (!empty) append_message(h, "GLPK failed (code " + std::to_string(lp.last_code()) + ")");
    least_squares_hull(body, t, w.rows, h.N, false, o, h);
    h.lp_count = lp.solved();
    build_fan(h);
    return h;
  }
  const double eps = 1e-9 * std::max(o.pddot_max, o.pdot2_max);
  clean_polygon(sweep, eps);

  // Refine every edge along its outward normal until the true hull reaches no farther than the
  // tolerance beyond it (fig. 4).
  std::vector<Vertex> hull;
  bool limit = false;
  auto refine = [&](auto&& self, const Vertex& a, const Vertex& b) -> void {
    const Eigen::Vector2d e = b.x - a.x;
    if (e.norm() <= eps) return;
    if (lp.solved() >= o.max_lps) {
      limit = true;
      return;
    }
    const Eigen::Vector2d normal = Eigen::Vector2d(e.y(), -e.x()).normalized();
    const FrameLp::Result r = lp.maximise(normal);
    if (r != FrameLp::Result::Optimal) {
      failed = true;
      return;
    }
    const Eigen::Vector2d x = lp.point();
    if (normal.dot(x - a.x) <= o.tolerance) return;
    const Vertex v{x, w.lambda};
    self(self, a, v);
    hull.push_back(v);
    self(self, v, b);
  };
  for (std::size_t i = 0; i < sweep.size(); ++i) {
    hull.push_back(sweep[i]);
    if (sweep.size() > 1) refine(refine, sweep[i], sweep[(i + 1) % sweep.size()]);
  }
  clean_polygon(hull, eps);

  h.status = HullStatus::Feasible;
  for (const Vertex& v : hull) {
    h.vertices.push_back(v.x);
    h.lambda.push_back(v.lambda);
    h.on_box.push_back(box_bits(v.x, o));
  }
  if (hull.size() == 1) append_message(h, "degenerate hull: a single point");
  if (hull.size() == 2) append_message(h, "degenerate hull: a segment");
  if (limit)
    append_message(h, "LP limit (" + std::to_string(o.max_lps) + ") reached before the tolerance held");
  if (failed)
    append_message(h, "GLPK failed on some directions (code " + std::to_string(lp.last_code()) + ")");

  // The centre: λ at (0, 1), or at the hull's nearest point.
  const Eigen::Vector2d original(0, 1);
  const HullPoint near = closest_point_on_polygon(h.vertices, original);
  h.centre_is_original = near.distance_squared <= eps * eps;
  h.centre = h.centre_is_original ? original : near.point;
  if (!h.centre_is_original)
    append_message(h, "(0, 1) lies outside the hull: centre at the nearest hull point " +
                          point_text(h.centre) + ", " +
                          text::significant(std::sqrt(near.distance_squared), 4) + " away");
  if (lp.minimise_patch_forces_at(h.centre, h.force_directions, h.column_patch) == FrameLp::Result::Optimal) {
    h.centre_lambda = w.lambda;
  } else {
    h.centre_lambda = interpolate_on_polygon(hull, h.centre);
    append_message(h, "the centre LP failed (GLPK code " + std::to_string(lp.last_code()) +
                          "): centre λ interpolated between the vertices'");
  }
  h.lp_count = lp.solved();
  build_fan(h);
  return h;
}

}  // namespace

const char* to_string(HullStatus status) {
  switch (status) {
    case HullStatus::Feasible:
      return "feasible";
    case HullStatus::Flight:
      return "flight";
    case HullStatus::Infeasible:
      return "infeasible";
  }
  return "?";
}

int Hulls::count(HullStatus status) const {
  return static_cast<int>(
      std::count_if(frames.begin(), frames.end(), [&](const FrameHull& f) { return f.status == status; }));
}

void HullOptions::validate() const {
  using options::require;
  const char* o = "HullOptions";
  require(options::positive(pddot_max), o, "pddot_max", pddot_max,
          "> 0 and finite (source s per output s^2)");
  require(options::positive(pdot2_max), o, "pdot2_max", pdot2_max, "> 0 and finite");
  require(options::positive(tolerance), o, "tolerance", tolerance, "> 0 and finite (plane units)");
  require(initial_directions >= 3, o, "initial_directions", initial_directions, ">= 3");
  require(max_lps >= initial_directions + 1, o, "max_lps", max_lps,
          ">= initial_directions + 1 (" + std::to_string(initial_directions + 1) + ")");
}

Hulls build_hulls(const body::BodyModel& body, const Contacts& contacts,
                  std::span<const FrameTorques> torques, const HullOptions& options) {
  options.validate();
  if (!body.skeleton) throw std::invalid_argument("hulls: the body model has no skeleton");
  if (contacts.frame_count() != static_cast<int>(torques.size()))
    throw std::invalid_argument("hulls: " + std::to_string(contacts.frame_count()) + " contact frames but " +
                                std::to_string(torques.size()) + " frames of torque coefficients");
  if (contacts.skeleton && contacts.skeleton->channel_count() != body.skeleton->channel_count())
    throw std::invalid_argument("hulls: the contacts' skeleton has " +
                                std::to_string(contacts.skeleton->channel_count()) +
                                " channels, the body's " + std::to_string(body.skeleton->channel_count()));
  Hulls out;
  out.options = options;
  out.gravity = body.gravity;
  out.friction = body.friction;
  for (const ContactPatch& p : contacts.patches) out.patch_names.push_back(p.name);
  const std::vector<bool> root = root_channels(*body.skeleton);
  Workspace w;
  out.frames.reserve(torques.size());
  for (std::size_t f = 0; f < torques.size(); ++f)
    out.frames.push_back(frame_hull(body, root, contacts.frames[f], torques[f], options, w));
  return out;
}

FrameHull build_frame_hull(const body::BodyModel& body, const ContactFrame& contact,
                           const FrameTorques& torques, const HullOptions& options) {
  options.validate();
  if (!body.skeleton) throw std::invalid_argument("hulls: the body model has no skeleton");
  Workspace w;
  return frame_hull(body, root_channels(*body.skeleton), contact, torques, options, w);
}

double max_row_violation(const body::BodyModel& body, const FrameTorques& t, const FrameHull& h,
                         const Eigen::Vector2d& x, const Eigen::VectorXd& lambda) {
  check_sizes(body, t);
  if (lambda.size() != h.N.cols())
    throw std::invalid_argument("hulls: " + std::to_string(lambda.size()) + " λ for " +
                                std::to_string(h.N.cols()) + " columns");
  Eigen::VectorXd tau = t.at(x.y(), x.x(), body.gravity);
  if (h.N.cols() > 0) tau.noalias() -= h.N * lambda;
  const std::vector<bool> root = root_channels(*body.skeleton);
  double worst = lambda.size() > 0 ? std::max(0.0, -lambda.minCoeff()) : 0.0;
  for (Eigen::Index c = 0; c < tau.size(); ++c) {
    const bool is_root = root[static_cast<std::size_t>(c)];
    const double lo = is_root ? 0.0 : body.torque_min[c], hi = is_root ? 0.0 : body.torque_max[c];
    worst = std::max({worst, lo - tau[c], tau[c] - hi});
  }
  return worst;
}

}  // namespace kg::retime
