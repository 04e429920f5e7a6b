// Definitions of mode_selection.hpp (see there for the math).
#pragma once

#include <Eigen/LU>
#include <algorithm>
#include <limits>
#include <saltus/hybrid/dynamics/mode_selection.hpp>

namespace saltus {

template <Scene S>
auto ModeSelector<S>::select(const VecT<double, nx>& x, const VecT<double, nu>& u,
                             const std::array<bool, nc>& candidates, const std::array<bool, nc>& rest) -> Mode<nc> {
  const VecT<double, nq> q = x.template head<nq>(), v = x.template tail<nq>();
  evaluate_kinematics(scene_, q, v, kin_);
  VecT<double, nq> free_force = -kin_.h;
  if constexpr (nu > 0) free_force += kin_.S_u * u;
  const VecT<double, nq> a_free = kin_.llt.solve(free_force);
  const double v_tol = options_.velocity_tolerance * std::max(1.0, v.cwiseAbs().maxCoeff());

  problem_.reset();
  std::array<int, nc> index{};
  std::array<Eigen::Vector2d, nc> slip_dir{};
  std::array<ContactRows, nc> layout{};
  bool any_spatial = false;
  for (int i = 0; i < nc; ++i) {
    index[i] = -1;
    layout[i] = ContactRows::None;
    if (!candidates[i]) continue;
    const auto& c = kin_.contacts[i];
    const int nt = c.tangents;
    const double speed = c.zeta_t.head(nt).norm();
    slip_dir[i].setZero();
    if (nt > 0 && !rest[i] && speed > v_tol) {
      slip_dir[i].head(nt) = c.zeta_t.head(nt) / speed;
      index[i] = problem_.add_contact(0, 0.0);  // friction prescribed along -zeta_t
      layout[i] = ContactRows::Slip;
    } else {
      index[i] = problem_.add_contact(nt, scene_.contact(i).mu);
      layout[i] = ContactRows::Stick;
      any_spatial = any_spatial || nt == 2;
    }
  }
  problem_.resize();
  // The assembly stacks the contacts in the problem's row order: normal, then its tangents.
  assembly_.assemble(scene_, kin_, layout, slip_dir);
  const int m = problem_.rows();
  SALTUS_INVARIANT(assembly_.rows == m, "the Delassus assembly has the contact problem's rows");
  uniqueness_ = SelectionUniqueness<nc>{};
  if (m == 0) return Mode<nc>{};
  assembly_.form(kin_);
  problem_.A = assembly_.D;
  problem_.b.noalias() = assembly_.J.topRows(m) * a_free;
  for (int i = 0; i < nc; ++i) {
    if (index[i] < 0) continue;
    const auto& c = kin_.contacts[i];
    const int r = problem_.row[index[i]];
    problem_.b[r] += c.kappa_n;
    for (int k = 0; k < problem_.tangents[index[i]]; ++k) problem_.b[r + 1 + k] += c.kappa_t[k];
  }

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

  const double force_scale = std::max(solution_.lambda.head(m).cwiseAbs().maxCoeff(),
                                      contact_problem_scale(problem_) * problem_.b.head(m).cwiseAbs().maxCoeff());
  const double acc_scale =
      std::max(problem_.b.head(m).cwiseAbs().maxCoeff(), solution_.y.head(m).cwiseAbs().maxCoeff());
  const double f_tol = options_.force_tolerance * force_scale, a_tol = options_.acceleration_tolerance * acc_scale;
  using Vector = typename Problem::Vector;
  // The mode of the candidates from a solution (lambda, y) of the problem.
  auto mode_of = [&](const Vector& lambda, const Vector& y) {
    Mode<nc> md;
    for (int i = 0; i < nc; ++i) {
      if (index[i] < 0) continue;
      const int r = problem_.row[index[i]];
      const int nt = problem_.tangents[index[i]];
      if (lambda[r] <= f_tol && y[r] > a_tol) {
        md[i] = ContactState::open();
        continue;
      }
      const int tangents = kin_.contacts[i].tangents;
      if (tangents == 0) {
        md[i] = ContactState::slip(Eigen::Vector2d::Zero());
      } else if (nt == 0) {  // already slipping
        md[i] =
            tangents == 1 ? ContactState::slip_planar(slip_dir[i][0] > 0 ? 1 : -1) : ContactState::slip(slip_dir[i]);
      } else {
        Eigen::Vector2d yt = Eigen::Vector2d::Zero();
        for (int k = 0; k < nt && k < 2; ++k) yt[k] = y[r + 1 + k];
        if (yt.norm() <= a_tol) {
          md[i] = ContactState::stick();
        } else {
          const Eigen::Vector2d d = yt / yt.norm();
          md[i] = nt == 1 ? ContactState::slip_planar(d[0] > 0 ? 1 : -1) : ContactState::slip(d);
        }
      }
    }
    return md;
  };

  // Uniqueness (SelectionUniqueness): enumerate the normal-force LCP's complementary index sets.
  uniqueness_ = SelectionUniqueness<nc>{};
  bool normal_only = true;
  for (int k = 0; k < problem_.contacts; ++k) normal_only = normal_only && problem_.tangents[k] == 0;
  if (normal_only && m <= 12) {
    constexpr int kept_max = SelectionUniqueness<nc>::max_kept;
    std::array<Vector, kept_max> kept_lambda, kept_y;
    int found = 0;
    typename Problem::Matrix sub;
    Vector rhs, lambda, y;
    std::array<int, 12> in_set{};
    for (unsigned set = 0; set < (1u << m); ++set) {
      int k = 0;
      for (int r = 0; r < m; ++r)
        if (set & (1u << r)) in_set[k++] = r;
      lambda.setZero(m);
      if (k > 0) {
        sub.resize(k, k);
        rhs.resize(k);
        for (int a = 0; a < k; ++a) {
          rhs[a] = -problem_.b[in_set[a]];
          for (int c = 0; c < k; ++c) sub(a, c) = problem_.A(in_set[a], in_set[c]);
        }
        const Eigen::FullPivLU<typename Problem::Matrix> lu(sub);
        if (!lu.isInvertible()) continue;  // a degenerate set: its solutions are another set's
        const Vector part = lu.solve(rhs);
        for (int a = 0; a < k; ++a) lambda[in_set[a]] = part[a];
      }
      y.noalias() = problem_.A.topLeftCorner(m, m) * lambda;
      y += problem_.b.head(m);
      bool feasible = true;
      for (int r = 0; r < m && feasible; ++r)
        feasible = (set & (1u << r)) ? lambda[r] >= -f_tol && std::abs(y[r]) <= a_tol + 1e-12 * acc_scale
                                     : y[r] >= -a_tol;
      if (!feasible) continue;
      // Solutions are told apart by the mode they give: redundant contacts (a flat box on four
      // corners) have many force distributions for one mode, which is not an ambiguity of the mode.
      const Mode<nc> candidate_mode = mode_of(lambda, y);
      bool seen = false;
      for (int s = 0; s < std::min(found, kept_max) && !seen; ++s) seen = uniqueness_.modes[s] == candidate_mode;
      if (seen) continue;
      if (found < kept_max) uniqueness_.modes[found] = candidate_mode;
      if (found < kept_max) {
        kept_lambda[found] = lambda;
        kept_y[found] = y;
      }
      ++found;
    }
    if (found >= 1) {
      uniqueness_.checked = true;
      uniqueness_.solutions = found;
      const int kept = std::min(found, kept_max);
      // Which one the solver returned (the one with its mode), and which one is taken.
      const Mode<nc> solver_mode = mode_of(solution_.lambda, solution_.y);
      int nearest = 0;
      for (int s = 0; s < kept; ++s)
        if (uniqueness_.modes[s] == solver_mode) nearest = s;
      int taken = nearest;
      if (found > 1 && options_.ambiguity != AmbiguityChoice::Solver) {
        auto closed_count = [&](int s) {
          int n = 0;
          for (int r = 0; r < m; ++r) n += kept_lambda[s][r] > f_tol ? 1 : 0;
          return n;
        };
        for (int s = 0; s < kept; ++s) {
          const bool better = options_.ambiguity == AmbiguityChoice::MostClosed ? closed_count(s) > closed_count(taken)
                                                                                 : closed_count(s) < closed_count(taken);
          if (better) taken = s;
        }
        solution_.lambda.head(m) = kept_lambda[taken];
        solution_.y.head(m) = kept_y[taken];
      }
      uniqueness_.taken = taken;
    }
  }
  const Mode<nc> mode = mode_of(solution_.lambda, solution_.y);
  return mode;
}

}  // namespace saltus
