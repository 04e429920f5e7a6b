// Definitions of derivatives.hpp (see there for the math).
#pragma once

#include <saltus/hybrid/dynamics/derivatives.hpp>

namespace saltus {

namespace detail {
template <Scene S>
void seed(const VecT<double, 2 * S::nq>& x, const VecT<double, S::nu>& u, VecT<StateInputDual<S>, 2 * S::nq>& xd,
          VecT<StateInputDual<S>, S::nu>& ud) {
  using D = StateInputDual<S>;
  constexpr int nx = 2 * S::nq;
  for (int k = 0; k < nx; ++k) xd[k] = ad::seed<D::directions>(x[k], k);
  for (int k = 0; k < S::nu; ++k) ud[k] = ad::seed<D::directions>(u[k], nx + k);
}
}  // namespace detail

template <Scene S>
void flow_jacobian(const S& scene, const Mode<S::nc>& mode, const VecT<double, 2 * S::nq>& x,
                   const VecT<double, S::nu>& u, DerivativeWorkspace<S>& ws, VecT<double, 2 * S::nq>& f,
                   MatT<double, 2 * S::nq, 2 * S::nq>& A, MatT<double, 2 * S::nq, S::nu>& B) {
  constexpr int nx = 2 * S::nq;
  using D = StateInputDual<S>;
  VecT<D, nx> xd;
  VecT<D, S::nu> ud;
  detail::seed<S>(x, u, xd, ud);
  evaluate_flow(scene, mode, xd, ud, ws.flow);
  for (int i = 0; i < nx; ++i) {
    const D& fi = ws.flow.xdot[i];
    f[i] = fi.value();
    for (int k = 0; k < nx; ++k) A(i, k) = fi.derivatives()[k];
    for (int k = 0; k < S::nu; ++k) B(i, k) = fi.derivatives()[nx + k];
  }
}

template <Scene S>
double guard_gradient(const S& scene, const Mode<S::nc>& mode, const Guard& guard, const VecT<double, 2 * S::nq>& x,
                      const VecT<double, S::nu>& u, DerivativeWorkspace<S>& ws,
                      Eigen::Matrix<double, 1, 2 * S::nq>& d_dx, Eigen::Matrix<double, 1, S::nu>& d_du) {
  constexpr int nx = 2 * S::nq;
  using D = StateInputDual<S>;
  VecT<D, nx> xd;
  VecT<D, S::nu> ud;
  detail::seed<S>(x, u, xd, ud);
  evaluate_flow(scene, mode, xd, ud, ws.flow);
  const D g = guard_value(scene, mode, guard, ws.flow);
  for (int k = 0; k < nx; ++k) d_dx[k] = g.derivatives()[k];
  for (int k = 0; k < S::nu; ++k) d_du[k] = g.derivatives()[nx + k];
  return g.value();
}

template <Scene S>
void jump_map_jacobian(const S& scene, const ImpactMode<S::nc>& impact_mode, const VecT<double, 2 * S::nq>& x_minus,
                       DerivativeWorkspace<S>& ws, VecT<double, 2 * S::nq>& x_plus,
                       MatT<double, 2 * S::nq, 2 * S::nq>& G) {
  constexpr int nx = 2 * S::nq;
  using D = StateInputDual<S>;
  VecT<D, nx> xd, xp;
  for (int k = 0; k < nx; ++k) xd[k] = ad::seed<D::directions>(x_minus[k], k);
  apply_jump_map(scene, impact_mode, xd, ws.jump, xp);
  for (int i = 0; i < nx; ++i) {
    x_plus[i] = xp[i].value();
    for (int k = 0; k < nx; ++k) G(i, k) = xp[i].derivatives()[k];
  }
}

}  // namespace saltus
