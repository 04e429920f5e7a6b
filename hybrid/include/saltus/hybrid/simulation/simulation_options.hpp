// Options of the event-driven simulation (simulator.hpp) and of the event physics it shares with
// the analyses (transition.hpp).
#pragma once

#include <saltus/hybrid/dynamics/impact.hpp>
#include <saltus/hybrid/dynamics/mode_selection.hpp>
#include <saltus/hybrid/simulation/integrator.hpp>

#include <vector>

namespace saltus {

struct SimulationOptions {
  IntegratorOptions integrator;
  ImpactOptions impact;
  ModeSelectionOptions selection;
  /// s: guard crossings this close in time form one simultaneous event.
  double simultaneity = 1e-9;
  int max_events = 100000;
  /// Transitions at one instant before the chain is declared cycling.
  int max_chain = 16;
  /// Relative tolerance of "a guard is zero" when a chain is checked.
  double guard_tolerance = 1e-9;
  /// m/s (scene units): impacts slower than this are inelastic; 0 disables the rest criterion.
  double rest_velocity = 0.0;
  /// Consecutive geometrically shrinking intervals between touchdowns (of one contact, or of
  /// contacts in turn) that signal a Zeno accumulation; 4 suffice once the intervals are below
  /// 1e3 simultaneity windows (simulator.hpp).
  int zeno_bounces = 12;
  bool record_dense_output = true;
  /// Times where the input law is not smooth (e.g. a switch at t = 1): the integrator stops and
  /// restarts there, so no step straddles a kink. Sorted or not.
  std::vector<double> breakpoints;
};

}  // namespace saltus
