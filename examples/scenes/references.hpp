// The canonical reference motions of the scenes, shared by the tests, the benchmarks and the
// examples: every event kind (impact into slip, impact into stick, release, stick->slip,
// slip->stick) on the point mass, the hopper and the plank-box, under open-loop inputs and, for
// the hopper's push-off, a PD feedback law (closed-loop gains and linearisation,
// sensitivity/linearisation.hpp). Simulated by references.cpp (library saltus_scenes).
#pragma once

#include "scenes/all_scenes.hpp"

#include <set>
#include <string>
#include <vector>

namespace saltus::references {

/// Tight tolerances: the numerical twin differentiates simulations by central differences, and
/// the eps^2 remainder test goes down to eps = 1e-6.
SimulationOptions tight();

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
Reference<scenes::PointMass> example3(double t_final = 2.0);

/// The point mass with planar Coulomb friction (mu = 0.5) under u = (t^2, 2 t^2), thrown from
/// height 0.3 at 2 m/s: impact into slip, slip->stick, stick->slip (the thrust leaves the
/// friction cone), release (the vertical thrust reaches m g).
Reference<scenes::PointMass> point_mass_with_friction();
Vec<4> point_mass_with_friction_perturbation();

/// A periodic hop of the point mass (period 1 s): at rest on the table, pushed by the vertical
/// thrust u2 = m g - 6 + 8 cos(2 pi (t + 1/2)) N (u1 = 0), it lifts off through the release guard
/// lambda_n = 6 - 8 cos(2 pi (t + 1/2)) = 0 at t = 0.385 s, flies 6 cm high and lands (into closed
/// contact) at 0.864 s, at rest on the table again until the next release: the state at t = 1 is
/// the state at t = 0. Simulated from 0 to t_final.
inline constexpr double point_mass_hop_period = 1.0;
Reference<scenes::PointMass> point_mass_hop(double t_final = 2.0);

/// The hopper dropped from 5 cm (foot height) with legs bent (phi_hip = 0.4, phi_knee = -0.8)
/// and 2 m/s forwards, under the open-loop torques (tau_hip, tau_knee) = (0, -10 t) N m (no
/// controller: the knee torque grows and folds the leg): touchdown into slip, lift-off (release)
/// 5 ms later, touchdown into slip, slip->stick.
Reference<scenes::Hopper> hopper();
/// Small: the 5 ms stance makes the hopper's second-order terms large (|remainder| / eps^2 ~ 1e6),
/// so at eps = 1e-2 a perturbation of size 1 would change the event structure.
Vec<8> hopper_perturbation();

/// The hopper under a joint-space PD controller (a feedback law, u depends on x): dropped from
/// 5 cm crouched (hip 0.4, knee -0.8 rad; kp 40 N m/rad, kd 2 N m s/rad) at 0.3 m/s forwards, it
/// lands into stick; around t = 0.3 s the targets and gains blend smoothly (tanh, 10 ms) to a
/// stiff push towards a stretched leg (hip 0.15, knee -0.3; kp 150, kd 3): the foot starts to
/// slip (stick->slip), then lifts off (release). Both state-input guards see the feedback.
Reference<scenes::Hopper> hopper_push_off();
Vec<8> hopper_push_off_perturbation();

/// The plank-box: the box tilted by -0.15 rad, 3 cm above the plank, lifted by the vertical force
/// 5 t^2 N (less than its weight until t = 1.4 s): its right corner lands and slips, then its left
/// corner lands and both stick. (Later both corners start slipping at once, a simultaneous
/// activation, so the reference ends at 1 s.)
Reference<scenes::PlankBox> plank_box();
Vec<8> plank_box_perturbation();

}  // namespace saltus::references
