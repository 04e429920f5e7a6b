// FesdMpcc: the objective and its gradient (fesd.hpp):
//     f = L(T~) + terminal_cost(x(T~), t(T~)) + rho_h sum (h_kj - h0)^2 + rho_s sum (s_k - 1)^2
//         + rho_c sum alpha_gap,
// L the running cost integrated over physical time (the quadrature state, time-freezing paper eq.
// 29), the step equilibration (fesd_step_equilibration.hxx), the speed-of-time weight, and the
// contact-side selection (below). Its Hessian terms: fesd_hessian.hxx.
//
// CONTACT-SIDE SELECTION (options.regularisation.contact_side = rho_c). While a contact's gap is
// exactly zero (its frozen phase: the auxiliary field moves v only, q' = 0; sliding along the
// surface) the gap's switching function vanishes, both its multipliers vanish, and complementarity
// leaves its step function alpha_gap anywhere in [0, 1]. The Filippov field does not care which
// weights realise it: with alpha_gap = a and alpha_vn = b the field weights the ODE by
// 1 - (1 - a)(1 - b), so sliding (clock speed 1/2 in the paper's Example 3) is a = 0, b = 1/2 or
// a = 1/2, b = 0 alike. But the second choice moves the end of the frozen phase into the degenerate
// gap pair, where cross-complementarity sees no switch, so the grid does not locate it: Example 3
// with n_s = 2 and 16 elements per control interval ends its frozen phase inside an element (tau
// off by 3.2e-3, q1 by 9e-6), and a relaxed homotopy also uses the freedom to let the gap drift
// (-1.6e-5) and the clock creep during the frozen phase. The linear cost rho_c sum over contacts
// and stage points of alpha_gap picks the contact side (alpha_gap = 0) wherever the gap is zero,
// and does nothing where the gap is not (there complementarity fixes alpha_gap); so the frozen
// phase's end becomes a switch of J_n v, which cross-complementarity locates. Under a relaxation
// it pulls alpha_gap in flight down to the relaxed bound 1 - alpha_gap = sigma / lambda_p <=
// sigma / (K gap): a phantom support that vanishes with sigma away from the surface but not near
// it (integrated over an approach, about sigma log sigma). At a lift-off the field is right (the
// ODE weight is 1 once alpha_vn = 1), but the gap's step function stays at 0 until the gap has grown
// to about sigma, so the gap's switch point comes late (Example 3's tangential lift-off: 3.6e-4 in
// tau). Off by default: on one contact it removes the drift and locates the frozen end, on the
// plank-box's two contacts it costs 6x the Ipopt iterations (FesdOptions::Regularisation).
// Derivatives: gradient rho_c on those entries, no Hessian term.
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hpp>
#include <saltus/timefreezing/discretisation/fesd_stage_rows.hxx>
#include <saltus/timefreezing/discretisation/fesd_step_equilibration.hxx>

namespace saltus::timefreezing {

// f plus interval k's terms, added one by one (the objective's order of summation).
template <Scene S, class Ocp>
double FesdMpcc<S, Ocp>::contact_side_selection(const Eigen::Ref<const Eigen::VectorXd>& x, int k, double f) const {
  const double rho_c = options_.regularisation.contact_side;
  if (rho_c <= 0.0) return f;
  for (int j = 0; j < options_.grid.finite_elements; ++j)
    for (int r = 0; r < options_.grid.stages; ++r)
      for (int i = 0; i < nc; ++i) f += rho_c * x[alpha_index(k, j, r) + 3 * i];
  return f;
}

template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::contact_side_selection_gradient(int k, Eigen::Ref<Eigen::VectorXd> g) const {
  const double rho_c = options_.regularisation.contact_side;
  if (rho_c <= 0.0) return;
  for (int j = 0; j < options_.grid.finite_elements; ++j)
    for (int r = 0; r < options_.grid.stages; ++r)
      for (int i = 0; i < nc; ++i) g[alpha_index(k, j, r) + 3 * i] += rho_c;
}

template <Scene S, class Ocp>
double FesdMpcc<S, Ocp>::objective(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  double f = x[final_state_index() + System::cost_index];
  const Eigen::Matrix<double, ny, 1> yf = x.template segment<ny>(final_state_index());
  if constexpr (HasTerminalCost<Ocp, double, nx>)
    f += ocp_.template terminal_cost<double>(yf.template head<nx>(), yf[System::clock_index]);
  for (int k = 0; k < options_.grid.control_intervals; ++k) {
    const double ds = x[speed_index(k)] - 1.0;
    f += options_.regularisation.speed_of_time * ds * ds;
    f = step_equilibration(x, k, f);
    f = contact_side_selection(x, k, f);
  }
  return f;
}

template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                                          Eigen::Ref<Eigen::VectorXd> g) const {
  g.setZero();
  const int yf = final_state_index();
  g[yf + System::cost_index] = 1.0;
  if constexpr (HasTerminalCost<Ocp, double, nx>) {
    Eigen::Matrix<double, ntw, 1> w;
    w << x.template segment<nx>(yf), x[yf + System::clock_index];
    const auto a = detail::seed_first<ntw>(w);
    const detail::Ad1<ntw> f = ocp_.template terminal_cost<detail::Ad1<ntw>>(a.template head<nx>(), a[nx]);
    g.template segment<nx>(yf) += f.derivatives().template head<nx>();
    g[yf + System::clock_index] += f.derivatives()[nx];
  }
  for (int k = 0; k < options_.grid.control_intervals; ++k) {
    g[speed_index(k)] += 2.0 * options_.regularisation.speed_of_time * (x[speed_index(k)] - 1.0);
    step_equilibration_gradient(x, k, g);
    contact_side_selection_gradient(k, g);
  }
}

}  // namespace saltus::timefreezing
