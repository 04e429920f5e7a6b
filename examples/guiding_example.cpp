// The guiding example of the time-freezing paper (Examples 1-3): a unit point mass dropped from
// height 1 onto a frictionless table, pushed sideways by u1 = 7 and, from t = 1, lifted by
// u2 = 2 g (t - 1). It lands at t = sqrt(2/g) (inelastic impact), slides, and lifts off at t = 1.5
// when the normal force m g - u2 reaches zero: a state-input guard.
#include <saltus/hybrid/vocabulary/trajectory_report.hpp>
#include "scenes/all_scenes.hpp"

#include <cmath>
#include <cstdio>

int main() {
  using namespace saltus;
  using Mass = scenes::PointMass;
  Mass mass;
  const double g = mass.parameters().gravity;
  auto thrust = open_loop<Mass>([g](double t) { return Vec<2>(7.0, t < 1.0 ? 0.0 : 2 * g * (t - 1.0)); });

  SimulationOptions options;
  options.integrator.relative_tolerance = 1e-12;
  options.integrator.absolute_tolerance = 1e-13;
  options.breakpoints = {1.0};  // the thrust has a kink at t = 1
  Simulator<Mass> simulator(mass, options);
  const auto traj = simulator.run(Vec<4>(0.0, 1.0, 0.0, 0.0), 0.0, 2.0, thrust);

  std::printf("guiding example (time-freezing paper, Example 3)\n");
  print_events(mass, traj);
  // Closed form at t = 2: q1 = 3.5 t^2, v1 = 7 t; after lift-off q2 = g (t - 1.5)^3 / 3, v2 = g (t - 1.5)^2.
  const Vec<4> exact(14.0, g * 0.125 / 3.0, 14.0, g * 0.25);
  const double error = (traj.final_state() - exact).cwiseAbs().maxCoeff();
  std::printf("  impact at %.15f (closed form %.15f), lift-off at %.15f (closed form 1.5)\n", traj.events.at(0).t,
              std::sqrt(2 / g), traj.events.at(1).t);
  std::printf("  final state error against the closed form: %.2e\n", error);
  write_trajectory_files(mass, traj, "guiding_example", 0.01);
  return error < 1e-8 ? 0 : 1;
}
