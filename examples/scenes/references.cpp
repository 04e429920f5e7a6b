// The canonical reference motions (references.hpp), simulated with the scenes' compiled machinery.
#include "scenes/references.hpp"

#include <cmath>
#include <numbers>

namespace saltus::references {

SimulationOptions tight() {
  SimulationOptions o;
  o.integrator.relative_tolerance = 1e-13;
  o.integrator.absolute_tolerance = 1e-13;
  return o;
}

Reference<scenes::PointMass> example3(double t_final) {
  Reference<scenes::PointMass> r{"point_mass (Example 3)", scenes::PointMass{}, tight(), {}};
  r.options.breakpoints = {1.0};
  auto input = open_loop<scenes::PointMass>([](double t) { return Vec<2>(7.0, t < 1.0 ? 0.0 : 2 * g * (t - 1.0)); });
  Simulator<scenes::PointMass> sim(r.scene, r.options);
  r.trajectory = sim.run(Vec<4>(0.0, 1.0, 0.0, 0.0), 0.0, t_final, input);
  return r;
}

Reference<scenes::PointMass> point_mass_hop(double t_final) {
  Reference<scenes::PointMass> r{"point_mass (periodic hop)", scenes::PointMass{}, tight(), {}};
  // At rest on the table the flow is constant and the integrator's steps grow past the thrust's
  // period: the releases after the first fall inside one step (a release guard lambda_n(t) below
  // zero and back), found by case 4 of the guard scan (simulation/guard_scan.hxx).
  const double m = r.scene.parameters().mass, grav = r.scene.parameters().gravity;
  auto input = open_loop<scenes::PointMass>([m, grav](double t) {
    return Vec<2>(0.0, m * grav - 6.0 + 8.0 * std::cos(2.0 * std::numbers::pi * (t + 0.5) / point_mass_hop_period));
  });
  Simulator<scenes::PointMass> sim(r.scene, r.options);
  r.trajectory = sim.run(Vec<4>(0.0, 0.0, 0.0, 0.0), 0.0, t_final, input);
  return r;
}

Reference<scenes::PointMass> point_mass_with_friction() {
  scenes::PointMassParameters p;
  p.friction = Friction::Planar;
  p.mu = 0.5;
  Reference<scenes::PointMass> r{"point_mass (friction)", scenes::PointMass{p}, tight(), {}};
  auto input = open_loop<scenes::PointMass>([](double t) { return Vec<2>(t * t, 2.0 * t * t); });
  Simulator<scenes::PointMass> sim(r.scene, r.options);
  r.trajectory = sim.run(Vec<4>(0.0, 0.3, 2.0, 0.0), 0.0, 3.0, input);
  return r;
}

Reference<scenes::Hopper> hopper() {
  Reference<scenes::Hopper> r{"hopper", scenes::Hopper{}, tight(), {}};
  Vec<4> q(0.0, 0.0, 0.4, -0.8);
  q[1] = -r.scene.foot(q)[1] + 0.05;
  Vec<8> x0 = Vec<8>::Zero();
  x0.head<4>() = q;
  x0[4] = 2.0;
  auto input = open_loop<scenes::Hopper>([](double t) { return Vec<2>(0.0, -10.0 * t); });
  Simulator<scenes::Hopper> sim(r.scene, r.options);
  r.trajectory = sim.run(x0, 0.0, 0.38, input);
  return r;
}

Reference<scenes::Hopper> hopper_push_off() {
  Reference<scenes::Hopper> r{"hopper push-off (PD feedback)", scenes::Hopper{}, tight(), {}};
  Vec<8> x0;
  x0 << 0.0, 0.0, 0.4, -0.8, 0.3, 0.0, 0.0, 0.0;
  x0[1] = 0.05 - r.scene.foot(Vec<4>(x0.head<4>()))[1];
  const InputLaw<scenes::Hopper> controller = [](double t, const Vec<8>& x, const Mode<1>&) {
    const double s = 0.5 * (1.0 + std::tanh((t - 0.3) / 0.01));  // 0: crouch, 1: push
    const auto blend = [s](double a, double b) { return a + s * (b - a); };
    const double hip = blend(0.4, 0.15), knee = blend(-0.8, -0.3), kp = blend(40.0, 150.0), kd = blend(2.0, 3.0);
    return Vec<2>(kp * (hip - x[2]) - kd * x[6], kp * (knee - x[3]) - kd * x[7]);
  };
  Simulator<scenes::Hopper> sim(r.scene, r.options);
  r.trajectory = sim.run(x0, 0.0, 0.45, controller);
  return r;
}

Reference<scenes::PlankBox> plank_box() {
  Reference<scenes::PlankBox> r{"plank_box", scenes::PlankBox{}, tight(), {}};
  const auto& p = r.scene.parameters();
  const double th = -0.15;
  Vec<8> x0 = Vec<8>::Zero();
  x0[0] = 0.6;
  x0[2] = th;
  x0[1] = 0.5 * p.box_height + 0.5 * p.plank_thickness + 0.03 + 0.5 * p.box_length * std::abs(std::sin(th));
  auto input = open_loop<scenes::PlankBox>([](double t) { return Vec<3>(0.0, 5.0 * t * t, 0.0); });
  Simulator<scenes::PlankBox> sim(r.scene, r.options);
  r.trajectory = sim.run(x0, 0.0, 1.0, input);
  return r;
}

Vec<4> point_mass_with_friction_perturbation() { return Vec<4>(0.2, -0.4, 0.5, 0.3); }

Vec<8> hopper_perturbation() { return 1e-3 * (Vec<8>() << 0.1, 0.2, -0.3, 0.2, 0.5, -0.4, 1.0, -0.5).finished(); }

Vec<8> hopper_push_off_perturbation() { return 1e-3 * (Vec<8>() << 0.2, 0.1, -0.3, 0.2, 0.5, -0.4, 1.0, -0.5).finished(); }

Vec<8> plank_box_perturbation() { return (Vec<8>() << 0.02, 0.01, 0.05, 0.01, 0.1, -0.2, 0.3, 0.1).finished(); }

}  // namespace saltus::references
