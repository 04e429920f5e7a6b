// Choosing a consistent contact mode at the acceleration level (thesis 2.20-2.23, 2.41, and the
// contact LCP of the time-freezing paper, eqs. 9-12): among the contacts that are closed at the
// velocity level (gap = 0, normal velocity = 0), which stay closed, and of those which stick and
// which slip, given the current state and input. It is the contact problem of
// contact_problem.hpp with accelerations in place of velocities:
//     y = J a + kappa = (J M^{-1} F) lambda + J a_free + kappa,
// Signorini between normal accelerations and forces, Coulomb between tangential accelerations and
// friction forces for contacts at tangential rest. A contact already slipping has its friction
// fixed along -zeta_t/||zeta_t|| (thesis A.23), folded into the columns of J M^{-1} F.
// Used after impacts (an impact into stick that slips at once, thesis B.3), at the stop of a
// slip (stick, or slip on the other way round), and for the initial state.
#pragma once

#include <saltus/hybrid/contact/contact_problem.hpp>
#include <saltus/hybrid/contact/coulomb_solver.hpp>
#include <saltus/hybrid/dynamics/flow.hpp>
#include <saltus/hybrid/contact/lemke.hpp>

#include <array>

namespace saltus {

struct ModeSelectionOptions {
  /// A contact velocity below velocity_tolerance * max(1, ||v||_inf) counts as zero.
  double velocity_tolerance = 1e-8;
  /// A normal force below force_tolerance * (force scale) counts as zero.
  double force_tolerance = 1e-10;
  /// An acceleration below acceleration_tolerance * (acceleration scale) counts as zero.
  double acceleration_tolerance = 1e-9;
  double residual_tolerance = 1e-9;
};

template <Scene S>
class ModeSelector {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nu = S::nu, nc = S::nc;
  static constexpr int max_rows = 3 * nc;
  using Problem = ContactProblem<contact_bound(nc)>;
  using Solution = ContactSolution<contact_bound(nc)>;
  using Lemke = LemkeSolver<contact_bound(nc)>;
  using Coulomb = CoulombSolver<contact_bound(nc)>;

  explicit ModeSelector(const S& scene, ModeSelectionOptions options = {}) : scene_(scene), options_(options) {}

  /// The mode of the contacts in `candidates` at (x, u); contacts not in it are open.
  /// `rest[i]` marks a candidate whose tangential velocity is to be taken as zero (the instant a
  /// slip stops). Throws ContactProblemFailure when the acceleration-level problem has no solution
  /// (Painleve's paradox: friction too large for the configuration).
  Mode<nc> select(const VecT<double, nx>& x, const VecT<double, nu>& u, const std::array<bool, nc>& candidates,
                  const std::array<bool, nc>& rest = {}) {
    const VecT<double, nq> q = x.template head<nq>(), v = x.template tail<nq>();
    evaluate_kinematics(scene_, q, v, kin_);
    VecT<double, nq> free_force = -kin_.h;
    if constexpr (nu > 0) free_force += kin_.S_u * u;
    const VecT<double, nq> a_free = kin_.llt.solve(free_force);
    const double v_tol = options_.velocity_tolerance * std::max(1.0, v.cwiseAbs().maxCoeff());

    problem_.reset();
    std::array<int, nc> index{};
    std::array<Eigen::Vector2d, nc> slip_dir{};
    bool any_spatial = false;
    for (int i = 0; i < nc; ++i) {
      index[i] = -1;
      if (!candidates[i]) continue;
      const auto& c = kin_.contacts[i];
      const int nt = c.tangents;
      const double speed = c.zeta_t.head(nt).norm();
      slip_dir[i].setZero();
      if (nt > 0 && !rest[i] && speed > v_tol) {
        slip_dir[i].head(nt) = c.zeta_t.head(nt) / speed;
        index[i] = problem_.add_contact(0, 0.0);  // friction prescribed along -zeta_t
      } else {
        index[i] = problem_.add_contact(nt, scene_.contact(i).mu);
        any_spatial = any_spatial || nt == 2;
      }
    }
    problem_.resize();
    const int m = problem_.rows();
    J_.resize(m, nq);
    F_.resize(nq, m);
    kappa_.resize(m);
    for (int i = 0; i < nc; ++i) {
      if (index[i] < 0) continue;
      const auto& c = kin_.contacts[i];
      const int r = problem_.row[index[i]];
      J_.row(r) = c.wn.transpose();
      kappa_[r] = c.kappa_n;
      if (problem_.tangents[index[i]] == 0 && c.tangents > 0) {
        F_.col(r) = c.wn - scene_.contact(i).mu * (c.Wt.leftCols(c.tangents) * slip_dir[i].head(c.tangents));
      } else {
        F_.col(r) = c.wn;
        for (int k = 0; k < problem_.tangents[index[i]]; ++k) {
          J_.row(r + 1 + k) = c.Wt.col(k).transpose();
          F_.col(r + 1 + k) = c.Wt.col(k);
          kappa_[r + 1 + k] = c.kappa_t[k];
        }
      }
    }
    Mode<nc> mode;
    if (m == 0) return mode;
    MinvF_.resize(nq, m);
    MinvF_ = kin_.llt.solve(F_);
    problem_.A.noalias() = J_ * MinvF_;
    problem_.b.noalias() = J_ * a_free;
    problem_.b += kappa_;

    solution_.lambda.resize(m);
    solution_.y.resize(m);
    bool solved = false;
    if (!any_spatial) {
      lemke_.solve(problem_, solution_);
      solved = solution_.residual <= options_.residual_tolerance;
    }
    if (!solved) {
      coulomb_.solve(problem_, solution_);
      solved = solution_.residual <= options_.residual_tolerance;
    }
    if (!solved) {
      throw ContactProblemFailure(detail::concat(
          "no consistent contact mode at the acceleration level (Painleve's paradox or a wrong contact set): "
          "natural-map residual ",
          solution_.residual, " at x = [", x.transpose(), "]"));
    }

    const double force_scale =
        std::max(solution_.lambda.head(m).cwiseAbs().maxCoeff(), contact_problem_scale(problem_) * problem_.b.head(m).cwiseAbs().maxCoeff());
    const double acc_scale = std::max(problem_.b.head(m).cwiseAbs().maxCoeff(), solution_.y.head(m).cwiseAbs().maxCoeff());
    for (int i = 0; i < nc; ++i) {
      if (index[i] < 0) continue;
      const int r = problem_.row[index[i]];
      const int nt = problem_.tangents[index[i]];
      const double ln = solution_.lambda[r], yn = solution_.y[r];
      if (ln <= options_.force_tolerance * force_scale && yn > options_.acceleration_tolerance * acc_scale) {
        mode[i] = ContactState::open();
        continue;
      }
      const int tangents = kin_.contacts[i].tangents;
      if (tangents == 0) {
        mode[i] = ContactState::slip(Eigen::Vector2d::Zero());
      } else if (nt == 0) {  // already slipping
        mode[i] = tangents == 1 ? ContactState::slip_planar(slip_dir[i][0] > 0 ? 1 : -1) : ContactState::slip(slip_dir[i]);
      } else {
        Eigen::Vector2d yt = Eigen::Vector2d::Zero();
        for (int k = 0; k < nt; ++k) yt[k] = solution_.y[r + 1 + k];
        if (yt.norm() <= options_.acceleration_tolerance * acc_scale) {
          mode[i] = ContactState::stick();
        } else {
          const Eigen::Vector2d d = yt / yt.norm();
          mode[i] = nt == 1 ? ContactState::slip_planar(d[0] > 0 ? 1 : -1) : ContactState::slip(d);
        }
      }
    }
    return mode;
  }

  const Solution& solution() const { return solution_; }

 private:
  const S& scene_;
  ModeSelectionOptions options_;
  Kinematics<S> kin_;
  Problem problem_;
  Solution solution_;
  Lemke lemke_;
  Coulomb coulomb_;
  BoundedMatrix<double, Eigen::Dynamic, nq, std::max(1, max_rows), nq> J_;
  BoundedMatrix<double, nq, Eigen::Dynamic, nq, std::max(1, max_rows)> F_, MinvF_;
  BoundedMatrix<double, Eigen::Dynamic, 1, std::max(1, max_rows), 1> kappa_;
};

}  // namespace saltus
