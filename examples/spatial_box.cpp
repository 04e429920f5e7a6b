// A 6-DOF box with spatial friction dropped flat, sliding along x: four corners hit at once
// (12 contact rows for 6 degrees of freedom: a singular Delassus matrix), the impact takes
// mu times the normal impulse off the sliding speed, the box slides and comes to rest at
// t_stop = t_impact + (v_x - mu v_n) / (mu g).
#include <saltus/hybrid/vocabulary/trajectory_report.hpp>
#include "report_files.hpp"
#include "scenes/all_scenes.hpp"

#include <cmath>
#include <cstdio>

int main() {
  using namespace saltus;
  using Box = scenes::SpatialBox;
  Box box;  // 2 kg, 0.4 x 0.3 x 0.2 m, mu = 0.5 (scenes/spatial_box.hpp)
  const double g = box.parameters().gravity, mu = box.parameters().mu, drop = 0.1, vx = 2.0;
  Vec<12> x0 = Vec<12>::Zero();
  x0[2] = 0.5 * box.parameters().size[2] + drop;
  x0[6] = vx;

  SimulationOptions options;
  options.integrator.relative_tolerance = 1e-12;
  options.integrator.absolute_tolerance = 1e-13;
  Simulator<Box> simulator(box, options);
  const auto traj = simulator.run(x0, 0.0, 1.0, zero_input<Box>());

  std::printf("spatial box: flat landing on four corners while sliding\n");
  print_events(box, traj);
  const double vn = std::sqrt(2 * g * drop), t_impact = std::sqrt(2 * drop / g);
  const double t_stop = t_impact + (vx - mu * vn) / (mu * g);
  std::printf("  stop at %.12f s (closed form %.12f, error %.2e)\n", traj.events.at(1).t, t_stop,
              std::abs(traj.events.at(1).t - t_stop));
  examples::write_scene_trajectory(box, traj, "spatial_box", 0.01);  // report/spatial_box/
  return std::abs(traj.events.at(1).t - t_stop) < 1e-8 ? 0 : 1;
}
