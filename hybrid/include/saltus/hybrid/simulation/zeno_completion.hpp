// Zeno completion: the limit state from which a motion is continued past an accumulation of
// impacts (SimulationOptions::zeno_completion).
//
// The construction is the completion of a Lagrangian hybrid system (A. D. Ames, H. Zheng,
// R. D. Gregg, S. Sastry, "Is there life after Zeno? Taking executions past the breaking (Zeno)
// point", American Control Conference 2006; Y. Or, A. D. Ames, "Stability and completion of Zeno
// equilibria in Lagrangian hybrid systems", IEEE Trans. Automatic Control 56(6), 2011): at the
// accumulation time t_inf the configuration converges to a point of the constraint surface
// h_n(q) = 0 and the normal velocity to zero, and the motion continues on the holonomically
// constrained system (the contact closed) from that limit. Here the constraint is that of every
// accumulating contact at once (the contacts that touched down within the detection window, one
// or several, alternating or simultaneous: a rocking block's two corners, a flat box's base),
// together with the contacts already closed in the current mode.
//
// The limit state. The simulator resolves the accumulation up to its last touchdown t_k and
// extrapolates t_inf from the touchdown times (simulator.hpp). The limit state is the state x_k
// after that touchdown projected onto the persistent mode's constraints in the kinetic metric
// (dynamics/constraints.hpp):
//     q <- q - M^{-1} G^T (G M^{-1} G^T)^+ h_n(q)            (Gauss-Newton, to round-off)
//     v <- v - M^{-1} J^T (J M^{-1} J^T)^+ J v               (J: the normal rows w_n^T)
// the least-squares change in the kinetic metric that closes the gaps and zeroes the normal
// velocities, a frictionless plastic impulse weighted by the Delassus matrix J M^{-1} J^T (its
// pseudo-inverse takes redundant contacts, a box flat on its corners). Sticking contacts of the
// current mode keep their tangential rows too. The neglected part is the motion over the tail
// t_inf - t_k in the directions the constraints leave free: of order |v| (t_inf - t_k) in q and
// |a| (t_inf - t_k) in v. The mode that continues is chosen from the projected state by the
// acceleration-level selection of a start (TransitionResolver::start): the accumulating contacts
// stay closed (stick or slip) where the contact forces hold them, which is the persistent mode of
// a body come to rest.
#pragma once

#include <saltus/hybrid/dynamics/constraints.hpp>
#include <saltus/hybrid/dynamics/kinematics.hpp>
#include <saltus/hybrid/vocabulary/errors.hpp>
#include <saltus/hybrid/vocabulary/mode.hpp>

#include <array>
#include <cmath>

namespace saltus {

/// The limit state of an accumulation (file comment): x (2 nq, q then v: the state after the
/// last touchdown) projected onto the contacts closed in `mode` (kept as they are: a sticking
/// contact also keeps its tangential velocity) and the `accumulating` ones (gap and normal velocity
/// zeroed). `gap_tolerance` (m, scene units): the gaps the projection must reach.
/// @throws NumericalFailure when a projected gap stays above gap_tolerance (the constraints of the
/// accumulating contacts cannot hold together: not a persistent contact mode); NonSpdMassMatrix.
template <Scene S>
VecT<double, 2 * S::nq> zeno_limit_state(const S& scene, const VecT<double, 2 * S::nq>& x, const Mode<S::nc>& mode,
                                         const std::array<bool, S::nc>& accumulating, double gap_tolerance,
                                         ConstraintProjection<S>& projection) {
  constexpr int nq = S::nq, nc = S::nc;
  Mode<nc> persistent = mode;
  for (int i = 0; i < nc; ++i)
    if (accumulating[i] && !persistent[i].closed())
      persistent[i] = ContactState{ContactMode::Slip, Eigen::Vector2d::Zero()};  // normal rows only
  VecT<double, 2 * nq> limit = x;
  projection.max_iterations = 20;
  projection.project(scene, persistent, limit);
  Kinematics<S> kin;
  evaluate_kinematics(scene, VecT<double, nq>(limit.template head<nq>()), VecT<double, nq>(limit.template tail<nq>()),
                      kin);
  for (int i = 0; i < nc; ++i)
    SALTUS_CHECK_NUMERICS(!persistent[i].closed() || std::abs(kin.contacts[i].gap) <= gap_tolerance,
                          "Zeno completion: contact '", scene.contact(i).name, "' is at gap ", kin.contacts[i].gap,
                          " after the projection of the accumulation's limit state (tolerance ", gap_tolerance,
                          "): the accumulating contacts cannot all be closed");
  return limit;
}

}  // namespace saltus
