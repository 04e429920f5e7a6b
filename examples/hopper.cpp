// The one-legged hopper (Capler) landing and hopping once under a simple joint-space controller:
// PD control of the hip and knee angles to a crouched posture while it falls and lands, then,
// from t_push, a stiffer PD towards a stretched leg, which pushes the body up until the foot's
// normal force reaches zero and the foot lifts off (the state-input release guard).
// The controller is a feedback law u(t, x, mode); the simulator evaluates it inside the flow.
#include "report.hpp"
#include "scenes/instances.hpp"

#include <cstdio>

int main() {
  using namespace saltus;
  using H = scenes::Hopper;
  H hopper;  // masses, lengths and inertias: scenes/hopper.hpp

  // Controller parameters (units: rad, N m/rad, N m s/rad, s).
  struct Gains { double hip, knee, kp, kd; };
  const Gains crouch{0.4, -0.8, 40.0, 2.0}, stretch{0.15, -0.3, 150.0, 3.0};
  const double t_push = 0.3;
  InputLaw<H> controller = [=](double t, const Vec<8>& x, const Mode<1>&) {
    const Gains& c = t < t_push ? crouch : stretch;
    return Vec<2>(c.kp * (c.hip - x[2]) - c.kd * x[6], c.kp * (c.knee - x[3]) - c.kd * x[7]);
  };

  Vec<8> x0 = Vec<8>::Zero();
  x0 << 0.0, 0.0, crouch.hip, crouch.knee, 0.3, 0.0, 0.0, 0.0;  // moving forward at 0.3 m/s
  x0[1] = 0.05 - hopper.foot(Vec<4>(x0.head<4>()))[1];          // foot 5 cm above the ground

  SimulationOptions options;
  options.integrator.relative_tolerance = 1e-11;
  options.integrator.absolute_tolerance = 1e-12;
  options.breakpoints = {t_push};
  Simulator<H> simulator(hopper, options);
  const auto traj = simulator.run(x0, 0.0, 0.7, controller);

  std::printf("hopper: landing and one hop under a joint PD controller\n");
  examples::print_events(hopper, traj);
  examples::write_trajectory(hopper, traj, "hopper", 0.005);
  bool lift_off = false;
  for (const auto& ev : traj.events)
    for (const Guard& g : ev.guards()) lift_off = lift_off || g.kind == GuardKind::Release;
  return lift_off ? 0 : 1;
}
