// The hopper's mode-schedule refinement, compiled once, its chain's settings and the chain itself
// (hopper_holes_refinement.hpp).
#include "scenes/hopper_holes_refinement.hpp"
#include "scenes/hopper_tracking.hpp"

#include <saltus/sensitivity/analysis/reference_analysis_io.hpp>
#include <saltus/timefreezing/instantiate.hxx>
#include <saltus/timefreezing/refinement/refinement_io.hpp>

#include <cmath>

SALTUS_INSTANTIATE_SCHEDULE_REFINEMENT_SCENE(saltus::scenes::Hopper)
SALTUS_INSTANTIATE_SCHEDULE_REFINEMENT(saltus::scenes::Hopper, saltus::scenes::HopperOverThreeHoles)

namespace saltus::scenes {

timefreezing::DiscoveryOptions hopper_discovery_options(int steps, std::ostream* progress) {
  timefreezing::DiscoveryOptions o;
  o.max_steps = steps;
  o.extraction.micro_flight_gap = 0.015;
  o.reading.gap_per_sigma = 0.15;
  o.reading.gap_max = 0.015;
  o.reading.velocity_per_sigma = 100.0;
  o.reading.velocity_max = 10.0;
  o.progress = progress;
  return o;
}

timefreezing::RefinementOptions hopper_refinement_options(std::ostream* progress) {
  timefreezing::RefinementOptions o;
  o.grid.max_element_duration = 0.05;
  o.grid.stages = 4;
  o.ipopt.max_iter = 3000;
  o.edits.max_edits = 0;
  o.stick_cone_margin = 0.05;
  o.min_phase_duration = 0.02;
  o.contact_stabilisation = 20.0;
  o.flight_clearance = 0.005;
  o.stance_load = 20.0;
  o.touchdown_speed = 0.3;
  o.mesh.local_error_tolerance = 2e-8;
  o.mesh.max_split = 4;
  o.mesh.max_rounds = 10;
  o.mesh.max_iter = 1000;
  o.mesh.warm_start_mu = 0.1;
  o.checks.resimulation_window = 0.02;
  o.progress = progress;
  return o;
}

timefreezing::OcpHorizon<Hopper> hopper_refinement_horizon(double T) {
  using Ocp = HopperOverThreeHoles;
  SALTUS_REQUIRE(std::isfinite(T) && T > 0.0, "hopper_refinement_horizon: T must be finite and > 0, got ", T);
  timefreezing::OcpHorizon<Hopper> h;
  h.x0 << Ocp::q0(), Ocp::v0();
  h.final_time = T;
  h.control_lower = Eigen::VectorXd::Constant(2, -Ocp::torque_limit);
  h.control_upper = Eigen::VectorXd::Constant(2, Ocp::torque_limit);
  return h;
}

timefreezing::ScheduleGuess<Hopper> hopper_guess_from(const timefreezing::DiscoveryResult<Hopper>& discovery,
                                                      HopperFootsteps* footsteps, const Vec<4>& q_end, double T) {
  using Ocp = HopperOverThreeHoles;
  SALTUS_REQUIRE(discovery.schedule_found, "hopper_guess_from: discovery found no schedule (", discovery.message, ")");
  const Hopper hopper{};
  const HopperFootsteps steps = footsteps_of(hopper, discovery.discovered.guess, Ocp::q0(), q_end, T);
  if (footsteps) *footsteps = steps;
  return footstep_guess(hopper, steps, Ocp::q0(), q_end, T);
}

HopperChainOptions hopper_chain_options(HopperTask task) {
  HopperChainOptions o;
  o.task = task;
  if (task == HopperTask::OneHole) {
    o.local_error_tolerance = 2e-7;
    o.runs = 30;
    o.deviation_times = 0;
  }
  return o;
}

namespace {

timefreezing::DiscoveryResult<Hopper> discover(const Hopper& hopper, const HopperChainOptions& o) {
  using namespace timefreezing;
  using Ocp = HopperOverThreeHoles;
  const DiscoveryOptions options = hopper_discovery_options(2, o.progress);
  if (o.task == HopperTask::OneHole) {
    using Short = HopperOverOneHole;
    return discover_schedule_by_continuation(hopper, Short::system(), Ocp::hole_continuation(Short::q_target()),
                                             Short::on_three_hole_rows(), Short::q0(), Short::v0(), Short::grid(),
                                             Short::solver(), options);
  }
  if (o.initialisation == HopperInitialisation::HopGuess) {
    const MotionGuess hops = [](double t) { return Eigen::VectorXd(Ocp::hop_guess(t)); };
    return discover_schedule_from_guess(hopper, Ocp::system(), Ocp{}, Ocp::q0(), Ocp::v0(), Ocp::grid(), hops,
                                        Ocp::solver(), options);
  }
  return discover_schedule_by_continuation(hopper, Ocp::system(), Ocp::hole_continuation(), Ocp{}, Ocp::q0(), Ocp::v0(),
                                           Ocp::grid(), Ocp::solver(), options);
}

}  // namespace

HopperChain run_hopper_chain(const HopperChainOptions& options) {
  using namespace timefreezing;
  const HopperChainOptions& o = options;
  SALTUS_REQUIRE(o.task == HopperTask::ThreeHoles || o.initialisation == HopperInitialisation::Paper,
                 "run_hopper_chain: hop_guess (three hops over 2.5 s) does not describe the one-hole bed");
  SALTUS_REQUIRE(o.runs >= 1, "run_hopper_chain: runs must be >= 1, got ", o.runs);
  SALTUS_REQUIRE(std::isfinite(o.perturbation_size) && o.perturbation_size > 0.0,
                 "run_hopper_chain: the perturbation size must be finite and > 0, got ", o.perturbation_size);
  SALTUS_REQUIRE(o.deviation_times >= 0, "run_hopper_chain: deviation_times must be >= 0, got ", o.deviation_times);
  SALTUS_REQUIRE(std::isfinite(o.local_error_tolerance) && o.local_error_tolerance > 0.0,
                 "run_hopper_chain: the local error tolerance must be finite and > 0, got ", o.local_error_tolerance);
  const bool one_hole = o.task == HopperTask::OneHole;
  const Vec<4> q_end = one_hole ? HopperOverOneHole::q_target() : HopperOverThreeHoles::q_target();
  const double T = one_hole ? HopperOverOneHole::horizon : HopperOverThreeHoles::horizon;
  const HopperOverThreeHoles ocp = one_hole ? HopperOverOneHole::on_three_hole_rows() : HopperOverThreeHoles{};
  const Hopper hopper{};
  HopperChain chain{o, discover(hopper, o), {}, std::nullopt, {}, std::nullopt};
  try {
    const ScheduleGuess<Hopper> guess = hopper_guess_from(chain.discovery, &chain.footsteps, q_end, T);
    RefinementOptions refinement = hopper_refinement_options(o.progress);
    refinement.mesh.local_error_tolerance = o.local_error_tolerance;
    chain.refined = refine_schedule(hopper, ocp, hopper_refinement_horizon(T), guess, refinement);
  } catch (const Error& e) {
    chain.refinement_failure = e.what();
  }
  if (!chain.refined || !chain.refined->converged) return chain;
  const HybridTrajectory<Hopper>& ref = chain.refined->trajectory;
  ReferenceAnalysisOptions<Hopper> analysis = stance_start_lqr_analysis(hopper, ref, o.runs, 1.0, o.progress);
  analysis.monte_carlo.size = o.perturbation_size;
  const double t0 = ref.t_begin(), t_end = ref.t_end();
  const int n = o.deviation_times;
  for (int k = 1; k <= n; ++k) analysis.monte_carlo.deviation_times.push_back(k == n ? t_end : t0 + (t_end - t0) * k / n);
  chain.analysis = analyse_reference(hopper, ref, hopper_monte_carlo_simulation(), analysis);
  return chain;
}

nlohmann::ordered_json to_json(const HopperChain& chain) {
  const Hopper hopper{};
  const timefreezing::DiscoveryResult<Hopper>& discovery = chain.discovery;
  nlohmann::ordered_json j;
  j["converged"] = false;
  j["initialisation"] = chain.options.initialisation == HopperInitialisation::HopGuess ? "hop_guess" : "paper";
  j["stage"] = chain.refinement_failure.empty() ? "discovery (" + discovery.message + ")"
                                                : "refinement (" + chain.refinement_failure + ")";
  j["relaxed_objective"] = discovery.relaxed.solution.objective;
  j["discovery_seconds"] = discovery.seconds;
  j["discovery"] = timefreezing::to_json(discovery);
  if (!chain.footsteps.footholds.empty()) j["footholds"] = chain.footsteps.footholds;
  if (chain.refined) {
    const timefreezing::RefinementResult<Hopper>& r = *chain.refined;
    const nlohmann::ordered_json rj = timefreezing::to_json(hopper, r);
    for (const char* key : {"converged", "stage", "mode_validity_violation", "objective", "schedule", "schedule_edits",
                            "phase_resim_max_error", "refinement_seconds"})
      j[key] = rj[key];
    j["events"] = rj["event_times"];
    j["max_path_violation"] = r.path_violation;
    j["target_error"] = r.terminal_violation;
    j["solve_seconds"] = discovery.seconds + r.seconds;
    j["refinement"] = rj;
  }
  if (chain.analysis) {
    j["analysis"] = to_json(*chain.analysis);
    // The batch's size and how many runs kept the events, beside the verdict (as well as in its
    // "monte_carlo" block): the figures a reader of the report compares first.
    if (j["analysis"].contains("monte_carlo"))
      for (const char* key : {"runs", "kept_event_sequence"}) j["analysis"][key] = j["analysis"]["monte_carlo"][key];
  }
  return j;
}

}  // namespace saltus::scenes
