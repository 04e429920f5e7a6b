// A user's scene, written only from positions and energies: a unit point mass above the ground,
// pushed upwards by a force u (N), bouncing with restitution 0.5. Its machinery (simulation and
// analyses) is compiled once, in falling_mass.cpp; every other file includes this header only.
#pragma once

#include <saltus/hybrid/instantiate.hpp>
#include <saltus/sensitivity/instantiate.hpp>

struct FallingMass {
  static constexpr int nq = 1, nu = 1, nc = 1;
  saltus::ContactSpec ground{"ground", saltus::Friction::None, 0.0, 0.5};
  const saltus::ContactSpec& contact(int) const { return ground; }
  template <class T> saltus::MatT<T, 1, 1> mass_matrix(const saltus::VecT<T, 1>&) const {
    return saltus::MatT<T, 1, 1>::Constant(T(1.0));
  }
  template <class T> saltus::VecT<T, 1> bias(const saltus::VecT<T, 1>&, const saltus::VecT<T, 1>&) const {
    return saltus::VecT<T, 1>::Constant(T(9.81));
  }
  template <class T> saltus::MatT<T, 1, 1> input_matrix(const saltus::VecT<T, 1>&) const {
    return saltus::MatT<T, 1, 1>::Constant(T(1.0));
  }
  template <class T> T gap(int, const saltus::VecT<T, 1>& q) const { return q[0]; }
  template <class T> saltus::VecT<T, 2> tangent_position(int, const saltus::VecT<T, 1>&) const {
    return saltus::VecT<T, 2>::Zero();
  }
};

SALTUS_DECLARE_SCENE(FallingMass)
SALTUS_DECLARE_SCENE_SENSITIVITY(FallingMass)
