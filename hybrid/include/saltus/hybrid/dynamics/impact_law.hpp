// The restitution coefficients one impact uses: the Newton-type impact law of Glocker
// ("Energetic consistency conditions for standard impacts, Part I: Newton-type inequality impact
// laws and Kane's example", Multibody System Dynamics 29 (2013) 77-117) in Delassus form.
//
// The Signorini-Coulomb conditions of an impact act on the velocities
//     xi_n = zeta_n^+ + e_n min(zeta_n^-, 0),      xi_t = zeta_t^+ + e_t zeta_t^-
// of every contact taking part (xi_n >= 0, Lambda_n >= 0, xi_n Lambda_n = 0; Lambda_t opposes
// xi_t, ||Lambda_t|| <= mu Lambda_n). With e_t = 0 this is Newton's kinematic law of the thesis
// (2.10 with 2.29-2.30); with friction and e_n > 0 it can create energy (Kane and Levinson's
// double pendulum: KE+/KE- up to 8.9 for e_n = 1, mu = 0.3, measured in test_impact).
//
// Why one coefficient e for all rows keeps KE+ <= KE- (derived here; Glocker's Part I states it
// as e_n = e_t). Stack the rows of the contacts taking part: gamma = W v, G = W M^{-1} W^T the
// Delassus matrix (positive semidefinite), gamma^+ = gamma^- + G Lambda, and for a scleronomic
// contact the kinetic energy changes by
//     dT = Lambda^T gamma^- + 1/2 Lambda^T G Lambda = Lambda^T gamma^+ - 1/2 Lambda^T G Lambda.
// Write c for the rows of gamma^- the law uses (c_t = zeta_t^-, c_n = min(zeta_n^-, 0)), so
// xi = gamma^+ + e c. Then e times the first form plus the second gives
//     (1 + e) dT = Lambda^T xi - (1 - e)/2 Lambda^T G Lambda + e Lambda^T (gamma^- - c).
// Coulomb and Signorini give Lambda^T xi = Lambda_n xi_n + Lambda_t^T xi_t = -mu Lambda_n ||xi_t||
// <= 0; the second term is <= 0 for e <= 1; the last is e sum Lambda_n max(zeta_n^-, 0), zero
// unless a contact already separating at the impact receives an impulse (a contact within the
// gap tolerance but moving away: the gain is then at most e Lambda_n zeta_n^- / (1 + e), of the
// order of that contact's separation speed). So dT <= 0 whenever all rows share one e in [0, 1].
// With different coefficients on different rows the cancellation fails, and Kane's example shows
// that e_t = 0 < e_n does gain energy.
//
// Default (every contact of the impact leaves `tangential_restitution` unset): the energy-
// consistent law, one coefficient e* for all normal and tangential rows of the impact, the
// smallest e_n among the approaching contacts taking part (zeta_n^- < 0), 0 if one of them is
// made inelastic (the simulator's rest criterion) or none approaches. A single contact, or
// contacts sharing e_n (every scene of the library), use their own e_n; a sticking contact
// then leaves with zeta_t^+ = -e zeta_t^- (tangential restitution), and a contact that was
// already closed and sliding when another one impacts has its slip reversed in proportion.
// Explicit per-contact coefficients (any contact of the impact sets `tangential_restitution`):
// each contact uses its own e_n and e_t, the general Newton-type law, energy-consistent only if
// all the impact's coefficients are equal (`energy_consistent` says whether they are); e_t = 0
// everywhere is the thesis' kinematic law.
//
// Where the two laws differ (friction and e_n > 0), the exits differ visibly: a disk dropped onto
// a slope that sticks leaves rolling under the kinematic law and over-spun under the default; a
// box landing while sliding stops under the kinematic law and bounces backward under the
// default (closed forms: tests/test_impact_law.cpp; numbers: README, impacts with restitution).
#pragma once

#include <saltus/hybrid/dynamics/kinematics.hpp>

#include <algorithm>
#include <array>

namespace saltus {

/// Restitution coefficients of one impact, per contact (entries of contacts not taking part
/// are 0).
template <int nc>
struct ImpactCoefficients {
  std::array<double, nc> normal{};      ///< e_n used on contact i's normal row
  std::array<double, nc> tangential{};  ///< e_t used on contact i's tangential rows
  bool energy_consistent = true;        ///< all coefficients of the impact equal (KE+ <= KE-)
};

/// The coefficients of the impact of the contacts with `taking_part[i]`, at the pre-impact
/// kinematics `kin` (only zeta_n^- of those contacts is read, by value); `inelastic[i]` sets
/// contact i's coefficients to 0 (the simulator's rest criterion). See the header comment for
/// the rule. Throws nothing.
template <Scene S, class T>
ImpactCoefficients<S::nc> impact_coefficients(const S& scene, const Kinematics<S, T>& kin,
                                              const std::array<bool, S::nc>& taking_part,
                                              const std::array<bool, S::nc>& inelastic = {}) {
  constexpr int nc = S::nc;
  ImpactCoefficients<nc> out;
  bool per_contact = false;
  for (int i = 0; i < nc; ++i) per_contact = per_contact || (taking_part[i] && scene.contact(i).tangential_restitution);
  if (!per_contact) {
    double e = 1.0;
    bool approaching = false;
    for (int i = 0; i < nc; ++i) {
      if (!taking_part[i] || !(ad::value_of(kin.contacts[i].zeta_n) < 0.0)) continue;
      approaching = true;
      e = std::min(e, inelastic[i] ? 0.0 : scene.contact(i).restitution);
    }
    if (!approaching) e = 0.0;
    for (int i = 0; i < nc; ++i)
      if (taking_part[i]) out.normal[i] = out.tangential[i] = e;
    return out;
  }
  double first = -1.0;
  for (int i = 0; i < nc; ++i) {
    if (!taking_part[i]) continue;
    const ContactSpec& c = scene.contact(i);
    out.normal[i] = inelastic[i] ? 0.0 : c.restitution;
    out.tangential[i] = inelastic[i] ? 0.0 : c.tangential_restitution.value_or(c.restitution);
    const bool frictionless = c.tangents() == 0 || c.mu == 0.0;
    for (double e : {out.normal[i], frictionless ? out.normal[i] : out.tangential[i]}) {
      if (first < 0.0) first = e;
      out.energy_consistent = out.energy_consistent && e == first;
    }
  }
  return out;
}

}  // namespace saltus
