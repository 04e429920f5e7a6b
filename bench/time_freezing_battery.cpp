// Robustness of the time-freezing simulation engine (simulate_time_freezing) on a battery of easy
// problems, scored as the field's MPCC benchmarks score solvers (NOSBENCH, Nurkanovic, Pozharskiy
// and Diehl 2024: the fraction of problems solved), with one difference: a case counts as solved
// only when every homotopy converged AND its final state matches the closed form AND every impact
// the run records (its frozen phases not flagged FrozenPhase::cut, and the recovered trajectory's
// impact events) ends at the impact's outcome, zero normal velocity (a converged homotopy on a wrong motion, or a record cut
// in the middle of its impact, is a failure here).
//
//   time_freezing_battery [--json] [--only SUBSTRING] [--no-fallback] [--refinements N]
//                         [--penetration-tolerance M] [--kappa K] [--sigma0 S] [--penalty] [--progress]
//
// Cases (closed forms in the comments of each family below):
//   ball     NOSNOC's bouncing ball without restitution: the point mass dropped from rest at
//            height h onto the frictionless table (g = 9.81), for h in {0.2, 0.8, 2}, a_n in
//            {g, 20, 100}, on NOSNOC's grid (N = 10 control intervals, N_fe = 2, n_s = 2,
//            horizon 3) and a finer one (N = 20, N_fe = 3), plain and with the contact-side
//            selection 1e-2 (the documented option for one-contact simulations): 36 cases.
//   slide    NOSNOC's frictional landing (mu = 0.2, g = 10, a_n = 20) thrown at v0 in {1, 3, 5}
//            from height 1, plain and with the contact-side selection: 6 cases.
//   rod      a rod dropped flat onto the table while sliding (scenes::Rod: two contacts landing
//            at once, NOSNOC's falling_rod): h in {0.3, 0.8}, v0 in {1, 3}, a_n = 100, plain and
//            with the contact-side selection: 8 cases. Scored at the run's own final physical time,
//            and on the touchdown's time (the frozen phase's numerical duration is not unique for
//            two contacts landing at once: rod_case).
//   guiding  the paper's Example 3 (tests/test_time_freezing.cpp) with n_s = 2, 4 elements per
//            control interval (56 in all), plain and with the contact-side selection: 2 cases.
//   painleve Painleve's inconsistent configuration (the rod of tests/painleve_rod.hpp), whose frozen
//            phase should be the impact without collision: a_n in {10, 100}, plain and with the
//            contact-side selection: 4 cases, scored on the first frozen phase's x_plus.
// --only keeps the cases whose name contains SUBSTRING; --no-fallback turns off the engine's
// fallback for failed control intervals (TimeFreezingSimulationOptions), to measure it;
// --refinements and --penetration-tolerance set its SimulationFallback::max_refinements and
// penetration_tolerance; --kappa, --sigma0 and --penalty set the homotopy's kappa, sigma_0 and the
// Penalty relaxation (MpccSolverOptions::Homotopy) for every case.
// --json prints one object {"cases": [{"name", "family", "solved", "converged", "final_error",
// "ipopt_iterations", "seconds", "fallbacks", "impact_outcome_error", "frozen_phases", "impacts",
// "cut_phases", "straddling_phases", "final_state", "exact_final_state", "message"}...], "solved": k, "total": n}; without it
// a table and the fraction solved per family. One progress line per case on stderr.
#include "scenes/point_mass.hpp"
#include "scenes/rod.hpp"
#include "scenes/time_freezing_examples.hpp"

#include <saltus/hybrid/dynamics/impact_without_collision.hpp>
#include <saltus/timefreezing/drivers/simulate.hpp>
#include <saltus/timefreezing/header_only.hpp>

#include "painleve_rod.hpp"  // tests/: the rod of Painleve's paradox, compiled here header-only

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <iostream>
#include <string>
#include <vector>

namespace {

using namespace saltus;
using namespace saltus::timefreezing;
using scenes::PointMass;

struct Outcome {
  std::string name, family;
  bool converged = false, solved = false;
  double final_error = 0.0, seconds = 0.0;
  /// The largest |normal velocity| after an impact (the table's, v2): 0 for these inelastic impacts,
  /// over every frozen phase's x_plus and every recovered impact event's x_plus.
  double impact_outcome_error = 0.0;
  int frozen_phases = 0, impacts = 0;
  int cut_phases = 0;         ///< frozen phases flagged FrozenPhase::cut
  int straddling_phases = 0;  ///< frozen phases (not cut) across a control interval's end
  std::vector<double> final_state, exact_state;
  int iterations = 0, fallbacks = 0;
  std::string message;
};

struct Case {
  std::string name, family;
  std::function<Outcome(const SimulationFallback&, const MpccSolverOptions&)> run;
};

/// Scores a simulation: the final state's (q, v, t) against `exact` (max norm), and the largest
/// post-impact normal speed `normal_speed(x_plus)` over its frozen phases and impact events.
template <class Sim, class NormalSpeed>
Outcome score(const Sim& sim, const Eigen::VectorXd& exact, double seconds, double tolerance, NormalSpeed normal_speed) {
  Outcome o;
  o.converged = sim.converged();
  const auto& y = sim.final_state();
  o.final_error = (y.head(exact.size()) - exact).cwiseAbs().maxCoeff();
  o.final_state.assign(y.data(), y.data() + exact.size());
  o.exact_state.assign(exact.data(), exact.data() + exact.size());
  for (const auto& f : sim.frozen_phases) {
    if (f.cut) {
      ++o.cut_phases;  // its x_plus is not the outcome, and says so
      continue;
    }
    o.impact_outcome_error = std::max(o.impact_outcome_error, normal_speed(f.x_plus));
    const double H = sim.points.back().tau / std::max<std::size_t>(1, sim.finite_elements.size());
    if (std::floor(f.tau_begin / H + 1e-9) != std::floor(f.tau_end / H - 1e-9)) ++o.straddling_phases;
  }
  for (const auto& e : sim.trajectory.events)
    if (e.impact()) {
      o.impact_outcome_error = std::max(o.impact_outcome_error, normal_speed(e.x_plus));
      ++o.impacts;
    }
  o.frozen_phases = static_cast<int>(sim.frozen_phases.size());
  o.solved = o.converged && o.final_error <= tolerance && o.impact_outcome_error <= tolerance;
  o.seconds = seconds;
  o.iterations = sim.solution.ipopt_iterations;
  o.fallbacks = sim.fallbacks;
  o.message = sim.solution.message;
  for (const std::string& line : sim.fallback_log) o.message += "; " + line;
  return o;
}

/// The point mass: (q1, q2, v1, v2, t) against `exact`, the table's normal velocity v2.
template <class Sim>
Outcome score(const Sim& sim, const Vec<5>& exact, double seconds, double tolerance) {
  return score(sim, Eigen::VectorXd(exact), seconds, tolerance, [](const auto& x) { return std::abs(x[3]); });
}

template <class F>
double timed(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The physical time at numerical time T of a point mass that reaches the table at tau = t = t1 with
/// normal speed v1 and then rests or slides on it: the frozen phase takes v1 / a_n of numerical
/// time; on the table the Filippov combination theta (-g) + (1 - theta) a_n = 0 of the ODE field
/// (clock speed 1) and the auxiliary field (clock speed 0) runs the clock at theta = a_n / (a_n + g).
double time_on_the_table(double T, double t1, double v1, double g, double a_n) {
  return t1 + (T - t1 - v1 / a_n) * a_n / (a_n + g);
}

/// Ball drop without restitution: free fall to t1 = sqrt(2 h / g) with v1 = sqrt(2 g h) downwards,
/// then rest. At numerical time T: q = (0, 0), v = 0, t = time_on_the_table(T, t1, v1, g, a_n).
Case ball_case(double h, double a_n, int N, int N_fe, bool side) {
  char name[96];
  std::snprintf(name, sizeof name, "ball h=%g a_n=%g N=%d N_fe=%d%s", h, a_n, N, N_fe, side ? " side" : "");
  return {name, "ball", [=](const SimulationFallback& fallback, const MpccSolverOptions& solver) {
            const double g = 9.81, T = 3.0;
            scenes::PointMassParameters p;
            p.gravity = g;
            const TimeFreezingSystem<PointMass> system(PointMass(p), a_n);
            FesdOptions o;
            o.grid.stages = 2;
            o.grid.control_intervals = N;
            o.grid.finite_elements = N_fe;
            o.grid.horizon = T;
            if (side) o.regularisation.contact_side = 1e-2;
            TimeFreezingSimulationOptions options;
            options.fallback = fallback;
            TimeFreezingSimulation<PointMass> sim;
            const double s = timed([&] { sim = simulate_time_freezing(system, Vec<2>(0.0, h), Vec<2>::Zero(), o, NoObjective{}, solver, options); });
            const Vec<5> exact(0.0, 0.0, 0.0, 0.0, time_on_the_table(T, std::sqrt(2.0 * h / g), std::sqrt(2.0 * g * h), g, a_n));
            return score(sim, exact, s, 1e-6);
          }};
}

/// NOSNOC's frictional landing thrown at v0: touchdown at t1 = sqrt(2/g) (h = 1), the impact
/// (frozen, a_n along the normal, friction mu a_n against the slip) leaves v_t = v0 - mu sqrt(2 g)
/// (while > 0), then the slide decelerates at mu g, x = v0 t1 + v_t s - mu g s^2 / 2 with
/// s = t - t1, until it stops at s = v_t / (mu g). The physical time at the horizon's end is
/// time_on_the_table (sliding and resting run the clock alike); the state there is the slide's or
/// the rest's.
Case slide_case(double v0, bool side) {
  char name[64];
  std::snprintf(name, sizeof name, "slide v0=%g%s", v0, side ? " side" : "");
  return {name, "slide", [=](const SimulationFallback& fallback, const MpccSolverOptions& solver) {
            using Landing = scenes::FrictionalLanding;
            const double g = 10.0, mu = 0.2, a_n = 20.0;
            FesdOptions o = Landing::grid();
            if (!side) o.regularisation.contact_side = 0.0;
            TimeFreezingSimulationOptions options;
            options.fallback = fallback;
            TimeFreezingSimulation<PointMass> sim;
            const double s = timed([&] {
              sim = simulate_time_freezing(Landing::system(), Landing::q0(), Vec<2>(v0, 0.0), o, NoObjective{}, solver, options);
            });
            const double t1 = std::sqrt(2.0 / g), vt = std::max(0.0, v0 - mu * std::sqrt(2.0 * g));
            const double t = time_on_the_table(o.grid.horizon, t1, std::sqrt(2.0 * g), g, a_n);
            const double slide = std::min(t - t1, vt / (mu * g));
            const Vec<5> exact(v0 * t1 + vt * slide - 0.5 * mu * g * slide * slide, 0.0, vt - mu * g * slide, 0.0, t);
            return score(sim, exact, s, 1e-6);
          }};
}

/// The rod (scenes::Rod, mu = 0.2, a_n = 100) dropped flat from height h while sliding at v0: the
/// point mass's motion (rod.hpp: both ends land at once and theta stays 0), touchdown at
/// t1 = sqrt(2 h / g) with v1 = sqrt(2 g h), v_x+ = v0 - mu v1, then the slide at mu g to rest.
/// N = 10, N_fe = 2, n_s = 2, horizon 2, with the contact-side selection or without.
/// Scored on the state at the run's own final physical time, and on the touchdown's time: the
/// numerical time the frozen phase takes is not unique here. Both ends sit on gap = 0 while the
/// positions are frozen, where their gaps' step functions are free; the Filippov sliding on both
/// gaps needs only Theta = prod_i (1 - beta_i) = 0, so one end pushes at the full a_n and the other
/// at any beta in [0, 1] (measured: omega reaches 3.1 rad/s inside the frozen phase and returns to
/// 0, the outcome the same). The impact's outcome is unique, its duration in numerical time is
/// not, and with it the physical time reached at the horizon's end; the message gives that time's
/// offset from the symmetric push's.
Case rod_case(double h, double v0, bool side) {
  char name[64];
  std::snprintf(name, sizeof name, "rod h=%g v0=%g%s", h, v0, side ? " side" : "");
  return {name, "rod", [=](const SimulationFallback& fallback, const MpccSolverOptions& solver) {
            const double g = 9.81, mu = 0.2, a_n = 100.0, T = 2.0;
            const TimeFreezingSystem<scenes::Rod> system(scenes::Rod(), a_n);
            FesdOptions o;
            o.grid.stages = 2;
            o.grid.control_intervals = 10;
            o.grid.finite_elements = 2;
            o.grid.horizon = T;
            if (side) o.regularisation.contact_side = 1e-2;
            TimeFreezingSimulationOptions options;
            options.fallback = fallback;
            TimeFreezingSimulation<scenes::Rod> sim;
            const double s = timed([&] {
              sim = simulate_time_freezing(system, Vec<3>(0.0, h, 0.0), Vec<3>(v0, 0.0, 0.0), o, NoObjective{}, solver, options);
            });
            const double t1 = std::sqrt(2.0 * h / g), v1 = std::sqrt(2.0 * g * h), vt = std::max(0.0, v0 - mu * v1);
            // The symmetric push (both ends at a_n): v1 / (2 a_n) of numerical time. On the table the
            // clock runs at Theta = (1 - beta)^2 (the product of the two ends' free weights, equal by
            // the torque balance), where the vertical balance Theta g = 2 a_n beta holds:
            // g beta^2 - 2 (g + a_n) beta + g = 0, the root in (0, 1).
            const double beta = ((g + a_n) - std::sqrt((g + a_n) * (g + a_n) - g * g)) / g;
            const double clock_speed = (1.0 - beta) * (1.0 - beta);
            const double t_symmetric = t1 + (T - t1 - v1 / (2.0 * a_n)) * clock_speed;
            const double t = sim.final_state()[6];
            const double slide = std::clamp(t - t1, 0.0, vt / (mu * g));
            Eigen::VectorXd exact(7);
            exact << v0 * t1 + vt * slide - 0.5 * mu * g * slide * slide, 0.0, 0.0, vt - mu * g * slide, 0.0, 0.0, t;
            // The ends' normal velocities v_y -+ (l/2) omega (l = 1).
            Outcome out = score(sim, exact, s, 1e-6,
                                [](const auto& x) { return std::max(std::abs(x[4] - 0.5 * x[5]), std::abs(x[4] + 0.5 * x[5])); });
            double touchdown_error = sim.trajectory.events.empty() ? std::numeric_limits<double>::infinity() : 0.0;
            for (const auto& e : sim.trajectory.events)
              if (e.impact()) touchdown_error = std::max(touchdown_error, std::abs(e.t - t1));
            out.final_error = std::max(out.final_error, touchdown_error);
            out.solved = out.solved && touchdown_error <= 1e-6;
            char note[128];
            std::snprintf(note, sizeof note, "; touchdown %.2e s off, final time %.2e s from the symmetric push's",
                          touchdown_error, t - t_symmetric);
            out.message += note;
            return out;
          }};
}

/// Painleve's inconsistent configuration (tests/painleve_rod.hpp): the rod at 45 degrees, mu = 2,
/// its lower end on the ground sliding at -1 m/s, where no normal force keeps the end on the
/// ground. The auxiliary dynamics should integrate the impact without collision in frozen time
/// (Genot and Brogliato 1999; closed form: dynamics/impact_without_collision.hpp): P = (3/8, 5/8)
/// N s, v+ = (-3/8, 3/8, 3 sqrt(2) / 4). Scored on the first frozen phase's x_plus (the final
/// state is not known in closed form): N = 4, N_fe = 2, horizon 0.2, a_n in {10, 100}.
Case painleve_case(double a_n, bool side) {
  char name[64];
  std::snprintf(name, sizeof name, "painleve a_n=%g%s", a_n, side ? " side" : "");
  return {name, "painleve", [=](const SimulationFallback& fallback, const MpccSolverOptions& solver) {
            using saltus::testing::PainleveRod;
            const double mu = 2.0, c = std::sqrt(0.5);
            const PainleveRod rod(mu);
            const Vec<3> q0(0.5 * c, 0.5 * c, M_PI / 4), v0(-1.0, 0.0, 0.0);
            Eigen::Matrix<double, 2, 3> J;  // rows w_n, w_t of the lower end
            J << 0.0, 1.0, -0.5 * c, 1.0, 0.0, 0.5 * c;
            const Eigen::Matrix3d Minv = Eigen::Vector3d(1.0, 1.0, 12.0).asDiagonal();
            const ImpactWithoutCollision iwc = impact_without_collision(J * Minv * J.transpose(), mu, 0.0, (J * v0)[1]);
            const Vec<3> v_plus = v0 + Minv * J.transpose() * Eigen::Vector2d(iwc.normal, iwc.tangent);
            const TimeFreezingSystem<PainleveRod> system(rod, a_n);
            FesdOptions o;
            o.grid.stages = 2;
            o.grid.control_intervals = 4;
            o.grid.finite_elements = 2;
            o.grid.horizon = 0.2;
            if (side) o.regularisation.contact_side = 1e-2;
            TimeFreezingSimulationOptions options;
            options.fallback = fallback;
            TimeFreezingSimulation<PainleveRod> sim;
            const double s = timed([&] { sim = simulate_time_freezing(system, q0, v0, o, NoObjective{}, solver, options); });
            Outcome out;
            out.converged = sim.converged();
            out.frozen_phases = static_cast<int>(sim.frozen_phases.size());
            out.final_error = sim.frozen_phases.empty()
                                  ? std::numeric_limits<double>::infinity()
                                  : (sim.frozen_phases[0].x_plus.tail<3>() - v_plus).cwiseAbs().maxCoeff();
            out.solved = out.converged && out.final_error <= 1e-6;
            out.seconds = s;
            out.iterations = sim.solution.ipopt_iterations;
            out.fallbacks = sim.fallbacks;
            out.message = sim.solution.message;
            return out;
          }};
}

/// Example 3 (closed form: scenes::Example3::final_state, derived in bench/fesd_accuracy.cpp).
Case guiding_case(bool side) {
  return {side ? "guiding side" : "guiding", "guiding", [=](const SimulationFallback& fallback, const MpccSolverOptions& solver) {
            const TimeFreezingSystem<PointMass> system(PointMass(), scenes::Example3::gravity);
            FesdOptions o;
            o.grid.stages = 2;
            o.grid.control_intervals = 14;
            o.grid.finite_elements = 4;
            o.grid.horizon = scenes::Example3::horizon;
            if (side) o.regularisation.contact_side = 1e-2;
            TimeFreezingSimulationOptions options;
            options.fallback = fallback;
            TimeFreezingSimulation<PointMass> sim;
            const double s = timed([&] {
              sim = simulate_time_freezing(system, Vec<2>(0.0, 1.0), Vec<2>::Zero(), o, scenes::Example3{}, solver, options);
            });
            return score(sim, scenes::Example3::final_state(), s, 1e-3);
          }};
}

std::vector<Case> battery() {
  std::vector<Case> cases;
  for (bool side : {false, true})
    for (auto [N, N_fe] : {std::pair{10, 2}, std::pair{20, 3}})
      for (double a_n : {9.81, 20.0, 100.0})
        for (double h : {0.2, 0.8, 2.0}) cases.push_back(ball_case(h, a_n, N, N_fe, side));
  for (bool side : {false, true})
    for (double v0 : {1.0, 3.0, 5.0}) cases.push_back(slide_case(v0, side));
  for (bool side : {false, true})
    for (double h : {0.3, 0.8})
      for (double v0 : {1.0, 3.0}) cases.push_back(rod_case(h, v0, side));
  for (bool side : {false, true}) cases.push_back(guiding_case(side));
  for (bool side : {false, true})
    for (double a_n : {10.0, 100.0}) cases.push_back(painleve_case(a_n, side));
  return cases;
}

}  // namespace

int main(int argc, char** argv) {
  setenv("OPENBLAS_NUM_THREADS", "1", 1);
  bool json = false;
  std::string only;
  SimulationFallback fallback;
  MpccSolverOptions solver;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--json") == 0) {
      json = true;
    } else if (std::strcmp(argv[i], "--only") == 0 && i + 1 < argc) {
      only = argv[++i];
    } else if (std::strcmp(argv[i], "--progress") == 0) {
      solver.progress = &std::cerr;
    } else if (std::strcmp(argv[i], "--kappa") == 0 && i + 1 < argc) {
      solver.homotopy.kappa = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--penalty") == 0) {
      solver.homotopy.relaxation = MpccSolverOptions::Relaxation::Penalty;
    } else if (std::strcmp(argv[i], "--sigma0") == 0 && i + 1 < argc) {
      solver.homotopy.sigma_0 = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--penetration-tolerance") == 0 && i + 1 < argc) {
      fallback.penetration_tolerance = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--refinements") == 0 && i + 1 < argc) {
      fallback.max_refinements = std::atoi(argv[++i]);
    } else if (std::strcmp(argv[i], "--no-fallback") == 0) {
      fallback.enabled = false;
    } else {
      std::cerr << "usage: time_freezing_battery [--json] [--only SUBSTRING] [--no-fallback] [--refinements N] [--penetration-tolerance M] [--kappa K] [--sigma0 S] [--penalty] [--progress]\n";
      return 2;
    }
  }
  std::vector<Outcome> outcomes;
  for (const Case& c : battery()) {
    if (!only.empty() && c.name.find(only) == std::string::npos) continue;
    Outcome o;
    try {
      o = c.run(fallback, solver);
    } catch (const std::exception& e) {
      o.message = std::string("threw: ") + e.what();
    }
    o.name = c.name;
    o.family = c.family;
    std::cerr << "time_freezing_battery: " << o.name << ": " << (o.solved ? "solved" : "NOT solved") << ", final error "
              << o.final_error << ", " << o.iterations << " iterations, " << o.seconds << " s, " << o.fallbacks
              << " fallbacks, impact outcome error " << o.impact_outcome_error << " over " << o.frozen_phases
              << " frozen phases (" << o.straddling_phases << " across an interval's end, " << o.cut_phases
              << " cut) and " << o.impacts << " impacts" << (o.solved ? "" : " (" + o.message + ")") << "\n";
    outcomes.push_back(o);
  }
  int solved = 0;
  for (const Outcome& o : outcomes) solved += o.solved;
  if (json) {
    nlohmann::json j;
    j["cases"] = nlohmann::json::array();
    for (const Outcome& o : outcomes)
      j["cases"].push_back({{"name", o.name}, {"family", o.family}, {"solved", o.solved}, {"converged", o.converged},
                            {"final_error", o.final_error}, {"ipopt_iterations", o.iterations}, {"seconds", o.seconds},
                            {"fallbacks", o.fallbacks}, {"impact_outcome_error", o.impact_outcome_error},
                            {"frozen_phases", o.frozen_phases}, {"impacts", o.impacts},
                            {"cut_phases", o.cut_phases}, {"straddling_phases", o.straddling_phases}, {"final_state", o.final_state},
                            {"exact_final_state", o.exact_state}, {"message", o.message}});
    j["solved"] = solved;
    j["total"] = outcomes.size();
    std::cout << j.dump(1) << "\n";
    return 0;
  }
  std::printf("%-36s %-7s %-9s %-10s %-10s %-7s %-8s %s\n", "case", "solved", "converged", "final err", "impact err",
              "iters", "seconds", "fallbacks");
  for (const Outcome& o : outcomes)
    std::printf("%-36s %-7s %-9s %-10.2e %-10.2e %-7d %-8.2f %d\n", o.name.c_str(), o.solved ? "yes" : "NO",
                o.converged ? "yes" : "no", o.final_error, o.impact_outcome_error, o.iterations, o.seconds, o.fallbacks);
  std::printf("solved %d of %zu\n", solved, outcomes.size());
  return 0;
}
