// FesdMpcc: the rows of one stage point (fesd.hpp): the stage dynamics, the collocation, the
// switching functions and the OCP's path rows, with their values and Jacobian entries; and the local
// kernels they differentiate.
//
// STAGE DYNAMICS. The stage DERIVATIVE K is a variable (NOSNOC's "differential" representation) so
// that the mass matrix is multiplied, never inverted: the nonlinear rows of a stage are
//     K_q - s Theta v = 0,   M(q) K_v - s F(q, v, u, alpha) = 0,   K_t - s Theta = 0,
//     K_L - s Theta l(x, u) = 0,   K_g - s Theta J_n(q) v = 0       (time_freezing_system.hpp),
// written around two AD kernels, the field G(z) = (Theta v, F, Theta, Theta l, Theta J_n v) of
// z = (q, v, t, u, alpha) and M(q) K_v: s and K enter linearly.
// COLLOCATION (Radau IIA, radau.hpp): Y_r - y_start - h sum_l a_rl K_l = 0, bilinear in (h, K).
// SWITCHING (time-freezing paper, eq. 31): K_m c_m(q_r, v_r) - lambda_p,r,m + lambda_n,r,m = 0 with
// the scale K of options.switching.scale; with options.switching.integrated_gap the gap entries
// read the integrated gaps g_r instead of gap(q_r) (below).
//
// INTEGRATED GAP. Why a moving stance and a gap nonlinear in q do not mix. In a stance the
// contact's gap pairs leave alpha_gap interior, so complementarity (relaxed to nothing) holds
// gap(q_r) = 0 at every stage, and the sliding mode on J_n v holds J_n(q_r) v_r = 0 at every stage.
// With Radau collocation, q_r = q_0 + h sum_l a_rl K_l, K_l = s Theta_l v_l. For n_s = 1 (a = c = 1),
// Taylor about q_1:
//     gap(q_1) = gap(q_0) + J_n(q_1) h K - (h^2 / 2) K' grad^2 gap K + O(h^3),
// so gap(q_0) = 0 and J_n(q_1) v_1 = 0 give gap(q_1) = -(h^2 / 2) K' grad^2 gap K + O(h^3): not
// zero unless the gap is linear in q (the point mass) or the motion stops (the hopper standing
// still). For n_s >= 2 Radau IIA's simplifying conditions sum_l a_rl c_l^(k-1) = c_r^k / k
// (k <= n_s) cancel the h^2 term; what is left is of higher order in h and involves the gap's
// second derivative along the velocity and the acceleration (grad^2 gap[q', q'']) or its third
// derivative (n_s = 2: a quadratic gap at constant velocity leaves no residual; in general O(h^3)
// at the inner stage, O(h^4) at the end point). So where the residual has the sign that lifts the
// contact, the discrete stance has no solution with both held: gap(q_r) > 0 forces alpha_gap = 1,
// i.e. no contact force at that stage. A relaxed homotopy can hide this while sigma is larger than
// the residual; then it cannot go on. The integrated gaps g (g' = Theta J_n v, collocated like q)
// have stage values g_r = g_0 + h sum_l a_rl s Theta_l J_n(q_l) v_l: zero whenever g_0 and the
// stages' J_n v are, for any gap. The switching function then reads g instead of gap(q); g - gap(q)
// is the collocation's own error in integrating gap' = J_n q', so it shrinks with the
// discretisation (q itself is integrated with the same error). Without the option g is still
// carried (its rows are cheap and keep the layout one), but nothing reads it.
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hpp>

namespace saltus::timefreezing {

// ---- the applied input -------------------------------------------------------------------------
template <Scene S, class Ocp>
template <class T>
auto FesdMpcc<S, Ocp>::input_law(const T& t, const VecT<T, nu>& decision) const -> VecT<T, nu> {
  if constexpr (HasInputLaw<Ocp, T, nu>) return ocp_.template input<T>(t, decision);
  else return decision;
}
template <Scene S, class Ocp>
auto FesdMpcc<S, Ocp>::applied_input(const Eigen::Ref<const Eigen::VectorXd>& x, int k, double t) const -> Vec<nu> {
  const Vec<nu> d = x.template segment<nu>(control_index(k));
  return input_law<double>(t, d);
}

// ---- the local kernels -------------------------------------------------------------------------
// Written out by hand around the two AD kernels G(z) and M(q) K_v: s and K enter linearly (their
// Jacobian entries and the (s, z) Hessian block come from grad G), so the second-order AD runs over
// nz = 2 nq + 1 + nu + 3 nc directions, not over all ~2 ny + nz local variables.
template <Scene S, class Ocp>
template <class T>
auto FesdMpcc<S, Ocp>::stage_field(const VecT<T, nz>& z) const -> VecT<T, ny> {
  const VecT<T, nq> q = z.template segment<nq>(0);
  const VecT<T, nq> v = z.template segment<nq>(nq);
  const T& t = z[2 * nq];
  const VecT<T, nu> u = input_law<T>(t, VecT<T, nu>(z.template segment<nu>(2 * nq + 1)));
  const VecT<T, nsw> alpha = z.template segment<nsw>(2 * nq + 1 + nu);
  const T theta = System::template ode_weight<T>(alpha);
  VecT<T, ny> gz;
  gz.template head<nq>() = theta * v;
  gz.template segment<nq>(nq) = system_.template generalised_force<T>(q, v, u, alpha);
  gz[System::clock_index] = theta;
  T running(0.0);
  if constexpr (HasTimedRunningCost<Ocp, T, nx, nu>)
    running = ocp_.template running_cost<T>(VecT<T, nx>(z.template head<nx>()), u, t);
  else if constexpr (HasRunningCost<Ocp, T, nx, nu>)
    running = ocp_.template running_cost<T>(VecT<T, nx>(z.template head<nx>()), u);
  gz[System::cost_index] = T(theta * running);
  if constexpr (nc > 0) {
    const VecT<T, nc> vn = system_.template normal_velocities<T>(q, v);
    for (int i = 0; i < nc; ++i) gz[System::gap_state_index + i] = T(theta * vn[i]);
  }
  return gz;
}
/// M(q) K_v at w = (q, K_v).
template <Scene S, class Ocp>
template <class T>
auto FesdMpcc<S, Ocp>::mass_times(const VecT<T, 2 * nq>& w) const -> VecT<T, nq> {
  const MatT<T, nq, nq> mass = system_.scene().template mass_matrix<T>(VecT<T, nq>(w.template head<nq>()));
  return mass * VecT<T, nq>(w.template segment<nq>(nq));
}
template <Scene S, class Ocp>
auto FesdMpcc<S, Ocp>::field_local(const Eigen::Ref<const Eigen::VectorXd>& x, int k, int j, int r) const
    -> Eigen::Matrix<double, nz, 1> {
  Eigen::Matrix<double, nz, 1> z;
  z.template head<2 * nq + 1>() = x.template segment<2 * nq + 1>(state_index(k, j, r));
  z.template segment<nu>(2 * nq + 1) = x.template segment<nu>(control_index(k));
  z.template segment<nsw>(2 * nq + 1 + nu) = x.template segment<nsw>(alpha_index(k, j, r));
  return z;
}
// The global variable of the field's local slot a.
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::field_global(int k, int j, int r, int a) const {
  if (a < 2 * nq + 1) return state_index(k, j, r) + a;
  if (a < 2 * nq + 1 + nu) return control_index(k) + (a - 2 * nq - 1);
  return alpha_index(k, j, r) + (a - 2 * nq - 1 - nu);
}
template <Scene S, class Ocp>
auto FesdMpcc<S, Ocp>::mass_local(const Eigen::Ref<const Eigen::VectorXd>& x, int k, int j, int r) const
    -> Eigen::Matrix<double, 2 * nq, 1> {
  Eigen::Matrix<double, 2 * nq, 1> w;
  w << x.template segment<nq>(state_index(k, j, r)), x.template segment<nq>(derivative_index(k, j, r) + nq);
  return w;
}
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::mass_global(int k, int j, int r, int a) const {
  return a < nq ? state_index(k, j, r) + a : derivative_index(k, j, r) + a;  // K_v starts at K + nq
}
// Path constraints at a stage: local (Y, u).
template <Scene S, class Ocp>
template <class T>
auto FesdMpcc<S, Ocp>::stage_path(const VecT<T, npw>& w) const -> VecT<T, (np > 0 ? np : 1)> {
  if constexpr (np > 0) {
    const VecT<T, nu> u = input_law<T>(w[System::clock_index], VecT<T, nu>(w.template segment<nu>(ny)));
    return ocp_.template path_constraints<T>(VecT<T, nx>(w.template head<nx>()), u);
  } else {
    return VecT<T, 1>::Zero();
  }
}
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::path_global(int k, int j, int r, int b) const {
  return b < ny ? state_index(k, j, r) + b : control_index(k) + (b - ny);
}
// Terminal constraints and cost: local (x, t) of the final state.
template <Scene S, class Ocp>
template <class T>
auto FesdMpcc<S, Ocp>::terminal_function(const VecT<T, ntw>& w) const -> VecT<T, (nt > 0 ? nt : 1)> {
  if constexpr (nt > 0) return ocp_.template terminal_constraints<T>(VecT<T, nx>(w.template head<nx>()), w[nx]);
  else return VecT<T, 1>::Zero();
}
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::terminal_global(int a) const {
  return final_state_index() + (a < nx ? a : System::clock_index);
}

// ---- the rows of one stage point ---------------------------------------------------------------
// Stage dynamics R = (K_q - s G_q, M(q) K_v - s G_v, K_t - s G_t, K_L - s G_L, K_g - s G_g).
template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::dynamics_rows(const Eigen::Ref<const Eigen::VectorXd>& x, int k, int j, int r,
                                     detail::JacobianSink& sink) const {
  const int row = stage_row(k, j, r), kd = derivative_index(k, j, r);
  const double sp = x[speed_index(k)];
  const Eigen::Matrix<double, nz, 1> z = field_local(x, k, j, r);
  if (!sink.derivatives()) {
    const VecT<double, ny> gz = stage_field<double>(z);
    const VecT<double, nq> mk = mass_times<double>(mass_local(x, k, j, r));
    for (int i = 0; i < ny; ++i) {
      const bool v_row = i >= nq && i < 2 * nq;
      sink.value(row + i, (v_row ? mk[i - nq] : x[kd + i]) - sp * gz[i]);
    }
    return;
  }
  const VecT<detail::Ad1<nz>, ny> gz = stage_field<detail::Ad1<nz>>(detail::seed_first<nz>(z));
  const VecT<detail::Ad1<2 * nq>, nq> mk = mass_times<detail::Ad1<2 * nq>>(detail::seed_first<2 * nq>(mass_local(x, k, j, r)));
  for (int i = 0; i < ny; ++i) {
    const bool v_row = i >= nq && i < 2 * nq;
    sink.value(row + i, (v_row ? mk[i - nq].value() : x[kd + i]) - sp * gz[i].value());
    sink.put(row + i, speed_index(k), -gz[i].value());
    for (int a = 0; a < nz; ++a) {
      double d = -sp * gz[i].derivatives()[a];
      if (v_row && a < nq) d += mk[i - nq].derivatives()[a];  // d(M K_v)/dq
      sink.put(row + i, field_global(k, j, r, a), d);
    }
    if (v_row)
      for (int b = 0; b < nq; ++b) sink.put(row + i, kd + nq + b, mk[i - nq].derivatives()[nq + b]);
    else
      sink.put(row + i, kd + i, 1.0);
  }
}

// Collocation: Y_r - y_start - h sum_l a_rl K_l.
template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::collocation_rows(const Eigen::Ref<const Eigen::VectorXd>& x, int k, int j, int r,
                                        detail::JacobianSink& sink) const {
  const int ns = options_.grid.stages, ys = start_state_index(k, j), row = stage_row(k, j, r) + ny;
  const double h = x[length_index(k, j)];
  for (int i = 0; i < ny; ++i) {
    double sum_k = 0.0;
    for (int l = 0; l < ns; ++l) sum_k += tableau_.a(r, l) * x[derivative_index(k, j, l) + i];
    const double start = ys < 0 ? y0_[i] : x[ys + i];
    sink.value(row + i, x[state_index(k, j, r) + i] - start - h * sum_k);
    sink.put(row + i, state_index(k, j, r) + i, 1.0);
    if (ys >= 0) sink.put(row + i, ys + i, -1.0);
    sink.put(row + i, length_index(k, j), -sum_k);
    for (int l = 0; l < ns; ++l) sink.put(row + i, derivative_index(k, j, l) + i, -h * tableau_.a(r, l));
  }
}

// Switching: K c(q, v) - lambda_p + lambda_n (the gap entries from g when integrated_gap).
template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::switching_rows(const Eigen::Ref<const Eigen::VectorXd>& x, int k, int j, int r,
                                      detail::JacobianSink& sink) const {
  const int row = stage_row(k, j, r) + 2 * ny, y = state_index(k, j, r);
  const int lp = lambda_p_index(k, j, r), ln = lambda_n_index(k, j, r);
  const Vec<nx> wx = x.template segment<nx>(y);
  if (!sink.derivatives()) {
    const Vec<nsw> c = system_.template switching_functions<double>(wx.template head<nq>(), wx.template segment<nq>(nq));
    for (int m = 0; m < nsw; ++m) {
      const double cm = reads_integrated_gap(m) ? x[y + System::gap_state_index + m / 3] : c[m];
      sink.value(row + m, switching_scale(m) * cm - x[lp + m] + x[ln + m]);
    }
    return;
  }
  const auto a = detail::seed_first<nx>(wx);
  const VecT<detail::Ad1<nx>, nsw> c =
      system_.template switching_functions<detail::Ad1<nx>>(a.template head<nq>(), a.template segment<nq>(nq));
  for (int m = 0; m < nsw; ++m) {
    const double k_m = switching_scale(m);
    if (reads_integrated_gap(m)) {
      const int gi = y + System::gap_state_index + m / 3;
      sink.value(row + m, k_m * x[gi] - x[lp + m] + x[ln + m]);
      sink.put(row + m, gi, k_m);
    } else {
      sink.value(row + m, k_m * c[m].value() - x[lp + m] + x[ln + m]);
      for (int b = 0; b < nx; ++b) sink.put(row + m, y + b, k_m * c[m].derivatives()[b]);
    }
    sink.put(row + m, lp + m, -1.0);
    sink.put(row + m, ln + m, 1.0);
  }
}

// The OCP's path rows at the stage point.
template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::path_rows(const Eigen::Ref<const Eigen::VectorXd>& x, int k, int j, int r,
                                 detail::JacobianSink& sink) const {
  if constexpr (np > 0) {
    const int row = stage_row(k, j, r) + 2 * ny + nsw;
    Eigen::Matrix<double, npw, 1> pw;
    pw << x.template segment<ny>(state_index(k, j, r)), x.template segment<nu>(control_index(k));
    const VecT<detail::Ad1<npw>, np> p = stage_path<detail::Ad1<npw>>(detail::seed_first<npw>(pw));
    for (int i = 0; i < np; ++i) {
      sink.value(row + i, p[i].value());
      for (int b = 0; b < npw; ++b) sink.put(row + i, path_global(k, j, r, b), p[i].derivatives()[b]);
    }
  } else {
    (void)x, (void)k, (void)j, (void)r, (void)sink;
  }
}

}  // namespace saltus::timefreezing
