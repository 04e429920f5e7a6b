// The validation protocol's item 4 (DESIGN.md): the first-order prediction of a perturbed motion
// against the nonlinear re-simulation of the perturbed system. For eps in `eps_values`, the
// Simulator runs from x(t0) + eps z0 under u + eps v(t) to each sample time t; with k the number
// of jumps the perturbed run has seen, the remainder
//     r(eps) = max_t |x_eps(t) - x_k(t) - eps z_k(t)|_inf
// (x_k: extended segment k of reference spreading, integrated afresh to t at the simulation's
// tolerances; z_k: LinearisedSystem's prediction on that segment) must shrink like eps^2: a
// fitted log-log slope of 2 (>= 1.9 in the protocol) says the prediction is right to first order;
// a slope of 1 says a first-order term is missing. Through a simultaneous event the perturbed run
// sees one jump per micro-event of the conewise piece its deviation falls in (conewise_gain.hpp):
// those count as one reference event. Cost: |eps_values| x |sample_times|
// simulations. Definitions in prediction_check.hxx (saltus/sensitivity/instantiate.hpp).
#pragma once

#include <saltus/hybrid/simulation/simulation_options.hpp>
#include <saltus/sensitivity/conewise_gain.hpp>
#include <saltus/sensitivity/linearisation.hpp>

#include <functional>
#include <vector>

namespace saltus {

/// The remainders r(eps) of a prediction and their fitted order.
struct RemainderFit {
  std::vector<double> eps, remainder;
  double slope = 0.0;             ///< least-squares slope of log r against log eps
  bool structure_matched = true;  ///< every perturbed run saw a jump count the reference has
};

/// Least-squares slope of log y against log x (x, y > 0, at least two points).
double fitted_log_slope(const std::vector<double>& x, const std::vector<double>& y);

/// eps = 1e-2, 1e-3, ..., 1e-6 (the protocol's range).
std::vector<double> default_prediction_eps();

/// r(eps) of lin's prediction from z0 under v (file comment), re-simulating the reference of lin
/// with `options` (use the reference's own). Runs whose jump count or final mode the reference
/// does not have are skipped and clear structure_matched. @throws whatever the Simulator throws.
template <Scene S>
RemainderFit prediction_remainder(const LinearisedSystem<S>& lin, const SimulationOptions& options,
                                  const Vec<2 * S::nq>& z0, const std::function<Vec<S::nu>(double)>& v,
                                  const std::vector<double>& sample_times,
                                  const std::vector<double>& eps_values = default_prediction_eps());

/// r(eps) of the first-order prediction through the simultaneous event `event` of lin's reference
/// in the cone of `piece` (one of lin.conewise_gain(event)'s pieces), relative to the piece's OWN
/// post-event outcome, so also for a piece whose outcome is not the nominal one (conewise_gain.hpp):
///     r(eps) = |x_eps(t) - x_p(t) - eps Phi_p(t, t*) G_z z-|_inf,
/// z- = the prediction of z0 (v = 0) at the end of segment `event` (the events before it ordinary,
/// or conewise with the nominal outcome), x_p the flow of piece.mode_after from (t*, piece.x_plus)
/// (events off), Phi_p z+ its central difference along z+ (step 1e-6 / |z+|), x_eps the Simulator's
/// run from x(t0) + eps z0 with `options`. `structure_matched` requires every run to see the events
/// before (one per ordinary event, one per micro-event at an earlier simultaneous one), one event
/// per micro-event of the piece, none after it before t, and to end in the piece's contact modes
/// (a spatial slip's direction may differ by O(eps)). Whether `piece` belongs to that event and
/// whether z- lies in its cone is not checked: applying another cone's piece is how a test shows
/// that it fails.
/// @throws InvalidArgument (event not simultaneous, t not after it), SimultaneousActivation (an
/// earlier simultaneous event's cone without the nominal outcome), what the Simulator throws.
template <Scene S>
RemainderFit piece_remainder(const LinearisedSystem<S>& lin, const SimulationOptions& options, int event,
                             const Vec<2 * S::nq>& z0, const ConewisePiece<S>& piece, double t,
                             const std::vector<double>& eps_values = default_prediction_eps());

}  // namespace saltus
