// Options of the mode-schedule refinement (refinement.hpp), nested by concern: the collocation
// grid, Ipopt, the schedule edits, the mesh refinement, the checks and the implied-row test.
#pragma once

#include <saltus/timefreezing/mpcc/mpcc_solver.hpp>

#include <iosfwd>
#include <vector>

namespace saltus::timefreezing {

/// The collocation grid of the refinement: per phase, N_p elements of equal length d_p / N_p
/// (d_p the phase's duration, a variable), each a Radau IIA step (discretisation/radau.hpp).
struct RefinementGrid {
  /// n_s of Radau IIA, 1 .. 5 (order 2 n_s - 1; 5: the degree of the dense output's pieces).
  int stages = 3;
  /// N_p = max(min_elements, ceil(d_p,guess / max_element_duration)) [s], > 0.
  double max_element_duration = 0.02;
  int min_elements = 2;                ///< >= 1
  /// In [0, 1]: where a phase's element boundaries sit, s_k = (1 - c) k / N_p + c (1 - cos(pi k / N_p)) / 2
  /// (fractions of the phase, k = 0 .. N_p): 0 uniform; 1 the Chebyshev-Lobatto points, the first and
  /// last elements about pi^2 / (4 N_p) of a uniform one's length. Phases begin and end at events,
  /// where the motion is often fastest (a push-off into a lift-off, docs/refinement.md, "Hopper").
  double end_clustering = 0.0;
  /// Explicit element boundaries, one list per phase of the schedule (empty: the rule above): phase
  /// p's boundaries as fractions of its duration, 0 = s_0 < s_1 < ... < s_N = 1, N >= 1 elements.
  /// When given, max_element_duration, min_elements and end_clustering are not used. The mesh
  /// refinement (RefinementMesh) writes them; a schedule edit returns to the rule.
  std::vector<std::vector<double>> element_boundaries;
};

/// Local-error mesh refinement after the schedule's last solve (refinement.hpp, "Mesh
/// refinement"): every element whose local error exceeds the tolerance is split, the NLP is
/// solved again from the previous solution, until every element is within the tolerance.
struct RefinementMesh {
  /// Largest local error [state units] of an element: the distance between its collocation end
  /// state and the exact flow of its phase's mode from its start state under its input
  /// (ScheduleRefinementNlp::element_local_errors). 0: no mesh refinement.
  double local_error_tolerance = 0.0;
  int max_rounds = 6;   ///< solves after the first at most, >= 0
  /// An element is split into k = ceil((error / (safety * tolerance))^(1 / (n_s + 1))) equal
  /// elements, 2 <= k <= max_split (the stage order n_s + 1 of the local error, the cautious one
  /// of Radau IIA's two: the end point's is 2 n_s).
  int max_split = 8;
  double safety = 0.25;  ///< in (0, 1]
  /// Ipopt iterations at most per round (>= 0; capped by RefinementIpopt::max_iter). A round that
  /// does not solve ends the mesh refinement with the previous grid's solution.
  int max_iter = 500;
  /// Ipopt's mu_init for the solves started from a previous solution. Ipopt's own default, 0.1:
  /// measured on the hopper (h = 0.05 s, tolerance 1e-2, max_split 4), a barrier parameter of 1e-6
  /// that would keep the warm start's active bounds took 209 iterations on the second round against
  /// 152, and stalled on the third (dual infeasibility 4e14) where 0.1 took 19 iterations: the
  /// coarse optimum is far from the fine one (objective 981 -> 164), not a point to stay near.
  /// Between 1e-4 and 0.1 it changes nothing under the solver's adaptive barrier strategy
  /// (MpccSolverOptions::IpoptSettings::solver_defaults: Ipopt's oracle sets the barrier
  /// parameter): the hopper's chain at local error 2e-8, every round started from the primal guess
  /// alone, took the same 122, 76, 72, 37, 26 and 27 iterations with 0.1, 1e-2 and 1e-4.
  double warm_start_mu = 0.1;
  /// A round that splits at most this fraction of the previous grid's elements (in [0, 1]; 0:
  /// none, 1: every round) starts from the previous grid's multipliers as well
  /// (ScheduleRefinementNlp::warm_start_from: the costate rows as they are, the O(h) rows in
  /// proportion to the split), with Ipopt's warm_start_init_point and mu_init =
  /// dual_warm_start_mu; the others from the primal guess alone at mu_init = warm_start_mu.
  /// Measured on the hopper's chain (local error 2e-8; docs/refinement.md, "Where the refinement's
  /// time goes"), every round warm-started with its multipliers: the rounds that split 2 of 456
  /// and 7 of 448 elements took 8 and 17 iterations against 27 and 26, the one that split 41 of
  /// 387 took 36 against 37, while the first two, which split 51 of 57 and 82 of 203 elements and
  /// move the objective from 334 to 163 to 113, took 88 and 76 against 76 and 72: where most
  /// of the grid changes, the old multipliers belong to another solution.
  double dual_warm_start_split_fraction = 0.1;
  double dual_warm_start_mu = 1e-6;  ///< Ipopt's mu_init for a dual warm start, > 0
  // The rounds are reproducible: they order MUMPS by AMD (Ipopt's mumps_pivot_order 0, set before
  // RefinementIpopt::options). MUMPS' automatic choice made two identical runs of the hopper's
  // rounds take 177 and 132, then 123 and 253 iterations; with AMD three runs agree to every
  // iteration (docs/refinement.md, "Mesh refinement by the local error").
};

/// Ipopt on the refinement NLP (a plain NLP: no complementarity pairs).
struct RefinementIpopt {
  double tol = 1e-10;    ///< Ipopt `tol`, > 0
  int max_iter = 500;    ///< Ipopt `max_iter` per solve, >= 0
  int print_level = 0;   ///< Ipopt `print_level` (0..12)
  /// Ipopt's own options by name, applied last (e.g. {"hessian_approximation", "limited-memory"}).
  std::vector<IpoptOption> options;
};

/// The schedule edits after a solve (refinement.hpp, "Schedule edits").
struct RefinementEdits {
  int max_edits = 4;                 ///< solves after the first, >= 0 (0: no edit, only the check)
  /// A validity row (lambda_n >= 0 of a closed contact, gap >= 0 of an open one) counts as active
  /// at a stage point where its value is <= active_tolerance (scene units) ...
  double active_tolerance = 1e-7;
  /// ... and its multiplier is >= multiplier_threshold (objective units per row unit).
  double multiplier_threshold = 1e-6;
  /// A phase wants to vanish when its duration is <= vanishing_duration [s] at the optimum.
  double vanishing_duration = 1e-6;
  /// Ipopt iterations at most for the solve of an edited schedule (>= 0; capped by
  /// RefinementIpopt::max_iter). An edit that does not solve is rejected; measured on the
  /// plank-box (h = 0.02 s): the accepted lift-off edit took 107 iterations, the rejected vanish
  /// edit ran into the 500 of max_iter (155 s).
  int max_iter = 200;
};

/// What "refined" means (RefinementResult::stage): a converged last solve AND these checks.
struct RefinementChecks {
  /// mode_validity_violation <= this (scene units: m, N, m/s). The refinement sets Ipopt's
  /// bound_relax_factor to 0 (RefinementIpopt::options can set it again), so the validity rows
  /// hold to the constraint tolerance rather than to Ipopt's 1e-8 relaxation of the bounds.
  double mode_validity = 1e-9;
  /// phase_resim_max_error <= this [state units] ("exact": 1e-6 on the default grid).
  double phase_resimulation = 1e-6;
  /// [s] 0: each phase re-simulated from its start to its end (single shooting). > 0: in windows
  /// that start at element boundaries at least this far apart (the last runs to the phase's end
  /// and may be shorter; a shorter phase is one window), the first from the phase's start as with
  /// 0, each later one from the reference's state at its start projected onto the phase's closed
  /// contacts (multiple shooting). A phase whose open-loop motion is unstable amplifies the
  /// reference's local errors by exp(rate * duration) over a single shot (the hopper's stances:
  /// about 40 / s, so about 2e10 over its 0.59 s first stance; docs/refinement.md): no
  /// double-precision reference passes 1e-6 there, and the windows measure the reference instead
  /// of the instability. Passing in windows is the weaker statement (the reference's error over
  /// each window, not the open-loop motion's). PhaseResimulation::windows reports the number of
  /// windows per phase. Negative or not finite: refine_schedule throws InvalidArgument.
  double resimulation_window = 0.0;
};

struct RefinementOptions {
  RefinementGrid grid;
  RefinementIpopt ipopt;
  RefinementEdits edits;
  RefinementChecks checks;
  RefinementMesh mesh;
  /// d_p >= min_phase_duration [s] for every phase (>= 0; 0: a phase may shrink to a point).
  double min_phase_duration = 0.0;
  /// In [0, 1). A sticking contact's cone rows inside its phase are
  /// (1 - stick_cone_margin) mu lambda_n -+ lambda_t >= 0: the refined stick keeps a relative
  /// distance from the friction cone's edge, where the event-driven simulator's mode selection may
  /// equally start a slip and the re-simulation departs from the reference (the hopper's stances,
  /// docs/refinement.md). 0: the cone itself. The guards (slip onset, release) and the impact rows
  /// keep the cone itself; mode_validity_violation reads the rows as imposed (with the margin), so
  /// the physical cone holds with room to spare where it is small.
  double stick_cone_margin = 0.0;
  /// [m/s], >= 0. A slipping contact's sign row inside its phase is s zeta_t - slip_speed_margin
  /// w(s) >= 0 instead of s zeta_t >= 0: the refined slide keeps a speed away from rest, where a
  /// perturbed motion would stop (slip -> stick) and the reference's first-order gain no longer
  /// describes it. w is 1, ramped linearly to 0 over the first quarter of a phase that a slip onset
  /// of the contact starts (the slide starts from rest) and over the last quarter of one that its
  /// stop ends. Without it the plank-box flat landing's optimal slide reaches rest exactly at its
  /// lift-off: 46 of 100 perturbed runs ended 1.33 times the first-order deviation, and those
  /// simulated alone had stopped a few microseconds before the release (docs/refinement.md). mode_validity_violation
  /// reads the rows as imposed. 0: the sign itself.
  double slip_speed_margin = 0.0;
  /// [N], >= 0. A closed contact that the schedule does not release at its phase's end (it stays
  /// closed into the next phase, or the phase is the last) has the row lambda_n - normal_force_margin
  /// >= 0 inside the phase instead of lambda_n >= 0: the refined stance keeps its foot loaded, so
  /// that a perturbed motion tracking it is less likely to lift the foot off (the hopper's last
  /// stance, where its Monte Carlo runs do: docs/refinement.md; not measured there yet). A stance
  /// that ends in a release keeps lambda_n >= 0 (its force reaches 0 at the release by design).
  /// mode_validity_violation reads the rows as imposed. 0: no margin.
  double normal_force_margin = 0.0;
  /// [N], >= 0. A closed contact that the schedule releases at its phase's end has the row
  /// lambda_n - stance_load 4 s (1 - s) >= 0 inside the phase, s in [0, 1] the fraction of the
  /// phase: a hump of peak stance_load, 0 at the phase's ends (the force may start anywhere after a
  /// touchdown and falls through 0 at the release, now at a rate of at least 4 stance_load per
  /// phase duration). The stance's counterpart of flight_clearance: without it the cheapest stance
  /// before a release may be a grazing one, its foot barely loaded (the hopper's stance before its
  /// last flight: lambda_n 0.13 N 5 ms before the release against the body's weight of 60 N), whose
  /// friction cone the event-driven re-simulation leaves between stage points (docs/refinement.md).
  /// With releases_at_input_jumps the row is lambda_n - stance_load >= 0 over the whole phase (the
  /// force need not fall to 0 at a release by an input jump; a stance that starts at a touchdown
  /// with lambda_n = 0 may open again at once in the simulator, measured on the hopper).
  /// mode_validity_violation reads the rows as imposed. 0: none.
  double stance_load = 0.0;
  /// [N], >= 0. A contact that a touchdown closes starts its stance loaded: its lambda_n row in
  /// that phase is lambda_n - max(b, touchdown_load (1 - 4 s)) >= 0 over the first quarter of the
  /// phase (s the phase fraction, b the bound of the options above), so that lambda_n >=
  /// touchdown_load at the post-impact state. Without it the cheapest landing may put the foot
  /// down with no load (the hopper's touchdown at 1.9123 s: lambda_n = 1.7e-7 N right after the
  /// impact), and every perturbed run of a tracking design either lifts the foot again at once or
  /// leaves the friction cone there (docs/refinement.md). mode_validity_violation reads the rows
  /// as imposed. 0: none.
  double touchdown_load = 0.0;
  /// [m], >= 0. An open contact's row inside its phase is h_n - flight_clearance b(s) >= 0, s in
  /// [0, 1] the fraction of the phase and b a hump of peak 1 that is 0 at the phase's ends (a
  /// lift-off starts and a touchdown ends at h_n = 0): b = 4 s (1 - s), or (256/27) s^3 (1 - s) when
  /// a release starts the phase (the gap rises like s^3 after it; refinement_nlp_blocks.hxx,
  /// ScheduleRefinementNlp::clearance); per phase, not per flight (a
  /// flight split into several phases gets one hump each). Without it the cheapest flight may skim
  /// the ground, and a perturbed motion, or the event-driven re-simulation, touches down there (two
  /// flights of the hopper's discovered gait, docs/refinement.md). mode_validity_violation reads
  /// the rows as imposed. 0: no clearance.
  double flight_clearance = 0.0;
  /// [m/s], >= 0. A touchdown's approach row is zeta_n(x-) <= -touchdown_speed instead of <= 0:
  /// the foot comes in at least that fast along the contact normal. A touchdown that comes in
  /// nearly tangentially has a saltation matrix of norm about (tangential speed / normal speed)
  /// (the hopper's chain without it: 2.4e3 .. 2.9e5 at four of its six touchdowns), and a tracking
  /// design's perturbed runs meet the ground at very different times and states there
  /// (docs/refinement.md). mode_validity_violation reads the rows as imposed. 0: approaching only.
  double touchdown_speed = 0.0;
  /// Releases at an input jump (refinement_nlp.hpp, "RELEASE AT AN INPUT JUMP"): false, a release
  /// is the guard lambda_n(x-, u-) = 0 (the force falls to zero under the stance's last input);
  /// true, the release guard is not imposed: the stance's validity rows hold at x- (lambda_n >= 0,
  /// a sticking contact in its cone) and the flight's first input makes the contact separate
  /// (h_n''(x-, u+) >= 0, RELEASE CONSISTENCY), so the force may drop from any value to zero where
  /// the piecewise-constant input jumps at the phase's end. The event-driven simulator finds such a
  /// release at the input breakpoint (Simulator: a guard due under the input after a breakpoint is
  /// an event there). Without it, a push-off that wants its force up to the lift-off spends its
  /// last, sub-millisecond element unloading the foot (the hopper, docs/refinement.md).
  bool releases_at_input_jumps = false;
  /// [1/s], >= 0. Baumgarte's stabilisation of the closed contacts in every phase's flow
  /// (FlowWorkspace::constraint_stabilisation): zeta_n' + 2 a zeta_n + a^2 h_n = 0 and, sticking,
  /// zeta_t' + a zeta_t = 0, a = contact_stabilisation. The phase's start imposes h_n = zeta_n = 0
  /// (and zeta_t = 0 when sticking), where the stabilised flow is the mode's flow; what it changes
  /// is the collocation's drift off that manifold, which without it grows with the phase's length
  /// (each element's local error adds to it) and reaches the re-simulation as the distance of its
  /// projected starts (PhaseResimulation::start_projection) and as a released contact's gap at a
  /// lift-off. 0: the mode's flow as the hybrid core defines it.
  double contact_stabilisation = 0.0;
  /// An equality path row of a phase whose gradient lies in the span of the closed contacts' gap
  /// gradients (relative least-squares residual <= this, and no dependence on v and u) is implied
  /// by the mode and is not imposed inside the phase; a guard whose gradient lies in the span of
  /// the rows already imposed at its event is implied the same way (refinement_nlp.hpp,
  /// "IMPLIED ROWS"). In (0, 1).
  double implied_row_tolerance = 1e-4;
  /// Dimensionless, > 0 (else refine_schedule throws InvalidArgument). A terminal equality row
  /// that does not depend on T and whose x-gradient lies in the span of the last phase's closed
  /// contacts' rows (h_n, zeta_n) and of the terminal rows kept before it (in index order) is
  /// implied only if its bound holds, to this tolerance times (1 + |bound|) in the row's units, on
  /// the manifold they hold: the guess's final state projected on it (least-norm Gauss-Newton; when
  /// it does not reach 1e-12 in 30 steps nothing is implied). refinement_nlp_terminal.hxx.
  double implied_terminal_value_tolerance = 1e-8;
  /// The state x0 must satisfy the first phase's closed contacts (gap and normal velocity) and
  /// open contacts (gap >= -tolerance) to this tolerance [scene units].
  double initial_state_tolerance = 1e-8;
  /// One line per solve and per edit when not null; not owned.
  std::ostream* progress = nullptr;

  /// Throws InvalidArgument naming the first field out of its domain.
  void validate() const;
};

}  // namespace saltus::timefreezing
