// The hopper over three holes refined from a footstep schedule (docs/refinement.md, "Hopper").
//
//   hopper_refinement [stance [h [max_iter [end_stance [cone_margin [n_s [print_level [then_n_s [end_clustering
//                     [local_error [warm_start_mu [max_split [mesh_max_iter]]]]]]]]]]]]] [name=value ...]
//   (defaults 0.45 0.02 1000 0.3 0 3 0 0 0 0 0.1 8 500)
//
// Positional: print_level is Ipopt's; then_n_s > 0: a second refinement with that many stages from
// the first one's result (the order continuation); end_clustering: RefinementGrid::end_clustering;
// local_error > 0: RefinementMesh::local_error_tolerance; warm_start_mu, max_split, mesh_max_iter:
// RefinementMesh's. Then name=value pairs:
//   resimulation_window=<s>        RefinementChecks::resimulation_window
//   mesh_max_rounds=<n>            RefinementMesh::max_rounds
//   dual_warm_start_split_fraction=<f>  RefinementMesh::dual_warm_start_split_fraction
//   normal_force_margin=<N>        RefinementOptions::normal_force_margin
//   then_normal_force_margin=<N>   a second refinement with that margin, from the first one's result on its grid
//   min_phase_duration=<s>         RefinementOptions::min_phase_duration
//   flight_clearance=<m>           RefinementOptions::flight_clearance
//   stance_load=<N>                RefinementOptions::stance_load
//   touchdown_load=<N>             RefinementOptions::touchdown_load
//   touchdown_speed=<m/s>          RefinementOptions::touchdown_speed
//   releases_at_input_jumps=<0|1>  RefinementOptions::releases_at_input_jumps
//   contact_stabilisation=<1/s>    RefinementOptions::contact_stabilisation
//   max_edits=<n>, edit_max_iter=<n>  RefinementEdits (max_edits is 0 here unless given)
//   discovery_from=hop_guess       discovery from the second initialisation (Ocp::hop_guess), no continuation
//   discovery_steps=<K>            the footsteps discovered from the paper's initialisation instead of
//                                  the holes' ones (discovered_footsteps below)
//   discovery_grid=<N>x<E>         discovery on N control intervals of E finite elements (Ocp::grid(N, E);
//                                  default the paper's 20x3)
//   analysis_runs=<n>, analysis_R=<r>  the refined reference analysed by analyse_reference with n Monte
//                                  Carlo runs under scenes::stance_start_lqr_analysis with R = r I
//                                  (default 1e-3; `hopper --json` uses analysis_runs=200 analysis_R=1);
//                                  report in hopper_analysis.json
//   any other name=value           an Ipopt option (RefinementIpopt::options: an integer, a number or a
//                                  string, e.g. mumps_pivot_order=0)
//
// The schedule by default is a user's guess, the footsteps the holes leave: four stances (the foot
// sticking) at x = 0, 1, 2, 3, the first and the last `end_stance` seconds long, the two middle
// ones `stance`, and three flights of equal length in between; the motion guessed by
// scenes::footstep_guess (scenes/hopper_footsteps.hpp: kinematically consistent, the foot on its
// foothold in a stance, ballistic hip arcs in a flight, velocities by central differences, zero
// torques). The OCP is scenes/hopper_holes.hpp as it is (T = 2.5 s, |u| <= 60, the 11 path rows at
// the full holes, the start at rest, the target q(T) = (3, 0.4, 0, 0)). Prints the refinement's
// progress, its result, where each stance's closed contact drifts (largest |gap| and |normal
// velocity| over 200 samples), the friction use and forces before each release, and its checks
// (in windows and in one shot); writes the result's JSON to hopper_refinement.json. About 4
// minutes on one thread with the defaults (docs/refinement.md, "Hopper over three holes").
#include "scenes/all_scenes.hpp"
#include "scenes/hopper_footsteps.hpp"
#include "scenes/hopper_holes.hpp"
#include "scenes/hopper_holes_refinement.hpp"
#include "scenes/hopper_tracking.hpp"

#include <saltus/sensitivity/analysis/reference_analysis.hpp>
#include <saltus/sensitivity/analysis/reference_analysis_io.hpp>
#include <saltus/timefreezing/refinement/refinement_io.hpp>
#include <saltus/timefreezing/refinement/schedule_extraction.hxx>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

namespace {

using saltus::scenes::Hopper;
using Ocp = saltus::scenes::HopperOverThreeHoles;

/// The footsteps the holes leave (file comment): stances on x = 0, 1, 2, 3, the first and the
/// last `end_stance` long, the middle ones `stance`, three flights of equal length between them.
saltus::scenes::HopperFootsteps holes_footsteps(double stance, double end_stance) {
  const double flight = (Ocp::horizon - 2 * end_stance - 2 * stance) / 3.0;
  saltus::scenes::HopperFootsteps steps{{0.0, 1.0, 2.0, 3.0}, {}};
  double t = 0.0;
  for (int k = 0; k < 3; ++k) {
    t += (k == 0) ? end_stance : stance;
    steps.event_times.push_back(t);
    t += flight;
    steps.event_times.push_back(t);
  }
  return steps;
}

/// The footsteps discovered from the paper's initialisation (the start state at every node, zero
/// torques; or, from_hop_guess, from the second one, Ocp::hop_guess, by discover_schedule_from_guess
/// without a continuation): discover_schedule_by_continuation with the hole continuation and at most `steps`
/// homotopy steps on `grid` (the paper's unless discovery_grid= says otherwise), read as scenes::hopper_discovery_options says, then
/// scenes::footsteps_of (a final flight lands for its last 0.1 s).
saltus::scenes::HopperFootsteps discovered_footsteps(const Hopper& hopper, int steps, bool from_hop_guess,
                                                    const saltus::timefreezing::FesdOptions& grid) {
  using namespace saltus::timefreezing;
  const DiscoveryOptions options = saltus::scenes::hopper_discovery_options(steps, &std::cout);
  const MotionGuess hops = [](double t) { return Eigen::VectorXd(Ocp::hop_guess(t)); };
  const DiscoveryResult<Hopper> d =
      from_hop_guess
          ? discover_schedule_from_guess(hopper, Ocp::system(), Ocp{}, Ocp::q0(), Ocp::v0(), grid, hops, Ocp::solver(), options)
          : discover_schedule_by_continuation(hopper, Ocp::system(), Ocp::hole_continuation(), Ocp{}, Ocp::q0(), Ocp::v0(),
                                              grid, Ocp::solver(), options);
  std::cout << "discovery: " << d.message << ", " << d.seconds << " s (continuation " << d.continuation_seconds << " s)\n";
  saltus::scenes::HopperFootsteps footsteps;
  (void)saltus::scenes::hopper_guess_from(d, &footsteps);
  return footsteps;
}

/// The element boundaries of a refined result as RefinementGrid::element_boundaries (per phase,
/// fractions of its duration).
std::vector<std::vector<double>> element_boundaries_of(const saltus::timefreezing::RefinementResult<Hopper>& r) {
  std::vector<std::vector<double>> out;
  for (const auto& seg : r.trajectory.segments) {
    std::vector<double> s{0.0};
    for (double t : r.element_times)
      if (t > seg.t_begin + 1e-12 && t < seg.t_end - 1e-12) s.push_back((t - seg.t_begin) / (seg.t_end - seg.t_begin));
    s.push_back(1.0);
    out.push_back(s);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace saltus;
  using namespace saltus::timefreezing;
  std::cout << std::unitbuf;
  const double stance = argc > 1 ? std::atof(argv[1]) : 0.45, h = argc > 2 ? std::atof(argv[2]) : 0.02;
  const int max_iter = argc > 3 ? std::atoi(argv[3]) : 1000;
  const double end_stance = argc > 4 ? std::atof(argv[4]) : 0.3;
  const double cone_margin = argc > 5 ? std::atof(argv[5]) : 0.0;  // RefinementOptions::stick_cone_margin
  const int stages = argc > 6 ? std::atoi(argv[6]) : 3;              // RefinementGrid::stages
  const int print_level = argc > 7 ? std::atoi(argv[7]) : 0;         // RefinementIpopt::print_level
  const int then_stages = argc > 8 ? std::atoi(argv[8]) : 0;
  const double end_clustering = argc > 9 ? std::atof(argv[9]) : 0.0;
  const double local_error = argc > 10 ? std::atof(argv[10]) : 0.0;
  const Hopper hopper{};
  const OcpHorizon<Hopper> horizon = scenes::hopper_refinement_horizon();
  RefinementOptions options;
  options.progress = &std::cout;
  options.grid.max_element_duration = h;
  options.grid.stages = stages;
  options.ipopt.print_level = print_level;
  options.grid.end_clustering = end_clustering;
  options.ipopt.max_iter = max_iter;
  options.edits.max_edits = 0;
  options.stick_cone_margin = cone_margin;
  options.mesh.local_error_tolerance = local_error;
  if (argc > 11) options.mesh.warm_start_mu = std::atof(argv[11]);
  if (argc > 12) options.mesh.max_split = std::atoi(argv[12]);
  if (argc > 13) options.mesh.max_iter = std::atoi(argv[13]);
  int analysis_runs = 0;
  double analysis_R = 1e-3;
  double then_margin = 0.0;
  int discovery_steps = 0;
  int discovery_intervals = 20, discovery_elements = 3;
  bool discovery_from_hop_guess = false;
  for (int a = 14; a < argc; ++a) {
    const std::string arg = argv[a];
    const std::size_t eq = arg.find('=');
    if (eq == std::string::npos) continue;
    const std::string name = arg.substr(0, eq), value = arg.substr(eq + 1);
    if (name == "resimulation_window") {  // RefinementChecks::resimulation_window [s], not an Ipopt option
      options.checks.resimulation_window = std::atof(value.c_str());
      continue;
    }
    if (name == "analysis_runs") {  // analyse_reference with that many Monte Carlo runs (scenes::stance_start_lqr_analysis)
      analysis_runs = std::atoi(value.c_str());
      continue;
    }
    if (name == "analysis_R") {  // the LQR's input weight R = analysis_R I (scenes::stance_start_lqr_analysis)
      analysis_R = std::atof(value.c_str());
      continue;
    }
    if (name == "normal_force_margin") {  // RefinementOptions::normal_force_margin [N]
      options.normal_force_margin = std::atof(value.c_str());
      continue;
    }
    if (name == "touchdown_speed") {  // RefinementOptions::touchdown_speed [m/s]
      options.touchdown_speed = std::atof(value.c_str());
      continue;
    }
    if (name == "releases_at_input_jumps") {  // RefinementOptions::releases_at_input_jumps
      options.releases_at_input_jumps = std::atoi(value.c_str()) != 0;
      continue;
    }
    if (name == "stance_load") {  // RefinementOptions::stance_load [N]
      options.stance_load = std::atof(value.c_str());
      continue;
    }
    if (name == "touchdown_load") {  // RefinementOptions::touchdown_load [N]
      options.touchdown_load = std::atof(value.c_str());
      continue;
    }
    if (name == "flight_clearance") {  // RefinementOptions::flight_clearance [m]
      options.flight_clearance = std::atof(value.c_str());
      continue;
    }
    if (name == "contact_stabilisation") {  // RefinementOptions::contact_stabilisation [1/s]
      options.contact_stabilisation = std::atof(value.c_str());
      continue;
    }
    if (name == "min_phase_duration") {  // RefinementOptions::min_phase_duration [s]
      options.min_phase_duration = std::atof(value.c_str());
      continue;
    }
    if (name == "max_edits") {  // RefinementEdits::max_edits (0 by default here)
      options.edits.max_edits = std::atoi(value.c_str());
      continue;
    }
    if (name == "edit_max_iter") {  // RefinementEdits::max_iter
      options.edits.max_iter = std::atoi(value.c_str());
      continue;
    }
    if (name == "discovery_from") {  // "hop_guess": discovery from Ocp::hop_guess (the second initialisation)
      discovery_from_hop_guess = value == "hop_guess";
      continue;
    }
    if (name == "discovery_grid") {  // N x E of the discovery's FESD grid
      discovery_intervals = std::atoi(value.c_str());
      discovery_elements = std::atoi(value.c_str() + value.find('x') + 1);
      continue;
    }
    if (name == "discovery_steps") {  // the footsteps discovered from the paper's initialisation
      discovery_steps = std::atoi(value.c_str());
      continue;
    }
    if (name == "then_normal_force_margin") {  // a second refinement with this margin, from the first's result
      then_margin = std::atof(value.c_str());
      continue;
    }
    if (name == "mesh_max_rounds") {  // RefinementMesh::max_rounds
      options.mesh.max_rounds = std::atoi(value.c_str());
      continue;
    }
    if (name == "dual_warm_start_split_fraction") {  // RefinementMesh::dual_warm_start_split_fraction
      options.mesh.dual_warm_start_split_fraction = std::atof(value.c_str());
      continue;
    }
    char* end = nullptr;
    const long i = std::strtol(value.c_str(), &end, 10);
    if (*end == '\0') {
      options.ipopt.options.push_back({name, static_cast<int>(i)});
      continue;
    }
    const double d = std::strtod(value.c_str(), &end);
    if (*end == '\0') options.ipopt.options.push_back({name, d});
    else options.ipopt.options.push_back({name, value});
  }
  scenes::HopperFootsteps steps = holes_footsteps(stance, end_stance);
  if (discovery_steps > 0)
    steps = discovered_footsteps(hopper, discovery_steps, discovery_from_hop_guess, Ocp::grid(discovery_intervals, discovery_elements));
  const ScheduleGuess<Hopper> guess = scenes::footstep_guess(hopper, steps, Ocp::q0(), Ocp::q_target(), Ocp::horizon);
  std::cout << "schedule: " << describe(hopper, guess.schedule) << "\nfootholds:";
  for (double x : steps.footholds) std::cout << " " << x;
  std::cout << "\nevent times:";
  for (double t : steps.event_times) std::cout << " " << t;
  std::cout << "\n";
  RefinementResult<Hopper> r = refine_schedule(hopper, Ocp{}, horizon, guess, options);
  if (then_stages > 0) {
    std::cout << "first solve (n_s = " << stages << "): objective " << r.objective << ", contact drift " << r.contact_drift
              << ", per-phase re-simulation " << r.phase_resim_max_error << ", " << r.seconds << " s\n";
    options.grid.stages = then_stages;
    r = refine_schedule(hopper, Ocp{}, horizon, extract_schedule(hopper, r.trajectory).guess, options);
  }
  if (then_margin > 0.0) {
    std::cout << "first refinement: " << r.stage << ", objective " << r.objective << ", local error " << r.local_error
              << ", " << r.seconds << " s; again with normal_force_margin " << then_margin << " N on its grid\n";
    options.normal_force_margin = then_margin;
    options.grid.element_boundaries = element_boundaries_of(r);
    r = refine_schedule(hopper, Ocp{}, horizon, extract_schedule(hopper, r.trajectory).guess, options);
  }
  std::cout << r.stage << " (" << r.message << ")\n  objective " << r.objective << ", mode validity "
            << r.mode_validity_violation << ", path rows " << r.path_violation << ", target " << r.terminal_violation
            << ", contact drift " << r.contact_drift << ", local error " << r.local_error
            << ", per-phase re-simulation " << r.phase_resim_max_error << ", open loop " << r.open_loop.max_error << " "
            << r.open_loop.note << ", " << r.seconds << " s\n  events:";
  for (double t : r.event_times) std::cout << " " << t;
  std::cout << "\n";
  // Where the closed contact drifts: |gap| and |normal velocity| of the foot over each stance of
  // the refined trajectory (its dense output, 200 samples per phase).
  for (std::size_t k = 0; k < r.schedule.phases.size() && k < r.trajectory.segments.size(); ++k) {
    if (!r.schedule.phases[k][0].closed()) continue;
    if (r.trajectory.segments[k].t_end - r.trajectory.segments[k].t_begin < 0.01) {
      std::cout << "  stance phase " << k << ": shorter than 10 ms\n";
      continue;
    }
    const auto& seg = r.trajectory.segments[k];
    double gap = 0, zeta = 0, t_gap = seg.t_begin, t_zeta = seg.t_begin;
    for (int i = 0; i <= 200; ++i) {
      const double t = seg.t_begin + (seg.t_end - seg.t_begin) * i / 200.0;
      const VecT<double, 8> x = r.trajectory.state(static_cast<int>(k), t);
      Kinematics<Hopper, double> kin;
      evaluate_kinematics<Hopper, double>(hopper, VecT<double, 4>(x.head<4>()), VecT<double, 4>(x.tail<4>()), kin);
      if (std::abs(kin.contacts[0].gap) > gap) gap = std::abs(kin.contacts[0].gap), t_gap = t;
      if (std::abs(kin.contacts[0].zeta_n) > zeta) zeta = std::abs(kin.contacts[0].zeta_n), t_zeta = t;
    }
    // The friction use |lambda_t| / (mu lambda_n) of the stance's mode along it (largest, and where
    // lambda_n is smallest), and the forces over the last 5 ms before the release.
    FlowWorkspace<Hopper, double> ws;
    const auto forces_at = [&](double t) {
      const VecT<double, 8> x = r.trajectory.state(static_cast<int>(k), t);
      evaluate_flow<Hopper, double>(hopper, r.schedule.phases[k], x, r.trajectory.input(t, x, r.schedule.phases[k]), ws);
      return ws.force[0];
    };
    double use = 0, t_use = seg.t_begin;
    const double scanned = seg.t_end - seg.t_begin - 5e-5;  // lambda_n = 0 at the release itself
    for (int i = 0; i <= 20000; ++i) {
      const double t = seg.t_begin + scanned * i / 20000.0;
      const ContactForce<double> f = forces_at(t);
      const double u = std::abs(f.tangent[0]) / (hopper.contact(0).mu * std::max(f.normal, 1e-300));
      if (u > use) use = u, t_use = t;
    }
    std::cout << "  stance phase " << k << ": largest friction use " << use << " at " << t_use << "; before its end:";
    for (double before : {5e-3, 2e-3, 1e-3, 3e-4, 1e-4}) {
      const ContactForce<double> f = forces_at(seg.t_end - before);
      std::cout << " [-" << before * 1e3 << " ms: lambda_n " << f.normal << ", lambda_t " << f.tangent[0] << "]";
    }
    std::cout << "\n";
    const VecT<double, 8> x_mid = r.trajectory.state(static_cast<int>(k), 0.5 * (seg.t_begin + seg.t_end));
    std::cout << "  stance phase " << k << " [" << seg.t_begin << ", " << seg.t_end << "]: foot at x = "
              << hopper.foot<double>(VecT<double, 4>(x_mid.head<4>()))[0] << ", max |gap| " << gap << " at "
              << t_gap << ", max |normal velocity| " << zeta << " at " << t_zeta << "\n";
  }
  for (const PhaseResimulation& p : r.phase_resimulation)
    std::cout << "  phase " << p.phase << " (" << p.windows << " windows): " << p.max_error << " (x+ " << p.x_plus_error
              << ") " << p.note << "\n";
  if (options.checks.resimulation_window > 0.0) {  // the same from each phase's start alone (single shooting)
    for (const PhaseResimulation& p : resimulate_phases(hopper, r.trajectory, r.schedule, r.element_times))
      std::cout << "  phase " << p.phase << " in one shot: " << p.max_error << " (x+ " << p.x_plus_error << ") " << p.note << "\n";
  }
  std::ofstream("hopper_refinement.json") << to_json(hopper, r).dump(1) << "\n";
  if (analysis_runs > 0 && r.converged) {
    const ReferenceAnalysis<Hopper> a =
        analyse_reference(hopper, r.trajectory, scenes::hopper_monte_carlo_simulation(),
                          scenes::stance_start_lqr_analysis(hopper, r.trajectory, analysis_runs, analysis_R, &std::cout));
    std::cout << "analysis: " << (a.completed() ? "completed" : "failed at " + std::string(to_string(*a.failed_at)) + ": " + a.failure);
    if (a.stability) std::cout << "; upper rate " << a.stability->upper_rate;
    if (a.monte_carlo)
      std::cout << "; Monte Carlo " << a.monte_carlo->runs << " runs, " << a.monte_carlo->failed << " failed, "
                << a.monte_carlo->kept_event_sequence << " kept the events, observed rate max " << a.monte_carlo->observed_rate_max
                << ", agree " << a.agree;
    std::cout << "\n";
    std::ofstream("hopper_analysis.json") << to_json(a).dump(1) << "\n";
  }
  return r.stage == "refined" ? 0 : 1;
}
