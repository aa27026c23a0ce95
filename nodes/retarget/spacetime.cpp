#include "kg/retarget/spacetime.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <span>
#include <stdexcept>
#include <string>

#include "kg/base/option_check.hpp"
#include "kg/motion/kinematics.hpp"
#include "kg/numerics/banded_cholesky.hpp"

namespace kg::retarget {

namespace {

using motion::FrameMatrix;
using motion::Skeleton;

std::string label_of(const Constraint& c) {
  return "constraint '" + (c.label.empty() ? std::string("(unlabelled)") : c.label) + "' (" + c.kind + ")";
}

// --- problem set-up ---------------------------------------------------------------------------

struct Character {
  const Skeleton* base = nullptr;
  std::vector<const Skeleton*> skeleton;  // per frame
  FrameMatrix m1;
  DisplacementLayout layout;
  std::vector<bool> free;
  Eigen::VectorXd sensitivity;
  int x_offset = 0;  // of its controls in x
  int c_offset = 0;  // of its channels among all characters' channels
  int channels = 0, joints = 0;
  std::vector<int> stamp;               // per channel: last group that touched it
  std::vector<std::vector<int>> chain;  // per joint: influencing channels (lazily filled)
  // Per evaluation.
  FrameMatrix values;
  std::vector<Eigen::Isometry3d> world;  // frame * joints + joint
  // Scratch of the per-frame accumulation.
  Eigen::MatrixXd normal;  // channels x channels
  Eigen::VectorXd gradient;
};

// A (character, frame) a sample reads, and the free channels whose values move what it reads.
struct Piece {
  int character = 0;
  int frame = 0;
  std::vector<int> channels;  // sorted
  std::size_t g_offset = 0;   // rows x channels.size() derivatives, column-major, in g_
};

struct SampleInfo {
  int constraint = 0;
  int sample = 0;
  int row_offset = 0;
  int rows = 0;
  std::vector<Piece> pieces;
  // Point p: its piece, and for each channel of its chain the position in that piece (-1: frozen).
  std::vector<int> point_piece;
  std::vector<std::vector<int>> point_pos;
  std::vector<int> value_piece, value_pos;
};

struct KindInfo {
  const ConstraintKind* kind = nullptr;
  int rows = 0;
  std::vector<char> inequality;
};

struct Group {  // single-piece samples of one (character, frame)
  int character = 0, frame = 0;
  std::vector<int> samples;
  std::vector<int> touched;  // per assembly
};

class Pass {
 public:
  Pass(std::vector<Character>& chars, const ConstraintSet& set, const std::vector<KindInfo>& kinds,
       const SpacetimeOptions& options, bool honour_frozen)
      : chars_(chars), set_(set), kinds_(kinds), options_(options) {
    frames_ = chars_[0].layout.frames();
    for (Character& ch : chars_) {
      ch.x_offset = x_size_;
      x_size_ += ch.layout.unknown_count();
      ch.c_offset = channel_total_;
      channel_total_ += ch.channels;
      ch.stamp.assign(static_cast<std::size_t>(ch.channels), -1);
      if (!honour_frozen) ch.free.assign(static_cast<std::size_t>(ch.channels), true);
      ch.normal = Eigen::MatrixXd::Zero(ch.channels, ch.channels);
      ch.gradient = Eigen::VectorXd::Zero(ch.channels);
      ch.world.resize(static_cast<std::size_t>(frames_) * ch.joints);
      ch.chain.assign(static_cast<std::size_t>(ch.joints), {});
    }
    build_samples();
  }

  int unknown_total() const { return x_size_; }
  int row_total() const { return rows_total_; }
  const Eigen::VectorXd& residual() const { return r_; }
  const std::vector<SampleInfo>& samples() const { return samples_; }
  bool row_inequality(int row) const { return inequality_[static_cast<std::size_t>(row)] != 0; }

  // Values, FK, residuals at x; with `jacobian` also the channel-space derivatives of the rows
  // that are active (all rows when `all_rows`).
  void evaluate(const Eigen::VectorXd& x, bool jacobian, bool all_rows = false) {
    for (Character& ch : chars_) {
      ch.values = ch.layout.apply(ch.m1, x.segment(ch.x_offset, ch.layout.unknown_count()));
      for (int f = 0; f < frames_; ++f)
        motion::forward_kinematics(*ch.skeleton[static_cast<std::size_t>(f)], ch.values.row(f),
                                   std::span(ch.world.data() + static_cast<std::size_t>(f) * ch.joints,
                                             static_cast<std::size_t>(ch.joints)));
    }
    for (SampleInfo& s : samples_) evaluate_sample(s, jacobian, all_rows);
  }

  // F(x) of the last evaluation at x.
  double objective(const Eigen::VectorXd& x) const {
    double f = 0;
    for (int i = 0; i < rows_total_; ++i) {
      double r = r_[i];
      if (inequality_[static_cast<std::size_t>(i)] && r > 0) r = 0;
      const double w = weight_[static_cast<std::size_t>(i)];
      f += w * w * r * r;
    }
    double reg = 0;
    for (const Character& ch : chars_)
      for (int c = 0; c < ch.channels; ++c) {
        if (!ch.free[static_cast<std::size_t>(c)]) continue;
        reg += ch.sensitivity[c] *
               x.segment(ch.x_offset + ch.layout.offset(c), ch.layout.control_count(c)).squaredNorm();
      }
    return 0.5 * f + 0.5 * options_.epsilon * reg;
  }

  // Required rows only (soft rows are never waited for).
  bool within_tolerance() const {
    for (int i = 0; i < rows_total_; ++i) {
      if (soft_[static_cast<std::size_t>(i)]) continue;
      const double r = r_[i];
      if (inequality_[static_cast<std::size_t>(i)]) {
        if (-r > options_.inequality_tolerance) return false;
      } else if (std::abs(r) > options_.equality_tolerance) {
        return false;
      }
    }
    return true;
  }

  // The Gauss-Newton step at the last evaluation (made with jacobian = true); returns the
  // directional derivative of F along it.
  // `lambda` adds lambda M to the matrix only (Levenberg-Marquardt: shorter, better-aimed steps
  // where the linearisation is poor), not to the objective.
  double step(const Eigen::VectorXd& x, Eigen::VectorXd& dx, double lambda) {
    assemble(x);
    for (int i = 0; i < band_.size(); ++i)
      band_.at(i, i) += lambda * band_sensitivity_[static_cast<std::size_t>(i)];
    save_matrix();
    return solve_step(x, dx, lambda);
  }

  // The step again after hold_blocking added rows and evaluate(x, true) gave their derivatives,
  // same x and lambda: the last step's matrix plus the new rows (satisfied at x, so they add to
  // the matrix only), refactored, without assembling everything again. A full step when a new
  // row touches a channel the band does not hold.
  double step_with_held(const Eigen::VectorXd& x, Eigen::VectorXd& dx, double lambda) {
    if (!saved_valid_) return step(x, dx, lambda);
    band_ = saved_band_;
    grad_ = saved_grad_;
    if (static_cast<int>(local_column_.size()) != band_.size())
      local_column_.assign(static_cast<std::size_t>(band_.size()), -1);
    auto fresh = [&](int row) {
      const auto k = static_cast<std::size_t>(row);
      return held_[k] && !held_at_save_[k] && active_[k];
    };
    for (const SampleInfo& s : samples_) {
      bool any = false;
      for (int r = 0; r < s.rows && !any; ++r) any = fresh(s.row_offset + r);
      if (any && !add_rows(s, fresh)) return step(x, dx, lambda);
    }
    save_matrix();
    return solve_step(x, dx, lambda);
  }

  void save_matrix() {
    saved_band_ = band_;
    saved_grad_ = grad_;
    held_at_save_ = held_;
    saved_valid_ = true;
  }

  // Factors the band and solves; channels outside it get eps M dx = -eps M x. Returns the
  // directional derivative of F along dx.
  double solve_step(const Eigen::VectorXd& x, Eigen::VectorXd& dx, double lambda) {
    dx.setZero(x_size_);
    double slope = 0;
    // Free channels no active row touches: eps M dx = -eps M x.
    for (const Character& ch : chars_)
      for (int c = 0; c < ch.channels; ++c) {
        if (!ch.free[static_cast<std::size_t>(c)] || band_channel_[static_cast<std::size_t>(ch.c_offset + c)])
          continue;
        const int o = ch.x_offset + ch.layout.offset(c);
        const int n = ch.layout.control_count(c);
        dx.segment(o, n) = -options_.epsilon / (options_.epsilon + lambda) * x.segment(o, n);
        slope += options_.epsilon * ch.sensitivity[c] * x.segment(o, n).dot(dx.segment(o, n));
      }
    if (band_.size() > 0) {
      if (!band_.factor())
        throw std::runtime_error(
            "spacetime: the normal matrix is not positive definite (epsilon too small?)");
      Eigen::VectorXd y = -grad_;
      band_.solve(y);
      for (int i = 0; i < band_.size(); ++i) {
        dx[band_global_[static_cast<std::size_t>(i)]] = y[i];
        slope += grad_[i] * y[i];
      }
    }
    return slope;
  }

  int bandwidth() const { return band_.bandwidth(); }
  // Working set of a blocked step: inequality rows satisfied at x (r_at_x) that the trial point
  // (the last evaluation) violates beyond `tolerance` join the active set, so the next step
  // resists crossing them instead of the line search cutting every step short. Returns how many.
  int hold_blocking(const Eigen::VectorXd& r_at_x, double tolerance) {
    int n = 0;
    for (int i = 0; i < rows_total_; ++i) {
      const std::size_t k = static_cast<std::size_t>(i);
      if (inequality_[k] && !held_[k] && r_at_x[i] >= 0 && r_[i] < -tolerance) {
        held_[k] = 1;
        ++n;
      }
    }
    return n;
  }
  // Held rows that the iterate left well inside (r > margin) leave the working set.
  void release_held(double margin) {
    for (int i = 0; i < rows_total_; ++i)
      if (held_[static_cast<std::size_t>(i)] && r_[i] > margin) held_[static_cast<std::size_t>(i)] = 0;
  }
  double worst_violation() const {  // of required rows
    double w = 0;
    for (int i = 0; i < rows_total_; ++i)
      if (!soft_[static_cast<std::size_t>(i)])
        w = std::max(w, inequality_[static_cast<std::size_t>(i)] ? -r_[i] : std::abs(r_[i]));
    return w;
  }
  bool has_soft() const { return has_soft_; }
  int active_count() const {
    int n = 0;
    for (int i = 0; i < rows_total_; ++i) n += row_active(i) ? 1 : 0;
    return n;
  }
  int band_size() const { return band_.size(); }

  // Dense d(w r)/dx of every row at the last evaluation (made with all_rows = true).
  Eigen::MatrixXd dense_jacobian() const {
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(rows_total_, x_size_);
    for (const SampleInfo& s : samples_) {
      const double w = set_.constraints[static_cast<std::size_t>(s.constraint)].weight;
      for (const Piece& p : s.pieces) {
        const Character& ch = chars_[static_cast<std::size_t>(p.character)];
        const Eigen::Map<const Eigen::MatrixXd> G(g_.data() + p.g_offset, s.rows,
                                                  static_cast<Eigen::Index>(p.channels.size()));
        for (std::size_t i = 0; i < p.channels.size(); ++i) {
          const int c = p.channels[i];
          const motion::BasisAt& b = ch.layout.basis(c, p.frame);
          for (int q = 0; q < 4; ++q)
            J.col(ch.x_offset + ch.layout.unknown(c, b.first + q)).segment(s.row_offset, s.rows) +=
                w * b.weight[static_cast<std::size_t>(q)] * G.col(static_cast<Eigen::Index>(i));
        }
      }
    }
    return J;
  }

  Eigen::VectorXd weighted_residual() const {
    Eigen::VectorXd r = r_;
    for (int i = 0; i < rows_total_; ++i) r[i] *= weight_[static_cast<std::size_t>(i)];
    return r;
  }

 private:
  const std::vector<int>& chain(Character& ch, int joint) {
    std::vector<int>& c = ch.chain[static_cast<std::size_t>(joint)];
    if (c.empty()) c = motion::influencing_channels(*ch.base, joint);
    return c;
  }

  // Every sample of every constraint: the (character, frame) pieces it reads and their free
  // channels (sample_pieces), where its points' chains and its values sit among those channels
  // (locate_channels), its rows (count_rows), its group (file_sample); then the buffers sized.
  void build_samples() {
    std::map<std::pair<int, int>, int> group_of;
    for (std::size_t ci = 0; ci < set_.constraints.size(); ++ci)
      for (std::size_t si = 0; si < set_.constraints[ci].samples.size(); ++si) {
        SampleInfo s = sample_pieces(static_cast<int>(ci), static_cast<int>(si));
        locate_channels(s);
        count_rows(s);
        file_sample(std::move(s), group_of);
      }
    size_buffers();
  }

  SampleInfo sample_pieces(int ci, int si) {
    const Constraint& con = set_.constraints[static_cast<std::size_t>(ci)];
    const Sample& sample = con.samples[static_cast<std::size_t>(si)];
    SampleInfo s;
    s.constraint = ci;
    s.sample = si;
    s.row_offset = rows_total_;
    s.rows = kinds_[static_cast<std::size_t>(ci)].rows;
    auto piece_of = [&](int character, int frame) {
      for (std::size_t i = 0; i < s.pieces.size(); ++i)
        if (s.pieces[i].character == character && s.pieces[i].frame == frame) return static_cast<int>(i);
      s.pieces.push_back({character, frame, {}, 0});
      return static_cast<int>(s.pieces.size() - 1);
    };
    const std::size_t np = con.points.size();
    for (std::size_t p = 0; p < np; ++p) {
      const PointRef& pr = con.points[p];
      Character& ch = chars_[static_cast<std::size_t>(pr.character)];
      const int piece = piece_of(pr.character, sample.frames[p]);
      s.point_piece.push_back(piece);
      for (int c : chain(ch, pr.joint))
        if (ch.free[static_cast<std::size_t>(c)])
          s.pieces[static_cast<std::size_t>(piece)].channels.push_back(c);
    }
    for (std::size_t v = 0; v < con.channels.size(); ++v) {
      const ChannelRef& cr = con.channels[v];
      const int piece = piece_of(cr.character, sample.frames[np + v]);
      s.value_piece.push_back(piece);
      if (chars_[static_cast<std::size_t>(cr.character)].free[static_cast<std::size_t>(cr.channel)])
        s.pieces[static_cast<std::size_t>(piece)].channels.push_back(cr.channel);
    }
    for (Piece& piece : s.pieces) {
      std::sort(piece.channels.begin(), piece.channels.end());
      piece.channels.erase(std::unique(piece.channels.begin(), piece.channels.end()), piece.channels.end());
      piece.g_offset = g_size_;
      g_size_ += static_cast<std::size_t>(s.rows) * piece.channels.size();
    }
    return s;
  }

  void locate_channels(SampleInfo& s) {
    const Constraint& con = set_.constraints[static_cast<std::size_t>(s.constraint)];
    const std::size_t np = con.points.size();
    auto position = [](const Piece& piece, int c) {
      auto it = std::lower_bound(piece.channels.begin(), piece.channels.end(), c);
      return it != piece.channels.end() && *it == c ? static_cast<int>(it - piece.channels.begin()) : -1;
    };
    for (std::size_t p = 0; p < np; ++p) {
      const PointRef& pr = con.points[p];
      const Piece& piece = s.pieces[static_cast<std::size_t>(s.point_piece[p])];
      std::vector<int> pos;
      for (int c : chain(chars_[static_cast<std::size_t>(pr.character)], pr.joint))
        pos.push_back(position(piece, c));
      s.point_pos.push_back(std::move(pos));
    }
    for (std::size_t v = 0; v < con.channels.size(); ++v)
      s.value_pos.push_back(
          position(s.pieces[static_cast<std::size_t>(s.value_piece[v])], con.channels[v].channel));
  }

  void count_rows(const SampleInfo& s) {
    const Constraint& con = set_.constraints[static_cast<std::size_t>(s.constraint)];
    const KindInfo& kind = kinds_[static_cast<std::size_t>(s.constraint)];
    for (int r = 0; r < s.rows; ++r) {
      inequality_.push_back(kind.inequality[static_cast<std::size_t>(r)]);
      soft_.push_back(con.soft ? 1 : 0);
      has_soft_ = has_soft_ || con.soft;
      weight_.push_back(con.weight);
    }
    rows_total_ += s.rows;
    max_rows_ = std::max(max_rows_, s.rows);
    max_points_ = std::max(max_points_, static_cast<int>(con.points.size()));
    max_values_ = std::max(max_values_, static_cast<int>(con.channels.size()));
  }

  // A single-piece sample joins the group of its (character, frame), others the multi-frame list.
  void file_sample(SampleInfo s, std::map<std::pair<int, int>, int>& group_of) {
    const int index = static_cast<int>(samples_.size());
    if (s.pieces.size() == 1) {
      const auto key = std::make_pair(s.pieces[0].character, s.pieces[0].frame);
      auto it = group_of.find(key);
      if (it == group_of.end()) {
        it = group_of.emplace(key, static_cast<int>(groups_.size())).first;
        groups_.push_back({key.first, key.second, {}, {}});
      }
      groups_[static_cast<std::size_t>(it->second)].samples.push_back(index);
    } else if (!s.pieces.empty()) {
      multi_.push_back(index);
    }
    samples_.push_back(std::move(s));
  }

  void size_buffers() {
    r_ = Eigen::VectorXd::Zero(rows_total_);
    g_.assign(g_size_, 0.0);
    points_.resize(static_cast<std::size_t>(max_points_));
    values_.resize(static_cast<std::size_t>(max_values_));
    d_points_ = Eigen::MatrixXd::Zero(max_rows_, 3 * max_points_);
    d_values_ = Eigen::MatrixXd::Zero(max_rows_, max_values_);
    int max_channels = 0;
    for (const Character& ch : chars_) max_channels = std::max(max_channels, ch.channels);
    jac_.resize(3, max_channels);
    active_.assign(static_cast<std::size_t>(rows_total_), 0);
    held_.assign(static_cast<std::size_t>(rows_total_), 0);
    band_channel_.assign(static_cast<std::size_t>(channel_total_), 0);  // indexed c_offset + c
  }

  bool row_active(int row) const {
    const std::size_t i = static_cast<std::size_t>(row);
    return !inequality_[i] || r_[row] < 0 || held_[i];
  }

  void evaluate_sample(SampleInfo& s, bool jacobian, bool all_rows) {
    const Constraint& con = set_.constraints[static_cast<std::size_t>(s.constraint)];
    const Sample& sample = con.samples[static_cast<std::size_t>(s.sample)];
    const KindInfo& kind = kinds_[static_cast<std::size_t>(s.constraint)];
    const std::size_t np = con.points.size(), nv = con.channels.size();
    for (std::size_t p = 0; p < np; ++p) {
      const PointRef pr = point_at(con, sample, p);
      const Character& ch = chars_[static_cast<std::size_t>(pr.character)];
      points_[p] = ch.world[static_cast<std::size_t>(sample.frames[p]) * ch.joints + pr.joint] * pr.local;
    }
    for (std::size_t v = 0; v < nv; ++v) {
      const ChannelRef& cr = con.channels[v];
      values_[v] = chars_[static_cast<std::size_t>(cr.character)].values(sample.frames[np + v], cr.channel);
    }
    const std::vector<double>& params = sample.params.empty() ? con.params : sample.params;
    auto dp = d_points_.topLeftCorner(s.rows, static_cast<Eigen::Index>(3 * np));
    auto dv = d_values_.topLeftCorner(s.rows, static_cast<Eigen::Index>(nv));
    dp.setZero();
    dv.setZero();
    kind.kind->evaluate(con, params, std::span<const Eigen::Vector3d>(points_.data(), np),
                        std::span<const double>(values_.data(), nv), r_.segment(s.row_offset, s.rows), dp,
                        dv);
    if (!jacobian) return;
    bool any = false;
    for (int r = 0; r < s.rows; ++r) {
      const bool a = all_rows || row_active(s.row_offset + r);
      active_[static_cast<std::size_t>(s.row_offset + r)] = a;
      any = any || a;
    }
    if (!any) return;
    for (const Piece& piece : s.pieces)
      std::fill_n(g_.data() + piece.g_offset, static_cast<std::size_t>(s.rows) * piece.channels.size(), 0.0);
    for (std::size_t p = 0; p < np; ++p) {
      const PointRef pr = point_at(con, sample, p);
      Character& ch = chars_[static_cast<std::size_t>(pr.character)];
      const Piece& piece = s.pieces[static_cast<std::size_t>(s.point_piece[p])];
      if (piece.channels.empty()) continue;
      const int f = sample.frames[p];
      auto J = jac_.leftCols(ch.channels);
      motion::point_jacobian(
          *ch.skeleton[static_cast<std::size_t>(f)], ch.values.row(f),
          std::span<const Eigen::Isometry3d>(ch.world.data() + static_cast<std::size_t>(f) * ch.joints,
                                             static_cast<std::size_t>(ch.joints)),
          pr.joint, pr.local, J);
      Eigen::Map<Eigen::MatrixXd> G(g_.data() + piece.g_offset, s.rows,
                                    static_cast<Eigen::Index>(piece.channels.size()));
      const std::vector<int>& chain_channels = ch.chain[static_cast<std::size_t>(pr.joint)];
      const std::vector<int>& pos = s.point_pos[p];
      for (std::size_t k = 0; k < pos.size(); ++k) {
        if (pos[k] < 0) continue;
        const Eigen::Vector3d col = J.col(chain_channels[k]);
        for (int r = 0; r < s.rows; ++r)
          G(r, pos[k]) += dp.row(r).segment<3>(static_cast<Eigen::Index>(3 * p)).dot(col);
      }
    }
    for (std::size_t v = 0; v < nv; ++v) {
      if (s.value_pos[v] < 0) continue;
      const Piece& piece = s.pieces[static_cast<std::size_t>(s.value_piece[v])];
      Eigen::Map<Eigen::MatrixXd> G(g_.data() + piece.g_offset, s.rows,
                                    static_cast<Eigen::Index>(piece.channels.size()));
      G.col(s.value_pos[v]) += dv.col(static_cast<Eigen::Index>(v));
    }
  }

  // The residual a row contributes to the gradient: a held, satisfied inequality row none (it
  // only resists moving along its Jacobian), so the gradient stays that of F.
  double rho(int row) const {
    const double r = r_[row];
    return inequality_[static_cast<std::size_t>(row)] && r > 0 ? 0.0 : r;
  }

  bool sample_active(const SampleInfo& s) const {
    for (int r = 0; r < s.rows; ++r)
      if (active_[static_cast<std::size_t>(s.row_offset + r)]) return true;
    return false;
  }

  int band_index(const Character& ch, int c, int control) const {
    return band_index_[static_cast<std::size_t>(ch.x_offset + ch.layout.unknown(c, control))];
  }

  // Adds rows of one sample (those `take` selects, by row index) to the band and the gradient:
  // the rows over the union of the controls they touch (a control weighed by two frames' bases
  // counted once), their small dense normal block formed at once, then scattered. False, adding
  // nothing, when a row touches a control the band does not hold.
  template <class Take>
  bool add_rows(const SampleInfo& s, Take take) {
    const double w = set_.constraints[static_cast<std::size_t>(s.constraint)].weight;
    int taken = 0;
    for (int r = 0; r < s.rows; ++r) taken += take(s.row_offset + r) ? 1 : 0;
    if (taken == 0) return true;
    columns_.clear();
    bool inside = true;
    for (const Piece& p : s.pieces) {
      const Character& ch = chars_[static_cast<std::size_t>(p.character)];
      for (int c : p.channels) {
        const motion::BasisAt& basis = ch.layout.basis(c, p.frame);
        for (int q = 0; q < 4; ++q) {
          const int u = band_index(ch, c, basis.first + q);
          if (u < 0) {
            inside = false;
            continue;
          }
          if (local_column_[static_cast<std::size_t>(u)] < 0) {
            local_column_[static_cast<std::size_t>(u)] = static_cast<int>(columns_.size());
            columns_.push_back(u);
          }
        }
      }
    }
    if (!inside) {
      for (int u : columns_) local_column_[static_cast<std::size_t>(u)] = -1;
      return false;
    }
    rows_dense_.setZero(taken, static_cast<Eigen::Index>(columns_.size()));
    rho_weighted_.resize(taken);
    int k = 0;
    for (int r = 0; r < s.rows; ++r) {
      if (!take(s.row_offset + r)) continue;
      for (const Piece& p : s.pieces) {
        const Character& ch = chars_[static_cast<std::size_t>(p.character)];
        const Eigen::Map<const Eigen::MatrixXd> G(g_.data() + p.g_offset, s.rows,
                                                  static_cast<Eigen::Index>(p.channels.size()));
        for (std::size_t i = 0; i < p.channels.size(); ++i) {
          const double gi = w * G(r, static_cast<Eigen::Index>(i));
          if (gi == 0) continue;
          const motion::BasisAt& basis = ch.layout.basis(p.channels[i], p.frame);
          for (int q = 0; q < 4; ++q)
            rows_dense_(
                k, local_column_[static_cast<std::size_t>(band_index(ch, p.channels[i], basis.first + q))]) +=
                gi * basis.weight[static_cast<std::size_t>(q)];
        }
      }
      rho_weighted_[k++] = w * rho(s.row_offset + r);
    }
    // The block's lower triangle, a few rows at a time (GEMM's set-up costs more at this size).
    for (std::size_t i = 0; i < columns_.size(); ++i) {
      const auto ci = static_cast<Eigen::Index>(i);
      const int u = columns_[i];
      grad_[u] += rows_dense_.col(ci).dot(rho_weighted_);
      for (std::size_t j = 0; j < columns_.size(); ++j) {
        const int v = columns_[j];
        if (u >= v) band_.at(u, v) += rows_dense_.col(ci).dot(rows_dense_.col(static_cast<Eigen::Index>(j)));
      }
    }
    for (int u : columns_) local_column_[static_cast<std::size_t>(u)] = -1;
    return true;
  }

  // Normal equations of the active rows over the controls of the channels they touch: the
  // channels (touched_channels), their controls in control-major order (order_controls), the
  // band they need (needed_bandwidth), the per-frame blocks (frame_block, spread_frame_block),
  // the samples reading several frames (add_rows), the damping eps M (add_damping).
  void assemble(const Eigen::VectorXd& x) {
    std::vector<char> touched = touched_channels();
    // Rebuilt only when the set changes.
    if (touched != band_channel_ || band_index_.empty()) order_controls(std::move(touched));
    const int n = static_cast<int>(band_global_.size());
    band_.reset(n, std::min(needed_bandwidth(), std::max(0, n - 1)));
    grad_.setZero(n);
    for (const Group& g : groups_) {
      if (g.touched.empty()) continue;
      Character& ch = chars_[static_cast<std::size_t>(g.character)];
      frame_block(g, ch);
      spread_frame_block(g, ch);
    }
    // Samples reading several frames or both characters, row blocks at once.
    if (static_cast<int>(local_column_.size()) != n) local_column_.assign(static_cast<std::size_t>(n), -1);
    for (int si : multi_) {
      const SampleInfo& s = samples_[static_cast<std::size_t>(si)];
      if (sample_active(s)) add_rows(s, [&](int row) { return active_[static_cast<std::size_t>(row)] != 0; });
    }
    add_damping(x);
  }

  // The channels (c_offset + c) the active rows touch; each group's own in Group::touched.
  std::vector<char> touched_channels() {
    std::vector<char> touched(band_channel_.size(), 0);
    for (std::size_t gi = 0; gi < groups_.size(); ++gi) {
      Group& g = groups_[gi];
      g.touched.clear();
      Character& ch = chars_[static_cast<std::size_t>(g.character)];
      for (int si : g.samples) {
        const SampleInfo& s = samples_[static_cast<std::size_t>(si)];
        if (!sample_active(s)) continue;
        for (int c : s.pieces[0].channels) {
          int& stamp = ch.stamp[static_cast<std::size_t>(c)];
          if (stamp == static_cast<int>(gi)) continue;
          stamp = static_cast<int>(gi);
          g.touched.push_back(c);
          touched[static_cast<std::size_t>(ch.c_offset + c)] = 1;
        }
      }
    }
    for (Character& ch : chars_) std::fill(ch.stamp.begin(), ch.stamp.end(), -1);
    for (int si : multi_) {
      const SampleInfo& s = samples_[static_cast<std::size_t>(si)];
      if (!sample_active(s)) continue;
      for (const Piece& p : s.pieces)
        for (int c : p.channels)
          touched[static_cast<std::size_t>(chars_[static_cast<std::size_t>(p.character)].c_offset + c)] = 1;
    }
    return touched;
  }

  // The unknowns of the touched channels in control-major order (every channel of one control
  // time together): band_index_, band_global_ and band_sensitivity_.
  void order_controls(std::vector<char> touched) {
    band_channel_ = std::move(touched);
    struct Item {
      int frame, character, channel, control;
    };
    std::vector<Item> items;
    for (std::size_t k = 0; k < chars_.size(); ++k) {
      const Character& ch = chars_[k];
      for (int c = 0; c < ch.channels; ++c) {
        if (!band_channel_[static_cast<std::size_t>(ch.c_offset + c)]) continue;
        for (int j = 0; j < ch.layout.control_count(c); ++j)
          items.push_back({ch.layout.control_frame(c, j), static_cast<int>(k), c, j});
      }
    }
    std::sort(items.begin(), items.end(), [](const Item& a, const Item& b) {
      if (a.frame != b.frame) return a.frame < b.frame;
      if (a.character != b.character) return a.character < b.character;
      return a.channel < b.channel;
    });
    band_index_.assign(static_cast<std::size_t>(x_size_), -1);
    band_global_.clear();
    band_sensitivity_.clear();
    for (const Item& it : items) {
      const Character& ch = chars_[static_cast<std::size_t>(it.character)];
      const int global = ch.x_offset + ch.layout.unknown(it.channel, it.control);
      band_index_[static_cast<std::size_t>(global)] = static_cast<int>(band_global_.size());
      band_global_.push_back(global);
      band_sensitivity_.push_back(ch.sensitivity[it.channel]);
    }
  }

  // Bandwidth: the widest index span of one group or one multi-frame row.
  int needed_bandwidth() const {
    int b = 0;
    for (const Group& g : groups_) {
      if (g.touched.empty()) continue;
      const Character& ch = chars_[static_cast<std::size_t>(g.character)];
      int lo = INT32_MAX, hi = -1;
      for (int c : g.touched) {
        const motion::BasisAt& basis = ch.layout.basis(c, g.frame);
        lo = std::min(lo, band_index(ch, c, basis.first));
        hi = std::max(hi, band_index(ch, c, basis.first + 3));
      }
      b = std::max(b, hi - lo);
    }
    for (int si : multi_) {
      const SampleInfo& s = samples_[static_cast<std::size_t>(si)];
      if (!sample_active(s)) continue;
      int lo = INT32_MAX, hi = -1;
      for (const Piece& p : s.pieces) {
        const Character& ch = chars_[static_cast<std::size_t>(p.character)];
        for (int c : p.channels) {
          const motion::BasisAt& basis = ch.layout.basis(c, p.frame);
          lo = std::min(lo, band_index(ch, c, basis.first));
          hi = std::max(hi, band_index(ch, c, basis.first + 3));
        }
      }
      if (hi >= 0) b = std::max(b, hi - lo);
    }
    return b;
  }

  // Rows of one (character, frame) in channel space: J^T J and J^T rho into the character's
  // normal and gradient scratch.
  void frame_block(const Group& g, Character& ch) {
    for (int si : g.samples) {
      const SampleInfo& s = samples_[static_cast<std::size_t>(si)];
      if (!sample_active(s)) continue;
      const Piece& piece = s.pieces[0];
      const double w = set_.constraints[static_cast<std::size_t>(s.constraint)].weight;
      const Eigen::Map<const Eigen::MatrixXd> G(g_.data() + piece.g_offset, s.rows,
                                                static_cast<Eigen::Index>(piece.channels.size()));
      const int m = static_cast<int>(piece.channels.size());
      for (int r = 0; r < s.rows; ++r) {
        if (!active_[static_cast<std::size_t>(s.row_offset + r)]) continue;
        const double wr = w * w * rho(s.row_offset + r);
        for (int i = 0; i < m; ++i) {
          const int ci = piece.channels[static_cast<std::size_t>(i)];
          const double gi = G(r, i);
          if (gi == 0) continue;
          ch.gradient[ci] += gi * wr;
          const double wgi = w * w * gi;
          for (int k = 0; k < m; ++k)
            ch.normal(ci, piece.channels[static_cast<std::size_t>(k)]) += wgi * G(r, k);
        }
      }
    }
  }

  // The frame's block spread over the 4 controls per channel that frame weighs, and the scratch
  // cleared.
  void spread_frame_block(const Group& g, Character& ch) {
    int ia[4], ib[4];
    for (int a : g.touched) {
      const motion::BasisAt& ba = ch.layout.basis(a, g.frame);
      for (int p = 0; p < 4; ++p) {
        ia[p] = band_index(ch, a, ba.first + p);
        grad_[ia[p]] += ba.weight[static_cast<std::size_t>(p)] * ch.gradient[a];
      }
      for (int bc : g.touched) {
        const double nab = ch.normal(a, bc);
        if (nab == 0) continue;
        const motion::BasisAt& bb = ch.layout.basis(bc, g.frame);
        for (int q = 0; q < 4; ++q) ib[q] = band_index(ch, bc, bb.first + q);
        for (int p = 0; p < 4; ++p) {
          const double wp = ba.weight[static_cast<std::size_t>(p)] * nab;
          for (int q = 0; q < 4; ++q)
            if (ia[p] >= ib[q]) band_.at(ia[p], ib[q]) += wp * bb.weight[static_cast<std::size_t>(q)];
        }
      }
    }
    for (int a : g.touched) {
      ch.gradient[a] = 0;
      for (int bc : g.touched) ch.normal(a, bc) = 0;
    }
  }

  // Damping: eps M on the diagonal, eps M x in the gradient.
  void add_damping(const Eigen::VectorXd& x) {
    const int n = static_cast<int>(band_global_.size());
    for (int i = 0; i < n; ++i) {
      const double em = options_.epsilon * band_sensitivity_[static_cast<std::size_t>(i)];
      band_.at(i, i) += em;
      grad_[i] += em * x[band_global_[static_cast<std::size_t>(i)]];
    }
  }

  std::vector<Character>& chars_;
  const ConstraintSet& set_;
  const std::vector<KindInfo>& kinds_;
  const SpacetimeOptions& options_;
  int frames_ = 0;
  int x_size_ = 0;
  int channel_total_ = 0;
  int rows_total_ = 0;
  int max_rows_ = 0, max_points_ = 0, max_values_ = 0;
  std::vector<SampleInfo> samples_;
  std::vector<Group> groups_;
  std::vector<int> multi_;
  std::vector<char> inequality_;
  std::vector<char> soft_;  // rows of soft constraints: in F, never waited for
  bool has_soft_ = false;
  std::vector<double> weight_;
  std::vector<char> active_;
  std::vector<char> held_;  // satisfied inequality rows kept in the working set (see hold_blocking)
  Eigen::VectorXd r_;
  std::vector<double> g_;
  std::size_t g_size_ = 0;
  std::vector<Eigen::Vector3d> points_;
  std::vector<double> values_;
  Eigen::MatrixXd d_points_, d_values_;
  Eigen::Matrix<double, 3, Eigen::Dynamic> jac_;
  // Band system.
  std::vector<char> band_channel_;
  std::vector<int> band_index_;   // global unknown -> band index, -1 outside the band
  std::vector<int> band_global_;  // band index -> global unknown
  std::vector<double> band_sensitivity_;
  std::vector<int> local_column_;  // band index -> column of the sample being added (-1), add_rows
  std::vector<int> columns_;       // add_rows: band indexes the sample touches, in first-seen order
  Eigen::MatrixXd rows_dense_;     // add_rows: taken rows x columns, weighted
  Eigen::VectorXd rho_weighted_;
  numerics::BandedCholesky saved_band_;  // the last step's matrix before factoring (lambda included)
  Eigen::VectorXd saved_grad_;
  std::vector<char> held_at_save_;  // held_ when it was assembled
  bool saved_valid_ = false;
  numerics::BandedCholesky band_;
  Eigen::VectorXd grad_;
};

// --- validation -------------------------------------------------------------------------------

// Each character against character 0 (frames, rate) and its own skeleton (key spacings, frozen
// flags, per-frame skeletons).
void check_characters(const SpacetimeProblem& problem) {
  const int frames = problem.characters[0].initial.frame_count();
  for (std::size_t k = 0; k < problem.characters.size(); ++k) {
    const CharacterProblem& cp = problem.characters[k];
    const std::string who = "spacetime: character " + std::to_string(k) + ": ";
    if (!cp.initial.skeleton) throw std::invalid_argument(who + "initial motion has no skeleton");
    try {
      cp.initial.check();
    } catch (const std::exception& e) {
      throw std::invalid_argument(who + e.what());
    }
    const Skeleton& s = *cp.initial.skeleton;
    if (cp.initial.frame_count() < 1) throw std::invalid_argument(who + "initial motion has no frames");
    if (cp.initial.frame_count() != frames)
      throw std::invalid_argument(who + std::to_string(cp.initial.frame_count()) +
                                  " frames, character 0 has " + std::to_string(frames) +
                                  " (both must have the same frames)");
    if (std::abs(cp.initial.fps - problem.characters[0].initial.fps) > 1e-9)
      throw std::invalid_argument(who + "frame rate differs from character 0's");
    if (!cp.frames_per_key.empty()) {
      if (static_cast<int>(cp.frames_per_key.size()) != s.channel_count())
        throw std::invalid_argument(who + std::to_string(cp.frames_per_key.size()) + " key spacings for " +
                                    std::to_string(s.channel_count()) + " channels");
      for (int k2 : cp.frames_per_key)
        if (k2 < 1)
          throw std::invalid_argument(who + "key spacing " + std::to_string(k2) + " (expected >= 1 frame)");
    }
    if (!cp.frozen.empty() && static_cast<int>(cp.frozen.size()) != s.channel_count())
      throw std::invalid_argument(who + std::to_string(cp.frozen.size()) + " frozen flags for " +
                                  std::to_string(s.channel_count()) + " channels");
    if (!cp.skeleton_per_frame.empty()) {
      if (static_cast<int>(cp.skeleton_per_frame.size()) != frames)
        throw std::invalid_argument(who + std::to_string(cp.skeleton_per_frame.size()) +
                                    " per-frame skeletons for " + std::to_string(frames) + " frames");
      for (const auto& sk : cp.skeleton_per_frame)
        if (!sk || sk->joint_count() != s.joint_count() || sk->channel_count() != s.channel_count())
          throw std::invalid_argument(who + "a per-frame skeleton differs in structure from the motion's");
    }
  }
}

// One constraint against its kind and the problem's characters; its rows.
KindInfo check_constraint(const SpacetimeProblem& problem, const Constraint& c, int frames) {
  KindInfo info;
  info.kind = problem.kinds(c.kind);
  if (info.kind == nullptr)
    throw std::invalid_argument(label_of(c) + ": unknown constraint kind '" + c.kind + "'");
  info.kind->check(c);
  info.rows = info.kind->rows(c);
  if (info.rows < 0) throw std::invalid_argument(label_of(c) + ": kind reports a negative row count");
  for (int r = 0; r < info.rows; ++r) info.inequality.push_back(info.kind->is_inequality(c, r) ? 1 : 0);
  if (!(c.weight > 0) || !std::isfinite(c.weight))
    throw std::invalid_argument(label_of(c) + ": weight " + std::to_string(c.weight) + " (expected > 0)");
  const int nchar = static_cast<int>(problem.characters.size());
  for (const PointRef& p : c.points) {
    if (p.character < 0 || p.character >= nchar)
      throw std::invalid_argument(label_of(c) + ": refers to character " + std::to_string(p.character) +
                                  " but the problem has " + std::to_string(nchar));
    const Skeleton& s = *problem.characters[static_cast<std::size_t>(p.character)].initial.skeleton;
    if (p.joint < 0 || p.joint >= s.joint_count())
      throw std::invalid_argument(label_of(c) + ": joint " + std::to_string(p.joint) +
                                  " out of range (skeleton has " + std::to_string(s.joint_count()) +
                                  " joints)");
    if (!p.local.allFinite()) throw std::invalid_argument(label_of(c) + ": point offset is not finite");
  }
  if (const std::string problem = sample_locals_problem(c); !problem.empty())
    throw std::invalid_argument(label_of(c) + ": " + problem);
  for (const ChannelRef& ch : c.channels) {
    if (ch.character < 0 || ch.character >= nchar)
      throw std::invalid_argument(label_of(c) + ": refers to character " + std::to_string(ch.character) +
                                  " but the problem has " + std::to_string(nchar));
    const Skeleton& s = *problem.characters[static_cast<std::size_t>(ch.character)].initial.skeleton;
    if (ch.channel < 0 || ch.channel >= s.channel_count())
      throw std::invalid_argument(label_of(c) + ": channel " + std::to_string(ch.channel) +
                                  " out of range (" + std::to_string(s.channel_count()) + " channels)");
  }
  const std::size_t want = c.points.size() + c.channels.size();
  for (const Sample& sm : c.samples) {
    if (sm.frames.size() != want)
      throw std::invalid_argument(label_of(c) + ": a sample has " + std::to_string(sm.frames.size()) +
                                  " frames, expected " + std::to_string(want) +
                                  " (one per point and channel)");
    for (int f : sm.frames)
      if (f < 0 || f >= frames)
        throw std::invalid_argument(label_of(c) + ": frame " + std::to_string(f) + " outside the clip [0, " +
                                    std::to_string(frames - 1) + "]");
  }
  return info;
}

std::vector<KindInfo> check_problem(const SpacetimeProblem& problem) {
  problem.options.validate();
  if (problem.characters.empty()) throw std::invalid_argument("spacetime: no characters");
  if (problem.characters.size() > 2)
    throw std::invalid_argument("spacetime: " + std::to_string(problem.characters.size()) +
                                " characters (at most 2 are supported)");
  if (problem.constraints == nullptr) throw std::invalid_argument("spacetime: no constraint set");
  if (!problem.kinds) throw std::invalid_argument("spacetime: no constraint kind lookup");
  check_characters(problem);
  const int frames = problem.characters[0].initial.frame_count();
  std::vector<KindInfo> kinds;
  for (const Constraint& c : problem.constraints->constraints)
    kinds.push_back(check_constraint(problem, c, frames));
  return kinds;
}

std::vector<Character> make_characters(const SpacetimeProblem& problem, const std::vector<FrameMatrix>& m1,
                                       const std::vector<std::vector<int>>& spacing) {
  std::vector<Character> chars;
  for (std::size_t k = 0; k < problem.characters.size(); ++k) {
    const CharacterProblem& cp = problem.characters[k];
    Character ch;
    ch.base = cp.initial.skeleton.get();
    ch.channels = ch.base->channel_count();
    ch.joints = ch.base->joint_count();
    ch.m1 = m1[k];
    const int frames = static_cast<int>(ch.m1.rows());
    for (int f = 0; f < frames; ++f)
      ch.skeleton.push_back(
          cp.skeleton_per_frame.empty() ? ch.base : cp.skeleton_per_frame[static_cast<std::size_t>(f)].get());
    ch.layout = DisplacementLayout(frames, spacing[k]);
    ch.free.assign(static_cast<std::size_t>(ch.channels), true);
    for (std::size_t c = 0; c < cp.frozen.size(); ++c) ch.free[c] = !cp.frozen[c];
    ch.sensitivity = channel_sensitivity(*ch.base);
    chars.push_back(std::move(ch));
  }
  return chars;
}

std::string format_length(double metres, bool in_metres) {
  char buf[64];
  if (!in_metres)
    std::snprintf(buf, sizeof buf, "%.3g", metres);
  else if (metres >= 0.01)
    std::snprintf(buf, sizeof buf, "%.1f cm", metres * 100);
  else
    std::snprintf(buf, sizeof buf, "%.2f mm", metres * 1000);
  return buf;
}

// --- the solve: §4 steps 4 and 5, the iteration of §6 ----------------------------------------

// One pass's Levenberg-Marquardt iterate: the controls x of its displacement d, the step dx of
// eq. 5, the trial point x + alpha dx, F (eq. 4) at x and the damping lambda.
struct Iterate {
  Eigen::VectorXd x, dx, trial;
  Eigen::VectorXd r_at_x;  // residuals at x, for the working set (hold_blocking)
  double F = 0;
  double lambda = 0;
  int iterations = 0;
};

// How one pass ended.
struct PassOutcome {
  bool converged = false;
  std::string stop_reason;  // when not converged: "iteration limit", "line search failed", ...
};

// The linearised subproblem (eq. 5, with lambda M) at x: its step dx, then the working set of
// the active-set method: inequality rows satisfied at x that the full step would cross by more
// than the tolerance join the active set, and the step is solved again with them (at most
// options.working_set_resolves times). Returns the slope of F along dx; `full_step_evaluated`
// says whether the pass's last evaluation is at x + dx.
double linear_subproblem(Pass& pass, Iterate& s, double slope, const SpacetimeOptions& o,
                         bool& full_step_evaluated) {
  s.r_at_x = pass.residual();
  full_step_evaluated = false;
  for (int again = 0; again < o.working_set_resolves && slope < 0; ++again) {
    s.trial = s.x + s.dx;
    pass.evaluate(s.trial, false);
    full_step_evaluated = true;
    if (pass.hold_blocking(s.r_at_x, o.inequality_tolerance) == 0) break;
    full_step_evaluated = false;
    pass.evaluate(s.x, true);
    slope = pass.step_with_held(s.x, s.dx, s.lambda);
  }
  return slope;
}

struct LineSearch {
  bool accepted = false;
  double alpha = 1;    // the accepted step length along dx
  double F_trial = 0;  // F at x + alpha dx
};

// The line search of §6 ("a value of k such that x + k Delta best satisfies the constraints"):
// backtracking from alpha = 1 by options.line_search_shrink until F decreases sufficiently
// (Armijo: F(x + alpha dx) <= F(x) + armijo alpha slope). Leaves the pass evaluated (without
// Jacobian) at the last trial point, s.trial.
LineSearch line_search(Pass& pass, Iterate& s, double slope, bool full_step_evaluated,
                       const SpacetimeOptions& o) {
  LineSearch ls;
  ls.F_trial = s.F;
  for (int tried = 0; tried < o.line_search_steps; ++tried, ls.alpha *= o.line_search_shrink) {
    if (tried > 0 || !full_step_evaluated) {
      s.trial = s.x + ls.alpha * s.dx;
      pass.evaluate(s.trial, false);
    }
    ls.F_trial = pass.objective(s.trial);
    if (ls.F_trial <= s.F + o.armijo * ls.alpha * slope) {
      ls.accepted = true;
      break;
    }
  }
  return ls;
}

// Levenberg-Marquardt's damping update: a full step (alpha = 1) says the linearisation is good,
// lambda shrinks; a shortened one says it is poor, lambda grows the more, the shorter the step.
double update_damping(double lambda, double alpha, const SpacetimeOptions& o) {
  return alpha == 1 ? std::max(lambda * o.damping_decrease, o.min_damping)
                    : std::min(lambda * o.damping_increase / alpha, o.max_damping);
}

// The worst violation over a pass's iterations, to see a pass that has stopped gaining.
struct Progress {
  double worst_before = 0;  // after the previous iteration
  std::vector<double> history;
  bool can_densify = false;  // a later pass (§4 step 5) has denser keys to try
};

// The stopping tests of an accepted step that did not converge: "" to go on, else why the pass
// stops. F and `decrease` are the objective after the step and what the step took off it.
const char* stop_test(const Pass& pass, Progress& p, double step_norm, double F, double decrease,
                      double alpha, const SpacetimeOptions& o) {
  // Soft rows minimised with the required ones met: only F's own progress stops the pass (the
  // tests on the worst violation would stop it on a required row's last 1e-7).
  if (pass.has_soft() && pass.within_tolerance()) {
    if (step_norm < o.min_step ||
        decrease <= (alpha == 1 ? o.min_decrease : o.min_decrease_short) * (F + decrease))
      return "no further progress";
    return "";
  }
  // Stalled: what is left is what this key spacing can do (or the constraints contradict).
  const double worst_now = pass.worst_violation();
  const bool worst_stuck = worst_now > o.stuck_ratio * p.worst_before;
  p.worst_before = worst_now;
  p.history.push_back(worst_now);
  // With denser keys to come, a pass whose worst violation has not gained enough over its last
  // stall_window iterations has done what its spacing can (the rest is the objective creeping
  // down): the next pass starts from here.
  const std::size_t window = static_cast<std::size_t>(o.stall_window);
  if (p.can_densify && p.history.size() > window &&
      worst_now > o.stall_ratio * p.history[p.history.size() - 1 - window])
    return "keys too far apart";
  if (step_norm < o.min_step ||
      decrease <= (alpha == 1 ? o.min_decrease : o.min_decrease_short) * (F + decrease) ||
      (worst_stuck && decrease <= o.stuck_decrease * (F + decrease)))
    return "no further progress";
  return "";
}

void trace_iteration(const Pass& pass, const Iterate& s, double alpha, double step_norm, int pass_number,
                     std::chrono::steady_clock::time_point start, const SpacetimeOptions& o) {
  char line[200];
  std::snprintf(
      line, sizeof line,
      "pass %d it %d: F %.6g worst %.3g alpha %.3g lambda %.2g |dx| %.3g band %d x %d active %d at %.1f ms",
      pass_number, s.iterations, s.F, pass.worst_violation(), alpha, s.lambda, step_norm, pass.band_size(),
      pass.bandwidth(), pass.active_count(),
      1000 * std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  o.trace(line);
}

// §4 step 4 for one key spacing: the damped least-squares iteration of §6 from x = 0 (d = 0)
// until the constraints hold within tolerance, options.max_iterations, or a stopping test.
// Leaves the pass evaluated (with Jacobian) at the final x. Writes the bandwidth and the
// iterations into `result`.
PassOutcome iterate_pass(Pass& pass, const SpacetimeOptions& o, bool can_densify,
                         std::chrono::steady_clock::time_point start, SpacetimeResult& result) {
  Iterate s;
  s.x = Eigen::VectorXd::Zero(pass.unknown_total());
  pass.evaluate(s.x, true);
  s.F = pass.objective(s.x);
  s.lambda = o.initial_damping;
  // With soft rows the pass goes on past the required rows' tolerance until F stops falling (or
  // the iteration limit): the soft rows are minimised, not met.
  const bool minimise = pass.has_soft();
  PassOutcome out{pass.within_tolerance() && !minimise, "iteration limit"};
  Progress progress{pass.worst_violation(), {}, can_densify};
  progress.history.push_back(progress.worst_before);
  while (!out.converged && s.iterations < o.max_iterations) {
    pass.release_held(o.working_set_release * o.inequality_tolerance);
    double slope = pass.step(s.x, s.dx, s.lambda);
    result.bandwidth = pass.bandwidth();
    ++s.iterations;
    bool full_step_evaluated = false;
    slope = linear_subproblem(pass, s, slope, o, full_step_evaluated);
    if (!(slope < 0)) {
      out.stop_reason = "no descent direction";
      break;
    }
    const LineSearch ls = line_search(pass, s, slope, full_step_evaluated, o);
    if (!ls.accepted) {
      pass.evaluate(s.x, true);
      out.stop_reason = "line search failed";
      break;
    }
    s.lambda = update_damping(s.lambda, ls.alpha, o);
    const double step_norm = ls.alpha * s.dx.lpNorm<Eigen::Infinity>();
    const double decrease = s.F - ls.F_trial;
    s.x.swap(s.trial);
    s.F = ls.F_trial;
    pass.evaluate(s.x, true);
    out.converged = pass.within_tolerance() && !minimise;
    if (o.trace) trace_iteration(pass, s, ls.alpha, step_norm, result.passes, start, o);
    if (out.converged) break;
    if (const char* stop = stop_test(pass, progress, step_norm, s.F, decrease, ls.alpha, o); *stop != 0) {
      out.stop_reason = stop;
      break;
    }
  }
  if (minimise) out.converged = pass.within_tolerance();
  result.iterations += s.iterations;
  return out;
}

// Whether §4 step 5 could still densify `spacing` (options.densify and a spacing above 1).
bool can_densify(const std::vector<std::vector<int>>& spacing, const SpacetimeOptions& o) {
  bool can = false;
  if (o.densify)
    for (const std::vector<int>& ks : spacing)
      for (int k : ks) can = can || k > 1;
  return can;
}

// §4 step 5: every key spacing halved (down to 1 frame). False when none could be.
bool halve_key_spacing(std::vector<std::vector<int>>& spacing) {
  bool denser = false;
  for (std::vector<int>& ks : spacing)
    for (int& k : ks)
      if (k > 1) {
        k = std::max(1, k / 2);
        denser = true;
      }
  return denser;
}

// A violated row of the constraint `index` (first frame `first`) into its ViolatedConstraint.
void note_violation(std::map<int, ViolatedConstraint>& by_constraint, int index, const Constraint& con,
                    int first, double viol) {
  auto [it, fresh] = by_constraint.try_emplace(index);
  ViolatedConstraint& vc = it->second;
  if (fresh) {
    vc.kind = con.kind;
    vc.label = con.label;
    vc.first_frame = vc.last_frame = first;
    vc.in_metres = !con.points.empty();
  }
  vc.worst = std::max(vc.worst, viol);
  vc.first_frame = std::min(vc.first_frame, first);
  vc.last_frame = std::max(vc.last_frame, first);
}

// The pass's end, as the result reports it: its unknowns and rows, the per-kind figures and the
// constraints still violated past tolerance (worst first).
void report_pass(const Pass& pass, const std::vector<Character>& chars, const ConstraintSet& set,
                 const SpacetimeOptions& o, SpacetimeResult& result) {
  result.unknowns = 0;
  for (const Character& ch : chars)
    for (int c = 0; c < ch.channels; ++c)
      if (ch.free[static_cast<std::size_t>(c)]) result.unknowns += ch.layout.control_count(c);
  result.total_rows = pass.row_total();
  const Eigen::VectorXd& residual = pass.residual();
  std::map<std::string, KindReport> by_kind;
  std::map<int, ViolatedConstraint> by_constraint;
  for (const SampleInfo& s : pass.samples()) {
    const Constraint& con = set.constraints[static_cast<std::size_t>(s.constraint)];
    if (con.soft) continue;  // minimised, not required: in no violation figure
    KindReport& kr = by_kind[con.kind];
    kr.kind = con.kind;
    const std::vector<int>& frames = con.samples[static_cast<std::size_t>(s.sample)].frames;
    const int first = frames.empty() ? 0 : frames[0];
    for (int r = 0; r < s.rows; ++r) {
      const double v = residual[s.row_offset + r];
      const bool ineq = pass.row_inequality(s.row_offset + r);
      ++kr.rows;
      if (!ineq || v < 0) ++kr.active_rows;
      const double viol = ineq ? std::max(0.0, -v) : std::abs(v);
      double& worst = ineq ? kr.worst_inequality : kr.worst_equality;
      worst = std::max(worst, viol);
      if (viol > (ineq ? o.inequality_tolerance : o.equality_tolerance))
        note_violation(by_constraint, s.constraint, con, first, viol);
    }
  }
  result.active_rows = 0;
  result.kinds.clear();
  for (auto& [name, kr] : by_kind) {
    result.active_rows += kr.active_rows;
    result.kinds.push_back(kr);
  }
  result.violated.clear();
  for (auto& [index, vc] : by_constraint) result.violated.push_back(vc);
  std::sort(result.violated.begin(), result.violated.end(),
            [](const ViolatedConstraint& a, const ViolatedConstraint& b) { return a.worst > b.worst; });
}

// "did not converge (line search failed after 12 iterations, 2 passes): 3 constraints still
// violated by up to 2.1 mm: position 'lfoot plant 3' frames 10-14 (2.1 mm); ..."
std::string failure_message(const SpacetimeResult& result, const std::string& stop) {
  double worst = 0;
  bool metres = true;
  for (const ViolatedConstraint& v : result.violated)
    if (v.worst > worst) {
      worst = v.worst;
      metres = v.in_metres;
    }
  char head[160];
  std::snprintf(
      head, sizeof head,
      "did not converge (%s after %d iterations, %d pass%s): %zu constraint%s still violated by up to %s",
      stop.c_str(), result.iterations, result.passes, result.passes == 1 ? "" : "es", result.violated.size(),
      result.violated.size() == 1 ? "" : "s", format_length(worst, metres).c_str());
  std::string msg = head;
  const std::size_t shown = std::min<std::size_t>(result.violated.size(), 5);
  for (std::size_t i = 0; i < shown; ++i) {
    const ViolatedConstraint& v = result.violated[i];
    msg += i == 0 ? ": " : "; ";
    msg += v.kind + " '" + v.label + "' frame" +
           (v.first_frame == v.last_frame
                ? " " + std::to_string(v.first_frame)
                : "s " + std::to_string(v.first_frame) + "-" + std::to_string(v.last_frame)) +
           " (" + format_length(v.worst, v.in_metres) + ")";
  }
  if (result.violated.size() > shown) msg += "; ...";
  return msg;
}

std::string converged_message(const SpacetimeResult& result) {
  char head[160];
  std::snprintf(head, sizeof head, "converged in %d iterations (%d pass%s), worst violation %s",
                result.iterations, result.passes, result.passes == 1 ? "" : "es",
                format_length(result.worst_violation(), true).c_str());
  return head;
}

}  // namespace

void SpacetimeOptions::validate() const {
  using options::non_negative;
  using options::positive;
  using options::require;
  const char* o = "SpacetimeOptions";
  require(positive(epsilon), o, "epsilon", epsilon, "> 0 and finite");
  require(positive(equality_tolerance), o, "equality_tolerance", equality_tolerance,
          "> 0 and finite (metres or radians)");
  require(positive(inequality_tolerance), o, "inequality_tolerance", inequality_tolerance,
          "> 0 and finite (metres or radians)");
  require(max_iterations >= 0, o, "max_iterations", max_iterations, ">= 0");
  require(non_negative(initial_damping), o, "initial_damping", initial_damping, ">= 0 and finite");
  require(damping_decrease > 0 && damping_decrease <= 1, o, "damping_decrease", damping_decrease,
          "in (0, 1]");
  require(damping_increase >= 1 && std::isfinite(damping_increase), o, "damping_increase", damping_increase,
          ">= 1 and finite");
  require(non_negative(min_damping), o, "min_damping", min_damping, ">= 0 and finite");
  require(max_damping >= min_damping && std::isfinite(max_damping), o, "max_damping", max_damping,
          ">= min_damping (" + text::format_double(min_damping) + ") and finite");
  require(armijo > 0 && armijo < 1, o, "armijo", armijo, "in (0, 1)");
  require(line_search_shrink > 0 && line_search_shrink < 1, o, "line_search_shrink", line_search_shrink,
          "in (0, 1)");
  require(line_search_steps >= 1, o, "line_search_steps", line_search_steps, ">= 1");
  require(working_set_resolves >= 0, o, "working_set_resolves", working_set_resolves, ">= 0");
  require(non_negative(working_set_release), o, "working_set_release", working_set_release,
          ">= 0 and finite");
  require(non_negative(min_step), o, "min_step", min_step, ">= 0 and finite");
  require(min_decrease >= 0 && min_decrease < 1, o, "min_decrease", min_decrease, "in [0, 1)");
  require(min_decrease_short >= 0 && min_decrease_short < 1, o, "min_decrease_short", min_decrease_short,
          "in [0, 1)");
  require(stuck_ratio >= 0 && stuck_ratio <= 1, o, "stuck_ratio", stuck_ratio, "in [0, 1]");
  require(stuck_decrease >= 0 && stuck_decrease < 1, o, "stuck_decrease", stuck_decrease, "in [0, 1)");
  require(stall_window >= 1, o, "stall_window", stall_window, ">= 1");
  require(stall_ratio >= 0 && stall_ratio <= 1, o, "stall_ratio", stall_ratio, "in [0, 1]");
}

const char* to_string(SpacetimeStatus status) {
  return status == SpacetimeStatus::Converged ? "converged" : "not converged";
}

double SpacetimeResult::worst_violation() const {
  double w = 0;
  for (const KindReport& k : kinds) w = std::max(w, k.worst());
  return w;
}

Eigen::VectorXd channel_sensitivity(const Skeleton& skeleton) {
  const int nj = skeleton.joint_count();
  std::vector<Eigen::Isometry3d> world(static_cast<std::size_t>(nj));
  const Eigen::RowVectorXd rest = Eigen::RowVectorXd::Zero(skeleton.channel_count());
  motion::forward_kinematics(skeleton, rest, world);
  std::vector<double> reach(static_cast<std::size_t>(nj), 0.0);
  auto spread = [&](int from, const Eigen::Vector3d& p) {
    for (int a = from; a >= 0; a = skeleton.joint(a).parent)
      reach[static_cast<std::size_t>(a)] = std::max(
          reach[static_cast<std::size_t>(a)], (p - world[static_cast<std::size_t>(a)].translation()).norm());
  };
  for (int j = 0; j < nj; ++j) {
    spread(j, world[static_cast<std::size_t>(j)].translation());
    for (const Eigen::Vector3d& e : skeleton.joint(j).end_sites)
      spread(j, world[static_cast<std::size_t>(j)] * e);
  }
  Eigen::VectorXd s(skeleton.channel_count());
  for (int j = 0; j < nj; ++j) {
    const motion::Joint& jt = skeleton.joint(j);
    const double r = std::max(reach[static_cast<std::size_t>(j)], 0.02);
    for (std::size_t c = 0; c < jt.channels.size(); ++c)
      s[jt.first_channel + static_cast<int>(c)] = motion::is_rotation(jt.channels[c].kind) ? r * r : 1.0;
  }
  return s;
}

std::vector<DisplacementLayout> spacetime_layouts(const SpacetimeProblem& problem) {
  std::vector<DisplacementLayout> layouts;
  for (const CharacterProblem& cp : problem.characters) {
    if (!cp.initial.skeleton) throw std::invalid_argument("spacetime: initial motion has no skeleton");
    std::vector<int> k = cp.frames_per_key;
    if (k.empty()) k.assign(static_cast<std::size_t>(cp.initial.skeleton->channel_count()), 4);
    layouts.emplace_back(cp.initial.frame_count(), k);
  }
  return layouts;
}

SpacetimeLinearization linearize_spacetime(const SpacetimeProblem& problem, const Eigen::VectorXd& x) {
  const std::vector<KindInfo> kinds = check_problem(problem);
  std::vector<FrameMatrix> m1;
  std::vector<std::vector<int>> spacing;
  for (const DisplacementLayout& l : spacetime_layouts(problem)) {
    std::vector<int> k;
    for (int c = 0; c < l.channel_count(); ++c) k.push_back(l.spacing(c));
    spacing.push_back(k);
  }
  for (const CharacterProblem& cp : problem.characters) m1.push_back(cp.initial.values);
  std::vector<Character> chars = make_characters(problem, m1, spacing);
  Pass pass(chars, *problem.constraints, kinds, problem.options, false);
  if (x.size() != pass.unknown_total())
    throw std::invalid_argument("linearize_spacetime: x has " + std::to_string(x.size()) +
                                " entries, the problem " + std::to_string(pass.unknown_total()));
  pass.evaluate(x, true, true);
  SpacetimeLinearization out;
  out.residual = pass.weighted_residual();
  out.jacobian = pass.dense_jacobian();
  for (int i = 0; i < pass.row_total(); ++i) out.inequality.push_back(pass.row_inequality(i));
  return out;
}

SpacetimeResult solve_spacetime(const SpacetimeProblem& problem) {
  const auto start = std::chrono::steady_clock::now();
  const std::vector<KindInfo> kinds = check_problem(problem);
  const SpacetimeOptions& options = problem.options;

  // §4: m1 of the first pass is the initial estimate, the later passes start from m1 + d.
  std::vector<FrameMatrix> m1;
  std::vector<std::vector<int>> spacing;
  for (const CharacterProblem& cp : problem.characters) {
    m1.push_back(cp.initial.values);
    spacing.push_back(
        cp.frames_per_key.empty()
            ? std::vector<int>(static_cast<std::size_t>(cp.initial.skeleton->channel_count()), 4)
            : cp.frames_per_key);
  }

  SpacetimeResult result;
  PassOutcome outcome;
  for (;;) {
    ++result.passes;
    std::vector<Character> chars = make_characters(problem, m1, spacing);
    Pass pass(chars, *problem.constraints, kinds, options, true);
    outcome = iterate_pass(pass, options, can_densify(spacing, options), start, result);
    for (std::size_t k = 0; k < chars.size(); ++k) m1[k] = chars[k].values;  // m1 + d at x
    report_pass(pass, chars, *problem.constraints, options, result);
    result.frames_per_key = spacing;
    if (outcome.converged || !options.densify || !halve_key_spacing(spacing)) break;
  }

  result.status = outcome.converged ? SpacetimeStatus::Converged : SpacetimeStatus::NotConverged;
  for (std::size_t k = 0; k < problem.characters.size(); ++k) {
    const motion::Motion& init = problem.characters[k].initial;
    result.motions.push_back({init.skeleton, m1[k], init.fps, init.name});
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.message =
      outcome.converged ? converged_message(result) : failure_message(result, outcome.stop_reason);
  return result;
}

}  // namespace kg::retarget
