// The README's usage example, verbatim: built and run by the consumer project (check.cmake).
#include <saltus/hybrid/instantiate.hxx>          // the definitions, compiled in this file
#include <saltus/hybrid/vocabulary/trajectory_io.hpp>

#include <cstdio>
#include <iostream>

struct FallingMass {  // a unit mass above the ground
  static constexpr int nq = 1, nu = 0, nc = 1;
  saltus::ContactSpec ground{"ground", saltus::Friction::None, /*mu=*/0.0, /*e_n=*/0.0};
  const saltus::ContactSpec& contact(int) const { return ground; }
  template <class T> saltus::MatT<T, 1, 1> mass_matrix(const saltus::VecT<T, 1>&) const { return saltus::MatT<T, 1, 1>::Constant(T(1)); }
  template <class T> saltus::VecT<T, 1> bias(const saltus::VecT<T, 1>&, const saltus::VecT<T, 1>&) const { return saltus::VecT<T, 1>::Constant(T(9.81)); }
  template <class T> saltus::MatT<T, 1, 0> input_matrix(const saltus::VecT<T, 1>&) const { return {}; }
  template <class T> T gap(int, const saltus::VecT<T, 1>& q) const { return q[0]; }
  template <class T> saltus::VecT<T, 2> tangent_position(int, const saltus::VecT<T, 1>&) const { return saltus::VecT<T, 2>::Zero(); }
};
SALTUS_INSTANTIATE_SCENE(FallingMass)  // the machinery of FallingMass, compiled here once

int main() {
  FallingMass scene;
  saltus::Simulator<FallingMass> sim(scene);                 // Dormand-Prince, rtol 1e-10
  auto traj = sim.run(saltus::Vec<2>(2.0, 0.0), 0.0, 1.0, saltus::zero_input<FallingMass>());
  for (const auto& ev : traj.events) std::printf("event at %.12f\n", ev.t);   // sqrt(4 / g)
  saltus::write_json(std::cout, traj, scene);                 // segments and events
}
