// A program written against 0.1: the flat include paths of 0.1, a scene of its own (Pebble) and
// no instantiation macro. The forwarding headers at those paths give the definitions as 0.1's
// headers did, so it compiles and links with a deprecation note per old path. Beside them, in
// the same file: a new path, and a scene whose machinery a scene library compiled explicitly
// (FallingMass: falling_mass.hpp declares its templates extern, falling_mass.cpp instantiates
// them), so that one program holds implicit instantiations of the forwarding headers'
// definitions and the library's explicit ones. Checks the first impact of each against
// t = sqrt(2 h / g) and the rebound velocity e sqrt(2 g h), and FallingMass's jump gain at that
// impact against its closed form: the sensitivity headers kept their 0.1 paths and declare only,
// the forwarding headers bring their definitions too (as 0.1's headers had them), and the extern
// declarations of falling_mass.hpp keep them from being compiled here. (Pebble's jump gains would
// compile here as well, in 17 s more at -O3 with clang 14: left out to keep this program small.)
#include <saltus/hybrid/scene.hpp>      // the 0.1 path of vocabulary/scene.hpp
#include <saltus/hybrid/simulator.hpp>  // the 0.1 path of simulation/simulator.hpp, with definitions

#include <saltus/hybrid/simulation/simulator.hpp>  // the new path of the same header
#include <saltus/sensitivity/jump_gain.hpp>        // a path of 0.1 and of today: declarations

#include "falling_mass.hpp"  // compiled in the scene library falling_mass

#include <cmath>
#include <cstdio>

/// A pebble of 0.2 kg at height q (m) above the ground, restitution 0.5, no input.
struct Pebble {
  static constexpr int nq = 1, nu = 0, nc = 1;
  saltus::ContactSpec ground{"ground", saltus::Friction::None, 0.0, 0.5};
  const saltus::ContactSpec& contact(int) const { return ground; }
  template <class T> saltus::MatT<T, 1, 1> mass_matrix(const saltus::VecT<T, 1>&) const {
    return saltus::MatT<T, 1, 1>::Constant(T(0.2));
  }
  template <class T> saltus::VecT<T, 1> bias(const saltus::VecT<T, 1>&, const saltus::VecT<T, 1>&) const {
    return saltus::VecT<T, 1>::Constant(T(0.2 * 9.81));
  }
  template <class T> saltus::MatT<T, 1, 0> input_matrix(const saltus::VecT<T, 1>&) const { return {}; }
  template <class T> T gap(int, const saltus::VecT<T, 1>& q) const { return q[0]; }
  template <class T> saltus::VecT<T, 2> tangent_position(int, const saltus::VecT<T, 1>&) const {
    return saltus::VecT<T, 2>::Zero();
  }
};

/// 0 when the first event of `traj` is an impact at sqrt(2 h / g) leaving upwards at
/// e sqrt(2 g h); 1 (and a line saying what differs) otherwise.
template <class Trajectory>
int check_first_bounce(const char* name, const Trajectory& traj, double h, double e) {
  const double g = 9.81, t = std::sqrt(2.0 * h / g), v = std::sqrt(2.0 * g * h);
  if (traj.events.empty()) {
    std::printf("%s: no event\n", name);
    return 1;
  }
  const auto& ev = traj.events.front();
  std::printf("%s: impact at %.12f s (expected %.12f), rebound %.12f m/s (expected %.12f)\n", name, ev.t, t,
              ev.x_plus[1], e * v);
  return std::abs(ev.t - t) < 1e-9 && std::abs(ev.x_plus[1] - e * v) < 1e-8 ? 0 : 1;
}

/// 0 when the saltation matrix of the first impact of a mass falling from h is
/// [[-e, 0], [(1 + e) g / sqrt(2 g h), -e]] (R = diag(1, -e), flows (v, -g) before and after).
template <class S, class Trajectory>
int check_first_jump_gain(const char* name, const S& scene, const Trajectory& traj, double h, double e) {
  const auto gains = saltus::jump_gains(scene, traj);
  const double g = 9.81, g10 = (1 + e) * g / std::sqrt(2.0 * g * h);
  if (gains.empty()) {
    std::printf("%s: no jump gain\n", name);
    return 1;
  }
  const auto& G = gains.front().G_z;
  std::printf("%s: G_z = [%.9f %.9f; %.9f %.9f] (expected [%.9f 0; %.9f %.9f])\n", name, G(0, 0), G(0, 1), G(1, 0),
              G(1, 1), -e, g10, -e);
  return std::abs(G(0, 0) + e) < 1e-9 && std::abs(G(0, 1)) < 1e-9 && std::abs(G(1, 0) - g10) < 1e-7 &&
                 std::abs(G(1, 1) + e) < 1e-9
             ? 0
             : 1;
}

int main() {
  Pebble pebble;
  saltus::Simulator<Pebble> pebble_sim(pebble);  // compiled here, from the forwarding header's definitions
  const auto pebble_traj = pebble_sim.run(saltus::Vec<2>(0.5, 0.0), 0.0, 0.4, saltus::zero_input<Pebble>());
  int failures = check_first_bounce("pebble", pebble_traj, 0.5, 0.5);
  FallingMass mass;
  saltus::Simulator<FallingMass> mass_sim(mass);  // linked from falling_mass.cpp
  const auto mass_traj = mass_sim.run(saltus::Vec<2>(2.0, 0.0), 0.0, 0.7, saltus::zero_input<FallingMass>());
  failures += check_first_bounce("falling mass", mass_traj, 2.0, 0.5);
  failures += check_first_jump_gain("falling mass", mass, mass_traj, 2.0, 0.5);
  return failures == 0 ? 0 : 1;
}
