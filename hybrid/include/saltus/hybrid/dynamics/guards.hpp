// Guards of a mode (thesis 2.42-2.53, A.1, A.16-A.27). Each is a scalar function of the state,
// and for the closed contacts also of the input (through the contact forces), that is positive
// while the mode is valid and crosses zero downwards when the contact changes mode:
//   touchdown   (open -> closed)    gamma = h_n(q)                                     state
//   release     (closed -> open)    gamma = lambda_n(x, u)                             state-input
//   stop        (slip -> stick)     gamma = zeta_t . d   (d: the mode's slip direction) state
//   slip onset  (stick -> slip)     gamma = mu^2 lambda_n^2 - ||lambda_t||^2            state-input
// The thesis writes the slip->stick guard as ||zeta_t||^2 (A.17); its time derivative vanishes
// where it reaches zero, so the event time would not be transversal and the jump gain (C.37)
// would divide by zero. zeta_t . d (planar: s zeta_t) is zero at the same instant and crosses
// it with slope d . zeta_t' != 0.
#pragma once

#include <saltus/hybrid/dynamics/flow.hpp>
#include <saltus/hybrid/vocabulary/guard.hpp>

#include <array>

namespace saltus {


/// Which guards are active in `mode`: open contacts can touch down; closed contacts can release;
/// frictional closed contacts can also stop slipping or start slipping.
template <Scene S>
GuardList<S::nc> active_guards(const S& scene, const Mode<S::nc>& mode) {
  GuardList<S::nc> list;
  for (int i = 0; i < S::nc; ++i) {
    const bool frictional = scene.contact(i).tangents() > 0;
    switch (mode[i].mode) {
      case ContactMode::Open: list.push({i, GuardKind::Touchdown}); break;
      case ContactMode::Stick:
        list.push({i, GuardKind::Release});
        if (frictional) list.push({i, GuardKind::SlipOnset});
        break;
      case ContactMode::Slip:
        list.push({i, GuardKind::Release});
        if (frictional) list.push({i, GuardKind::Stop});
        break;
    }
  }
  return list;
}

/// The value of guard g after evaluate_flow(scene, mode, x, u, ws) has been called.
template <Scene S, class T>
T guard_value(const S& scene, const Mode<S::nc>& mode, const Guard& g, const FlowWorkspace<S, T>& ws) {
  const auto& c = ws.kin.contacts[g.contact];
  const auto& f = ws.force[g.contact];
  switch (g.kind) {
    case GuardKind::Touchdown: return c.gap;
    case GuardKind::Release: return f.normal;
    case GuardKind::Stop: {
      T s = T(0);
      for (int k = 0; k < c.tangents; ++k) s += c.zeta_t[k] * mode[g.contact].slip_direction[k];
      return s;
    }
    case GuardKind::SlipOnset: {
      const double mu = scene.contact(g.contact).mu;
      return T(mu * mu) * f.normal * f.normal - f.tangent.squaredNorm();
    }
  }
  return T(0);
}

}  // namespace saltus
