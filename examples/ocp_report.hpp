// The JSON report of an optimal reference from the time-freezing OCP (`plank_box --json`): the
// OCP's figures, one entry per Ipopt solve, the events read off the discrete solution, and the
// re-simulation of the recovered reference by the event-driven
// simulator (only for a converged solution: an unconverged one is not a motion to re-simulate).
#pragma once

#include <saltus/hybrid/reference/resimulation.hpp>
#include <saltus/timefreezing/drivers/optimal_control.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace saltus::examples {

/// What the OCP's own feasibility check found (path rows at every stage point, the target).
struct OcpFeasibility {
  double path_violation = 0.0;
  std::string worst_path_constraint;  ///< empty when no row is violated
  double target_error = 0.0;
};

/// A state as a JSON array.
template <class V>
std::vector<double> as_vector(const V& x) {
  return std::vector<double>(x.data(), x.data() + x.size());
}

/// {"converged", "message", "complementarity", "max_path_violation", "worst_path_constraint",
/// "target_error", "constraint_violation", "objective", "homotopy_steps", "continuation_stages",
/// "ipopt_iterations", "solve_seconds", "steps": [{sigma, polish, complementarity, objective,
/// constraint_violation, ipopt_iterations, ipopt_status, worst_violation, seconds}],
/// "continuation": [...],
/// "events": [{kind: "impact" (t, clock_advance) | "gap" | "normal velocity" | "tangential
/// velocity" (t, alpha_before, alpha_after, switching_function)}], "recovered_events": [{t,
/// impact, guards: ["touchdown C_L", ...], mode_before, mode_after, x_minus, x_plus, x_plus_t}]
/// (the HybridTrajectory of recover_trajectory: impacts and mode changes in physical time; states
/// are (q, v), size 2 nq; x_plus_t: the time x+ belongs to, later than t where the discretisation's
/// clock ran on before the impact ended, timefreezing::x_plus_time), "resim_max_error",
/// "resim_max_error_at": {t, state_component} (where the largest distance is attained; the
/// component indexes (q, v)),
/// "resim_event_time_error" (null when the event counts differ: the imported reference counts its
/// impacts only, the re-simulation every event), "resim_events": [{t, guards (their count),
/// x_minus, x_plus}]}.
/// The re-simulation runs with SimulationOptions{} (polish's default); when `resim_out` is given
/// it receives the re-simulation (nullopt when there is none: not converged, or the re-simulation threw).
template <Scene S>
nlohmann::ordered_json ocp_report(const S& scene, const timefreezing::TimeFreezingOcpResult<S>& r,
                                  const OcpFeasibility& f, std::optional<PolishResult<S>>* resim_out = nullptr) {
  using namespace saltus::timefreezing;
  nlohmann::ordered_json j;
  j["converged"] = r.converged();
  j["message"] = r.solution.message;
  j["complementarity"] = r.solution.complementarity;
  j["max_path_violation"] = f.path_violation;
  j["worst_path_constraint"] = f.worst_path_constraint.empty() ? nlohmann::ordered_json(nullptr)
                                                               : nlohmann::ordered_json(f.worst_path_constraint);
  j["target_error"] = f.target_error;
  j["constraint_violation"] = r.solution.constraint_violation;
  j["objective"] = r.solution.objective;
  j["homotopy_steps"] = r.solution.steps.size();
  j["continuation_stages"] = r.continuation_steps.size();
  j["ipopt_iterations"] = r.solution.ipopt_iterations;
  j["solve_seconds"] = r.solution.seconds;
  auto steps = nlohmann::ordered_json::array();
  for (const MpccHomotopyStep& s : r.solution.steps)
    steps.push_back({{"sigma", s.sigma}, {"polish", s.polish}, {"complementarity", s.complementarity},
                     {"objective", s.objective}, {"constraint_violation", s.constraint_violation},
                     {"ipopt_iterations", s.ipopt_iterations}, {"ipopt_status", s.ipopt_status},
                     {"worst_violation", s.worst_violation}, {"seconds", s.seconds}});
  j["steps"] = steps;
  auto continuation = nlohmann::ordered_json::array();
  for (const MpccHomotopyStep& s : r.continuation_steps)
    continuation.push_back({{"ipopt_iterations", s.ipopt_iterations}, {"ipopt_status", s.ipopt_status}, {"seconds", s.seconds}});
  j["continuation"] = continuation;
  auto events = nlohmann::ordered_json::array();
  for (const auto& p : r.frozen_phases)
    events.push_back({{"kind", "impact"}, {"t", p.time}, {"clock_advance", p.clock_advance}});
  for (const SwitchPoint& s : r.switch_points) {
    const int m = s.switching_function % 3;
    events.push_back({{"kind", m == 0 ? "gap" : (m == 1 ? "normal velocity" : "tangential velocity")},
                      {"switching_function", s.switching_function},
                      {"t", s.time},
                      {"alpha_before", s.alpha_before},
                      {"alpha_after", s.alpha_after}});
  }
  j["events"] = events;
  auto recovered = nlohmann::ordered_json::array();
  for (std::size_t e = 0; e < r.trajectory.events.size(); ++e) {
    const auto& ev = r.trajectory.events[e];
    auto guards = nlohmann::ordered_json::array();
    for (const Guard& g : ev.guards()) guards.push_back(std::string(to_string(g.kind)) + " " + scene.contact(g.contact).name);
    recovered.push_back({{"t", ev.t},
                         {"impact", ev.impact()},
                         {"guards", guards},
                         {"mode_before", describe(scene, ev.mode_before)},
                         {"mode_after", describe(scene, ev.mode_after)},
                         {"x_minus", as_vector(ev.x_minus)},
                         {"x_plus", as_vector(ev.x_plus)},
                         {"x_plus_t", x_plus_time(r.trajectory, e)}});
  }
  j["recovered_events"] = recovered;
  j["resim_max_error"] = nullptr;
  j["resim_max_error_at"] = nullptr;
  j["resim_event_time_error"] = nullptr;
  j["resim_events"] = nlohmann::ordered_json::array();
  if (resim_out) resim_out->reset();
  if (r.converged()) {
    try {
      PolishResult<S> resim = polish(scene, r.reference, SimulationOptions{});
      j["resim_max_error"] = resim.state_distance;
      j["resim_max_error_at"] = {{"t", resim.worst_sample_time}, {"state_component", resim.worst_component}};
      if (std::isfinite(resim.event_time_distance)) j["resim_event_time_error"] = resim.event_time_distance;
      for (const auto& ev : resim.trajectory.events)
        j["resim_events"].push_back({{"t", ev.t},
                                     {"guards", ev.guards().size()},
                                     {"x_minus", as_vector(ev.x_minus)},
                                     {"x_plus", as_vector(ev.x_plus)}});
      if (resim_out) *resim_out = std::move(resim);
    } catch (const Error& e) {
      j["resim_failure"] = e.what();
    }
  }
  return j;
}

}  // namespace saltus::examples
