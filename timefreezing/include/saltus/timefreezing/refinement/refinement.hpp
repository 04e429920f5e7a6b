// The mode-schedule refinement: the second stage of the optimiser. A relaxed contact-implicit
// solution (the time-freezing homotopy) is good at discovering WHERE and WHEN contacts happen and
// bad at being exact; a smooth OCP whose mode sequence is fixed is exact and cannot discover. The
// refinement takes a schedule (from a relaxed solution or a user's trajectory, extraction.hpp),
// solves the smooth multi-phase OCP of refinement_nlp.hpp on the hybrid core's own flows, guards
// and jump maps, reads the multipliers for schedule edits, and checks the result with the
// event-driven simulator. (Staged contact optimisation, arXiv 2304.04923, chains a contact-implicit
// and a fixed-sequence stage the same way; hybrid iLQR, Kong et al. T-RO 2023, is the
// saltation-matrix form of a fixed-sequence optimiser.)
//
// SCHEDULE EDITS. After a converged solve the multipliers and bounds say where the schedule is not
// locally optimal:
//   - a closed contact whose lambda_n >= 0 row is active with a positive multiplier at a stage
//     point inside its phase wants to lift off there (over the arc of consecutive stage points
//     where that row is active): the phase is split by a release, a flight of
//     that contact, and a touchdown back into the phase's mode (a vanishing flight is removed by the
//     next check);
//   - an open contact whose gap >= 0 row is active with a positive multiplier inside its phase
//     wants to touch there: the phase is split by a touchdown, a stance of that contact (slipping
//     along its tangential velocity, or sticking when that is below the active tolerance), and a
//     release back;
//   - a phase whose duration is at its lower bound (d_p <= vanishing_duration) wants to vanish: it
//     is removed and its two events become one (guards_between of the modes around it).
//   - a slipping contact whose s zeta_t >= 0 row is active inside its phase wants to stick there
//     (stop, stick, slip onset back), a sticking one whose cone row is active wants to slip (slip
//     onset, slip in the direction the cone row names, stop back).
// One edit per solve, the vanishing phases first, then the largest multiplier; each edit is
// reported. The result says whether the final schedule passed this check (no edit proposed: no
// better schedule by one such edit, locally); it never claims global optimality.
//
// MESH REFINEMENT. The grid that finds the schedule need not resolve the motion: the optimum can
// put its fastest motion into one element (the hopper's push-off, where 30-50 rad/s of joint rate
// build up in the last 20 ms of a stance), and the optimiser uses the collocation's error there
// (docs/refinement.md, "Hopper"). After the last edit, when RefinementMesh::local_error_tolerance
// > 0: every element's local error is measured against the exact flow of its mode
// (ScheduleRefinementNlp::element_local_errors); those over the tolerance are split into equal
// parts, as many as the local error's order asks for; the NLP of the same schedule is built on the
// finer grid (RefinementGrid::element_boundaries) and solved from the previous solution (its
// dense output and its inputs; Ipopt's barrier parameter starts at RefinementMesh::warm_start_mu;
// a round that splits few elements also from its multipliers,
// RefinementMesh::dual_warm_start_split_fraction), until every element is within the tolerance or
// max_rounds solves are spent. A round whose solve fails is reported and the previous solution kept. Local-error control of the mesh is the
// standard of direct collocation (Betts, "Practical Methods for Optimal Control", ch. 4.7).
#pragma once

#include <saltus/hybrid/simulation/simulator.hpp>
#include <saltus/timefreezing/refinement/refinement_nlp.hpp>
#include <saltus/timefreezing/refinement/schedule_extraction.hpp>

#include <string>
#include <vector>

namespace saltus::timefreezing {

/// One schedule edit (refinement.hpp, "SCHEDULE EDITS").
struct ScheduleEdit {
  std::string kind;         ///< "lift-off", "touch", "stick", "slip+", "slip-", "vanish"
  int phase = -1;           ///< the phase edited (in the schedule it was read from)
  int contact = -1;         ///< the contact (-1 for "vanish")
  double t = 0.0;           ///< where [s]: the stage point's time, or the vanishing phase's start
  /// the active arc around t [s]: the consecutive stage points where the same row is active (the
  /// edited mode is put over it, at least 0.02 s or a quarter of the phase around t); t, t for "vanish"
  double t_begin = 0.0, t_end = 0.0;
  double multiplier = 0.0;  ///< the row's multiplier (0 for "vanish")
  std::string schedule_after;  ///< describe() of the edited schedule
};

/// One Ipopt solve of a schedule.
struct RefinementSolve {
  std::string schedule;     ///< describe() of the schedule solved
  bool succeeded = false;   ///< Ipopt accepted the solution (Solve_Succeeded or Solved_To_Acceptable_Level)
  std::string ipopt_status;
  double objective = 0.0, constraint_violation = 0.0;
  int ipopt_iterations = 0;
  double seconds = 0.0;
  /// Started from carried-over multipliers as well as a primal point (a mesh round's dual warm
  /// start, RefinementMesh::dual_warm_start_split_fraction); false: from the primal guess alone.
  bool warm_started = false;
  /// The rows with the largest |multiplier| at the solve's last point, largest first (at most
  /// five: "name (multiplier)", ScheduleRefinementNlp::constraint_name): where a solve that does
  /// not converge loses its regularity.
  std::vector<std::string> largest_multipliers;
};

/// One round of the mesh refinement (refinement.hpp, "MESH REFINEMENT"): the local errors of the
/// solution it started from, the elements it split, and the solve on the finer grid.
struct MeshRound {
  double largest_local_error = 0.0;  ///< before the round [state units]
  int worst_phase = -1;              ///< where it was
  double worst_time = 0.0;           ///< the worst element's start [s]
  int elements_split = 0;            ///< elements over the tolerance, each split into 2 .. max_split
  int elements = 0;                  ///< elements of the finer grid
  bool solved = false;               ///< its solve succeeded (RefinementResult::solves has its record)
  bool dual_warm_start = false;      ///< its solve started from the previous grid's multipliers
};

/// The event-driven re-simulation of one phase from its start state (x+ of the event before it)
/// under the optimal input, in the phase's mode; in windows (RefinementChecks::resimulation_window),
/// each later window from the reference's state at its start.
struct PhaseResimulation {
  int phase = 0;
  /// max ||x_sim - x_refined||_inf over the phase's element boundaries (the collocation's nodes,
  /// where Radau IIA is of order 2 n_s - 1), the phase's end included. The comparison goes on
  /// through events the simulator finds inside the phase (unplanned_events): where a contact's
  /// force and gap are both zero on the reference, the simulator may label it open or closed with
  /// the same motion, and this distance says whether the motion is the same. In windows: over
  /// every window's nodes, its start node included (the projection's distance there).
  double max_error = 0.0;
  double end_error = 0.0;      ///< the same at the phase's end (x-)
  double compared_until = 0.0; ///< the last node compared [s] (the phase's end unless the simulation failed)
  int unplanned_events = 0;    ///< events the simulator found inside the phase (named in `note`)
  int windows = 1;             ///< simulations the phase was split into (RefinementChecks::resimulation_window)
  /// ||x_start projected - x_start||_inf: the start state brought onto the contacts it closes (its
  /// own closed contacts, and those released at its start) before it is simulated; the size of the
  /// collocation's drift (contact_drift), which the simulator's initial-mode check would refuse.
  /// In windows: the largest over the windows' starts.
  double start_projection = 0.0;
  /// The events the simulator finds within 1e-6 (relative) of the phase's end (it runs past the
  /// end by a margin, under the optimal input, the next phase's beyond the end): the first one's
  /// time minus the scheduled event time [s] (NaN when none, and for the last phase); the state
  /// after them (x+ of the last one, else the state at the end) against the reference's x+; and,
  /// as information, whether their guards together are the schedule's and whether the mode after
  /// them is the next phase's. The labels can differ where the reference is degenerate (a force
  /// and a gap both zero at the boundary, e.g. a touchdown at zero approach speed): the states say
  /// whether the motion is the same.
  double event_time_error = 0.0;
  double x_plus_error = 0.0;
  bool event_guards_match = true;
  bool next_mode_matches = true;
  std::string note;            ///< what the comparison found besides the distance, or ""

  /// The phase passes check (a): the distance <= tolerance at every node of the phase and across
  /// the boundary at its end.
  bool passes(double tolerance) const { return max_error <= tolerance && x_plus_error <= tolerance; }
};

/// The event-driven re-simulation of the whole refined horizon open loop from x0, under the
/// optimal input ((b) of the checks).
struct OpenLoopResimulation {
  /// max ||x_sim - x_refined||_inf over all element boundaries of the horizon (before any event at
  /// a boundary): an unstable motion departs open loop, and this says by how much
  double max_error = 0.0;
  double compared_until = 0.0;  ///< the last boundary compared [s] (the horizon's end)
  int events = 0;               ///< events of the open-loop simulation (the schedule has P - 1)
  std::string note;             ///< "" or why there is no comparison (max_error NaN: the simulation failed)
};

template <Scene S>
struct RefinementResult {
  /// "refined" when the last solve converged and mode_validity_violation and phase_resim_max_error
  /// are within RefinementOptions::checks; "converged, checks failed: ..." naming each failed
  /// check with its figures (and the phase and the simulator's note); "not converged" (Ipopt
  /// failed on the schedule: `message` has its status and worst row).
  std::string stage;
  bool converged = false;         ///< the last solve succeeded and its constraint violation <= 1e-6
  std::string message;
  ModeSchedule<S::nc> schedule;   ///< the final schedule
  std::vector<double> event_times;
  /// The refined reference in physical time: one segment per phase (dense output: the collocation
  /// polynomial of every element), exact events (x- the phase's end, x+ the next phase's start,
  /// the schedule's guards, impulse mode and impulses), the optimal input law (piecewise constant
  /// per element, right-continuous; through the OCP's input law when it has one).
  HybridTrajectory<S> trajectory;
  std::vector<double> element_times;  ///< the element boundaries, t0 .. T (input breakpoints)
  double objective = 0.0;               ///< the OCP's cost (running + terminal)
  double mode_validity_violation = 0.0; ///< refinement_nlp.hpp: largest violation of the validity rows
  double path_violation = 0.0, terminal_violation = 0.0, constraint_violation = 0.0;
  double contact_drift = 0.0;           ///< ScheduleRefinementNlp::contact_drift [scene units]
  /// The largest local error of an element at the final solution
  /// (ScheduleRefinementNlp::element_local_errors) [state units], and the rounds of the mesh
  /// refinement that led there (none when RefinementMesh::local_error_tolerance is 0).
  double local_error = 0.0;
  std::vector<double> element_local_errors;  ///< per element of the final grid (between element_times)
  std::vector<MeshRound> mesh_rounds;
  std::vector<ImpliedRow> implied_rows;
  std::vector<ScheduleEdit> edits;
  bool schedule_check_passed = false;   ///< no edit proposed after the last solve
  std::vector<RefinementSolve> solves;
  std::vector<PhaseResimulation> phase_resimulation;
  double phase_resim_max_error = 0.0;   ///< max over the phases' max_error
  OpenLoopResimulation open_loop;
  int ipopt_iterations = 0;
  double seconds = 0.0;
};

/// Tight tolerances for the re-simulation of refined references (relative 1e-12, absolute 1e-13).
inline SimulationOptions precise_simulation() {
  SimulationOptions o;
  o.integrator.relative_tolerance = 1e-12;
  o.integrator.absolute_tolerance = 1e-13;
  return o;
}

/// (a) of the checks: every phase of `traj` (a refined reference, one segment per phase of
/// `schedule`, with its element boundaries) re-simulated by the event-driven simulator from its
/// start state (projected onto the contacts it closes) in its mode under its own input, compared
/// at the element boundaries, the first event after its start against the schedule's.
/// window > 0 [s]: each phase in windows starting at element boundaries at least that far apart
/// (the last may be shorter), the first as above, each later one from the reference's state at
/// its start projected onto the phase's closed contacts: multiple shooting, for phases whose
/// open-loop motion is unstable (RefinementChecks::resimulation_window). Throws InvalidArgument
/// for a negative or non-finite window.
template <Scene S>
std::vector<PhaseResimulation> resimulate_phases(const S& scene, const HybridTrajectory<S>& traj,
                                                 const ModeSchedule<S::nc>& schedule,
                                                 const std::vector<double>& element_times,
                                                 const SimulationOptions& simulation = precise_simulation(),
                                                 double window = 0.0);

/// (b) of the checks: simulates `traj`'s input from its initial state over its horizon with
/// `simulation` (breakpoints replaced by `element_times`) and compares at `element_times`.
template <Scene S>
OpenLoopResimulation resimulate_open_loop(const S& scene, const HybridTrajectory<S>& traj,
                                          const std::vector<double>& element_times,
                                          const SimulationOptions& simulation = precise_simulation());

/// Refines `guess` (a schedule, its event times and a motion) for the OCP `ocp` (the struct the
/// time-freezing solver takes) on `horizon`: solves the refinement NLP, edits the schedule up to
/// options.edits.max_edits times, assembles the trajectory and re-simulates every phase with
/// `simulation` (its breakpoints are replaced by the element boundaries).
/// @throws InvalidArgument as ScheduleRefinementNlp's constructor (a bad schedule, horizon, guess,
///   options or initial state, naming the phase and the condition), and Ipopt's rejection of an
///   option. A schedule that cannot reach the target within the bounds is not thrown: the result
///   says "not converged" with Ipopt's status and the worst row.
template <Scene S, class Ocp>
RefinementResult<S> refine_schedule(const S& scene, const Ocp& ocp, const OcpHorizon<S>& horizon,
                                    const ScheduleGuess<S>& guess, const RefinementOptions& options = {},
                                    const SimulationOptions& simulation = precise_simulation());

}  // namespace saltus::timefreezing
