// Writing the result of refine_schedule (refinement.hpp) as JSON (nlohmann-json), as
// sensitivity/analysis/reference_analysis_io.hpp writes an analysis. The trajectory itself is
// written by hybrid/vocabulary/trajectory_io.hpp.
#pragma once

#include <saltus/timefreezing/refinement/discovery.hpp>
#include <saltus/timefreezing/refinement/refinement.hpp>
#include <saltus/timefreezing/refinement/schedule_extraction.hpp>

#include <nlohmann/json.hpp>

#include <cmath>

namespace saltus::timefreezing {

/// A finite number, or null.
inline nlohmann::ordered_json finite_or_null(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}

/// The result as a JSON object, keys in this order:
///   stage, converged, message   RefinementResult's (stage: "refined", "not converged", ...)
///   schedule                    describe() of the final schedule, e.g. "open [touchdown table] slip+"
///   event_times                 [s]
///   objective, mode_validity_violation, path_violation, terminal_violation, constraint_violation,
///   contact_drift               as in RefinementResult
///   local_error                 as in RefinementResult
///   mesh_rounds                 [{largest_local_error, worst_phase, worst_time, elements_split, elements, solved,
///                                 dual_warm_start}]
///   schedule_edits              [{kind, phase, contact, t, t_begin, t_end, multiplier, schedule_after}]
///   schedule_check_passed       no edit proposed after the last solve
///   solves                      [{schedule, succeeded, ipopt_status, objective, constraint_violation,
///                               ipopt_iterations, seconds, warm_started, largest_multipliers}]
///   phase_resim_max_error       max over phases of the per-phase re-simulation's distance
///   phase_resimulation          [{phase, max_error, end_error, start_projection, event_time_error,
///                               x_plus_error, event_guards_match, next_mode_matches, compared_until,
///                               unplanned_events, windows, note}] (event_time_error null where no event)
///   open_loop                   {max_error, compared_until, events, note}
///   implied_rows                [description]
///   ipopt_iterations, refinement_seconds
template <Scene S>
nlohmann::ordered_json to_json(const S& scene, const RefinementResult<S>& r) {
  using json = nlohmann::ordered_json;
  json j;
  j["stage"] = r.stage;
  j["converged"] = r.converged;
  j["message"] = r.message;
  j["schedule"] = r.schedule.phases.empty() ? json(nullptr) : json(describe(scene, r.schedule));
  j["event_times"] = r.event_times;
  j["objective"] = finite_or_null(r.objective);
  j["mode_validity_violation"] = finite_or_null(r.mode_validity_violation);
  j["path_violation"] = finite_or_null(r.path_violation);
  j["terminal_violation"] = finite_or_null(r.terminal_violation);
  j["constraint_violation"] = finite_or_null(r.constraint_violation);
  j["contact_drift"] = finite_or_null(r.contact_drift);
  j["local_error"] = finite_or_null(r.local_error);
  json rounds = json::array();
  for (const MeshRound& m : r.mesh_rounds)
    rounds.push_back({{"largest_local_error", finite_or_null(m.largest_local_error)}, {"worst_phase", m.worst_phase},
                      {"worst_time", m.worst_time}, {"elements_split", m.elements_split}, {"elements", m.elements},
                      {"solved", m.solved}, {"dual_warm_start", m.dual_warm_start}});
  j["mesh_rounds"] = rounds;
  json edits = json::array();
  for (const ScheduleEdit& e : r.edits)
    edits.push_back({{"kind", e.kind}, {"phase", e.phase}, {"contact", e.contact}, {"t", e.t},
                     {"t_begin", e.t_begin}, {"t_end", e.t_end},
                     {"multiplier", e.multiplier}, {"schedule_after", e.schedule_after}});
  j["schedule_edits"] = edits;
  j["schedule_check_passed"] = r.schedule_check_passed;
  json solves = json::array();
  for (const RefinementSolve& s : r.solves)
    solves.push_back({{"schedule", s.schedule}, {"succeeded", s.succeeded}, {"ipopt_status", s.ipopt_status},
                      {"objective", finite_or_null(s.objective)},
                      {"constraint_violation", finite_or_null(s.constraint_violation)},
                      {"ipopt_iterations", s.ipopt_iterations}, {"seconds", s.seconds},
                      {"warm_started", s.warm_started}, {"largest_multipliers", s.largest_multipliers}});
  j["solves"] = solves;
  j["phase_resim_max_error"] = finite_or_null(r.phase_resim_max_error);
  json phases = json::array();
  for (const PhaseResimulation& p : r.phase_resimulation)
    phases.push_back({{"phase", p.phase}, {"max_error", finite_or_null(p.max_error)},
                      {"end_error", finite_or_null(p.end_error)}, {"start_projection", finite_or_null(p.start_projection)},
                      {"event_time_error", finite_or_null(p.event_time_error)},
                      {"x_plus_error", finite_or_null(p.x_plus_error)}, {"event_guards_match", p.event_guards_match},
                      {"next_mode_matches", p.next_mode_matches}, {"compared_until", p.compared_until},
                      {"unplanned_events", p.unplanned_events}, {"windows", p.windows}, {"note", p.note}});
  j["phase_resimulation"] = phases;
  j["open_loop"] = {{"max_error", finite_or_null(r.open_loop.max_error)}, {"compared_until", r.open_loop.compared_until},
                    {"events", r.open_loop.events}, {"note", r.open_loop.note}};
  json implied = json::array();
  for (const ImpliedRow& row : r.implied_rows) implied.push_back(row.description);
  j["implied_rows"] = implied;
  j["ipopt_iterations"] = r.ipopt_iterations;
  j["refinement_seconds"] = r.seconds;
  return j;
}

/// The extraction's notes (the micro-phase rules that fired): [{rule, t_begin, t_end}].
template <Scene S>
nlohmann::ordered_json to_json(const ExtractedSchedule<S>& extracted) {
  nlohmann::ordered_json notes = nlohmann::ordered_json::array();
  for (const ExtractionNote& n : extracted.notes)
    notes.push_back({{"rule", n.rule}, {"t_begin", n.t_begin}, {"t_end", n.t_end}});
  return notes;
}

/// The discovery stage (discovery.hpp): {settled, message, seconds, steps: [{index, sigma,
/// complementarity, objective, ipopt_status, ipopt_iterations, seconds, schedule,
/// extraction_error}]}.
template <Scene S>
nlohmann::ordered_json to_json(const DiscoveryResult<S>& d) {
  nlohmann::ordered_json steps = nlohmann::ordered_json::array();
  for (const DiscoveryStep& s : d.steps)
    steps.push_back({{"index", s.index}, {"sigma", s.sigma}, {"complementarity", finite_or_null(s.complementarity)},
                     {"objective", finite_or_null(s.objective)}, {"ipopt_status", s.ipopt_status},
                     {"ipopt_iterations", s.ipopt_iterations}, {"seconds", s.seconds}, {"schedule", s.schedule},
                     {"extraction_error", s.extraction_error}});
  return {{"settled", d.settled}, {"message", d.message}, {"seconds", d.seconds}, {"steps", steps}};
}

}  // namespace saltus::timefreezing
