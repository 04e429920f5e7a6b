// Definitions of jump_map.hpp (see there for the math).
#pragma once

#include <saltus/hybrid/dynamics/jump_map.hpp>

namespace saltus {

namespace detail {

/// xi_t = zeta_t^+ + e_t zeta_t^- of contact i after a solve of the jump system (ws.kin at x-).
template <Scene S, class T>
VecT<T, 2> tangential_law_velocity(const JumpWorkspace<S, T>& ws, int i) {
  const auto& c = ws.kin.contacts[i];
  const double et = (ws.coefficients ? *ws.coefficients : ws.own_coefficients).tangential[i];
  return VecT<T, 2>(c.Wt.transpose() * ws.v_plus) + T(et) * c.zeta_t;
}

/// Solves the linear jump system for fixed slip directions (ws.slip_direction of spatial slip
/// contacts already set); requires ws.kin evaluated at (q, v-).
template <Scene S, class T>
void solve_jump_system(const S& scene, const ImpactMode<S::nc>& mode, const VecT<T, S::nq>& v_minus,
                       JumpWorkspace<S, T>& ws) {
  constexpr int nc = S::nc;
  for (int i = 0; i < nc; ++i) {
    if (mode[i].role == ImpulseRole::None)
      ws.layout[i] = ContactRows::None;
    else
      ws.layout[i] = mode[i].role == ImpulseRole::Slip ? ContactRows::Slip : ContactRows::Stick;
  }
  if (!ws.coefficients) {
    std::array<bool, nc> taking_part{};
    for (int i = 0; i < nc; ++i) taking_part[i] = mode[i].role != ImpulseRole::None;
    ws.own_coefficients = impact_coefficients(scene, ws.kin, taking_part);
  }
  const ImpactCoefficients<nc>& e = ws.coefficients ? *ws.coefficients : ws.own_coefficients;
  auto& as = ws.assembly;
  as.assemble(scene, ws.kin, ws.layout, ws.slip_direction);
  const int m = as.rows;
  // The impact law (impact_law.hpp): xi_n = 0 on the normal rows (Newton, 2.10), xi_t = 0 on the
  // sticking tangents (2.57 with tangential restitution: zeta_t^+ = -e_t zeta_t^-).
  for (int i = 0; i < nc; ++i) {
    if (as.normal_row[i] < 0) continue;
    const auto& c = ws.kin.contacts[i];
    ws.target[as.normal_row[i]] = c.zeta_n < T(0) ? T(-e.normal[i]) * c.zeta_n : T(0);
    if (as.tangent_row[i] >= 0)
      for (int k = 0; k < c.tangents; ++k) ws.target[as.tangent_row[i] + k] = T(-e.tangential[i]) * c.zeta_t[k];
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

/// R(y) = xi_t(d(y)) - y for the spatial slip contacts, stacked two per contact, with
/// xi_t = zeta_t^+ + e_t zeta_t^- the velocity the impact law's friction opposes.
template <Scene S, class T, class VecIn, class VecOut>
void spatial_slip_residual(const S& scene, const ImpactMode<S::nc>& mode, const VecT<T, S::nq>& v_minus, const VecIn& y,
                           JumpWorkspace<S, T>& ws, VecOut& out) {
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
    const VecT<T, 2> zt = tangential_law_velocity(ws, i);
    out[k] = zt[0] - y[k];
    out[k + 1] = zt[1] - y[k + 1];
    k += 2;
  }
}

}  // namespace detail

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
      const VecT<T, 2> zt = detail::tangential_law_velocity(ws, i);
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
    SALTUS_CHECK_NUMERICS(converged, 
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
