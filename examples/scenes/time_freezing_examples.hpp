// The time-freezing cases shared by tests/test_time_freezing.cpp, bench/fesd_accuracy.cpp and
// examples/guiding_example.cpp: the paper's guiding example (Example 3: its input law and the
// closed form of its state at numerical time 3.5, derivation in bench/fesd_accuracy.cpp), NOSNOC's
// frictional landing, and the point-mass OCP that lands and slides to a target.
#pragma once

#include "scenes/point_mass.hpp"

#include <saltus/hybrid/vocabulary/scene.hpp>
#include <saltus/timefreezing/formulation/time_freezing_system.hpp>
#include <saltus/timefreezing/instantiate.hpp>
#include <saltus/timefreezing/mpcc/mpcc_solver.hpp>

#include <cmath>

namespace saltus::scenes {

/// Example 3: g = 9.81 and a_n = g, y0 = (0, 1, 0, 0, 0), tau in [0, 3.5].
struct Example3 {
  static constexpr double gravity = 9.81;
  static constexpr double horizon = 3.5;

  /// u = (7, 0) for t < 1 and (7, 2 g (t - 1)) after (t the physical time, the clock state).
  template <class T>
  VecT<T, 2> input(const T& t, const VecT<T, 2>&) const {
    if (t < 1.0) return VecT<T, 2>(T(7.0), T(0.0));
    return VecT<T, 2>(T(7.0), T(2.0 * gravity * T(t - 1.0)));
  }

  /// (q1, q2, v1, v2, t) at tau = 3.5: t = 2.25, q1 = 3.5 t^2, v1 = 7 t, and after the lift-off at
  /// t = 1.5, v2 = g (t - 1.5)^2, q2 = g (t - 1.5)^3 / 3.
  static Vec<5> final_state() {
    const double t = 2.25;
    return (Vec<5>() << 3.5 * t * t, gravity * std::pow(t - 1.5, 3) / 3.0, 7.0 * t,
            gravity * (t - 1.5) * (t - 1.5), t)
        .finished();
  }
};

/// NOSNOC's smallest time-freezing example: g = 10, mu = 0.2, a_n = 20, from q0 = (0, 1),
/// v0 = (3, 0); 20 control intervals of 0.125, N_fe = 5, n_s = 2. The mass stops at x = 2.45
/// exactly (tests/test_time_freezing.cpp derives it).
struct FrictionalLanding {
  static constexpr double stop = 2.45;
  static PointMassParameters parameters() {
    PointMassParameters p;
    p.gravity = 10.0;
    p.friction = Friction::Planar;
    p.mu = 0.2;
    return p;
  }
  static timefreezing::TimeFreezingSystem<PointMass> system() { return {PointMass(parameters()), 20.0}; }
  static timefreezing::FesdOptions grid() {
    timefreezing::FesdOptions o;
    o.grid.stages = 2;
    o.grid.control_intervals = 20;
    o.grid.finite_elements = 5;
    o.grid.horizon = 2.5;
    // The contact-side selection (fesd.hpp): sliding keeps the gap at exactly zero, where alpha_gap
    // is free; measured stop error 2.0e-6 without it, 6.2e-12 with it (bench/README.md).
    o.regularisation.contact_side = 1e-2;
    return o;
  }
  static Vec<2> q0() { return Vec<2>(0, 1); }
  static Vec<2> v0() { return Vec<2>(3, 0); }
};

/// A small time-freezing OCP: the point mass with friction (mu = 0.2, a_n = 3 g) from rest at
/// (0, 1) to rest on the table at x = 3 at T = 2 s, minimising the integral of u'u over physical
/// time, |u_i| <= 20; N = 10, N_fe = 3, n_s = 2, terminal clock, s_max = 5; penalty homotopy with
/// Ipopt tol 1e-8 (solve_time_freezing_ocp's docstring: the Scholtes defaults take 15x more
/// iterations here).
struct PointMassToTheTarget {
  static constexpr int terminal_constraint_count = 4;
  template <class T>
  T running_cost(const VecT<T, 4>&, const VecT<T, 2>& u) const {
    return u.squaredNorm();
  }
  template <class T>
  VecT<T, 4> terminal_constraints(const VecT<T, 4>& x, const T&) const {
    return x;
  }
  Vec<4> terminal_lower() const { return target; }
  Vec<4> terminal_upper() const { return target; }
  /// The terminal state (x [m], z [m], v_x [m/s], v_z [m/s]) the four terminal rows pin; rest at
  /// x = 3 unless set. A value, not a type, so that a task with another target (the refinement
  /// tests' slide to x = 1, a target above the table) runs on this OCP's compiled machinery.
  Vec<4> target = Vec<4>(3, 0, 0, 0);

  static PointMassParameters parameters() {
    PointMassParameters p;
    p.friction = Friction::Planar;
    p.mu = 0.2;
    return p;
  }
  static timefreezing::TimeFreezingSystem<PointMass> system() {
    return {PointMass(parameters()), 3.0 * parameters().gravity};
  }
  static timefreezing::FesdOptions grid() {
    timefreezing::FesdOptions o;
    o.grid.stages = 2;
    o.grid.control_intervals = 10;
    o.grid.finite_elements = 3;
    o.grid.horizon = 2.0;
    o.clock.constraint = timefreezing::ClockConstraint::Terminal;
    o.clock.physical_horizon = 2.0;
    o.clock.speed_of_time_max = 5.0;
    o.bounds.control_lower = Eigen::VectorXd::Constant(2, -20.0);
    o.bounds.control_upper = Eigen::VectorXd::Constant(2, 20.0);
    return o;
  }
  static timefreezing::MpccSolverOptions solver() {
    timefreezing::MpccSolverOptions s;
    s.homotopy.relaxation = timefreezing::MpccSolverOptions::Relaxation::Penalty;
    s.ipopt.tol = 1e-8;
    return s;
  }
  static Vec<2> q0() { return Vec<2>(0, 1); }
  static Vec<2> v0() { return Vec<2>(0, 0); }
  /// The start, the horizon and the input bounds of grid() for the mode-schedule refinement.
  static timefreezing::OcpHorizon<PointMass> refinement_horizon() {
    timefreezing::OcpHorizon<PointMass> h;
    h.x0 << q0(), v0();
    h.final_time = grid().clock.physical_horizon;
    h.control_lower = grid().bounds.control_lower;
    h.control_upper = grid().bounds.control_upper;
    return h;
  }
};

}  // namespace saltus::scenes

// Compiled once in time_freezing_examples.cpp: the point mass's recovery, its simulations without
// input and under Example 3's input law, and the OCP to the target.
SALTUS_DECLARE_TIME_FREEZING_SCENE(saltus::scenes::PointMass)
SALTUS_DECLARE_TIME_FREEZING_SIMULATION(saltus::scenes::PointMass, saltus::timefreezing::NoObjective)
SALTUS_DECLARE_TIME_FREEZING_SIMULATION(saltus::scenes::PointMass, saltus::scenes::Example3)
SALTUS_DECLARE_TIME_FREEZING_OCP(saltus::scenes::PointMass, saltus::scenes::PointMassToTheTarget)
SALTUS_DECLARE_SCHEDULE_REFINEMENT_SCENE(saltus::scenes::PointMass)
SALTUS_DECLARE_SCHEDULE_REFINEMENT(saltus::scenes::PointMass, saltus::scenes::PointMassToTheTarget)
