// Definitions of resimulation.hpp.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <saltus/hybrid/reference/reference_spreading.hpp>
#include <saltus/hybrid/reference/resimulation.hpp>
#include <saltus/hybrid/simulation/simulator.hpp>

namespace saltus {

template <Scene S>
PolishResult<S> polish(const S& scene, const ImportedReference<S>& reference, SimulationOptions options,
                       bool breakpoints_at_samples) {
  reference.validate();
  const auto samples = std::make_shared<const ImportedReference<S>>(reference);
  const double t0 = reference.t.front(), t1 = reference.t.back();
  if (breakpoints_at_samples)
    for (double t : reference.t)
      if (t > t0 && t < t1 && (options.breakpoints.empty() || options.breakpoints.back() != t))
        options.breakpoints.push_back(t);
  const InputLaw<S> input = [samples](double t, const VecT<double, 2 * S::nq>&, const Mode<S::nc>&) {
    return samples->input(t);
  };
  Simulator<S> simulator(scene, options);
  PolishResult<S> result{simulator.run(reference.x.front(), t0, t1, input)};
  const auto& traj = result.trajectory;
  result.imported_events = reference.event_times.size();
  result.simulated_events = traj.events.size();
  // The events paired in order; with different counts only the first min(counts) pair up.
  double paired_distance = 0.0;
  for (std::size_t e = 0; e < std::min(result.imported_events, result.simulated_events); ++e)
    paired_distance = std::max(paired_distance, std::abs(reference.event_times[e] - traj.events[e].t));
  result.event_time_distance = result.imported_events == result.simulated_events
                                   ? paired_distance
                                   : std::numeric_limits<double>::infinity();
  // The segments are spread over the paired events' time differences also when the counts
  // differ (an extra simulated event, e.g. a stick onset at the very end): without it a pre-event
  // sample 1e-12 s after a simulated event was compared with the post-event state (a distance of
  // the size of the jump itself).
  ExtensionOptions spread;
  spread.before = spread.after = 2 * paired_distance + 1e-12 * (1 + std::abs(t1));
  spread.integrator = options.integrator;
  const ExtendedReference<S> extended(scene, traj, spread);
  for (std::size_t k = 0; k < reference.size(); ++k) {
    const double t = reference.t[k];
    const int s = reference.segment_of(k);
    VecT<double, 2 * S::nq> x_sim;
    if (s < traj.segment_count() && t >= extended.t_begin(s) && t <= extended.t_end(s))
      x_sim = extended.state(s, t);
    else
      x_sim = traj.state_at(t);
    Eigen::Index i = 0;
    const double d = (reference.x[k] - x_sim).cwiseAbs().maxCoeff(&i);
    if (d > result.state_distance || result.worst_component < 0) {
      result.state_distance = std::max(result.state_distance, d);
      result.worst_sample_time = t;
      result.worst_component = static_cast<int>(i);
    }
  }
  return result;
}

}  // namespace saltus
