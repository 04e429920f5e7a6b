// Speed against error of the event-driven simulator: for each case, backend (dopri5, cvode-bdf,
// cvode-adams) and tolerance (relative 1e-4 ... 1e-12, absolute a tenth of it), the final-state
// error ||x(T) - x_exact(T)||_inf against the closed form (the plank-box has none: against the
// dopri5 run at 1e-12), the largest event-time error against the analytic event times, the wall
// time (median of `--repeats` runs, steady_clock around Simulator::run), the number of events and
// of integrator steps.
//
//   simulation_accuracy [--json] [--repeats N]
//
// Cases:
//   ball_e0       bouncing ball, e_n = 0, from 1 m at rest, T = 1: impact at sqrt(2/g), then rest
//   ball_e0.5     bouncing ball, e_n = 0.5, T = 1.2: the first three bounces, t_{k+1} = t_k + 2 e^k v1 / g
//   example3      point mass, Example 3 of the time-freezing paper, T = 2: impact, sliding, lift-off
//                 at 1.5, x(T) from the closed form (tests/test_simulation.cpp)
//   box_slide     spatial box sliding flat at 1.2 m/s on four corners, T = 0.5: stop at v0 / (mu g)
//   plank_box     plank-box landing flat (simultaneous touchdown at sqrt(0.05)), T = 0.5
//
// --json prints exactly one JSON object on stdout: {"repeats": N, "runs": [{"case", "backend",
// "tolerance", "final_state_error", "event_time_error", "wall_seconds", "events", "steps",
// "error"}, ...]} (errors null when a run threw; "error" then holds the message). Without it, a
// table. Exit status 0 unless a run threw.
#include "scenes/all_scenes.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace {

using namespace saltus;
constexpr double g = 9.81;

struct Outcome {
  Eigen::VectorXd final_state;
  std::vector<double> event_times;
  long steps = 0;
};

struct Case {
  std::string name;
  std::function<Outcome(const SimulationOptions&)> run;
  Eigen::VectorXd exact_final;       ///< empty: compare with dopri5 at 1e-12
  std::vector<double> exact_events;  ///< analytic event times
};

template <Scene S>
Outcome outcome_of(const HybridTrajectory<S>& traj) {
  Outcome o;
  o.final_state = traj.final_state();
  for (const auto& ev : traj.events) o.event_times.push_back(ev.t);
  o.steps = traj.statistics.steps;
  return o;
}

std::vector<Case> cases() {
  std::vector<Case> all;
  {  // inelastic ball
    Case c;
    c.name = "ball_e0";
    c.run = [](const SimulationOptions& o) {
      scenes::BouncingBallParameters p;
      p.restitution = 0.0;
      scenes::BouncingBall ball(p);
      Simulator<scenes::BouncingBall> sim(ball, o);
      return outcome_of(sim.run(Vec<2>(1.0, 0.0), 0.0, 1.0, zero_input<scenes::BouncingBall>()));
    };
    c.exact_final = Eigen::Vector2d(0.0, 0.0);
    c.exact_events = {std::sqrt(2.0 / g)};
    all.push_back(c);
  }
  {  // elastic ball, first three bounces
    Case c;
    c.name = "ball_e0.5";
    const double e = 0.5, T = 1.2, v1 = std::sqrt(2 * g);
    c.run = [T](const SimulationOptions& o) {
      scenes::BouncingBall ball;
      Simulator<scenes::BouncingBall> sim(ball, o);
      return outcome_of(sim.run(Vec<2>(1.0, 0.0), 0.0, T, zero_input<scenes::BouncingBall>()));
    };
    double t = std::sqrt(2.0 / g), v = v1;
    while (t < T) {
      c.exact_events.push_back(t);
      v *= e;
      t += 2 * v / g;
    }
    const double s = T - c.exact_events.back(), v_plus = v1 * std::pow(e, double(c.exact_events.size()));
    c.exact_final = Eigen::Vector2d(v_plus * s - 0.5 * g * s * s, v_plus - g * s);
    all.push_back(c);
  }
  {  // Example 3
    Case c;
    c.name = "example3";
    c.run = [](const SimulationOptions& base) {
      scenes::PointMass mass;
      SimulationOptions o = base;
      o.breakpoints = {1.0};
      auto input = open_loop<scenes::PointMass>([](double t) { return Vec<2>(7.0, t < 1.0 ? 0.0 : 2 * g * (t - 1.0)); });
      Simulator<scenes::PointMass> sim(mass, o);
      return outcome_of(sim.run(Vec<4>(0.0, 1.0, 0.0, 0.0), 0.0, 2.0, input));
    };
    c.exact_final = Eigen::Vector4d(3.5 * 4, g * 0.125 / 3, 14.0, g * 0.25);
    c.exact_events = {std::sqrt(2.0 / g), 1.5};
    all.push_back(c);
  }
  {  // spatial box sliding to a stop
    Case c;
    c.name = "box_slide";
    scenes::SpatialBox box;
    const double mu = box.parameters().mu, v0 = 1.2, half_height = 0.5 * box.parameters().size[2];
    c.run = [v0, half_height](const SimulationOptions& o) {
      scenes::SpatialBox box;
      Vec<12> x0 = Vec<12>::Zero();
      x0[2] = half_height;
      x0[6] = v0;
      Simulator<scenes::SpatialBox> sim(box, o);
      return outcome_of(sim.run(x0, 0.0, 0.5, zero_input<scenes::SpatialBox>()));
    };
    c.exact_final = Eigen::VectorXd::Zero(12);
    c.exact_final[0] = v0 * v0 / (2 * mu * g);
    c.exact_final[2] = half_height;
    c.exact_events = {v0 / (mu * g)};
    all.push_back(c);
  }
  {  // plank-box landing flat
    Case c;
    c.name = "plank_box";
    c.run = [](const SimulationOptions& o) {
      scenes::PlankBox plank_box;
      auto input = open_loop<scenes::PlankBox>([&](double) { return plank_box.lowering_input(); });
      Simulator<scenes::PlankBox> sim(plank_box, o);
      return outcome_of(sim.run(plank_box.flat_state(), 0.0, 0.5, input));
    };
    c.exact_events = {std::sqrt(0.05)};  // a = 2 N / 1 kg over 0.05 m
    all.push_back(c);
  }
  return all;
}

struct Run {
  std::string case_name, backend, error;
  double tolerance = 0, final_error = NAN, event_error = NAN, wall = NAN;
  int events = 0;
  long steps = 0;
};

SimulationOptions options_for(IntegratorKind kind, double tol) {
  SimulationOptions o;
  o.integrator.kind = kind;
  o.integrator.relative_tolerance = tol;
  o.integrator.absolute_tolerance = 0.1 * tol;
  return o;
}

/// A JSON number as printed with `format` (JSON has no NaN or infinity: those become null).
nlohmann::ordered_json number(double x, const char* format = "%.6e") {
  if (!std::isfinite(x)) return nullptr;
  char buf[64];
  std::snprintf(buf, sizeof buf, format, x);
  return std::strtod(buf, nullptr);
}

}  // namespace

int main(int argc, char** argv) {
  bool json = false;
  int repeats = 3;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--json") == 0) {
      json = true;
    } else if (std::strcmp(argv[i], "--repeats") == 0 && i + 1 < argc) {
      repeats = std::max(1, std::atoi(argv[++i]));
    } else {
      std::fprintf(stderr, "usage: %s [--json] [--repeats N]\n", argv[0]);
      return 2;
    }
  }
  const std::vector<IntegratorKind> backends = {IntegratorKind::DormandPrince, IntegratorKind::CvodeBdf,
                                                IntegratorKind::CvodeAdams};
  const std::vector<double> tolerances = {1e-4, 1e-6, 1e-8, 1e-10, 1e-12};
  std::vector<Run> runs;
  bool failed = false;
  for (Case& c : cases()) {
    if (c.exact_final.size() == 0) c.exact_final = c.run(options_for(IntegratorKind::DormandPrince, 1e-12)).final_state;
    for (IntegratorKind kind : backends) {
      for (double tol : tolerances) {
        Run r;
        r.case_name = c.name;
        r.backend = to_string(kind);
        r.tolerance = tol;
        try {
          std::vector<double> walls;
          Outcome out;
          for (int k = 0; k < repeats; ++k) {
            const auto start = std::chrono::steady_clock::now();
            out = c.run(options_for(kind, tol));
            walls.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
          }
          std::sort(walls.begin(), walls.end());
          r.wall = walls[walls.size() / 2];
          r.final_error = (out.final_state - c.exact_final).cwiseAbs().maxCoeff();
          r.events = static_cast<int>(out.event_times.size());
          r.steps = out.steps;
          // Event times against the analytic ones, paired in order (only as many as are known).
          if (out.event_times.size() >= c.exact_events.size()) {
            r.event_error = 0.0;
            for (std::size_t e = 0; e < c.exact_events.size(); ++e)
              r.event_error = std::max(r.event_error, std::abs(out.event_times[e] - c.exact_events[e]));
          }
        } catch (const std::exception& e) {
          r.error = e.what();
          failed = true;
        }
        runs.push_back(r);
        if (!json) std::fprintf(stderr, ".");
      }
    }
  }
  if (json) {
    auto all = nlohmann::ordered_json::array();
    for (const Run& r : runs) {
      std::string message = r.error;  // on one line
      std::replace(message.begin(), message.end(), '\n', ' ');
      all.push_back({{"case", r.case_name},
                     {"backend", r.backend},
                     {"tolerance", number(r.tolerance, "%.0e")},
                     {"final_state_error", number(r.final_error)},
                     {"event_time_error", number(r.event_error)},
                     {"wall_seconds", number(r.wall)},
                     {"events", r.events},
                     {"steps", r.steps},
                     {"error", r.error.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(message)}});
    }
    const nlohmann::ordered_json out = {{"repeats", repeats}, {"runs", std::move(all)}};
    std::printf("%s\n", out.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace).c_str());
  } else {
    std::fprintf(stderr, "\n");
    std::printf("%-10s %-12s %8s %14s %14s %12s %7s %8s\n", "case", "backend", "tol", "final err", "event err",
                "wall [ms]", "events", "steps");
    for (const Run& r : runs) {
      if (!r.error.empty()) {
        std::printf("%-10s %-12s %8.0e  error: %s\n", r.case_name.c_str(), r.backend.c_str(), r.tolerance,
                    r.error.c_str());
        continue;
      }
      std::printf("%-10s %-12s %8.0e %14.3e %14.3e %12.3f %7d %8ld\n", r.case_name.c_str(), r.backend.c_str(),
                  r.tolerance, r.final_error, r.event_error, 1e3 * r.wall, r.events, r.steps);
    }
  }
  return failed ? 1 : 0;
}
