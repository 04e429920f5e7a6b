// A ball dropped from 1 m onto the ground with restitution e_n = 0.5: the bounces accumulate in
// finite time (Zeno). The simulator stops with status "zeno" and predicts the accumulation time;
// the closed form is t_inf = sqrt(2 h / g) (1 + e) / (1 - e).
#include <saltus/hybrid/vocabulary/trajectory_report.hpp>
#include "report_files.hpp"
#include "scenes/all_scenes.hpp"

#include <cmath>
#include <cstdio>

int main() {
  using namespace saltus;
  using Ball = scenes::BouncingBall;
  Ball ball;  // 0.1 kg, e_n = 0.5 (scenes/bouncing_ball.hpp)
  const double g = ball.parameters().gravity, e = ball.parameters().restitution, h0 = 1.0;

  SimulationOptions options;
  options.integrator.relative_tolerance = 1e-12;
  options.integrator.absolute_tolerance = 1e-13;
  Simulator<Ball> simulator(ball, options);
  const auto traj = simulator.run(Vec<2>(h0, 0.0), 0.0, 5.0, zero_input<Ball>());

  std::printf("bouncing ball, e_n = %.2f, dropped from %.2f m\n", e, h0);
  std::printf("  first bounce at t = %.15f (closed form %.15f)\n", traj.events.front().t, std::sqrt(2 * h0 / g));
  const double t_inf = std::sqrt(2 * h0 / g) * (1 + e) / (1 - e);
  std::printf("  %zu bounces, status %s, accumulation predicted at %.12f s (closed form %.12f, error %.2e)\n",
              traj.events.size(), to_string(traj.status), traj.zeno_time, t_inf, std::abs(traj.zeno_time - t_inf));
  examples::write_scene_trajectory(ball, traj, "bouncing_ball", 0.01);  // report/bouncing_ball/
  return traj.status == SimulationStatus::Zeno && std::abs(traj.zeno_time - t_inf) < 1e-6 ? 0 : 1;
}
