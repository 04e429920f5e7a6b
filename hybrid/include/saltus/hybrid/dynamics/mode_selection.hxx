// Definitions of mode_selection.hpp (see there for the math).
#pragma once

#include <Eigen/LU>
#include <algorithm>
#include <limits>
#include <saltus/hybrid/dynamics/mode_selection.hpp>

namespace saltus {

template <Scene S>
void ModeSelector<S>::assemble(const VecT<double, nx>& x, const VecT<double, nu>& u,
                               const std::array<bool, nc>& candidates, const std::array<bool, nc>& rest) {
  const VecT<double, nq> q = x.template head<nq>(), v = x.template tail<nq>();
  evaluate_kinematics(scene_, q, v, kin_);
  VecT<double, nq> free_force = -kin_.h;
  if constexpr (nu > 0) free_force += kin_.S_u * u;
  const VecT<double, nq> a_free = kin_.llt.solve(free_force);
  const double v_tol = options_.velocity_tolerance * std::max(1.0, v.cwiseAbs().maxCoeff());

  problem_.reset();
  std::array<ContactRows, nc> layout{};
  for (int i = 0; i < nc; ++i) {
    index_[i] = -1;
    layout[i] = ContactRows::None;
    slip_dir_[i].setZero();
    if (!candidates[i]) continue;
    const auto& c = kin_.contacts[i];
    const int nt = c.tangents;
    const double speed = c.zeta_t.head(nt).norm();
    if (nt > 0 && !rest[i] && speed > v_tol) {
      slip_dir_[i].head(nt) = c.zeta_t.head(nt) / speed;
      index_[i] = problem_.add_contact(0, 0.0);  // friction prescribed along -zeta_t
      layout[i] = ContactRows::Slip;
    } else {
      index_[i] = problem_.add_contact(nt, scene_.contact(i).mu);
      layout[i] = ContactRows::Stick;
    }
  }
  problem_.resize();
  // The assembly stacks the contacts in the problem's row order: normal, then its tangents.
  assembly_.assemble(scene_, kin_, layout, slip_dir_);
  const int m = problem_.rows();
  SALTUS_INVARIANT(assembly_.rows == m, "the Delassus assembly has the contact problem's rows");
  if (m == 0) return;
  assembly_.form(kin_);
  problem_.A = assembly_.D;
  problem_.b.noalias() = assembly_.J.topRows(m) * a_free;
  for (int i = 0; i < nc; ++i) {
    if (index_[i] < 0) continue;
    const auto& c = kin_.contacts[i];
    const int r = problem_.row[index_[i]];
    problem_.b[r] += c.kappa_n;
    for (int k = 0; k < problem_.tangents[index_[i]]; ++k) problem_.b[r + 1 + k] += c.kappa_t[k];
  }
}

template <Scene S>
auto ModeSelector<S>::select(const VecT<double, nx>& x, const VecT<double, nu>& u,
                             const std::array<bool, nc>& candidates, const std::array<bool, nc>& rest,
                             const Mode<nc>* current) -> Mode<nc> {
  assemble(x, u, candidates, rest);
  uniqueness_ = SelectionUniqueness<nc>{};
  const int m = problem_.rows();
  if (m == 0) return Mode<nc>{};
  bool any_spatial = false;
  for (int k = 0; k < problem_.contacts; ++k) any_spatial = any_spatial || problem_.tangents[k] == 2;

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
  force_tolerance_ = options_.force_tolerance * force_scale;
  acceleration_tolerance_ = options_.acceleration_tolerance * acc_scale;
  if (!any_spatial) enumerate_solutions(current, candidates);
  return mode_of(solution_.lambda, solution_.y);
}

template <Scene S>
auto ModeSelector<S>::mode_of(const Vector& lambda, const Vector& y) const -> Mode<nc> {
  const double f_tol = force_tolerance_, a_tol = acceleration_tolerance_;
  Mode<nc> md;
  for (int i = 0; i < nc; ++i) {
    if (index_[i] < 0) continue;
    const int r = problem_.row[index_[i]];
    const int nt = problem_.tangents[index_[i]];
    if (lambda[r] <= f_tol && y[r] > a_tol) {
      md[i] = ContactState::open();
      continue;
    }
    const int tangents = kin_.contacts[i].tangents;
    if (tangents == 0) {
      md[i] = ContactState::slip(Eigen::Vector2d::Zero());
    } else if (nt == 0) {  // already slipping
      md[i] = tangents == 1 ? ContactState::slip_planar(slip_dir_[i][0] > 0 ? 1 : -1) : ContactState::slip(slip_dir_[i]);
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
}

template <Scene S>
bool ModeSelector<S>::solve_combination(const std::array<int, contact_bound(nc)>& state, Vector& lambda,
                                        Vector& y) const {
  const int m = problem_.rows();
  using Matrix = typename Problem::Matrix;
  // lambda = E z over the unknown forces z; one equation (a zero acceleration) per unknown.
  Matrix E = Matrix::Zero(m, m);
  std::array<int, Problem::max_rows> equation{};
  int p = 0;
  for (int k = 0; k < problem_.contacts; ++k) {
    const int r = problem_.row[k], s = state[k];
    if (s == 0) continue;  // open
    E(r, p) = 1.0;
    equation[p++] = r;
    if (problem_.tangents[k] == 0) continue;
    if (s == 1) {  // stick: the friction force is an unknown of its own
      E(r + 1, p) = 1.0;
      equation[p++] = r + 1;
    } else {  // slip towards s y_t > 0: friction -s mu lambda_n
      E(r + 1, p - 1) = (s == 2 ? -1.0 : 1.0) * problem_.mu[k];
    }
  }
  lambda.setZero(m);
  if (p > 0) {
    Matrix K(p, p);
    Vector rhs(p);
    for (int a = 0; a < p; ++a) {
      rhs[a] = -problem_.b[equation[a]];
      K.row(a) = problem_.A.row(equation[a]).head(m) * E.leftCols(p);
    }
    const Eigen::FullPivLU<Matrix> lu(K);
    if (!lu.isInvertible()) return false;  // degenerate: its solutions are a neighbouring combination's
    lambda.noalias() = E.leftCols(p) * lu.solve(rhs);
  }
  y.noalias() = problem_.A.topLeftCorner(m, m) * lambda;
  y += problem_.b.head(m);
  const double f_tol = force_tolerance_, a_tol = acceleration_tolerance_;
  const double zero_band = a_tol + 1e-12 * std::max(problem_.b.head(m).cwiseAbs().maxCoeff(), 1.0);
  for (int k = 0; k < problem_.contacts; ++k) {
    const int r = problem_.row[k], s = state[k];
    if (s == 0) {
      if (y[r] < -a_tol) return false;
      continue;
    }
    if (lambda[r] < -f_tol || std::abs(y[r]) > zero_band) return false;
    if (problem_.tangents[k] == 0) continue;
    if (s == 1 && (std::abs(lambda[r + 1]) > problem_.mu[k] * lambda[r] + f_tol || std::abs(y[r + 1]) > zero_band))
      return false;
    if (s >= 2 && (s == 2 ? 1.0 : -1.0) * y[r + 1] < -a_tol) return false;
  }
  return true;
}

template <Scene S>
void ModeSelector<S>::enumerate_solutions(const Mode<nc>* current, const std::array<bool, nc>& candidates) {
  const int m = problem_.rows(), contacts = problem_.contacts;
  if (m > 12) return;
  int combinations = 1;
  std::array<int, contact_bound(nc)> choices{}, state{};
  for (int k = 0; k < contacts; ++k) {
    choices[k] = problem_.tangents[k] == 0 ? 2 : 4;  // open, closed | open, stick, slip +, slip -
    combinations *= choices[k];
    if (combinations > 4096) return;
  }
  constexpr int kept_max = SelectionUniqueness<nc>::max_kept;
  std::array<Vector, kept_max> kept_lambda, kept_y;
  int found = 0;
  Vector lambda, y;
  for (int n = 0; n < combinations; ++n) {
    for (int k = 0, rest = n; k < contacts; ++k) {
      state[k] = rest % choices[k];
      rest /= choices[k];
    }
    if (!solve_combination(state, lambda, y)) continue;
    const Mode<nc> candidate_mode = mode_of(lambda, y);
    bool seen = false;
    for (int s = 0; s < std::min(found, kept_max) && !seen; ++s) seen = uniqueness_.modes[s] == candidate_mode;
    if (seen) continue;
    if (found < kept_max) {
      uniqueness_.modes[found] = candidate_mode;
      kept_lambda[found] = lambda;
      kept_y[found] = y;
    }
    ++found;
  }
  if (found == 0) return;  // the solver's solution lies outside the enumeration's zero bands: unchecked
  uniqueness_.checked = true;
  uniqueness_.solutions = found;
  const int kept = std::min(found, kept_max);
  const Mode<nc> solver_mode = mode_of(solution_.lambda, solution_.y);
  int solvers = -1;  // which kept solution is the solver's (-1: beyond the kept ones)
  for (int s = 0; s < kept; ++s)
    if (uniqueness_.modes[s] == solver_mode) solvers = s;
  int taken = solvers;
  if (found > 1 && options_.ambiguity == AmbiguityChoice::Persistent && current != nullptr) {
    for (int s = 0; s < kept; ++s) {
      bool same = true;
      for (int i = 0; i < nc && same; ++i) same = !candidates[i] || uniqueness_.modes[s][i] == (*current)[i];
      if (same) taken = s;
    }
  } else if (found > 1 && (options_.ambiguity == AmbiguityChoice::MostClosed ||
                           options_.ambiguity == AmbiguityChoice::FewestClosed)) {
    const double f_tol = force_tolerance_;
    auto closed_count = [&](int s) {
      int count = 0;
      for (int k = 0; k < contacts; ++k) count += kept_lambda[s][problem_.row[k]] > f_tol ? 1 : 0;
      return count;
    };
    taken = std::max(taken, 0);
    for (int s = 0; s < kept; ++s) {
      const bool better = options_.ambiguity == AmbiguityChoice::MostClosed ? closed_count(s) > closed_count(taken)
                                                                             : closed_count(s) < closed_count(taken);
      if (better) taken = s;
    }
  }
  if (taken >= 0 && taken != solvers) {
    solution_.lambda.head(m) = kept_lambda[taken];
    solution_.y.head(m) = kept_y[taken];
  }
  taken = std::max(taken, 0);
  uniqueness_.taken = taken;
}

}  // namespace saltus
