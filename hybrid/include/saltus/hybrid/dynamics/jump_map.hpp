// Jump maps x+ = g(x-) for a given post-impact impulse mode (thesis A.34-A.49, generalised to any
// mix of contacts). q is continuous; with the participating contacts' rows J (w_n^T, and W_t^T
// for sticking ones) and impulse columns F (w_n, or w_n - mu W_t d for slip along d; W_t for
// sticking tangents):
//     M (v+ - v-) = F Lambda,    J v+ = target,
//     target_n = -e_n min(zeta_n^-, 0) (Newton's law, 2.10),  target_t = 0 (stick, 2.57),
// hence (J M^{-1} F) Lambda = target - J v-,  v+ = v- + M^{-1} F Lambda.
//
// Slip direction. Saltus follows Coulomb's law on impulses (thesis 2.29-2.30): a slipping
// contact's tangential impulse opposes its POST-impact tangential velocity, d = zeta_t^+/||zeta_t^+||.
// The thesis' explicit map A.36-A.39 uses the ante-impact direction instead, which violates 2.30
// whenever the impulse turns the slip (spatial friction, or coupled contacts). For planar
// contacts the direction is the sign s stored in the impulse mode and the map is linear in v-;
// for spatial contacts d is defined implicitly and solved for by Newton's method on
// R(y) = zeta_t^+(d(y)) - y. The Newton matrix is a central difference of R (it affects only the
// rate of convergence); iterating in the scalar type T until the value has converged, plus two
// more steps, makes the derivatives those of the implicit function (each step contracts their
// error like the value's).
//
// Redundant contacts make J M^{-1} F singular; the post-impact velocity is still unique and the
// impulse returned is the minimum-norm one (same decomposition and threshold as flow.hpp).
#pragma once

#include <saltus/hybrid/dynamics/delassus.hpp>
#include <saltus/hybrid/dynamics/flow.hpp>
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
  /// Restitution per contact overriding the scene's when set (an impact taken as inelastic).
  const std::array<double, nc>* restitution = nullptr;
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

namespace detail {

/// Solves the linear jump system for fixed slip directions (ws.slip_direction of spatial slip
/// contacts already set); requires ws.kin evaluated at (q, v-).
template <Scene S, class T>
void solve_jump_system(const S& scene, const ImpactMode<S::nc>& mode, const VecT<T, S::nq>& v_minus,
                       JumpWorkspace<S, T>& ws) {
  const auto restitution = [&](int i) { return ws.restitution ? (*ws.restitution)[i] : scene.contact(i).restitution; };
  constexpr int nc = S::nc;
  for (int i = 0; i < nc; ++i) {
    if (mode[i].role == ImpulseRole::None)
      ws.layout[i] = ContactRows::None;
    else
      ws.layout[i] = mode[i].role == ImpulseRole::Slip ? ContactRows::Slip : ContactRows::Stick;
  }
  auto& as = ws.assembly;
  as.assemble(scene, ws.kin, ws.layout, ws.slip_direction);
  const int m = as.rows;
  // Newton's law on the normal rows (2.10), tangential rest on the sticking ones (2.57).
  for (int i = 0; i < nc; ++i) {
    if (as.normal_row[i] < 0) continue;
    const auto& c = ws.kin.contacts[i];
    ws.target[as.normal_row[i]] = c.zeta_n < T(0) ? T(-restitution(i)) * c.zeta_n : T(0);
    if (as.tangent_row[i] >= 0)
      for (int k = 0; k < c.tangents; ++k) ws.target[as.tangent_row[i] + k] = T(0);
  }
  ws.v_plus = v_minus;
  if (m == 0) return;
  as.form(ws.kin);
  ws.target.conservativeResize(m);
  ws.target.noalias() -= as.J.topRows(m) * v_minus;
  ws.lambda.resize(m);
  ws.delassus.solve(as.D, ws.target, ws.lambda);
  ws.target.resize(JumpWorkspace<S, T>::max_rows);
  ws.v_plus.noalias() += as.MinvF * ws.lambda;
}

/// R(y) = zeta_t^+(d(y)) - y for the spatial slip contacts, stacked two per contact.
template <Scene S, class T, class VecIn, class VecOut>
void spatial_slip_residual(const S& scene, const ImpactMode<S::nc>& mode, const VecT<T, S::nq>& v_minus,
                           const VecIn& y, JumpWorkspace<S, T>& ws, VecOut& out) {
  using std::sqrt;
  int k = 0;
  for (int i = 0; i < S::nc; ++i) {
    if (mode[i].role != ImpulseRole::Slip || ws.kin.contacts[i].tangents != 2) continue;
    VecT<T, 2> yi(y[k], y[k + 1]);
    const T n = sqrt(yi.squaredNorm());
    ws.slip_direction[i] = n > T(0) ? VecT<T, 2>(yi / n) : VecT<T, 2>(VecT<T, 2>::Zero());
    k += 2;
  }
  solve_jump_system(scene, mode, v_minus, ws);
  k = 0;
  for (int i = 0; i < S::nc; ++i) {
    if (mode[i].role != ImpulseRole::Slip || ws.kin.contacts[i].tangents != 2) continue;
    const VecT<T, 2> zt = ws.kin.contacts[i].Wt.transpose() * ws.v_plus;
    out[k] = zt[0] - y[k];
    out[k + 1] = zt[1] - y[k + 1];
    k += 2;
  }
}

}  // namespace detail

/// Applies the jump map of `mode` to x- = (q, v-): fills ws.v_plus, ws.impulse and x_plus.
/// For spatial slip the stored direction is the starting guess of the implicit direction.
/// Throws NumericalFailure if that Newton iteration does not converge (a slip that stops within
/// the impact: the mode is wrong, choose stick).
template <Scene S, class T>
void apply_jump_map(const S& scene, const ImpactMode<S::nc>& mode, const VecT<T, 2 * S::nq>& x_minus,
                    JumpWorkspace<S, T>& ws, VecT<T, 2 * S::nq>& x_plus) {
  constexpr int nq = S::nq, nc = S::nc;
  const VecT<T, nq> q = x_minus.template head<nq>();
  const VecT<T, nq> v = x_minus.template tail<nq>();
  evaluate_kinematics(scene, q, v, ws.kin);

  int spatial_slips = 0;
  for (int i = 0; i < nc; ++i) {
    ws.impulse[i] = ContactForce<T>{};
    const int nt = ws.kin.contacts[i].tangents;
    if (mode[i].role != ImpulseRole::Slip || nt == 0) continue;
    if (nt == 1) {
      ws.slip_direction[i] = VecT<T, 2>(T(mode[i].slip_direction[0] >= 0 ? 1.0 : -1.0), T(0));
    } else {
      ws.slip_direction[i] = VecT<T, 2>(T(mode[i].slip_direction[0]), T(mode[i].slip_direction[1]));
      ++spatial_slips;
    }
  }

  detail::solve_jump_system(scene, mode, v, ws);
  ws.newton_iterations = 0;
  if (spatial_slips > 0) {
    // Newton on y = zeta_t^+ of the spatial slipping contacts, started from the linear solve.
    const int n = 2 * spatial_slips;
    ws.y.resize(n);
    ws.residual.resize(n);
    ws.step.resize(n);
    ws.probe_plus.resize(n);
    ws.probe_minus.resize(n);
    int k = 0;
    for (int i = 0; i < nc; ++i) {
      if (mode[i].role != ImpulseRole::Slip || ws.kin.contacts[i].tangents != 2) continue;
      const VecT<T, 2> zt = ws.kin.contacts[i].Wt.transpose() * ws.v_plus;
      ws.y[k] = zt[0];
      ws.y[k + 1] = zt[1];
      k += 2;
    }
    double scale = 0.0;
    for (int j = 0; j < n; ++j) scale = std::max(scale, std::abs(ad::value_of(ws.y[j])));
    scale = std::max(scale, 1e-300);
    int extra = 0;
    bool converged = false;
    // Converged at round-off (1e-12 relative), then two more steps for the derivatives.
    for (int it = 0; it < 60 && extra < 3; ++it) {
      detail::spatial_slip_residual(scene, mode, v, ws.y, ws, ws.residual);
      double rnorm = 0.0;
      for (int j = 0; j < n; ++j) rnorm = std::max(rnorm, std::abs(ad::value_of(ws.residual[j])));
      if (rnorm <= 1e-12 * scale) converged = true;
      if (converged) ++extra;
      // Newton matrix by central differences of the value part.
      const double h = 1e-7 * scale;
      auto& newton_matrix = ws.newton_solver.matrix(n);
      for (int j = 0; j < n; ++j) {
        ws.step = ws.y;
        ws.step[j] += T(h);
        detail::spatial_slip_residual(scene, mode, v, ws.step, ws, ws.probe_plus);
        ws.step[j] -= T(2 * h);
        detail::spatial_slip_residual(scene, mode, v, ws.step, ws, ws.probe_minus);
        for (int r = 0; r < n; ++r)
          newton_matrix(r, j) = (ad::value_of(ws.probe_plus[r]) - ad::value_of(ws.probe_minus[r])) / (2 * h);
      }
      ws.newton_solver.factorize();
      // step = J^{-1} R in the scalar type T, J a double matrix applied to each component.
      ws.step = ws.residual;
      detail::apply_inverse([&ws](auto& b) { ws.newton_solver.solve_in_place(b); }, ws.step);
      ws.y -= ws.step;
      ++ws.newton_iterations;
    }
    SALTUS_DEMAND(converged, NumericalFailure,
                  "jump map: the implicit post-impact slip direction did not converge (a spatial "
                  "slip that stops within the impact should be given the stick role)");
    detail::spatial_slip_residual(scene, mode, v, ws.y, ws, ws.residual);
  }

  const auto& as = ws.assembly;
  for (int i = 0; i < nc; ++i) {
    if (as.normal_row[i] < 0) continue;
    const int nt = ws.kin.contacts[i].tangents;
    ws.impulse[i].normal = ws.lambda[as.normal_row[i]];
    if (as.tangent_row[i] >= 0) {
      for (int k = 0; k < nt; ++k) ws.impulse[i].tangent[k] = ws.lambda[as.tangent_row[i] + k];
    } else if (nt > 0) {
      ws.impulse[i].tangent = -T(scene.contact(i).mu) * ws.impulse[i].normal * ws.slip_direction[i];
    }
  }
  x_plus.template head<nq>() = q;
  x_plus.template tail<nq>() = ws.v_plus;
}

}  // namespace saltus
