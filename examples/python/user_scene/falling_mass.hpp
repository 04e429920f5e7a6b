// A user's own scene (the README's FallingMass): a unit mass above the ground, pushed vertically
// by a thrust u [N]; q = height [m]. Declared here, compiled once in falling_mass.cpp.
#pragma once

#include <saltus/hybrid/instantiate.hpp>
#include <saltus/sensitivity/instantiate.hpp>

struct FallingMass {
  static constexpr int nq = 1, nu = 1, nc = 1;
  saltus::ContactSpec ground{"ground", saltus::Friction::None, /*mu=*/0.0, /*e_n=*/0.0};
  const saltus::ContactSpec& contact(int) const { return ground; }
  template <class T> saltus::MatT<T, 1, 1> mass_matrix(const saltus::VecT<T, 1>&) const { return saltus::MatT<T, 1, 1>::Constant(T(1)); }
  template <class T> saltus::VecT<T, 1> bias(const saltus::VecT<T, 1>&, const saltus::VecT<T, 1>&) const { return saltus::VecT<T, 1>::Constant(T(9.81)); }
  template <class T> saltus::MatT<T, 1, 1> input_matrix(const saltus::VecT<T, 1>&) const { return saltus::MatT<T, 1, 1>::Constant(T(1)); }
  template <class T> T gap(int, const saltus::VecT<T, 1>& q) const { return q[0]; }
  template <class T> saltus::VecT<T, 2> tangent_position(int, const saltus::VecT<T, 1>&) const { return saltus::VecT<T, 2>::Zero(); }
};

SALTUS_DECLARE_SCENE(FallingMass)
SALTUS_DECLARE_SCENE_SENSITIVITY(FallingMass)
