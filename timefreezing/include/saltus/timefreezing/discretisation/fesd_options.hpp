// The options of the FESD discretisation (FesdMpcc, fesd.hpp), nested by concern: the grid, the
// switch detection, the clock and the speed of time, the regularisation terms of the objective, the
// bounds. Defaults: NOSNOC's where NOSNOC has the option (Radau IIA with n_s = 2, FESD with
// cross-complementarity on every switching function, heuristic step equilibration rho_h = 1,
// gamma_h = 1, no speed of time). Experiments measured worse and removed: docs/decisions/fesd-*.md.
#pragma once

#include <Eigen/Core>

#include <array>
#include <limits>

namespace saltus::timefreezing {

/// How the clock is tied to physical time (time-freezing paper, eq. 35f).
enum class ClockConstraint {
  None,       ///< free (simulation)
  Terminal,   ///< t(T~) = physical_horizon
  Stagewise,  ///< t(tau_k) = initial_time + k physical_horizon / N at every control node (eq. 35f)
};

/// Options of the FESD discretisation. Checked by FesdMpcc's constructor (InvalidArgument).
struct FesdOptions {
  /// The grid in numerical time (fesd.hpp, "GRID").
  struct Grid {
    int stages = 2;             ///< n_s of Radau IIA (1, 2, 3)
    int control_intervals = 1;  ///< N >= 1
    int finite_elements = 2;    ///< N_fe >= 1 per control interval
    double horizon = 1.0;       ///< numerical horizon T~ [s of numerical time], > 0
    /// gamma_h in [0, 1]: every element length h in [(1 - gamma_h) h0, (1 + gamma_h) h0] (with
    /// switch detection; the fixed grid has h = h0).
    double element_length_freedom = 1.0;
  };

  /// Which switching functions get the FESD cross-complementarity, and how they are read.
  struct Switching {
    /// FESD: free element lengths and cross-complementarity; false: the fixed grid (h = h0,
    /// stage-wise pairs only: the standard Radau time-stepping).
    bool detection = true;
    /// With detection: also the velocity switching functions (J_n v, J_t v) get the
    /// cross-complementarity (NOSNOC); false: only the gaps do, and the velocities get the
    /// stage-wise pairs of the fixed grid. Why false: in flight (gap > 0) J_n v and J_t v change
    /// sign (the foot's apex, a leg swinging back) with no effect on the field (theta^free = 1
    /// whatever alpha_2, alpha_3), yet cross-complementarity forbids a sign change inside an
    /// element, so every such change must sit on an element boundary: spurious switches that the
    /// grid cannot all host (the hopper OCP: after the homotopy the worst pair was J_n v's in a
    /// flight element, 0.67). Cost: the end of a frozen phase and slip-stick are not located by
    /// the grid (an O(h) error there); touchdown and lift-off are (the gap's switches). The
    /// stage-wise pairs are the ones MpccSolverOptions::Relaxation::Smoothing smooths: with this
    /// option true (and detection true) Smoothing has nothing to smooth.
    bool velocity_detection = true;
    /// The gap switching functions read the integrated gaps g [m] (the state's last nc entries,
    /// g' = s Theta J_n v, g(0) = gap(q0); time_freezing_system.hpp) instead of gap(q) at each
    /// stage point. When to turn it on: a contact that slides or sticks while its gap is nonlinear
    /// in q and the configuration moves (a box on a rotating plank; a foot whose height depends on
    /// joint angles), when the homotopy or its branch NLP stalls there. Why: in a moving stance,
    /// holding gap(q) = 0 and J_n v = 0 at every stage point is overdetermined for a gap nonlinear
    /// in q (fesd_stage_rows.hxx, "INTEGRATED GAP"); the two agree exactly for g. For gaps linear
    /// in q the discrete problem is the same as with false (Example 3's first 16 elements: final
    /// states 1.4e-9 apart, Ipopt's tolerance). The recovered trajectory (recover_trajectory)
    /// still reads the gaps from q, within its gap_tolerance. Measured: the plank-box flagship
    /// converges with it (and the early polish) where with gap(q) it stalled at complementarity
    /// 8.4e-7; the hopper's homotopy with it stalls near 5e-3 (with gap(q): near 1e-3 .. 2.4e-4).
    /// Hence off by default and on in the plank-box flagship's grid.
    bool integrated_gap = false;
    /// Scales K = {gap [1/m], J_n v [s/m], J_t v [s/m]} of the switching functions, the same for
    /// every contact (function m uses entry m % 3); > 0. The rows read
    /// K c(q, v) - lambda_p + lambda_n = 0. The step functions and the switches do not change, the
    /// multipliers and so the complementarity products do: a relaxation that holds
    /// lambda (1 - alpha) = sigma leaves 1 - alpha = sigma / (K c), so K is the unit in which a
    /// relaxation parameter is read. In flight the auxiliary weight (1 - alpha_gap)(...) with a_n
    /// behind it is a phantom support of size a_n sigma / (K gap): a larger gap scale makes the
    /// loosely relaxed problems more physical.
    std::array<double, 3> scale{1.0, 1.0, 1.0};
  };

  /// The clock and the speed of time (time-freezing paper, eqs. 33, 35f-g).
  struct Clock {
    ClockConstraint constraint = ClockConstraint::None;
    double physical_horizon = std::numeric_limits<double>::quiet_NaN();  ///< T [s], > 0 with a constraint
    double initial_time = 0.0;       ///< t at tau = 0 [s] (the clock rows count from it), finite
    double speed_of_time_max = 1.0;  ///< s_max >= 1 of the speed of time s_k in [1, s_max] (1: s fixed at 1)
  };

  /// Terms of the objective that select among the discrete solutions (fesd_objective.hxx).
  struct Regularisation {
    /// rho_h >= 0 of the heuristic step equilibration rho_h sum (h_kj - h0)^2 (NOSNOC's
    /// heuristic_mean, unscaled; with switch detection only).
    double step_equilibration = 1.0;
    /// rho_c >= 0 (objective units per unit step function) of the contact-side selection
    /// rho_c sum alpha_gap over contacts and stage points (fesd_objective.hxx; a reward per stage
    /// point, so it grows with n_s and the number of elements): where a gap is exactly zero
    /// (frozen phases, sliding) complementarity leaves alpha_gap free and this picks the contact
    /// side, so that frozen-phase ends are switches of J_n v that the grid locates. 0: off (the
    /// default). When to turn it on: simulations of one contact with impacts or sliding (then
    /// rho_c = 1e-2 is a safe choice); not measured to help with several contacts. Measured,
    /// simulations with rho_c = 1e-2: Example 3 (one contact), n_s = 2, 224 elements, final error
    /// 9.8e-6 -> 7.1e-7 and 7,492 -> 3,104 Ipopt iterations; NOSNOC's frictional landing, stop
    /// error 2.0e-6 -> 6.2e-12; but the plank-box flat landing (two contacts) 2,567 -> 16,071
    /// iterations and 6.7e-5 -> 1.3e-4 from the event-driven simulation, and Example 3 at 56
    /// elements does not converge (its tangential lift-off interval): not a default. A heuristic
    /// size: rho_c above rho_h h0^2, the heuristic step equilibration's price of moving a boundary
    /// by h0 = horizon / (control_intervals finite_elements) (Example 3, h0 = 0.0625: 1e-3 left
    /// the frozen end inside an element, 1e-2 did not; smaller weights can work when the switch
    /// falls near a grid node). On the fixed grid there is no such price: the term still picks the
    /// side, which then only removes the drift (the grid cannot move). In an OCP the term is a
    /// reward of rho_c per stage point in contact and can move the optimum; it is part of the
    /// NLP's objective (MpccSolution::objective).
    double contact_side = 0.0;
    double speed_of_time = 0.0;  ///< rho_s >= 0 of rho_s sum (s_k - 1)^2
  };

  /// Bounds of the decisions and of the initial state.
  struct Bounds {
    Eigen::VectorXd control_lower;  ///< size nu (empty: -infinity)
    Eigen::VectorXd control_upper;  ///< size nu (empty: +infinity)
    /// The initial configuration may penetrate a contact by at most this much [m] (InvalidArgument
    /// beyond: the time-freezing system would slide along inside the obstacle, clock running).
    double gap_tolerance = 1e-9;
  };

  Grid grid;
  Switching switching;
  Clock clock;
  Regularisation regularisation;
  Bounds bounds;
};

}  // namespace saltus::timefreezing
