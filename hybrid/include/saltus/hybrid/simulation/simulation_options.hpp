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
  /// At a detected accumulation: false, the run ends with status Zeno; true, it is continued past
  /// it in the persistent contact mode of the accumulating contacts, from the projected limit state
  /// at the predicted accumulation time (Zeno completion, zeno_completion.hpp), and recorded in
  /// HybridTrajectory::zeno_completions. An accumulation predicted at or after t_final ends the run
  /// with status Zeno either way.
  bool zeno_completion = false;
  bool record_dense_output = true;
  /// Times where the input law is not smooth (e.g. a switch at t = 1): the integrator stops and
  /// restarts there, so no step straddles a kink. Sorted or not.
  std::vector<double> breakpoints;
};

}  // namespace saltus
