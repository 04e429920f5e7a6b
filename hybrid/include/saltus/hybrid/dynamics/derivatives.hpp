// First derivatives of the flow, the guards and the jump maps with respect to the state x and
// the input u, by forward-mode automatic differentiation: the same templated code that computes
// the value runs on dual numbers (ad::Dual, Eigen's AutoDiffScalar) seeded along the nx + nu
// directions of (x, u). The scene's contact functions are then differentiated to third order
// (three nested levels, ad::Dual<ad::Dual<ad::Dual<double, nx + nu>, nq>, 1>), with no derivative
// written by hand anywhere.
#pragma once

#include <saltus/ad/autodiff.hpp>
#include <saltus/hybrid/dynamics/guards.hpp>
#include <saltus/hybrid/dynamics/jump_map.hpp>

namespace saltus {

/// The dual type that carries d/d(x, u) for scene S.
template <Scene S>
using StateInputDual = ad::Dual<double, 2 * S::nq + S::nu>;

/// Workspaces for the derivative evaluations (they hold dual-number matrices: make them once).
template <Scene S>
struct DerivativeWorkspace {
  using D = StateInputDual<S>;
  FlowWorkspace<S, D> flow;
  JumpWorkspace<S, D> jump;
};

/// A = df/dx (nx x nx), B = df/du (nx x nu) of the flow of `mode` at (x, u); also the value f.
template <Scene S>
void flow_jacobian(const S& scene, const Mode<S::nc>& mode, const VecT<double, 2 * S::nq>& x,
                   const VecT<double, S::nu>& u, DerivativeWorkspace<S>& ws, VecT<double, 2 * S::nq>& f,
                   MatT<double, 2 * S::nq, 2 * S::nq>& A, MatT<double, 2 * S::nq, S::nu>& B);

/// Value and gradients (d/dx, d/du) of one guard of `mode` at (x, u).
template <Scene S>
double guard_gradient(const S& scene, const Mode<S::nc>& mode, const Guard& guard, const VecT<double, 2 * S::nq>& x,
                      const VecT<double, S::nu>& u, DerivativeWorkspace<S>& ws,
                      Eigen::Matrix<double, 1, 2 * S::nq>& d_dx, Eigen::Matrix<double, 1, S::nu>& d_du);

/// x+ and Dg = dx+/dx- of the jump map of `impact_mode` at x-.
template <Scene S>
void jump_map_jacobian(const S& scene, const ImpactMode<S::nc>& impact_mode, const VecT<double, 2 * S::nq>& x_minus,
                       DerivativeWorkspace<S>& ws, VecT<double, 2 * S::nq>& x_plus,
                       MatT<double, 2 * S::nq, 2 * S::nq>& G);

}  // namespace saltus
