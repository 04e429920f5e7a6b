// A user's program: simulates the user's scene (falling_mass.hpp) and checks the impact time,
// which must be sqrt(2 h / g). Includes no definition of the simulator: it links falling_mass.cpp.
#include "falling_mass.hpp"

#include <saltus/hybrid/simulation/simulator.hpp>

#include <cmath>
#include <cstdio>

int main() {
  FallingMass scene;
  saltus::Simulator<FallingMass> sim(scene);
  const auto traj = sim.run(saltus::Vec<2>(2.0, 0.0), 0.0, 1.0, saltus::zero_input<FallingMass>());
  const double expected = std::sqrt(2 * 2.0 / 9.81);
  std::printf("impact at %.12f (expected %.12f)\n", traj.events.at(0).t, expected);
  return std::abs(traj.events.at(0).t - expected) < 1e-9 ? 0 : 1;
}
