// The flagship OCP of the time-freezing paper (Section 6): the one-legged hopper (scenes/hopper.hpp)
// travels from rest at x = 0 to x = 3 in T = 2.5 s over three holes, minimising the integral of
// u'u over physical time. Shared by examples/hopper.cpp (--json), tests/test_flagship_ocps.cpp and
// bench/experiments/hopper_ocp.cpp.
//
// q = (x, z, phi_hip, phi_knee), u = (tau_hip, tau_knee) with |u_i| <= 60 N m; foot contact with
// mu = 0.8, e_n = 0, auxiliary acceleration a_n = 200 (paper).
// Start q0 = (0, 0.4, 0, 0) at rest: the leg hangs straight down and the foot touches the ground
// (gap 0). Target q(T) = (3, 0.4, 0, 0), the velocity left free (the paper's terminal constraint;
// a target at rest is an option, `terminal_at_rest`).
//
// Path constraints, at every stage point of every finite element (FesdMpcc):
//   0  x        >= -0.05          (hip)
//   1  foot_x   >= -0.05
//   2  knee_x   >= -0.05
//   3  0.2 <= z <= 0.55
//   4  |phi_hip|  <= 3 pi / 8
//   5  |phi_knee| <= pi / 2
//   6  knee_z   >= 0.05
//   7  -0.005 <= foot_z <= 0.2
//   8..10  ((foot_x - x_c) / a)^2 + (foot_z / b)^2 >= 1,  x_c = 0.5, 1.5, 2.5,  a = 0.25, b = 0.1.
// The holes' half-width: the paper's text calls a_k = 0.5 "the width" of a hole; read as the
// semi-axis, holes at x_c = 0.5, 1.5, 2.5 would leave only the single points x = 0, 1, 2, 3 of
// ground to stand on (the foot could never land with any slack), so a = 0.25 is the semi-axis and
// 0.5 the full width: the ground in [-0.05, 0.25], [0.75, 1.25], [1.75, 2.25], [2.75, oo) remains.
// `hole_level` beta in [0, 1] is the lower bound of the three ellipse rows: the excluded region is
// the ellipse of semi-axes sqrt(beta) (a, b), from no hole at all (beta = 0: the rows always hold)
// to the problem itself (beta = 1); a continuation on the holes moves beta.
#pragma once

#include "scenes/hopper.hpp"
#include "scenes/ocp_grid.hpp"

#include <saltus/timefreezing/formulation/time_freezing_system.hpp>
#include <saltus/timefreezing/instantiate.hpp>
#include <saltus/timefreezing/mpcc/mpcc_solver.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace saltus::scenes {

struct HopperOverThreeHoles {
  static constexpr double horizon = 2.5;          ///< T [s]
  static constexpr double torque_limit = 60.0;    ///< |u_i| [N m]
  static constexpr double auxiliary_acceleration = 200.0;  ///< a_n of the time-freezing system
  static constexpr std::array<double, 3> hole_centres{0.5, 1.5, 2.5};  ///< x_c [m]
  static constexpr double hole_half_width = 0.25;  ///< a [m] (file comment)
  static constexpr double hole_depth = 0.1;        ///< b [m]
  static constexpr int path_constraint_count = 11;
  static constexpr int terminal_constraint_count = 4;

  Hopper hopper{};
  double hole_level = 1.0;  ///< beta in [0, 1] (file comment); 1: the problem itself
  /// The terminal target q(T) = (x [m], z [m], phi_hip [rad], phi_knee [rad]) that the four
  /// terminal rows pin (terminal_lower() = terminal_upper() = target); q_target() unless set. A
  /// value, not a type, so that another task on the same rows reuses this OCP's compiled
  /// machinery: the one-hole bed's target (1, 0.4, 0, 0) with the horizon T = 1 s of its grid and
  /// refinement horizon (HopperOverOneHole::on_three_hole_rows; holes 2 and 3 lie beyond its
  /// target's foothold and never bind).
  Vec<4> target = q_target();

  static Vec<4> q0() { return Vec<4>(0.0, 0.4, 0.0, 0.0); }
  static Vec<4> v0() { return Vec<4>::Zero(); }
  static Vec<4> q_target() { return Vec<4>(3.0, 0.4, 0.0, 0.0); }

  static timefreezing::TimeFreezingSystem<Hopper> system() { return {Hopper{}, auxiliary_acceleration}; }

  template <class T>
  T running_cost(const VecT<T, 8>&, const VecT<T, 2>& u) const {
    return u.squaredNorm();
  }

  template <class T>
  VecT<T, 11> path_constraints(const VecT<T, 8>& x, const VecT<T, 2>&) const {
    const VecT<T, 4> q = x.template head<4>();
    const VecT<T, 2> foot = hopper.foot<T>(q);
    const VecT<T, 2> knee = hopper.knee<T>(q);
    VecT<T, 11> c;
    c[0] = q[0];
    c[1] = foot[0];
    c[2] = knee[0];
    c[3] = q[1];
    c[4] = q[2];
    c[5] = q[3];
    c[6] = knee[1];
    c[7] = foot[1];
    const double a = hole_half_width, b = hole_depth;
    for (int k = 0; k < 3; ++k) {
      const T dx = (foot[0] - hole_centres[k]) / a, dz = foot[1] / b;
      c[8 + k] = dx * dx + dz * dz;
    }
    return c;
  }
  Vec<11> path_lower() const {
    const double pi = std::numbers::pi;
    Vec<11> l;
    l << -0.05, -0.05, -0.05, 0.2, -3 * pi / 8, -pi / 2, 0.05, -0.005, hole_level, hole_level, hole_level;
    return l;
  }
  Vec<11> path_upper() const {
    const double pi = std::numbers::pi, inf = std::numeric_limits<double>::infinity();
    Vec<11> u;
    u << inf, inf, inf, 0.55, 3 * pi / 8, pi / 2, inf, 0.2, inf, inf, inf;
    return u;
  }

  template <class T>
  VecT<T, 4> terminal_constraints(const VecT<T, 8>& x, const T&) const {
    return x.template head<4>();
  }
  Vec<4> terminal_lower() const { return target; }
  Vec<4> terminal_upper() const { return target; }

  /// The paper's discretisation (time-freezing paper, Nurkanović, Albrecht, Brogliato, Diehl,
  /// Automatica 2023, Section 6, as in NOSNOC's hopper script):
  /// N = 20 control intervals, 3 finite elements each, Radau IIA with n_s stages, numerical horizon
  /// T~ = T with the terminal clock constraint t(T~) = T, speed of time s in [1, 5] with
  /// rho_s = 0.01, heuristic step equilibration rho_h = 1, |u_i| <= 60; one change:
  /// cross-complementarity for the gap only (FesdOptions::switching.velocity_detection = false: the
  /// foot's velocities change sign in flight, bench/experiments/README.md).
  static timefreezing::FesdOptions grid(int control_intervals = 20, int finite_elements = 3, int stages = 2) {
    return terminal_clock_grid(horizon, control_intervals, finite_elements, stages,
                               Eigen::VectorXd::Constant(2, -torque_limit), Eigen::VectorXd::Constant(2, torque_limit));
  }
  /// The continuation on the holes that precedes the homotopy
  /// (solve_time_freezing_ocp_by_continuation): hole levels 1e-4, 1e-3, 1e-2, 0.05, 0.2, 0.5, 1 at
  /// the first relaxation parameter. Nothing in it hints at the contact timing: the start is still
  /// the start state at every node with zero torques. Every stage has the terminal target
  /// `q_end` (the member `target`).
  static std::vector<HopperOverThreeHoles> hole_continuation(const Vec<4>& q_end = q_target()) {
    std::vector<HopperOverThreeHoles> stages;
    for (double level : {1e-4, 1e-3, 1e-2, 0.05, 0.2, 0.5, 1.0}) {
      HopperOverThreeHoles o;
      o.hole_level = level;
      o.target = q_end;
      stages.push_back(o);
    }
    return stages;
  }
  /// The paper's homotopy (sigma_0 = 1, kappa = 0.1, 10 steps, at most 1500 Ipopt iterations per
  /// step) with the smoothing relaxation (mpcc/solve.hpp: the stage-wise pairs as equalities
  /// G H = sigma; the paper's Scholtes inequalities leave the step functions free in a band and
  /// Ipopt wanders); Ipopt tol 1e-8 (1e-10 only adds iterations at mu = 1e-11 on these OCPs:
  /// solve_time_freezing_ocp's docstring).
  static timefreezing::MpccSolverOptions solver() {
    timefreezing::MpccSolverOptions s;
    s.homotopy.relaxation = timefreezing::MpccSolverOptions::Relaxation::Smoothing;
    s.homotopy.sigma_0 = 1.0;
    s.homotopy.kappa = 0.1;
    s.homotopy.max_steps = 10;
    s.ipopt.max_iter = 1500;
    s.ipopt.tol = 1e-8;
    return s;
  }

  /// The second initialisation (reported beside the contact-implicit one, never instead of it): a
  /// kinematic guess of three hops, fed to solve_time_freezing_ocp_from_guess. The hip moves at
  /// the constant speed 3 / T, its height is 0.4 + 0.14 sin^2(3 pi t / T) (the leg straight, so the
  /// foot touches the ground at x = 0, 1, 2, 3 and is 0.14 m up over each hole's centre, outside
  /// every hole: the smallest ellipse value along the guess is 1.47 > 1), the joint angles 0. It
  /// says where the feet go, not how: it is not dynamically consistent (no stance, no push-off).
  /// Measured (bench/experiments/README.md, `hopper_ocp --only hop-guess`): from it the default homotopy meets
  /// its wall at sigma ~ 1e-2, two decades before its first failure from the start state (1e-4).
  static Vec<8> hop_guess(double t) {
    constexpr double height = 0.14, pi = std::numbers::pi;
    const double w = 3.0 * pi / horizon, s = std::sin(w * t), c = std::cos(w * t);
    Vec<8> g = Vec<8>::Zero();
    g[0] = 3.0 * t / horizon;
    g[1] = 0.4 + height * s * s;
    g[4] = 3.0 / horizon;
    g[5] = 2.0 * height * w * s * c;
    return g;
  }

  /// The largest violation of the path constraints (at the FULL holes, hole_level 1) over the
  /// given stage points, and which row; and the target error max_i |q_i(T) - q_target,i|.
  struct Feasibility {
    double path_violation = 0.0;
    int worst_row = -1;  ///< index into path_names, -1 when none is violated
    double target_error = 0.0;
  };
  template <class Points>
  static Feasibility feasibility(const Points& points) {
    return feasibility_against(points, q_target());
  }
  /// feasibility() with the target error measured against `target` (q(T), size nq = 4).
  template <class Points>
  static Feasibility feasibility_against(const Points& points, const Vec<4>& target) {
    const HopperOverThreeHoles full;
    const Vec<11> lo = full.path_lower(), hi = full.path_upper();
    Feasibility f;
    for (const auto& p : points) {
      const Vec<11> c = full.path_constraints<double>(p.y.template head<8>(), p.u);
      for (int i = 0; i < 11; ++i) {
        const double v = std::max(lo[i] - c[i], c[i] - hi[i]);
        if (v > f.path_violation) {
          f.path_violation = v;
          f.worst_row = i;
        }
      }
    }
    f.target_error = (points.back().y.template head<4>() - target).cwiseAbs().maxCoeff();
    return f;
  }

  /// Names of the path constraints, for reports.
  static constexpr std::array<const char*, 11> path_names{
      "hip x >= -0.05", "foot x >= -0.05", "knee x >= -0.05", "0.2 <= z <= 0.55", "|phi_hip| <= 3 pi/8",
      "|phi_knee| <= pi/2", "knee z >= 0.05", "-0.005 <= foot z <= 0.2", "outside hole 1", "outside hole 2",
      "outside hole 3"};
};

/// The same hopper over the first hole only, the shorter task of the hopper's test (a shorter
/// horizon, 8 of the flagship's 20 control intervals; bench/experiments/hopper_ocp --one-hole; bench/experiments/README.md,
/// "The one-hole test bed"):
/// T = 1 s, target q(T) = (1, 0.4, 0, 0), N = 8 control intervals (0.125 s each, as the
/// flagship's), 3 finite elements, n_s = 2; the same path rows (holes 2 and 3 lie beyond the
/// target: the foot ends on the ground in [0.75, 1.25]), start, torque bounds, a_n and hole
/// continuation. hop_guess (three hops over 2.5 s) does not describe this task.
/// Its solver settings are the flagship's with three changes, which make it converge
/// (bench/experiments/README.md, "The one-hole bed converges"; measured with `hopper_ocp --one-hole`, a
/// scratch driver and the test HopperOverOneHole.CoarseGridConvergesAndJumpsTheHole):
/// - the contact-side selection rho_c = 1e-2 (grid(); FesdOptions::regularisation.contact_side): it pushes
///   alpha_gap to 0 in the relaxed stances, where a fractional alpha_gap next to the sliding mode
///   on J_n v leaves the weights of the Filippov field undetermined (the branch NLPs from such
///   iterates have rank-deficient active Jacobians; measured);
/// - every solve after the first starts from the previous x alone (MpccSolverOptions::warm_start
///   = false): Ipopt's own bound push and multiplier initialisation instead of the previous
///   solve's multipliers and an iterate 1e-9 from its bounds;
/// - 11 homotopy steps, the last at sigma = 1e-10: the smoothed products equal sigma to Ipopt's
///   tolerance only (at sigma = 1e-9 the residual was 1.0000003e-9 > 1e-9).
/// The homotopy converges by itself (its final branch NLP fails, which does not matter). With the
/// flagship's settings it stops at complementarity 1.3e-4; with the selection alone (warm
/// starts) at 3.3e-4, with primal-only starts alone at 1.43e-6. On the flagship these settings
/// stop at 1e-3.
/// Its OCP is the three-hole one with another target (the member `target`, set by the
/// constructor): on_three_hole_rows() is that OCP as a HopperOverThreeHoles, whose discovery and
/// refinement are compiled once (hopper_holes_refinement.hpp), over the horizon T = 1 s of grid().
struct HopperOverOneHole : HopperOverThreeHoles {
  static constexpr double horizon = 1.0;  ///< T [s]
  static constexpr double contact_side_weight = 1e-2;  ///< rho_c (struct comment)
  static Vec<4> q_target() { return Vec<4>(1.0, 0.4, 0.0, 0.0); }
  HopperOverOneHole() { target = q_target(); }
  /// The same OCP (rows, target (1, 0.4, 0, 0), hole level) typed as the three-hole OCP, for its
  /// compiled discovery and refinement.
  static HopperOverThreeHoles on_three_hole_rows(double hole_level = 1.0) {
    HopperOverThreeHoles o;
    o.hole_level = hole_level;
    o.target = q_target();
    return o;
  }
  static timefreezing::FesdOptions grid(int control_intervals = 8, int finite_elements = 3, int stages = 2) {
    timefreezing::FesdOptions o =
        terminal_clock_grid(horizon, control_intervals, finite_elements, stages,
                            Eigen::VectorXd::Constant(2, -torque_limit), Eigen::VectorXd::Constant(2, torque_limit));
    o.regularisation.contact_side = contact_side_weight;
    return o;
  }
  /// The flagship's homotopy (HopperOverThreeHoles::solver) with primal-only warm starts and 11
  /// steps (struct comment).
  static timefreezing::MpccSolverOptions solver() {
    timefreezing::MpccSolverOptions s = HopperOverThreeHoles::solver();
    s.warm_start = false;
    s.homotopy.max_steps = 11;
    return s;
  }
  static std::vector<HopperOverOneHole> hole_continuation() {
    std::vector<HopperOverOneHole> stages;
    for (const HopperOverThreeHoles& full : HopperOverThreeHoles::hole_continuation()) {
      HopperOverOneHole o;
      o.hole_level = full.hole_level;
      stages.push_back(o);
    }
    return stages;
  }
  template <class Points>
  static Feasibility feasibility(const Points& points) {
    return feasibility_against(points, q_target());
  }
};

}  // namespace saltus::scenes

// Compiled once in hopper_holes.cpp: the hopper's recovery and both hole OCPs.
SALTUS_DECLARE_TIME_FREEZING_SCENE(saltus::scenes::Hopper)
SALTUS_DECLARE_TIME_FREEZING_OCP(saltus::scenes::Hopper, saltus::scenes::HopperOverThreeHoles)
SALTUS_DECLARE_TIME_FREEZING_OCP(saltus::scenes::Hopper, saltus::scenes::HopperOverOneHole)
