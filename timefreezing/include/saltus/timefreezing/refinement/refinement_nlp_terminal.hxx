// (e) Implied terminal rows (refinement_nlp.hpp, "IMPLIED ROWS"): an equality terminal row that
// the last phase's mode already holds, in gradient AND in value.
//
// The last phase's closed contacts hold h_n = 0 and zeta_n = 0 on the whole phase (imposed at its
// start, kept by the flow at the acceleration level). A terminal equality row r(x) = b whose
// x-gradient lies in the span of those rows' gradients and of the terminal rows kept before it
// (and that does not depend on T) is, to first order, the same condition twice: the hopper's
// target z(T) = 0.4 with the leg straight (phi_hip = phi_knee = 0) is the foot's gap = 0. Imposed
// twice, the collocation's drift from the contact manifold makes the two rows disagree by the
// drift and the multipliers grow without bound (3.5e9 on the hopper's finer grids).
//
// The gradient alone does not decide it: z(T) = 0.5 with the point mass's contact closed has the
// gradient of the gap and cannot be met at all. So the VALUE is checked as well: the guess's final
// state is projected (Gauss-Newton, least-norm steps) onto the manifold {h_n = 0, zeta_n = 0 of the
// closed contacts, the kept equality rows at their bounds}, and a candidate is implied only when
// its bound holds there to RefinementOptions::implied_terminal_value_tolerance. Where the
// projection does not converge, nothing is implied. An implied row is not a row of the NLP; the
// terminal_violation reading still includes it (it reports the drift).
#pragma once

#include <saltus/timefreezing/refinement/refinement_nlp_rows.hxx>

#include <Eigen/QR>

#include <cmath>
#include <string>
#include <vector>

namespace saltus::timefreezing {

template <Scene S, class Ocp>
template <class T>
VecT<T, 2 * S::nc> ScheduleRefinementNlp<S, Ocp>::held_contact_values(const VecT<T, nx>& x) const {
  Kinematics<S, T> kin;
  evaluate_kinematics<S, T>(scene_, VecT<T, nq>(x.template head<nq>()), VecT<T, nq>(x.template tail<nq>()), kin);
  VecT<T, 2 * nc> out;
  for (int i = 0; i < nc; ++i) {
    out[2 * i] = kin.contacts[i].gap;
    out[2 * i + 1] = kin.contacts[i].zeta_n;
  }
  return out;
}

template <Scene S, class Ocp>
auto ScheduleRefinementNlp<S, Ocp>::linearise_terminal(const VecT<double, nwt>& w) const -> TerminalLinearisation {
  TerminalLinearisation out;
  detail::local_jacobian<nwt, terminal_outputs>([&](const auto& a) { return terminal_block(a); }, w, out.value,
                                                out.jacobian);
  detail::local_jacobian<nx, 2 * nc>([&](const auto& a) { return held_contact_values(a); },
                                     VecT<double, nx>(w.template head<nx>()), out.held_value, out.held_jacobian);
  return out;
}

template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::find_implied_terminal_rows() {
  imposed_terminal_rows_.clear();
  for (int k = 0; k < nt; ++k) imposed_terminal_rows_.push_back(k);
  if constexpr (nt > 0) {
    const Mode<nc>& last = schedule_.phases.back();
    std::vector<int> held;  // output indices of held_contact_values
    for (int i = 0; i < nc; ++i)
      if (last[i].closed()) held.insert(held.end(), {2 * i, 2 * i + 1});
    if (held.empty()) return;
    const VecT<double, nwt> w = terminal_local(guess_x_);
    const TerminalLinearisation at_guess = linearise_terminal(w);
    const auto& J = at_guess.jacobian;
    const auto& H = at_guess.held_jacobian;
    const VecT<double, nt> lo = ocp_.terminal_lower(), hi = ocp_.terminal_upper();
    Eigen::MatrixXd K(0, nx);
    for (int r : held) detail::append_row(K, H.row(r).transpose());
    std::vector<int> kept, candidates;
    std::vector<double> residuals(static_cast<std::size_t>(nt), 1.0);
    for (int k = 0; k < nt; ++k) {
      if (lo[k] != hi[k]) continue;  // an inequality row: imposed
      const Eigen::VectorXd grad = J.row(k).head(nx).transpose();
      const bool timeless = std::abs(J(k, nx)) <= options_.implied_row_tolerance * std::max(grad.norm(), 1e-300);
      residuals[static_cast<std::size_t>(k)] = detail::span_residual(K, grad);
      if (timeless && grad.norm() > 0.0 && residuals[static_cast<std::size_t>(k)] <= options_.implied_row_tolerance) {
        candidates.push_back(k);
        continue;
      }
      kept.push_back(k);
      detail::append_row(K, grad);
    }
    if (candidates.empty()) return;
    VecT<double, nx> x;
    if (!project_on_held_manifold(w, held, kept, x)) return;
    VecT<double, nwt> at = w;
    at.template head<nx>() = x;
    const VecT<double, terminal_outputs> there = terminal_block<double>(at);
    for (int k : candidates) {
      if (std::abs(there[k] - lo[k]) > options_.implied_terminal_value_tolerance * (1.0 + std::abs(lo[k]))) continue;
      implied_.push_back({-1, -1, k,
                          "terminal row " + std::to_string(k) + " (held by the last phase's closed contacts)",
                          residuals[static_cast<std::size_t>(k)], true});
      std::erase(imposed_terminal_rows_, k);
    }
  }
}

/// Least-norm Gauss-Newton from w's state onto {held contact values = 0, the kept terminal rows at
/// their bounds} (T fixed at w's); false when it does not reach 1e-12 in 30 steps.
template <Scene S, class Ocp>
bool ScheduleRefinementNlp<S, Ocp>::project_on_held_manifold(const VecT<double, nwt>& w, const std::vector<int>& held,
                                                             const std::vector<int>& kept, VecT<double, nx>& x) const {
  const VecT<double, nt> lo = ocp_.terminal_lower();
  const int m = static_cast<int>(held.size() + kept.size());
  VecT<double, nwt> at = w;
  Eigen::VectorXd c(m);
  Eigen::MatrixXd A(m, nx);
  for (int step = 0; step < 30; ++step) {
    const TerminalLinearisation lin = linearise_terminal(at);
    int row = 0;
    for (int r : held) {
      c[row] = lin.held_value[r];
      A.row(row++) = lin.held_jacobian.row(r);
    }
    for (int k : kept) {
      c[row] = lin.value[k] - lo[k];
      A.row(row++) = lin.jacobian.row(k).head(nx);
    }
    if (!c.allFinite()) return false;
    if (c.lpNorm<Eigen::Infinity>() <= 1e-12 * (1.0 + at.template head<nx>().template lpNorm<Eigen::Infinity>())) {
      x = at.template head<nx>();
      return true;
    }
    at.template head<nx>() -= A.completeOrthogonalDecomposition().solve(c);
  }
  return false;
}

}  // namespace saltus::timefreezing
