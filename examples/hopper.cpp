// The one-legged hopper (Capler) landing and hopping once under a simple joint-space controller,
// then the analysis of that motion as a reference: its jump gains and the first-order prediction
// of a perturbed hop.
//
// Motion: PD control of the hip and knee angles to a crouched posture while it falls and lands,
// then around t_push a stiffer PD towards a stretched leg (targets and gains blend over 10 ms, so
// the law is smooth in t), which makes the foot slip and then pushes the body up until the foot's
// normal force reaches zero and the foot lifts off (the state-input release guard).
// The controller is a feedback law u(t, x, mode); the simulator evaluates it inside the flow, and
// the gains and the linearisation are closed-loop: d u / dx enters them (jump_gain.hpp).
//
// `hopper --json` instead optimises the flagship OCP, the hopper over three holes (time-freezing
// paper Section 6; scenes/hopper_holes.hpp), from the paper's initialisation (the start state at
// every node, zero torques), in three stages with one progress line each on stderr (the chain is
// the scene library's run_hopper_chain, scenes/hopper_holes_refinement.hpp, which the Python
// bindings and the one-hole test run too):
//   discovery    the hole continuation, then the time-freezing homotopy for two steps (sigma = 1,
//                0.1), the footsteps read off its relaxed motion (scenes/hopper_holes_refinement.hpp);
//   refinement   the smooth multi-phase OCP of those footsteps' schedule on the hopper's own flows,
//                guards and jump maps, Radau IIA n_s = 4, the mesh refined to local error 2e-8
//                (refinement.hpp);
//   analysis     the refined reference's jump gains, an LQR reference-spreading design, its
//                stability check and 200 perturbed closed-loop runs at eps = 1e-6 (scenes/hopper_tracking.hpp).
// `hopper --json --hop-guess` runs the same chain from the second initialisation instead, the
// kinematic guess of three hops (HopperOverThreeHoles::hop_guess) in place of the hole continuation.
// It prints {"converged", "initialisation" ("paper" or "hop_guess"), "stage" ("refined",
// "converged, checks failed: ..." naming the failed
// checks, or the stage where it stopped), "mode_validity_violation",
// "max_path_violation", "target_error", "objective", "relaxed_objective", "schedule",
// "schedule_edits", "events", "footholds", "phase_resim_max_error", "discovery_seconds",
// "refinement_seconds", "solve_seconds", "discovery", "refinement", "analysis"} (refinement_io.hpp,
// reference_analysis_io.hpp) and writes the refined reference's trajectory and forces into
// report/hopper_over_three_holes/ (from hop_guess report/hopper_over_three_holes_hop_guess/;
// report_files.hpp), where the main job also puts that JSON as report.json.
// Exit status 0 only when the reference is refined; the analysis's outcome is reported, not
// reflected in it. About 3 minutes on one thread, the machine otherwise idle: discovery and
// refinement 141 s, the analysis 30 s, most of it the Monte Carlo runs (beside a compilation on the
// other core 243 s and 60 s; docs/refinement.md, "Hopper over three holes").
#include <saltus/hybrid/reference/resimulation.hpp>
#include <saltus/hybrid/vocabulary/trajectory_report.hpp>
#include "report_files.hpp"
#include "scenes/all_scenes.hpp"
#include "scenes/hopper_holes_refinement.hpp"

#include <saltus/sensitivity/sensitivity.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>

namespace {

int optimal_hop_over_three_holes(bool from_hop_guess) {
  using namespace saltus;
  scenes::HopperChainOptions options = scenes::hopper_chain_options(scenes::HopperTask::ThreeHoles);
  options.initialisation = from_hop_guess ? scenes::HopperInitialisation::HopGuess : scenes::HopperInitialisation::Paper;
  options.progress = &std::cerr;
  const scenes::HopperChain chain = scenes::run_hopper_chain(options);
  if (chain.refined && chain.refined->converged) {
    // The refined reference's files: report/<folder>/trajectory.json, trajectory.csv, forces.csv.
    const char* folder = from_hop_guess ? "hopper_over_three_holes_hop_guess" : "hopper_over_three_holes";
    const scenes::Hopper hopper{};
    examples::write_scene_trajectory(hopper, chain.refined->trajectory, folder, 0.005, stderr);
    examples::write_scene_forces(hopper, chain.refined->trajectory, folder, 0.005, stderr);
  }
  std::cout << to_json(chain).dump(2) << "\n";
  return chain.refined && chain.refined->stage == "refined" ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace saltus;
  if (argc > 1 && std::strcmp(argv[1], "--json") == 0)
    return optimal_hop_over_three_holes(argc > 2 && std::strcmp(argv[2], "--hop-guess") == 0);
  using H = scenes::Hopper;
  H hopper;  // masses, lengths and inertias: scenes/hopper.hpp

  // Controller parameters (units: rad, N m/rad, N m s/rad, s).
  struct Gains { double hip, knee, kp, kd; };
  const Gains crouch{0.4, -0.8, 40.0, 2.0}, stretch{0.15, -0.3, 150.0, 3.0};
  const double t_push = 0.3, blend_time = 0.01;
  InputLaw<H> controller = [=](double t, const Vec<8>& x, const Mode<1>&) {
    const double s = 0.5 * (1.0 + std::tanh((t - t_push) / blend_time));  // 0: crouch, 1: stretch
    const auto mix = [s](double a, double b) { return a + s * (b - a); };
    const double hip = mix(crouch.hip, stretch.hip), knee = mix(crouch.knee, stretch.knee);
    const double kp = mix(crouch.kp, stretch.kp), kd = mix(crouch.kd, stretch.kd);
    return Vec<2>(kp * (hip - x[2]) - kd * x[6], kp * (knee - x[3]) - kd * x[7]);
  };

  Vec<8> x0 = Vec<8>::Zero();
  x0 << 0.0, 0.0, crouch.hip, crouch.knee, 0.3, 0.0, 0.0, 0.0;  // moving forward at 0.3 m/s
  x0[1] = 0.05 - hopper.foot(Vec<4>(x0.head<4>()))[1];          // foot 5 cm above the ground

  SimulationOptions options;
  options.integrator.relative_tolerance = 1e-12;
  options.integrator.absolute_tolerance = 1e-13;
  Simulator<H> simulator(hopper, options);
  const double t_end = 0.45;
  const auto traj = simulator.run(x0, 0.0, t_end, controller);

  std::printf("hopper: landing and one hop under a joint PD controller\n");
  print_events(hopper, traj);
  examples::write_scene_trajectory(hopper, traj, "hopper", 0.005);  // report/hopper/
  examples::write_scene_forces(hopper, traj, "hopper", 0.005);
  bool lift_off = false;
  for (const auto& ev : traj.events)
    for (const Guard& g : ev.guards()) lift_off = lift_off || g.kind == GuardKind::Release;
  if (!lift_off) return 1;

  // ---- analysis: jump gains (closed loop) and the first-order prediction ---------------------
  LinearisationOptions lo;
  lo.spreading.before = lo.spreading.after = 0.02;  // covers the perturbed event shifts below
  const LinearisedSystem<H> lin(hopper, traj, lo);
  std::printf("\njump gains z+ = G_z z- + G_v v- (closed loop), event-time shift dt = dt_dz z- + dt_dv v-:\n");
  // report/hopper/jump_gains.json: {"events": [{t, guard, G_z_minus_identity_max, G_v_max, dt_dz_norm}]},
  // numbers to 6 significant digits.
  const auto number = [](double x) -> nlohmann::ordered_json {
    if (!std::isfinite(x)) return nullptr;
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", x);
    return std::strtod(buf, nullptr);
  };
  auto gains = nlohmann::ordered_json::array();
  for (std::size_t e = 0; e < lin.gains().size(); ++e) {
    const auto& g = lin.gains()[e];
    const auto& ev = traj.events[e];
    const double off_identity = (g.G_z - Mat<8, 8>::Identity()).cwiseAbs().maxCoeff();
    std::printf("  t = %.6f %-10s |G_z - I|max = %-10.3g |G_v|max = %-10.3g |dt_dz| = %.3g\n", ev.t,
                to_string(ev.guards().at(0).kind), off_identity, g.G_v.cwiseAbs().maxCoeff(), g.dt_dz.norm());
    gains.push_back({{"t", number(ev.t)},
                     {"guard", to_string(ev.guards().at(0).kind)},
                     {"G_z_minus_identity_max", number(off_identity)},
                     {"G_v_max", number(g.G_v.cwiseAbs().maxCoeff())},
                     {"dt_dz_norm", number(g.dt_dz.norm())}});
  }
  std::ofstream json(examples::scene_directory("hopper") / "jump_gains.json");
  json << nlohmann::ordered_json{{"events", gains}}.dump() << "\n";

  // A perturbed hop: initial state x0 + eps z0, torques + eps v(t). The reference-spreading
  // remainder |x_eps(t_end) - x_k(t_end) - eps z_k(t_end)| must shrink like eps^2.
  Vec<8> z0;
  z0 << 0.6, 0.3, -0.9, 0.6, 1.5, -1.2, 3.0, -1.5;
  const auto v = [](double t) { return Vec<2>(0.3 * std::sin(10 * t), -0.2); };
  const auto prediction = lin.predict(z0, v);
  const int last = lin.segment_count() - 1;
  DormandPrinceIntegrator<H> integrator(options.integrator);
  std::printf("\nfirst-order prediction of a perturbed hop at t = %.2f s:\n", t_end);
  double previous = 0.0;
  bool second_order = true;
  for (double eps : {1e-3, 1e-4, 1e-5}) {
    const InputLaw<H> perturbed = [&, eps](double t, const Vec<8>& x, const Mode<1>& m) {
      return Vec<2>(controller(t, x, m) + eps * v(t));
    };
    const auto run = simulator.run(Vec<8>(x0 + eps * z0), 0.0, t_end, perturbed);
    if (static_cast<int>(run.events.size()) != last) return 1;  // the same events as the reference
    ModeSystem<H> sys(hopper, controller);
    sys.set_mode(lin.mode(last));
    Vec<8> x_ref = lin.begin_state(last);
    integrator.integrate(sys, lin.t_begin(last), x_ref, t_end, 0.0, nullptr, false);
    const double remainder = (run.final_state() - x_ref - eps * prediction.z(last, t_end)).cwiseAbs().maxCoeff();
    std::printf("  eps = %.0e   |deviation| = %.3e   remainder = %.3e%s\n", eps, (run.final_state() - x_ref).cwiseAbs().maxCoeff(),
                remainder, previous > 0 ? (" (x " + std::to_string(remainder / previous) + ")").c_str() : "");
    if (previous > 0) second_order = second_order && remainder < 0.03 * previous;
    previous = remainder;
  }
  return second_order ? 0 : 1;
}
