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
// freedom). Then the accelerations are still unique but the forces are not: Saltus returns the
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
/// Planar: the sign the mode keeps. Spatial: the current direction of zeta_t (zero only at the
/// stop itself, a set of measure zero that the slip->stick guard ends the mode at).
template <class T>
VecT<T, 2> slip_direction_of(const ContactState& state, int tangents, const VecT<T, 2>& zeta_t) {
  VecT<T, 2> d = VecT<T, 2>::Zero();
  if (tangents == 1) {
    d[0] = T(state.slip_direction[0] >= 0 ? 1.0 : -1.0);
  } else if (tangents == 2) {
    using std::sqrt;
    const T n = sqrt(zeta_t.squaredNorm());
    if (n > T(0)) d = zeta_t / n;
  }
  return d;
}

/// The weighted minimum-norm friction split of redundant sticking contacts (file comment):
/// re-solves the Delassus system D lambda = ws.rhs (m = rows of ws.assembly) with the tangent columns of
/// every sticking contact scaled by sqrt(mu lambda_n), lambda_n from the current ws.lambda.
template <Scene S, class T>
void split_friction_by_utilisation(const S& scene, FlowWorkspace<S, T>& ws) {
  const auto& as = ws.assembly;
  const int m = as.rows;
  double largest_normal = 0.0;
  bool any_stick_tangent = false;
  for (int i = 0; i < S::nc; ++i) {
    if (as.normal_row[i] < 0) continue;
    largest_normal = std::max(largest_normal, std::abs(ad::value_of(ws.lambda[as.normal_row[i]])));
    any_stick_tangent = any_stick_tangent || as.tangent_row[i] >= 0;
  }
  if (!any_stick_tangent || !(largest_normal > 0.0)) return;
  // A contact about to release (lambda_n -> 0) keeps a small positive weight, so the scaled
  // matrix keeps the rank of the unscaled one.
  const double floor = 1e-6 * largest_normal;
  ws.split_scale.resize(m);
  ws.split_scale.setConstant(T(1));
  for (int i = 0; i < S::nc; ++i) {
    if (as.tangent_row[i] < 0) continue;
    using std::sqrt;
    T load = T(std::max(scene.contact(i).mu, 1e-12)) * ws.lambda[as.normal_row[i]];
    if (ad::value_of(load) < floor) load = T(floor);
    const T s = sqrt(load);
    for (int k = 0; k < scene.contact(i).tangents(); ++k) ws.split_scale[as.tangent_row[i] + k] = s;
  }
  ws.D_scaled.resize(m, m);
  ws.D_scaled = as.D * ws.split_scale.asDiagonal();
  ws.delassus.solve(ws.D_scaled, ws.rhs, ws.work);
  ws.lambda = ws.split_scale.cwiseProduct(ws.work);
}

/// Evaluates the flow of `mode` at x = (q, v) under input u: fills ws.kin (all contacts),
/// ws.acceleration, ws.xdot and ws.force. Allocation-free. Throws NonSpdMassMatrix.
template <Scene S, class T>
void evaluate_flow(const S& scene, const Mode<S::nc>& mode, const VecT<T, 2 * S::nq>& x,
                   const VecT<T, S::nu>& u, FlowWorkspace<S, T>& ws) {
  constexpr int nq = S::nq, nc = S::nc;
  const VecT<T, nq> q = x.template head<nq>();
  const VecT<T, nq> v = x.template tail<nq>();
  evaluate_kinematics(scene, q, v, ws.kin);
  auto& kin = ws.kin;

  if constexpr (S::nu > 0)
    ws.free_force.noalias() = kin.S_u * u;
  else
    ws.free_force.setZero();
  ws.free_force -= kin.h;
  kin.solve_mass(ws.free_force, ws.a_free);

  // Rows and columns of the closed contacts (delassus.hpp), then the right-hand side -kappa.
  for (int i = 0; i < nc; ++i) {
    ws.force[i] = ContactForce<T>{};
    ws.layout[i] = ContactRows::None;
    if (!mode[i].closed()) continue;
    const int nt = kin.contacts[i].tangents;
    if (nt > 0 && mode[i].mode == ContactMode::Slip) {
      ws.slip_direction[i] = slip_direction_of<T>(mode[i], nt, kin.contacts[i].zeta_t);
      ws.layout[i] = ContactRows::Slip;
    } else {
      ws.layout[i] = ContactRows::Stick;  // sticking: the tangential velocity is held at zero
    }
  }
  auto& as = ws.assembly;
  as.assemble(scene, kin, ws.layout, ws.slip_direction);
  const int m = as.rows;
  for (int i = 0; i < nc; ++i) {
    if (as.normal_row[i] < 0) continue;
    const auto& c = kin.contacts[i];
    ws.rhs[as.normal_row[i]] = -c.kappa_n;
    if (as.tangent_row[i] >= 0)
      for (int k = 0; k < c.tangents; ++k) ws.rhs[as.tangent_row[i] + k] = -c.kappa_t[k];
  }

  if (m == 0) {
    ws.acceleration = ws.a_free;
  } else {
    as.form(kin);
    ws.rhs.conservativeResize(m);
    ws.rhs.noalias() -= as.J.topRows(m) * ws.a_free;
    ws.lambda.resize(m);
    ws.delassus.solve(as.D, ws.rhs, ws.lambda);
    if (ws.delassus.rank() < m) split_friction_by_utilisation(scene, ws);
    ws.rhs.resize(FlowWorkspace<S, T>::max_rows);
    ws.acceleration = ws.a_free;
    ws.acceleration.noalias() += as.MinvF * ws.lambda;
  }

  for (int i = 0; i < nc; ++i) {
    if (as.normal_row[i] < 0) continue;
    const int nt = kin.contacts[i].tangents;
    ws.force[i].normal = ws.lambda[as.normal_row[i]];
    if (as.tangent_row[i] >= 0) {
      for (int k = 0; k < nt; ++k) ws.force[i].tangent[k] = ws.lambda[as.tangent_row[i] + k];
    } else if (nt > 0) {
      ws.force[i].tangent = -T(scene.contact(i).mu) * ws.force[i].normal * ws.slip_direction[i];
    }
  }
  ws.xdot.template head<nq>() = v;
  ws.xdot.template tail<nq>() = ws.acceleration;
  if (!ws.xdot.allFinite()) {
    VecT<double, 2 * nq> xv;
    for (int k = 0; k < 2 * nq; ++k) xv[k] = ad::value_of(x[k]);
    SALTUS_DEMAND(false, NumericalFailure, "the flow is not finite at x = [", xv.transpose(),
                  "] (a non-finite state or input, or a degenerate contact configuration)");
  }
}

/// Convenience: x' of a mode (allocates nothing beyond the workspace).
template <Scene S, class T>
VecT<T, 2 * S::nq> flow(const S& scene, const Mode<S::nc>& mode, const VecT<T, 2 * S::nq>& x,
                        const VecT<T, S::nu>& u, FlowWorkspace<S, T>& ws) {
  evaluate_flow(scene, mode, x, u, ws);
  return ws.xdot;
}

}  // namespace saltus
