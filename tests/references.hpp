// Reference trajectories shared by the sensitivity tests and the jump-gain benchmark: every event
// kind (impact into slip, impact into stick, release, stick->slip, slip->stick) on the point
// mass, the hopper and the plank-box, under open-loop inputs and, for the hopper's push-off, a
// PD feedback law (closed-loop gains and linearisation, sensitivity/linearisation.hpp).
#pragma once

#include "sensitivity_instances.hpp"

#include <cmath>

#include <set>
#include <string>
#include <vector>

namespace saltus::references {

/// Tight tolerances: the numerical twin differentiates simulations by central differences, and
/// the eps^2 remainder test goes down to eps = 1e-6.
inline SimulationOptions tight() {
  SimulationOptions o;
  o.integrator.relative_tolerance = 1e-13;
  o.integrator.absolute_tolerance = 1e-13;
  return o;
}

/// The event kinds of Saltus' transitions, named as in the issue.
inline std::string event_kind(const auto& scene, const auto& tr) {
  if (tr.guards.empty()) return "initial impact";
  const GuardKind k = tr.guards.front().kind;
  const int i = tr.guards.front().contact;
  switch (k) {
    case GuardKind::Touchdown:
      return tr.mode_after[i].mode == ContactMode::Stick ||
                     (scene.contact(i).tangents() == 0 && tr.mode_after[i].closed())
                 ? (scene.contact(i).tangents() == 0 ? "impact into closed (frictionless)" : "impact into stick")
                 : (tr.mode_after[i].mode == ContactMode::Slip ? "impact into slip" : "impact and bounce");
    case GuardKind::Release: return "release";
    case GuardKind::SlipOnset: return "stick->slip";
    case GuardKind::Stop: return "slip->stick";
  }
  return "?";
}

/// The kind of an event: its transitions' kinds joined by " + " (a chain has several).
template <Scene S>
std::string event_kind(const S& scene, const Event<S>& ev) {
  std::string s;
  for (const auto& tr : ev.transitions) s += (s.empty() ? "" : " + ") + event_kind(scene, tr);
  return s;
}

template <Scene S>
struct Reference {
  std::string name;
  S scene;
  SimulationOptions options;
  HybridTrajectory<S> trajectory;
};

constexpr double g = 9.81;

/// Time-freezing paper, Example 3: u = (7, 0) for t < 1, (7, 2 g (t - 1)) after; from height 1
/// at rest. Impact at sqrt(2/g) into frictionless contact, sliding, lift-off through the
/// input-dependent release guard lambda_n = m g - u2 at t = 1.5.
inline Reference<scenes::PointMass> example3(double t_final = 2.0) {
  Reference<scenes::PointMass> r{"point_mass (Example 3)", scenes::PointMass{}, tight(), {}};
  r.options.breakpoints = {1.0};
  auto input = open_loop<scenes::PointMass>([](double t) { return Vec<2>(7.0, t < 1.0 ? 0.0 : 2 * g * (t - 1.0)); });
  Simulator<scenes::PointMass> sim(r.scene, r.options);
  r.trajectory = sim.run(Vec<4>(0.0, 1.0, 0.0, 0.0), 0.0, t_final, input);
  return r;
}

/// The point mass with planar Coulomb friction (mu = 0.5) under u = (t^2, 2 t^2), thrown from
/// height 0.3 at 2 m/s: impact into slip, slip->stick, stick->slip (the thrust leaves the
/// friction cone), release (the vertical thrust reaches m g).
inline Reference<scenes::PointMass> point_mass_with_friction() {
  scenes::PointMassParameters p;
  p.friction = Friction::Planar;
  p.mu = 0.5;
  Reference<scenes::PointMass> r{"point_mass (friction)", scenes::PointMass{p}, tight(), {}};
  auto input = open_loop<scenes::PointMass>([](double t) { return Vec<2>(t * t, 2.0 * t * t); });
  Simulator<scenes::PointMass> sim(r.scene, r.options);
  r.trajectory = sim.run(Vec<4>(0.0, 0.3, 2.0, 0.0), 0.0, 3.0, input);
  return r;
}
inline Vec<4> point_mass_with_friction_perturbation() { return Vec<4>(0.2, -0.4, 0.5, 0.3); }

/// The hopper dropped from 5 cm (foot height) with legs bent (phi_hip = 0.4, phi_knee = -0.8)
/// and 2 m/s forwards, under the open-loop torques (tau_hip, tau_knee) = (0, -10 t) N m (no
/// controller: the knee torque grows and folds the leg): touchdown into slip, lift-off (release)
/// 5 ms later, touchdown into slip, slip->stick.
inline Reference<scenes::Hopper> hopper() {
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
/// Small: the 5 ms stance makes the hopper's second-order terms large (|remainder| / eps^2 ~ 1e6),
/// so at eps = 1e-2 a perturbation of size 1 would change the event structure.
inline Vec<8> hopper_perturbation() { return 1e-3 * (Vec<8>() << 0.1, 0.2, -0.3, 0.2, 0.5, -0.4, 1.0, -0.5).finished(); }

/// The hopper under a joint-space PD controller (a feedback law, u depends on x): dropped from
/// 5 cm crouched (hip 0.4, knee -0.8 rad; kp 40 N m/rad, kd 2 N m s/rad) at 0.3 m/s forwards, it
/// lands into stick; around t = 0.3 s the targets and gains blend smoothly (tanh, 10 ms) to a
/// stiff push towards a stretched leg (hip 0.15, knee -0.3; kp 150, kd 3): the foot starts to
/// slip (stick->slip), then lifts off (release). Both state-input guards see the feedback.
inline Reference<scenes::Hopper> hopper_push_off() {
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
inline Vec<8> hopper_push_off_perturbation() { return 1e-3 * (Vec<8>() << 0.2, 0.1, -0.3, 0.2, 0.5, -0.4, 1.0, -0.5).finished(); }

/// The plank-box: the box tilted by -0.15 rad, 3 cm above the plank, lifted by the vertical force
/// 5 t^2 N (less than its weight until t = 1.4 s): its right corner lands and slips, then its left
/// corner lands and both stick. (Later both corners start slipping at once, a simultaneous
/// activation, so the reference ends at 1 s.)
inline Reference<scenes::PlankBox> plank_box() {
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
inline Vec<8> plank_box_perturbation() { return (Vec<8>() << 0.02, 0.01, 0.05, 0.01, 0.1, -0.2, 0.3, 0.1).finished(); }

}  // namespace saltus::references
