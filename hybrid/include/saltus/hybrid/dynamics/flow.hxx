// Definitions of flow.hpp (see there for the math).
#pragma once

#include <saltus/hybrid/dynamics/flow.hpp>

namespace saltus {

namespace detail {

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

}  // namespace detail

template <Scene S, class T>
void evaluate_flow(const S& scene, const Mode<S::nc>& mode, const VecT<T, 2 * S::nq>& x, const VecT<T, S::nu>& u,
                   FlowWorkspace<S, T>& ws) {
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

  // A slip speed below this is at the stop (slip_direction_of, flow.hpp).
  double slip_tolerance = 0.0;
  for (int k = 0; k < nq; ++k) slip_tolerance = std::max(slip_tolerance, std::abs(ad::value_of(v[k])));
  slip_tolerance = 1e-9 * std::max(1.0, slip_tolerance);
  // Rows and columns of the closed contacts (delassus.hpp), then the right-hand side -kappa.
  for (int i = 0; i < nc; ++i) {
    ws.force[i] = ContactForce<T>{};
    ws.layout[i] = ContactRows::None;
    if (!mode[i].closed()) continue;
    const int nt = kin.contacts[i].tangents;
    if (nt > 0 && mode[i].mode == ContactMode::Slip) {
      ws.slip_direction[i] = slip_direction_of<T>(mode[i], nt, kin.contacts[i].zeta_t, slip_tolerance);
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
    if (ws.constraint_stabilisation > 0.0) {  // Baumgarte (flow.hpp, FlowWorkspace::constraint_stabilisation)
      const double alpha = ws.constraint_stabilisation;
      ws.rhs[as.normal_row[i]] -= T(2.0 * alpha) * c.zeta_n + T(alpha * alpha) * c.gap;
      if (as.tangent_row[i] >= 0)
        for (int k = 0; k < c.tangents; ++k) ws.rhs[as.tangent_row[i] + k] -= T(alpha) * c.zeta_t[k];
    }
  }

  if (m == 0) {
    ws.acceleration = ws.a_free;
  } else {
    as.form(kin);
    ws.rhs.conservativeResize(m);
    ws.rhs.noalias() -= as.J.topRows(m) * ws.a_free;
    ws.lambda.resize(m);
    ws.delassus.solve(as.D, ws.rhs, ws.lambda);
    if (ws.delassus.rank() < m) detail::split_friction_by_utilisation(scene, ws);
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
    SALTUS_CHECK_NUMERICS(false, "the flow is not finite at x = [", xv.transpose(),
                  "] (a non-finite state or input, or a degenerate contact configuration)");
  }
}

}  // namespace saltus
