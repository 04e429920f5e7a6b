// FesdMpcc: the Lagrangian Hessian sigma grad^2 f + sum_i mu_i grad^2 g_i, lower triangle, one pass
// in the order of its structure (fesd.hpp; forward-over-forward AD on the local kernels of
// fesd_stage_rows.hxx, bilinear terms written out).
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hpp>
#include <saltus/timefreezing/discretisation/fesd_jacobian.hxx>
#include <saltus/timefreezing/discretisation/fesd_step_equilibration.hxx>

#include <algorithm>

namespace saltus::timefreezing {

template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::hessian_pass(const Eigen::Ref<const Eigen::VectorXd>& x, double sigma,
                                    const Eigen::Ref<const Eigen::VectorXd>& mu, detail::HessianSink& sink) const {
  for (int k = 0; k < options_.grid.control_intervals; ++k) {
    for (int j = 0; j < options_.grid.finite_elements; ++j)
      for (int r = 0; r < options_.grid.stages; ++r) {
        dynamics_hessian(x, mu, k, j, r, sink);
        collocation_hessian(mu, k, j, r, sink);
        switching_hessian(x, mu, k, j, r, sink);
        path_hessian(x, mu, k, j, r, sink);
      }
    sink.put(speed_index(k), speed_index(k), sigma * 2.0 * options_.regularisation.speed_of_time);
    step_equilibration_hessian(k, sigma, sink);
  }
  terminal_hessian(x, sigma, mu, sink);
}

// sum_i mu_i d2 R_i = -s sum mu_i d2 G_i on (z, z), -sum mu_i dG_i on (s, z), and the mass term
// mu_v' M(q) K_v on (q, q) and (K_v, q); (K_v, K_v) is zero (linear in K_v).
template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::dynamics_hessian(const Eigen::Ref<const Eigen::VectorXd>& x,
                                        const Eigen::Ref<const Eigen::VectorXd>& mu, int k, int j, int r,
                                        detail::HessianSink& sink) const {
  const int row = stage_row(k, j, r);
  Eigen::Matrix<double, nz, nz> hz = Eigen::Matrix<double, nz, nz>::Zero();
  Eigen::Matrix<double, nz, 1> hs = Eigen::Matrix<double, nz, 1>::Zero();
  Eigen::Matrix<double, 2 * nq, 2 * nq> hm = Eigen::Matrix<double, 2 * nq, 2 * nq>::Zero();
  if (sink.evaluating()) {
    const double sp = x[speed_index(k)];
    const VecT<detail::Ad2<nz>, ny> gz = stage_field<detail::Ad2<nz>>(detail::seed_second<nz>(field_local(x, k, j, r)));
    for (int i = 0; i < ny; ++i) {
      const double m = mu[row + i];
      if (m == 0.0) continue;
      for (int a = 0; a < nz; ++a) {
        hz.row(a) -= (sp * m) * gz[i].derivatives()[a].derivatives().transpose();
        hs[a] -= m * gz[i].derivatives()[a].value();
      }
    }
    const VecT<detail::Ad2<2 * nq>, nq> mk =
        mass_times<detail::Ad2<2 * nq>>(detail::seed_second<2 * nq>(mass_local(x, k, j, r)));
    for (int i = 0; i < nq; ++i) {
      const double m = mu[row + nq + i];
      if (m == 0.0) continue;
      for (int a = 0; a < 2 * nq; ++a) hm.row(a) += m * mk[i].derivatives()[a].derivatives().transpose();
    }
  }
  for (int a = 0; a < nz; ++a)
    for (int b = 0; b <= a; ++b) sink.put(field_global(k, j, r, a), field_global(k, j, r, b), hz(a, b));
  for (int a = 0; a < nz; ++a) sink.put(field_global(k, j, r, a), speed_index(k), hs[a]);
  for (int a = 0; a < 2 * nq; ++a)
    for (int b = 0; b < std::min(a + 1, nq); ++b) sink.put(mass_global(k, j, r, a), mass_global(k, j, r, b), hm(a, b));
}

// Collocation: d2 / dh dK_l,i of -h a_rl K_l,i, weighted.
template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::collocation_hessian(const Eigen::Ref<const Eigen::VectorXd>& mu, int k, int j, int r,
                                           detail::HessianSink& sink) const {
  const int row = stage_row(k, j, r) + ny;
  for (int i = 0; i < ny; ++i) {
    const double m = sink.evaluating() ? mu[row + i] : 0.0;
    for (int l = 0; l < options_.grid.stages; ++l)
      sink.put(length_index(k, j), derivative_index(k, j, l) + i, -m * tableau_.a(r, l));
  }
}

// Switching functions on (q, v); an integrated gap enters linearly.
template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::switching_hessian(const Eigen::Ref<const Eigen::VectorXd>& x,
                                         const Eigen::Ref<const Eigen::VectorXd>& mu, int k, int j, int r,
                                         detail::HessianSink& sink) const {
  const int row = stage_row(k, j, r) + 2 * ny, y = state_index(k, j, r);
  Eigen::Matrix<double, nx, nx> hl = Eigen::Matrix<double, nx, nx>::Zero();
  if (sink.evaluating()) {
    const auto a = detail::seed_second<nx>(Vec<nx>(x.template segment<nx>(y)));
    const VecT<detail::Ad2<nx>, nsw> c =
        system_.template switching_functions<detail::Ad2<nx>>(a.template head<nq>(), a.template segment<nq>(nq));
    for (int m = 0; m < nsw; ++m) {
      const double w = switching_scale(m) * mu[row + m];
      if (w == 0.0 || reads_integrated_gap(m)) continue;
      for (int p = 0; p < nx; ++p) hl.row(p) += w * c[m].derivatives()[p].derivatives().transpose();
    }
  }
  for (int p = 0; p < nx; ++p)
    for (int b = 0; b <= p; ++b) sink.put(y + p, y + b, hl(p, b));
}

template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::path_hessian(const Eigen::Ref<const Eigen::VectorXd>& x,
                                    const Eigen::Ref<const Eigen::VectorXd>& mu, int k, int j, int r,
                                    detail::HessianSink& sink) const {
  if constexpr (np > 0) {
    const int row = stage_row(k, j, r) + 2 * ny + nsw;
    Eigen::Matrix<double, npw, npw> hl = Eigen::Matrix<double, npw, npw>::Zero();
    if (sink.evaluating()) {
      Eigen::Matrix<double, npw, 1> pw;
      pw << x.template segment<ny>(state_index(k, j, r)), x.template segment<nu>(control_index(k));
      const VecT<detail::Ad2<npw>, np> p = stage_path<detail::Ad2<npw>>(detail::seed_second<npw>(pw));
      for (int i = 0; i < np; ++i) {
        const double w = mu[row + i];
        if (w == 0.0) continue;
        for (int a = 0; a < npw; ++a) hl.row(a) += w * p[i].derivatives()[a].derivatives().transpose();
      }
    }
    for (int a = 0; a < npw; ++a)
      for (int b = 0; b <= a; ++b) sink.put(path_global(k, j, r, a), path_global(k, j, r, b), hl(a, b));
  } else {
    (void)x, (void)mu, (void)k, (void)j, (void)r, (void)sink;
  }
}

// Terminal constraints and terminal cost on (x, t) of the final state.
template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::terminal_hessian(const Eigen::Ref<const Eigen::VectorXd>& x, double sigma,
                                        const Eigen::Ref<const Eigen::VectorXd>& mu, detail::HessianSink& sink) const {
  constexpr bool has_cost = HasTerminalCost<Ocp, double, nx>;
  if constexpr (nt > 0 || has_cost) {
    Eigen::Matrix<double, ntw, ntw> hl = Eigen::Matrix<double, ntw, ntw>::Zero();
    if (sink.evaluating()) {
      Eigen::Matrix<double, ntw, 1> tw;
      for (int a = 0; a < ntw; ++a) tw[a] = x[terminal_global(a)];
      const auto a = detail::seed_second<ntw>(tw);
      if constexpr (nt > 0) {
        const VecT<detail::Ad2<ntw>, nt> tf = terminal_function<detail::Ad2<ntw>>(a);
        for (int i = 0; i < nt; ++i) {
          const double w = mu[terminal_row_ + i];
          if (w == 0.0) continue;
          for (int p = 0; p < ntw; ++p) hl.row(p) += w * tf[i].derivatives()[p].derivatives().transpose();
        }
      }
      if constexpr (HasTerminalCost<Ocp, detail::Ad2<ntw>, nx>) {
        const detail::Ad2<ntw> f = ocp_.template terminal_cost<detail::Ad2<ntw>>(a.template head<nx>(), a[nx]);
        for (int p = 0; p < ntw; ++p) hl.row(p) += sigma * f.derivatives()[p].derivatives().transpose();
      }
    }
    for (int p = 0; p < ntw; ++p)
      for (int b = 0; b <= p; ++b) sink.put(terminal_global(p), terminal_global(b), hl(p, b));
  } else {
    (void)x, (void)sigma, (void)mu, (void)sink;
  }
}

template <Scene S, class Ocp>
const std::vector<SparseEntry>& FesdMpcc<S, Ocp>::hessian_structure() const {
  return hessian_structure_;
}
template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::hessian_values(const Eigen::Ref<const Eigen::VectorXd>& x, double objective_factor,
                                      const Eigen::Ref<const Eigen::VectorXd>& multipliers,
                                      Eigen::Ref<Eigen::VectorXd> values) const {
  detail::HessianSink sink;
  sink.values = &values;
  hessian_pass(x, objective_factor, multipliers, sink);
}

// The Jacobian's and the Hessian's structures, from one pass each at the initial point.
template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::build_structures() {
  Eigen::VectorXd x(n_);
  initial_point(x);
  jacobian_structure_.clear();
  detail::JacobianSink jacobian;
  jacobian.structure = &jacobian_structure_;
  jacobian_pass(x, jacobian);
  hessian_structure_.clear();
  const Eigen::VectorXd mu = Eigen::VectorXd::Zero(m_);
  detail::HessianSink hessian;
  hessian.structure = &hessian_structure_;
  hessian_pass(x, 0.0, mu, hessian);
}

}  // namespace saltus::timefreezing
