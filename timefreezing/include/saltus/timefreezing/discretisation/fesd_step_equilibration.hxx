// FesdMpcc: the heuristic step equilibration (fesd.hpp). Where no switch happens at the boundary
// between two elements of one control interval, nothing in the FESD equations fixes the two
// lengths (the collocation is exact for any split). The penalty
//     rho_h sum_j (h_kj - h0)^2,      rho_h = options.regularisation.step_equilibration,
// in the objective pulls them towards the nominal h0 (NOSNOC's heuristic_mean, unscaled like
// NOSNOC's so that weights compare); only with switch detection (the fixed grid has h = h0). The
// exact equilibration of the FESD paper (the eta rows) was measured worse:
// docs/decisions/fesd-exact-step-equilibration.md.
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hpp>

namespace saltus::timefreezing {

// f plus interval k's terms, added one by one (the objective's order of summation).
template <Scene S, class Ocp>
double FesdMpcc<S, Ocp>::step_equilibration(const Eigen::Ref<const Eigen::VectorXd>& x, int k, double f) const {
  if (!options_.switching.detection) return f;
  for (int j = 0; j < options_.grid.finite_elements; ++j) {
    const double dh = x[length_index(k, j)] - h0_;
    f += options_.regularisation.step_equilibration * dh * dh;
  }
  return f;
}

template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::step_equilibration_gradient(const Eigen::Ref<const Eigen::VectorXd>& x, int k,
                                                   Eigen::Ref<Eigen::VectorXd> g) const {
  if (!options_.switching.detection) return;
  for (int j = 0; j < options_.grid.finite_elements; ++j)
    g[length_index(k, j)] += 2.0 * options_.regularisation.step_equilibration * (x[length_index(k, j)] - h0_);
}

template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::step_equilibration_hessian(int k, double sigma, detail::HessianSink& sink) const {
  if (!options_.switching.detection) return;
  for (int j = 0; j < options_.grid.finite_elements; ++j)
    sink.put(length_index(k, j), length_index(k, j), sigma * 2.0 * options_.regularisation.step_equilibration);
}

}  // namespace saltus::timefreezing
