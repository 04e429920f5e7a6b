// Options of the event-driven simulation (simulator.hpp) and of the event physics it shares with
// the analyses (transition.hpp).
#pragma once

#include <saltus/hybrid/dynamics/impact.hpp>
#include <saltus/hybrid/dynamics/impact_without_collision.hpp>
#include <saltus/hybrid/dynamics/mode_selection.hpp>
#include <saltus/hybrid/simulation/integrator.hpp>

#include <vector>

namespace saltus {

/// Painleve's inconsistent configuration: a closed planar contact sliding with zero normal
/// velocity where no nonnegative normal force keeps it on the surface (W_nn - mu s W_nt <= 0 and
/// a free normal acceleration below zero; dynamics/impact_without_collision.hpp derives it).
struct PainleveOptions {
  /// Refuse (the default): the run throws where it meets one, at its start or later (the
  /// behaviour without this option). ImpactWithoutCollision: the tangential impulse of Genot &
  /// Brogliato, "New results on Painleve paradoxes", Eur. J. Mech. A/Solids 18 (1999) 653-677 --
  /// slip until the slip stops, then stick until the normal velocity is zero again -- is applied
  /// at that instant, recorded as a transition flagged Transition::impact_without_collision (its
  /// impulse in Transition::impulse, role Stick: the total is the contact's stick impulse), and
  /// the run continues in the mode the acceleration-level selection finds after it (stick, slip
  /// from rest or lift-off). Implemented for one closed planar contact: with several closed
  /// contacts, or spatial friction, the run throws ContactProblemFailure naming the case.
  InconsistentContactResolution resolution = InconsistentContactResolution::Refuse;
};

struct SimulationOptions {
  IntegratorOptions integrator;
  ImpactOptions impact;
  ModeSelectionOptions selection;
  PainleveOptions painleve;
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
