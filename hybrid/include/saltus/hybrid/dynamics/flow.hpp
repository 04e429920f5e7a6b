// The flow of a mode: x' = f(x, u) with x = (q, v) (thesis 2.40), the contact forces of the
// closed contacts from the Delassus system, for any mix of sticking and slipping contacts.
//
// With the constraint rows J (w_n^T of every closed contact, W_t^T of every sticking one), the
// force columns F (w_n, or w_n - mu W_t d for a contact slipping along d; W_t for sticking
// tangents) and the curvature terms kappa, the accelerations satisfy
//     M a = S u - h + F lambda,        J a + kappa = 0                     (thesis A.21-A.33)
// so that, with a_free = M^{-1}(S u - h),
//     (J M^{-1} F) lambda = -(J a_free + kappa),     a = a_free + M^{-1} F lambda.
// J M^{-1} F is the Delassus matrix D of A.15/A.33 (symmetric when nothing slips; A.25 when all
// contacts slip). It is singular when contacts are redundant (a box resting flat on two
// corners has equal tangent rows; the spatial box on four corners has 12 rows for 6 degrees of
// freedom). Then the forces are not unique; the accelerations are, unless redundant contacts
// slip along different directions (a box sliding flat on four corners while it turns: the null
// vector of J M^-1 F then changes M^-1 F lambda, derivation in impact.hpp's file comment; for the
// mode's slip directions the acceleration is undetermined there, and the rule below is Saltus'
// selection). Saltus returns the
// minimum-Euclidean-norm forces, from a complete orthogonal decomposition whose rank threshold
// (1e-10 relative to the largest pivot) also treats contacts that are redundant up to drift of
// the integrator as redundant. For a symmetric box this splits the load equally. Only the double
// value of each matrix is factorised (linear_solve.hpp); derivatives reuse that factorisation.
//
// Friction split between redundant sticking contacts. The Euclidean minimum-norm split shares a
// tangential load equally between contacts whose tangent rows coincide (the plank-box's two
// corners, the spatial box's four), whatever their normal forces. The stick->slip guard
// mu^2 lambda_n^2 - ||lambda_t||^2 of the less loaded contact would then fire although another
// split holds both in their cones, and the acceleration-level mode selection (an LCP, which finds
// that split) would put the contact back into stick at once: a cycle. So when the Delassus matrix
// is rank deficient and some contact sticks, the tangential forces are chosen to minimise
//     sum_i ||lambda_t,i||^2 / (mu_i lambda_n,i)    over all solutions of the Delassus system
// (normal and slip rows keep unit weight), with lambda_n from the minimum-norm pass. For tangent
// rows that coincide this gives each contact the same friction utilisation
// ||lambda_t,i|| / (mu_i lambda_n,i), so the guards reach zero when the total tangential load
// reaches mu sum lambda_n: slip starts when no split is left, as rigid-body Coulomb friction says.
// A weighted minimum-norm solution is a column scaling: with lambda = diag(s) y, s_j = sqrt(mu
// lambda_n) on tangent columns, y is the minimum-norm solution of (D diag(s)) y = rhs.
#pragma once

#include <saltus/hybrid/dynamics/delassus.hpp>
#include <saltus/hybrid/dynamics/kinematics.hpp>
#include <saltus/hybrid/contact/linear_solve.hpp>
#include <saltus/hybrid/vocabulary/contact_force.hpp>
#include <saltus/hybrid/vocabulary/mode.hpp>

#include <algorithm>
#include <array>

namespace saltus {

/// Preallocated storage for evaluate_flow; one per thread and scalar type.
template <Scene S, class T = double>
struct FlowWorkspace {
  static constexpr int nq = S::nq, nu = S::nu, nc = S::nc, nx = 2 * S::nq;
  using Assembly = DelassusAssembly<S, T>;
  static constexpr int max_rows = Assembly::max_rows;
  using SquareMatrix = typename Assembly::SquareMatrix;
  using RowsVector = Eigen::Matrix<T, Eigen::Dynamic, 1, 0, max_rows, 1>;

  Kinematics<S, T> kin;
  /// J, F, M^{-1} F and D = J M^{-1} F of the closed contacts (rows, normal_row, tangent_row).
  Assembly assembly;
  RowsVector rhs, lambda, work, split_scale;
  SquareMatrix D_scaled;
  MinNormSolve<T, max_rows> delassus;  ///< D, factorised by value
  std::array<ContactRows, nc> layout{};
  std::array<VecT<T, 2>, nc> slip_direction{};  ///< unit direction used by each slipping contact
  /// Baumgarte's constraint stabilisation alpha [1/s], >= 0 (Baumgarte 1972): a closed contact is
  /// held by zeta_n' + 2 alpha zeta_n + alpha^2 h_n = 0 instead of zeta_n' = 0, and a sticking
  /// one's tangential velocity by zeta_t' + alpha zeta_t = 0. On the contact manifold (h_n = zeta_n
  /// = 0, zeta_t = 0) the flow is unchanged; off it (the drift of a discretised flow, which the
  /// acceleration-level condition alone lets grow linearly in time) the drift decays at the rate
  /// alpha. 0 (default): the flow of the hybrid core. Used by the mode-schedule refinement
  /// (RefinementOptions::contact_stabilisation); the event-driven simulator keeps 0.
  double constraint_stabilisation = 0.0;

  VecT<T, nq> a_free, acceleration, free_force;
  VecT<T, nx> xdot;
  std::array<ContactForce<T>, nc> force{};

  FlowWorkspace() {
    rhs.resize(max_rows);
    lambda.resize(max_rows);
    work.resize(max_rows);
    split_scale.resize(max_rows);
    D_scaled.resize(max_rows, max_rows);
  }
};

/// Direction of the friction force of a slipping contact, opposite to -lambda_t / (mu lambda_n).
/// Planar: the sign the mode keeps. Spatial: the current direction of zeta_t while the slip goes
/// on along the mode's direction d, and d itself once the slip speed is at the stop: when
/// zeta_t . d <= 0 (the mode's flow continued past its stop) or ||zeta_t|| <= slip_tolerance.
/// Why: continued with the current direction, the friction would flip with zeta_t at the stop and
/// hold zeta_t at zero from above, so the slip->stick guard zeta_t . d would approach zero without
/// crossing it, and an integrator that steps over the stop (CVODE-BDF at rtol 1e-4 on the spatial
/// box) would miss the event. Continued along d, the guard crosses zero transversally (at the rate
/// d . zeta_t'), as the planar slip's s zeta_t does; reference spreading uses the same
/// continuation. The tolerance: within round-off of the stop, zeta_t / ||zeta_t|| is the direction
/// of round-off (a Runge-Kutta stage a few ulps from the stop turned a straight slide sideways),
/// while the motion spends a time of order slip_tolerance / (its deceleration) there, so taking d
/// costs O(slip_tolerance) in the state. The flow passes 1e-9 times the largest velocity component
/// (at least 1e-9 in the scene's velocity units).
template <class T>
VecT<T, 2> slip_direction_of(const ContactState& state, int tangents, const VecT<T, 2>& zeta_t,
                             double slip_tolerance = 0.0) {
  VecT<T, 2> d = VecT<T, 2>::Zero();
  if (tangents == 1) {
    d[0] = T(state.slip_direction[0] >= 0 ? 1.0 : -1.0);
  } else if (tangents == 2) {
    const double z0 = ad::value_of(zeta_t[0]), z1 = ad::value_of(zeta_t[1]);
    const double along = z0 * state.slip_direction[0] + z1 * state.slip_direction[1];
    const bool at_stop = along <= 0.0 || z0 * z0 + z1 * z1 <= slip_tolerance * slip_tolerance;
    if (at_stop && state.slip_direction.squaredNorm() > 0.0) {
      d[0] = T(state.slip_direction[0]);
      d[1] = T(state.slip_direction[1]);
    } else {
      using std::sqrt;
      const T n = sqrt(zeta_t.squaredNorm());
      if (n > T(0)) d = zeta_t / n;
    }
  }
  return d;
}

/// Evaluates the flow of `mode` at x = (q, v) under input u: fills ws.kin (all contacts),
/// ws.acceleration, ws.xdot and ws.force. Allocation-free. Throws NonSpdMassMatrix.
template <Scene S, class T>
void evaluate_flow(const S& scene, const Mode<S::nc>& mode, const VecT<T, 2 * S::nq>& x,
                   const VecT<T, S::nu>& u, FlowWorkspace<S, T>& ws);

/// Convenience: x' of a mode (allocates nothing beyond the workspace).
template <Scene S, class T>
VecT<T, 2 * S::nq> flow(const S& scene, const Mode<S::nc>& mode, const VecT<T, 2 * S::nq>& x,
                        const VecT<T, S::nu>& u, FlowWorkspace<S, T>& ws) {
  evaluate_flow(scene, mode, x, u, ws);
  return ws.xdot;
}

}  // namespace saltus
