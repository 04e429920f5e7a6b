// A user's scene and optimal-control problem: a 1 kg puck dropped from 1 m onto an inelastic table
// with Coulomb friction (mu = 0.3), pushed by a horizontal and a vertical force; the OCP asks it to
// land, slide and come to rest at x = 2 m at T = 2 s with the least integral of |u|^2. Its machinery
// (simulation, analyses, time-freezing OCP and mode-schedule refinement) is compiled once, in
// puck.cpp; optimal_landing.cpp includes this header only.
#pragma once

#include <saltus/hybrid/instantiate.hpp>
#include <saltus/sensitivity/instantiate.hpp>
#include <saltus/timefreezing/instantiate.hpp>

struct Puck {
  static constexpr int nq = 2, nu = 2, nc = 1;  // q = (x, height) [m], u = (push, lift) [N]
  saltus::ContactSpec table{"table", saltus::Friction::Planar, 0.3, 0.0};
  const saltus::ContactSpec& contact(int) const { return table; }
  template <class T> saltus::MatT<T, 2, 2> mass_matrix(const saltus::VecT<T, 2>&) const {
    return saltus::MatT<T, 2, 2>::Identity();
  }
  template <class T> saltus::VecT<T, 2> bias(const saltus::VecT<T, 2>&, const saltus::VecT<T, 2>&) const {
    return saltus::VecT<T, 2>(T(0.0), T(9.81));  // gravity
  }
  template <class T> saltus::MatT<T, 2, 2> input_matrix(const saltus::VecT<T, 2>&) const {
    return saltus::MatT<T, 2, 2>::Identity();
  }
  template <class T> T gap(int, const saltus::VecT<T, 2>& q) const { return q[1]; }
  template <class T> saltus::VecT<T, 2> tangent_position(int, const saltus::VecT<T, 2>& q) const {
    return saltus::VecT<T, 2>(q[0], T(0.0));
  }
};

/// Land, slide and stop at x = 2 m at T = 2 s: min the integral of |u|^2 [N^2 s], |u_i| <= 15 N.
struct PuckToTheMark {
  static constexpr int terminal_constraint_count = 4;
  template <class T> T running_cost(const saltus::VecT<T, 4>&, const saltus::VecT<T, 2>& u) const {
    return u.squaredNorm();
  }
  template <class T> saltus::VecT<T, 4> terminal_constraints(const saltus::VecT<T, 4>& x, const T&) const { return x; }
  saltus::Vec<4> terminal_lower() const { return saltus::Vec<4>(2.0, 0.0, 0.0, 0.0); }
  saltus::Vec<4> terminal_upper() const { return terminal_lower(); }
};

SALTUS_DECLARE_SCENE(Puck)
SALTUS_DECLARE_SCENE_SENSITIVITY(Puck)
SALTUS_DECLARE_TIME_FREEZING_SCENE(Puck)
SALTUS_DECLARE_TIME_FREEZING_OCP(Puck, PuckToTheMark)
SALTUS_DECLARE_SCHEDULE_REFINEMENT_SCENE(Puck)
SALTUS_DECLARE_SCHEDULE_REFINEMENT(Puck, PuckToTheMark)
