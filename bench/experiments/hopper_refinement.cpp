// The hopper over three holes refined from a footstep schedule (docs/refinement.md, "Hopper").
//
//   hopper_refinement [stance [h [max_iter [end_stance [cone_margin [n_s [print_level [then_n_s [end_clustering
//                     [local_error [warm_start_mu [max_split [mesh_max_iter]]]]]]]]]]]]]
//   (defaults 0.45 0.02 1000 0.3 0 3 0 0 0 0 0.1 8 500; print_level is Ipopt's; then_n_s > 0: a second refinement
//   with that many stages, started from the first one's result, the order continuation;
//   end_clustering: RefinementGrid::end_clustering; local_error > 0: the mesh refinement's
//   RefinementMesh::local_error_tolerance; warm_start_mu, max_split, mesh_max_iter: RefinementMesh's
//   warm_start_mu, max_split, max_iter); any further arguments name=value are Ipopt options
//   (RefinementIpopt::options: an integer, a number or a string, e.g. mumps_pivot_order=0), except
//   resimulation_window=<s> (RefinementChecks::resimulation_window), mesh_max_rounds=<n>
//   (RefinementMesh::max_rounds), analysis_runs=<n> (the refined reference analysed by
//   analyse_reference with n Monte Carlo runs, report in hopper_analysis.json) and analysis_R=<r>
//   (its LQR's input weight, default 1e-3)
//
// Discovery by the time-freezing homotopy gives no usable schedule on this OCP (docs/refinement.md,
// "Hopper over three holes"), so the schedule here is a user's guess, the footsteps the holes
// leave: four stances (the foot sticking) at x = 0, 1, 2, 3, the first and the last `end_stance`
// seconds long, the two middle ones `stance`, and three flights of equal length in between. The
// motion guessed, kinematically consistent with the schedule: in a stance the foot stays on its
// foothold while the hip moves at constant speed from 0.15 m behind it to 0.15 m ahead (from and to
// the start and target poses in the first and last stance), the hip-to-foot distance 0.39 m (the
// knee bent forward, angles by inverse kinematics; 0.4 m, the leg straight, at t = 0 and T); in a
// flight the hip moves at constant speed to the next touchdown pose on a ballistic arc (capped at
// z = 0.54) and the joint angles go linearly from the lift-off pose to the touchdown pose;
// velocities by central differences; zero torques. The OCP is scenes/hopper_holes.hpp as it is
// (T = 2.5 s, |u| <= 60, the 11 path rows at the full holes, the start at rest, the target
// q(T) = (3, 0.4, 0, 0)). Prints the refinement's progress, its result, where each stance's closed
// contact drifts (largest |gap| and |normal velocity| over 200 samples) and its checks; writes the
// result's JSON to hopper_refinement.json. About 4 minutes on one thread with the defaults
// (docs/refinement.md, "Hopper over three holes").
#include "scenes/all_scenes.hpp"
#include "scenes/hopper_holes.hpp"

#include <saltus/sensitivity/analysis/reference_analysis.hpp>
#include <saltus/sensitivity/analysis/reference_analysis_io.hpp>
#include <saltus/timefreezing/refinement/refinement.hxx>
#include <saltus/timefreezing/refinement/refinement_io.hpp>
#include <saltus/timefreezing/refinement/schedule_extraction.hpp>

#include <Eigen/SVD>

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

constexpr double hip_offset = 0.15;      // hip ahead of / behind the foothold at lift-off / touchdown [m]
constexpr double stance_leg = 0.39;      // hip-to-foot distance in a stance [m]
constexpr double link_length = 0.2;      // thigh = shank (scenes/hopper.hpp)

/// (phi_hip, phi_knee) that put the foot at (fx, 0) below a hip at (hx, hz), the knee bent forward.
saltus::Vec<2> leg_angles_reaching(double hx, double hz, double fx) {
  const double rx = fx - hx, rz = -hz, reach = std::min(std::hypot(rx, rz), 2 * link_length);
  const double knee = -2.0 * std::acos(std::min(1.0, reach / (2 * link_length)));
  return saltus::Vec<2>(std::atan2(rx, -rz) - knee / 2, knee);
}

/// One phase of the guessed gait: [begin, end], a stance on `foothold` or a flight from it.
struct GuessPhase {
  double begin = 0.0, end = 0.0;
  bool stance = true;
  int foothold = 0;
};

saltus::Vec<4> stance_pose(const GuessPhase& p, double t) {
  const double s = (t - p.begin) / (p.end - p.begin), x = p.foothold;
  const double from = p.foothold == 0 ? 0.0 : x - hip_offset, to = p.foothold == 3 ? 3.0 : x + hip_offset;
  const double leg = p.foothold == 0 ? 0.4 + (stance_leg - 0.4) * s
                     : p.foothold == 3 ? stance_leg + (0.4 - stance_leg) * s : stance_leg;
  const double hx = from + (to - from) * s, hz = std::sqrt(std::max(0.04, leg * leg - (hx - x) * (hx - x)));
  const saltus::Vec<2> a = leg_angles_reaching(hx, hz, x);
  return saltus::Vec<4>(hx, hz, a[0], a[1]);
}

saltus::Vec<4> flight_pose(const GuessPhase& p, double t) {
  const double s = (t - p.begin) / (p.end - p.begin), z0 = std::sqrt(stance_leg * stance_leg - hip_offset * hip_offset);
  const double x0 = p.foothold + hip_offset, x1 = p.foothold + 1 - hip_offset;
  const saltus::Vec<2> a0 = leg_angles_reaching(x0, z0, p.foothold), a1 = leg_angles_reaching(x1, z0, p.foothold + 1);
  const double hz = std::min(0.54, z0 + 0.5 * 9.81 * (t - p.begin) * (p.end - t));
  const saltus::Vec<2> a = a0 + (a1 - a0) * s;
  return saltus::Vec<4>(x0 + (x1 - x0) * s, hz, a[0], a[1]);
}

saltus::timefreezing::ScheduleGuess<Hopper> footstep_guess(const Hopper& hopper, double stance, double end_stance) {
  using namespace saltus;
  using namespace saltus::timefreezing;
  const double flight = (Ocp::horizon - 2 * end_stance - 2 * stance) / 3.0;
  std::vector<GuessPhase> phases;
  double t = 0.0;
  for (int k = 0; k < 4; ++k) {
    const double d = (k == 0 || k == 3) ? end_stance : stance;
    phases.push_back({t, t + d, true, k});
    t += d;
    if (k < 3) phases.push_back({t, t + flight, false, k});
    if (k < 3) t += flight;
  }
  ScheduleGuess<Hopper> g;
  Mode<1> stick, open;
  stick[0] = ContactState::stick();
  for (const GuessPhase& p : phases) g.schedule.phases.push_back(p.stance ? stick : open);
  for (std::size_t k = 0; k + 1 < phases.size(); ++k) {
    g.schedule.events.push_back(guards_between(hopper, g.schedule.phases[k], g.schedule.phases[k + 1]));
    g.event_times.push_back(phases[k].end);
  }
  g.schedule = validated(hopper, g.schedule);
  g.state = [phases](int k, double t) {
    const GuessPhase& p = phases[static_cast<std::size_t>(k)];
    const auto pose = [&p](double s) { return p.stance ? stance_pose(p, s) : flight_pose(p, s); };
    const double c = std::clamp(t, p.begin, p.end), a = std::max(p.begin, c - 1e-5), b = std::min(p.end, c + 1e-5);
    VecT<double, 8> x;
    x << pose(c), (pose(b) - pose(a)) / (b - a);
    return x;
  };
  g.input = [](double) { return VecT<double, 2>::Zero(); };
  return g;
}

/// An LQR tracking design for a hopper reference (Q = 10 on q, 1 on v, R = `R` I, by default
/// 1e-3: the torques reach 60 N m) and its check: deviations of the initial state that keep the first stance (the
/// foot on the ground, at rest: the gap's and the foot velocity's rows removed), measured on the
/// whole state.
saltus::ReferenceAnalysisOptions<Hopper> hopper_analysis(const Hopper& hopper, const saltus::HybridTrajectory<Hopper>& ref,
                                                         int runs, double R) {
  using namespace saltus;
  ReferenceAnalysisOptions<Hopper> o;
  o.design.name = "LQR, Q = (10 q, 1 v), R = " + std::to_string(R) + " I";
  o.design.weights.Q.diagonal() << 10, 10, 10, 10, 1, 1, 1, 1;
  o.design.weights.Q_final = o.design.weights.Q;
  o.design.weights.R *= R;
  const VecT<double, 8> x0 = ref.state(0, ref.t_begin());
  Kinematics<Hopper, double> kin;
  evaluate_kinematics<Hopper, double>(hopper, VecT<double, 4>(x0.head<4>()), VecT<double, 4>(x0.tail<4>()), kin);
  Eigen::Matrix<double, 3, 8> C = Eigen::Matrix<double, 3, 8>::Zero();  // gap, normal and tangential velocity
  C.block<1, 4>(0, 0) = kin.contacts[0].wn.transpose();
  C.block<1, 4>(1, 4) = kin.contacts[0].wn.transpose();
  C.block<1, 4>(2, 4) = kin.contacts[0].Wt.col(0).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix<double, 3, 8>> svd(C, Eigen::ComputeFullV);
  const Eigen::Matrix<double, 8, 5> E = svd.matrixV().rightCols<5>();
  o.stability.initial_subspace = E;
  o.monte_carlo.runs = runs;
  o.monte_carlo.threads = 1;
  o.monte_carlo.project = [E](const Vec<8>& d) { return Vec<8>(E * (E.transpose() * d)); };
  o.progress = &std::cout;
  return o;
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
  const ScheduleGuess<Hopper> guess = footstep_guess(hopper, stance, end_stance);
  std::cout << "schedule: " << describe(hopper, guess.schedule) << "\n";
  OcpHorizon<Hopper> horizon;
  horizon.x0 << Ocp::q0(), Ocp::v0();
  horizon.final_time = Ocp::horizon;
  horizon.control_lower = Eigen::VectorXd::Constant(2, -Ocp::torque_limit);
  horizon.control_upper = Eigen::VectorXd::Constant(2, Ocp::torque_limit);
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
  for (int a = 14; a < argc; ++a) {
    const std::string arg = argv[a];
    const std::size_t eq = arg.find('=');
    if (eq == std::string::npos) continue;
    const std::string name = arg.substr(0, eq), value = arg.substr(eq + 1);
    if (name == "resimulation_window") {  // RefinementChecks::resimulation_window [s], not an Ipopt option
      options.checks.resimulation_window = std::atof(value.c_str());
      continue;
    }
    if (name == "analysis_runs") {  // analyse_reference with that many Monte Carlo runs (hopper_analysis below)
      analysis_runs = std::atoi(value.c_str());
      continue;
    }
    if (name == "analysis_R") {  // the LQR's input weight R = analysis_R I (hopper_analysis below)
      analysis_R = std::atof(value.c_str());
      continue;
    }
    if (name == "mesh_max_rounds") {  // RefinementMesh::max_rounds
      options.mesh.max_rounds = std::atoi(value.c_str());
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
  RefinementResult<Hopper> r = refine_schedule(hopper, Ocp{}, horizon, guess, options);
  if (then_stages > 0) {
    std::cout << "first solve (n_s = " << stages << "): objective " << r.objective << ", contact drift " << r.contact_drift
              << ", per-phase re-simulation " << r.phase_resim_max_error << ", " << r.seconds << " s\n";
    options.grid.stages = then_stages;
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
    const ReferenceAnalysis<Hopper> a = analyse_reference(hopper, r.trajectory, SimulationOptions{}, hopper_analysis(hopper, r.trajectory, analysis_runs, analysis_R));
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
