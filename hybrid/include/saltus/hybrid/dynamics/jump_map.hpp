// Jump maps x+ = g(x-) for a given post-impact impulse mode (thesis A.34-A.49, generalised to any
// mix of contacts). q is continuous; with the participating contacts' rows J (w_n^T, and W_t^T
// for sticking ones) and impulse columns F (w_n, or w_n - mu W_t d for slip along d; W_t for
// sticking tangents):
//     M (v+ - v-) = F Lambda,    J v+ = target,
//     target_n = -e_n min(zeta_n^-, 0) (Newton's law, 2.10),
//     target_t = -e_t zeta_t^- (stick, 2.57, with the tangential restitution of impact_law.hpp),
// hence (J M^{-1} F) Lambda = target - J v-,  v+ = v- + M^{-1} F Lambda.
//
// Slip direction. Saltus follows Coulomb's law on impulses (thesis 2.29-2.30): a slipping
// contact's tangential impulse opposes its POST-impact tangential velocity of the impact law,
// d = xi_t/||xi_t|| with xi_t = zeta_t^+ + e_t zeta_t^- (= zeta_t^+ when e_t = 0).
// The thesis' explicit map A.36-A.39 uses the ante-impact direction instead, which violates 2.30
// whenever the impulse turns the slip (spatial friction, or coupled contacts). For planar
// contacts the direction is the sign s stored in the impulse mode and the map is linear in v-;
// for spatial contacts d is defined implicitly and solved for by Newton's method on
// R(y) = xi_t(d(y)) - y. The Newton matrix is a central difference of R (it affects only the
// rate of convergence); iterating in the scalar type T until the value has converged, plus two
// more steps, makes the derivatives those of the implicit function (each step contracts their
// error like the value's).
//
// Redundant contacts make J M^{-1} F singular; the impulse returned is the minimum-norm one
// (same decomposition and threshold as flow.hpp). The post-impact velocity is unique unless
// redundant contacts slip along different directions (impact.hpp's file comment): then the
// minimum-norm split is a selection, and another solution of the same roles has another v+.
#pragma once

#include <saltus/hybrid/dynamics/delassus.hpp>
#include <saltus/hybrid/dynamics/flow.hpp>
#include <saltus/hybrid/dynamics/impact_law.hpp>
#include <saltus/hybrid/contact/linear_solve.hpp>
#include <saltus/hybrid/vocabulary/impact_mode.hpp>


#include <array>

namespace saltus {


template <Scene S, class T = double>
struct JumpWorkspace {
  static constexpr int nq = S::nq, nc = S::nc, nx = 2 * S::nq;
  using Assembly = DelassusAssembly<S, T>;
  static constexpr int max_rows = Assembly::max_rows;
  using RowsVector = Eigen::Matrix<T, Eigen::Dynamic, 1, 0, max_rows, 1>;
  static constexpr int max_slip = delassus_bound(std::max(1, 2 * S::nc));
  using SlipVector = Eigen::Matrix<T, Eigen::Dynamic, 1, 0, max_slip, 1>;

  Kinematics<S, T> kin;
  /// J, F, M^{-1} F and D = J M^{-1} F of the contacts taking an impulse (rows, normal_row, ...).
  Assembly assembly;
  RowsVector target, lambda;
  MinNormSolve<T, max_rows> delassus;  ///< D, factorised by value
  /// The impact's restitution coefficients when set (the impact solver's, which knows the
  /// contacts in its problem and those made inelastic); when null, the map takes those of
  /// impact_coefficients() over the contacts the mode gives an impulse (own_coefficients).
  const ImpactCoefficients<nc>* coefficients = nullptr;
  ImpactCoefficients<nc> own_coefficients{};
  std::array<ContactRows, nc> layout{};
  std::array<VecT<T, 2>, nc> slip_direction{};
  VecT<T, nq> v_plus;
  std::array<ContactForce<T>, nc> impulse{};
  // Newton on the implicit spatial slip directions.
  SlipVector y, residual, step, probe_plus, probe_minus;
  MinNormSolver<max_slip> newton_solver;  ///< of the Newton matrix (a double matrix)
  int newton_iterations = 0;

  JumpWorkspace() {
    target.resize(max_rows);
    lambda.resize(max_rows);
  }
};

/// Applies the jump map of `mode` to x- = (q, v-): fills ws.v_plus, ws.impulse and x_plus.
/// For spatial slip the stored direction is the starting guess of the implicit direction.
/// Throws NumericalFailure if that Newton iteration does not converge (a slip that stops within
/// the impact: the mode is wrong, choose stick).
template <Scene S, class T>
void apply_jump_map(const S& scene, const ImpactMode<S::nc>& mode, const VecT<T, 2 * S::nq>& x_minus,
                    JumpWorkspace<S, T>& ws, VecT<T, 2 * S::nq>& x_plus);

}  // namespace saltus
