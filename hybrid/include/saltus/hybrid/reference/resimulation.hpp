// Re-simulation of references: polish() re-simulates a reference produced elsewhere (another
// optimiser, an experiment, Saltus' own time-freezing optimiser) with the event-driven simulator
// under its own input, and measures how far the two are apart (the validation protocol's step 5).
// Definitions in resimulation.hxx, compiled once per scene (saltus/hybrid/instantiate.hpp).
#pragma once

#include <saltus/hybrid/simulation/simulation_options.hpp>
#include <saltus/hybrid/vocabulary/trajectory.hpp>

#include <cstddef>

namespace saltus {

/// The result of polishing an imported reference.
template <Scene S>
struct PolishResult {
  HybridTrajectory<S> trajectory;  ///< the re-simulation under the imported input
  /// max over the samples of ||x_imported - x_simulated||_inf. Each sample is compared with the
  /// simulated segment that has seen the same number of events, extended past its ends by
  /// reference spreading (reference_spreading.hpp) over the largest event-time difference of the
  /// events paired in order (the first min(imported, simulated) when the counts differ), so a
  /// sample just before an imported event is not compared with a post-event state because the
  /// simulated event came 1e-11 s earlier; samples outside every such segment are compared with
  /// the simulated state at their time.
  double state_distance = 0.0;
  /// Where state_distance is attained: the sample's time [s] and the state component (0 <= i < 2 nq;
  /// -1 when there is no sample).
  double worst_sample_time = 0.0;
  int worst_component = -1;
  /// max |t_imported - t_simulated| over the events, paired in order; infinite if the counts differ.
  double event_time_distance = 0.0;
  std::size_t imported_events = 0, simulated_events = 0;
};

/// (Not MpccSolverOptions::polish of the time-freezing solver, a branch NLP.)
/// Re-simulates an imported reference with the event-driven simulator from its first sample
/// under its own input, u(t) interpolated linearly between the samples
/// (ImportedReference::input), and measures how far the two are apart (the validation protocol's
/// step 5). With `breakpoints_at_samples` every sample time is an input breakpoint, so that no
/// integration step straddles a kink of the interpolated input. Throws InvalidArgument on a bad
/// reference (validate()), and whatever the simulation throws.
template <Scene S>
PolishResult<S> polish(const S& scene, const ImportedReference<S>& reference, SimulationOptions options = {},
                       bool breakpoints_at_samples = true);

}  // namespace saltus
