// A user's scene, written only from positions and energies: a unit point mass falling onto the
// ground. Prints the impact time, which must be sqrt(2 h / g).
#include <saltus/hybrid/simulation/simulator.hpp>

#include <cmath>
#include <cstdio>

struct FallingMass {
  static constexpr int nq = 1, nu = 0, nc = 1;
  saltus::ContactSpec ground{"ground", saltus::Friction::None, 0.0, 0.0};
  const saltus::ContactSpec& contact(int) const { return ground; }
  template <class T> saltus::MatT<T, 1, 1> mass_matrix(const saltus::VecT<T, 1>&) const {
    return saltus::MatT<T, 1, 1>::Constant(T(1.0));
  }
  template <class T> saltus::VecT<T, 1> bias(const saltus::VecT<T, 1>&, const saltus::VecT<T, 1>&) const {
    return saltus::VecT<T, 1>::Constant(T(9.81));
  }
  template <class T> saltus::MatT<T, 1, 0> input_matrix(const saltus::VecT<T, 1>&) const { return {}; }
  template <class T> T gap(int, const saltus::VecT<T, 1>& q) const { return q[0]; }
  template <class T> saltus::VecT<T, 2> tangent_position(int, const saltus::VecT<T, 1>&) const {
    return saltus::VecT<T, 2>::Zero();
  }
};

int main() {
  FallingMass scene;
  saltus::Simulator<FallingMass> sim(scene);
  const auto traj = sim.run(saltus::Vec<2>(2.0, 0.0), 0.0, 1.0, saltus::zero_input<FallingMass>());
  const double expected = std::sqrt(2 * 2.0 / 9.81);
  std::printf("impact at %.12f (expected %.12f)\n", traj.events.at(0).t, expected);
  return std::abs(traj.events.at(0).t - expected) < 1e-9 ? 0 : 1;
}
