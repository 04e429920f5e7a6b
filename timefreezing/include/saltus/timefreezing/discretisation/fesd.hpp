// Finite elements with switch detection (FESD) for the time-freezing system: the discretisation
// of the OCP in numerical time (time-freezing paper eq. 33, discretised as eq. 35) as an MPCC with
// exact sparse derivatives (mpcc.hpp), for the solver in mpcc_solver.hpp.
//
// GRID. N control intervals of equal numerical length T~/N (T~ = options.horizon); each holds
// N_fe finite elements of free lengths h_kj with sum_j h_kj = T~/N and (1 - gamma_h) h0 <= h_kj
// <= (1 + gamma_h) h0, h0 = T~/(N N_fe) (FESD paper; options.switch_detection = false fixes
// h_kj = h0: the standard Radau time-stepping). Each element is a Radau IIA collocation step with
// n_s stages (radau.hpp); the last stage is the element's end point, which starts the next
// element (continuity).
//
// VARIABLES, per control interval k: the speed of time s_k in [1, s_max] (eq. 35g; fixed at 1
// when s_max = 1), the control u_k (piecewise constant); per element: h_kj; per stage r:
//     Y (ny = 2 nq + 2 + nc: q, v, t, L, g)   the stage state (g: the integrated gaps),
//     K (ny)                           the stage derivative,
//     alpha (3 nc)                     the step functions of the switching functions,
//     lambda_p, lambda_n (3 nc)        their multipliers.
// The stage DERIVATIVE K is a variable (NOSNOC's "differential" representation) so that the
// mass matrix is multiplied, never inverted: the nonlinear rows of a stage are
//     K_q - s Theta v = 0,   M(q) K_v - s F(q, v, u, alpha) = 0,   K_t - s Theta = 0,
//     K_L - s Theta l(x, u) = 0                                  (time_freezing_system.hpp),
// and the collocation rows Y_r - y_start - h sum_l a_rl K_l = 0 are bilinear. Switching rows
// (eq. 31): c(q_r, v_r) - lambda_p,r + lambda_n,r = 0 (with FesdOptions::integrated_gap, the gap
// entries of c read the integrated gaps g_r instead of gap(q_r); below).
//
// COMPLEMENTARITY (all sides affine). Switch detection (FESD paper, cross-complementarity in
// NOSNOC's FE_STAGE form): for each element, each switching function m and each point p among
// the element's stages AND the previous element's end point,
//     0 <= lambda_n,p,m  _|_  sum_r alpha_r,m >= 0,     0 <= lambda_p,p,m  _|_  sum_r (1 - alpha_r,m) >= 0.
// Since every term is nonnegative, this is equivalent to lambda_n,p alpha_r = 0 for every pair
// of points: inside one element the active set cannot change, so a switch can only happen at an
// element boundary, where the free h puts it. The fixed grid uses the stage-wise pairs only.
// Frictionless contacts fix alpha_3 = 1 and lambda_n,3 = 0 by bounds and have no tangential pairs.
//
// OBJECTIVE: L(T~) (the running cost over physical time, eq. 29), plus the terminal cost, plus
// the heuristic step equilibration rho_h sum (h_kj - h0)^2 (NOSNOC's heuristic_mean, unscaled
// like NOSNOC's so that weights compare; StepEquilibration::Heuristic), plus rho_s sum (s_k - 1)^2,
// plus the contact-side selection rho_c sum alpha_gap (FesdOptions::contact_side_weight, below).
//
// CONTACT-SIDE SELECTION. While a contact's gap is exactly zero (its frozen phase: the auxiliary
// field moves v only, q' = 0; sliding along the surface) the gap's switching function vanishes,
// both its multipliers vanish, and complementarity leaves its step function alpha_gap anywhere in
// [0, 1]. The Filippov field does not care which weights realise it: with alpha_gap = a and
// alpha_vn = b the field weights the ODE by 1 - (1 - a)(1 - b), so sliding (clock speed 1/2 in
// Example 3) is a = 0, b = 1/2 or a = 1/2, b = 0 alike. But the second choice moves the end of the
// frozen phase into the degenerate gap pair, where cross-complementarity sees no switch, so the
// grid does not locate it: Example 3 with n_s = 2 and 16 elements per control interval ends its
// frozen phase inside an element (tau off by 3.2e-3, q1 by 9e-6), and a relaxed homotopy also
// uses the freedom to let the gap drift (-1.6e-5) and the clock creep during the frozen phase.
// The linear cost rho_c sum over contacts and stage points of alpha_gap picks the contact side
// (alpha_gap = 0) wherever the gap is zero, and does nothing where the gap is not (there
// complementarity fixes alpha_gap); so the frozen phase's end becomes a switch of J_n v, which
// cross-complementarity locates. Under a relaxation it pulls alpha_gap in flight down to the
// relaxed bound 1 - alpha_gap = sigma / lambda_p <= sigma / (K gap): a phantom support that
// vanishes with sigma away from the surface but not near it (integrated over an approach, about
// sigma log sigma). At a lift-off the field is right (the ODE weight is 1 once alpha_vn = 1), but
// the gap's step function stays at 0 until the gap has grown to about sigma, so the gap's switch
// point comes late (Example 3's tangential lift-off: 3.6e-4 in tau).
// Off by default: measured on one contact it removes the drift and locates the frozen end, on
// the plank-box's two contacts it costs 6x the Ipopt iterations (FesdOptions::contact_side_weight).
// Derivatives: gradient rho_c on those entries, no Hessian term.
//
// INTEGRATED GAP (FesdOptions::integrated_gap; time_freezing_system.hpp). Derivation of why a
// moving stance and a gap nonlinear in q do not mix. In a stance the contact's gap pairs leave
// alpha_gap interior, so complementarity (relaxed to nothing) holds gap(q_r) = 0 at every stage,
// and the sliding mode on J_n v holds J_n(q_r) v_r = 0 at every stage. With Radau collocation,
// q_r = q_0 + h sum_l a_rl K_l, K_l = s Theta_l v_l. For n_s = 1 (a = c = 1), Taylor about q_1:
//     gap(q_1) = gap(q_0) + J_n(q_1) h K - (h^2 / 2) K' grad^2 gap K + O(h^3),
// so gap(q_0) = 0 and J_n(q_1) v_1 = 0 give gap(q_1) = -(h^2 / 2) K' grad^2 gap K + O(h^3): not
// zero unless the gap is linear in q (the point mass) or the motion stops (the hopper standing
// still). For n_s >= 2 Radau IIA's simplifying conditions sum_l a_rl c_l^(k-1) = c_r^k / k
// (k <= n_s) cancel the h^2 term; what is left is of higher order in h and involves the gap's
// second derivative along the velocity and the acceleration (grad^2 gap[q', q'']) or its third
// derivative (a user's check with n_s = 2: a quadratic gap at constant velocity leaves no
// residual; in general O(h^3) at the inner stage, O(h^4) at the end point). So where the residual
// has the sign that lifts the contact, the discrete stance has no solution with both held: gap(q_r) > 0
// forces alpha_gap = 1, i.e. no contact force at that stage. A relaxed homotopy can hide this
// while sigma is larger than the residual; then it cannot go on (bench/README.md, the flagships).
// The integrated gaps g (g' = Theta J_n v, collocated like q) have stage values g_r = g_0 + h sum_l
// a_rl s Theta_l J_n(q_l) v_l: zero whenever g_0 and the stages' J_n v are, for any gap. The switching
// function then reads g instead of gap(q); g - gap(q) is the collocation's own error in
// integrating gap' = J_n q', so it shrinks with the discretisation (q itself is integrated
// with the same error). Without the option g is still carried (its rows are cheap and keep
// the layout one), but nothing reads it.
//
// DERIVATIVES: every nonlinear block is a templated function of a small local vector (the stage
// dynamics: (s, Y, K, u, alpha); the switching functions: (q, v); path and terminal functions);
// its Jacobian is forward AD (saltus::ad::Dual) and its Lagrangian Hessian forward-over-forward
// AD, assembled into the global sparse structure built once. Bilinear terms are written out.
#pragma once

#include <saltus/ad/autodiff.hpp>
#include <saltus/hybrid/vocabulary/errors.hpp>
#include <saltus/timefreezing/mpcc/mpcc.hpp>
#include <saltus/timefreezing/discretisation/radau.hpp>
#include <saltus/timefreezing/formulation/time_freezing_system.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace saltus::timefreezing {

/// How the clock is tied to physical time (eq. 35f).
enum class ClockConstraint {
  None,       ///< free (simulation)
  Terminal,   ///< t(T~) = physical_horizon
  Stagewise,  ///< t(tau_k) = k physical_horizon / N at every control node (eq. 35f)
};

/// Options of the FESD discretisation (defaults: NOSNOC's, nosnoc_facts.md section 1).
struct FesdOptions {
  int stages = 2;               ///< n_s of Radau IIA (1, 2, 3)
  int control_intervals = 1;    ///< N
  int finite_elements = 2;      ///< N_fe per control interval
  double horizon = 1.0;         ///< numerical horizon T~ [s of numerical time], > 0
  bool switch_detection = true; ///< FESD (free h, cross-complementarity); false: fixed grid
  /// With switch_detection: also the velocity switching functions (J_n v, J_t v) get the
  /// cross-complementarity (NOSNOC); false: only the gaps do, and the velocities get the
  /// stage-wise pairs of the fixed grid. Why false: in flight (gap > 0) J_n v and J_t v change
  /// sign (the foot's apex, a leg swinging back) with no effect on the field (theta^free = 1
  /// whatever alpha_2, alpha_3), yet cross-complementarity forbids a sign change inside an
  /// element, so every such change must sit on an element boundary: spurious switches that the
  /// grid cannot all host (the hopper OCP: after the homotopy the worst pair was J_n v's in a
  /// flight element, 0.67). Cost: the end of a frozen phase and slip-stick are not located by
  /// the grid (an O(h) error there); touchdown and lift-off are (the gap's switches). The
  /// stage-wise pairs are the ones MpccSolverOptions::Relaxation::Smoothing smooths: with this
  /// option true (and switch_detection true) Smoothing has nothing to smooth.
  bool velocity_switch_detection = true;
  double element_length_freedom = 1.0;  ///< gamma_h in [0, 1]: h in [(1-gamma_h) h0, (1+gamma_h) h0]
  /// The gap switching functions read the integrated gaps g [m] (the state's last nc entries,
  /// g' = s Theta J_n v, g(0) = gap(q0); time_freezing_system.hpp) instead of gap(q) at each stage
  /// point. Throws nothing of its own. When to turn it on: a contact that slides or sticks while
  /// its gap is nonlinear in q and the configuration moves (a box on a rotating plank; a foot
  /// whose height depends on joint angles), when the homotopy or its branch NLP stalls there.
  /// Why: in a moving stance, holding gap(q) = 0 and J_n v = 0 at every stage point is
  /// overdetermined for a gap nonlinear in q (file comment, "INTEGRATED GAP"); the two agree
  /// exactly for g. For gaps linear in q the discrete problem is the same as with false (Example
  /// 3's first 16 elements: final states 1.4e-9 apart, Ipopt's tolerance). The recovered
  /// trajectory (recover_trajectory) still reads the gaps from q, within its gap_tolerance.
  /// Measured (bench/README.md, "Plank-box flat landing"): the plank-box flagship converges with
  /// it (and the early polish) where with gap(q) it stalled at complementarity 8.4e-7; the
  /// hopper's homotopy with it stalls near 5e-3 (with gap(q): near 1e-3 .. 2.4e-4). Hence off by
  /// default and on in the plank-box flagship's grid.
  bool integrated_gap = false;
  /// Scales K = {gap [1/m], J_n v [s/m], J_t v [s/m]} of the switching functions, the same for
  /// every contact (function m uses entry m % 3); > 0. The rows
  /// read K c(q, v) - lambda_p + lambda_n = 0. The step functions and the switches do not change,
  /// the multipliers and so the complementarity products do: a relaxation that holds
  /// lambda (1 - alpha) = sigma leaves 1 - alpha = sigma / (K c), so K is the unit in which a
  /// relaxation parameter is read. In flight the auxiliary weight (1 - alpha_gap)(...) with
  /// a_n behind it is a phantom support of size a_n sigma / (K gap): a larger gap scale makes the
  /// loosely relaxed problems more physical (bench/README.md, "Switching-function scale").
  std::array<double, 3> switching_scale{1.0, 1.0, 1.0};
  double step_equilibration_weight = 1.0;  ///< rho_h of the heuristic penalty
  /// rho_c >= 0 (objective units per unit step function) of the contact-side selection
  /// rho_c sum alpha_gap over contacts and stage points (file comment; a reward per stage point,
  /// so it grows with n_s and the number of elements): where a gap is exactly zero (frozen
  /// phases, sliding) complementarity leaves alpha_gap free and this picks the contact side, so
  /// that frozen-phase ends are switches of J_n v that the grid locates. 0: off (the default).
  /// When to turn it on: simulations of one contact with impacts or sliding (then rho_c = 1e-2 is
  /// a safe choice); not measured to help with several contacts (below). Measured
  /// (bench/README.md, "Where Example 3's error came from"), simulations with rho_c = 1e-2:
  /// Example 3 (one contact), n_s = 2, 224 elements, final error 9.8e-6 -> 7.1e-7 and 7,492 ->
  /// 3,104 Ipopt iterations; NOSNOC's frictional landing, stop error 2.0e-6 -> 6.2e-12; but the
  /// plank-box flat landing (two contacts) 2,567 -> 16,071 iterations and 6.7e-5 -> 1.3e-4 from the
  /// event-driven simulation, and Example 3 at 56 elements does not converge (its tangential
  /// lift-off interval): not a default. A heuristic size: rho_c above rho_h h0^2, the heuristic
  /// step equilibration's price of moving a boundary by h0 = horizon / (control_intervals
  /// finite_elements) (Example 3, h0 = 0.0625: 1e-3 left the frozen end inside an element, 1e-2
  /// did not; smaller weights can work when the switch falls near a grid node). With
  /// switch_detection = false there is no such price: the term still
  /// picks the side, which then only removes the drift (the grid cannot move). In an OCP the term
  /// is a reward of rho_c per stage point in contact and can move the optimum; it is part of the
  /// NLP's objective (MpccSolution::objective).
  double contact_side_weight = 0.0;
  double speed_of_time_max = 1.0;          ///< s_max >= 1 (1: s fixed at 1)
  double speed_of_time_weight = 0.0;       ///< rho_s
  ClockConstraint clock = ClockConstraint::None;
  double physical_horizon = std::numeric_limits<double>::quiet_NaN();  ///< T [s], for the clock
  double initial_time = 0.0;  ///< t at tau = 0 [s] (the clock's initial value; clock rows count from it)
  /// The initial configuration may penetrate a contact by at most this much [m] (InvalidArgument
  /// beyond: the time-freezing system would slide along inside the obstacle, clock running).
  double gap_tolerance = 1e-9;
  Eigen::VectorXd control_lower;  ///< size nu (empty: -infinity)
  Eigen::VectorXd control_upper;  ///< size nu (empty: +infinity)
};

/// An OCP without costs, constraints or input law: a simulation under u = decision (zero).
struct NoObjective {};

namespace detail {

template <int N>
using Ad1 = ad::Dual<double, N>;
template <int N>
using Ad2 = ad::Dual<ad::Dual<double, N>, N>;

template <int N>
VecT<Ad1<N>, N> seed_first(const Eigen::Matrix<double, N, 1>& w) {
  VecT<Ad1<N>, N> x;
  for (int k = 0; k < N; ++k) x[k] = ad::seed<N>(w[k], k);
  return x;
}
/// Forward-over-forward seeds: value w_k, inner direction k, outer direction k.
template <int N>
VecT<Ad2<N>, N> seed_second(const Eigen::Matrix<double, N, 1>& w) {
  VecT<Ad2<N>, N> x;
  for (int k = 0; k < N; ++k) {
    Eigen::Matrix<Ad1<N>, N, 1> outer;
    for (int j = 0; j < N; ++j) outer[j] = Ad1<N>(j == k ? 1.0 : 0.0);
    x[k] = Ad2<N>(ad::seed<N>(w[k], k), outer);
  }
  return x;
}

// What an OCP description may provide (all optional).
template <class O, class T, int nx, int nu>
concept HasRunningCost = requires(const O& o, const VecT<T, nx>& x, const VecT<T, nu>& u) {
  { o.template running_cost<T>(x, u) } -> std::convertible_to<T>;
};
template <class O, class T, int nx, int nu>
concept HasTimedRunningCost = requires(const O& o, const VecT<T, nx>& x, const VecT<T, nu>& u, const T& t) {
  { o.template running_cost<T>(x, u, t) } -> std::convertible_to<T>;
};
/// A running_cost that is not a member template (its address can be taken): AD cannot see it.
template <class O>
concept HasNonTemplateRunningCost = requires { &O::running_cost; };
template <class O, class T, int nx>
concept HasTerminalCost = requires(const O& o, const VecT<T, nx>& x, const T& t) {
  { o.template terminal_cost<T>(x, t) } -> std::convertible_to<T>;
};
template <class O, class T, int nu>
concept HasInputLaw = requires(const O& o, const T& t, const VecT<T, nu>& u) {
  { o.template input<T>(t, u) } -> std::convertible_to<VecT<T, nu>>;
};
template <class O>
concept HasPathConstraints = requires { O::path_constraint_count; };
template <class O>
concept HasTerminalConstraints = requires { O::terminal_constraint_count; };

template <class O>
constexpr int path_count() {
  if constexpr (HasPathConstraints<O>) return O::path_constraint_count; else return 0;
}
template <class O>
constexpr int terminal_count() {
  if constexpr (HasTerminalConstraints<O>) return O::terminal_constraint_count; else return 0;
}

}  // namespace detail

/// One point of the discrete solution: the initial point (element -1) or a stage point.
template <int ny, int n_switch, int nu>
struct FesdPoint {
  int interval = 0, element = -1, stage = -1;
  double tau = 0.0;                        ///< numerical time
  Eigen::Matrix<double, ny, 1> y;          ///< (q, v, t, L, g): time_freezing_system.hpp
  Eigen::Matrix<double, n_switch, 1> alpha;
  double ode_weight = 1.0;                 ///< Theta: 1 while the clock runs, 0 when frozen
  Eigen::Matrix<double, nu, 1> u;          ///< the input applied (after the input law)
};

/// The FESD-discretised time-freezing OCP as an MPCC (file comment). Ocp provides, optionally:
///   template <class T> T running_cost(const VecT<T, nx>& x, const VecT<T, nu>& u) const;   [per s]
///       or running_cost(x, u, t) with the physical time t [s] (the clock: e.g. a tracking term
///       of a time-dependent reference); the three-argument form is used when both exist;
///   template <class T> T terminal_cost(const VecT<T, nx>& x, const T& t) const;
///   template <class T> VecT<T, nu> input(const T& t, const VecT<T, nu>& decision) const;
///       (the input applied at physical time t; default: the decision itself)
///   static constexpr int path_constraint_count; path_constraints<T>(x, u) -> VecT<T, np>,
///       path_lower(), path_upper() -> Vec<np>: imposed at every stage point;
///   static constexpr int terminal_constraint_count; terminal_constraints<T>(x, t) -> VecT<T, nt>,
///       terminal_lower(), terminal_upper().
/// Throws InvalidArgument for bad options or a non-finite initial state.
template <Scene S, class Ocp = NoObjective>
class FesdMpcc final : public Mpcc {
 public:
  using System = TimeFreezingSystem<S>;
  static constexpr int nq = S::nq, nu = S::nu, nc = S::nc;
  static constexpr int nx = 2 * nq;
  static constexpr int ny = System::ny;
  static constexpr int nsw = System::n_switch;
  static constexpr int np = detail::path_count<Ocp>();
  static constexpr int nt = detail::terminal_count<Ocp>();
  /// Local variables of the stage field G (below): z = (q, v, t, u, alpha).
  static constexpr int nz = 2 * nq + 1 + nu + nsw;
  /// Variables per stage point: Y, K, alpha, lambda_p, lambda_n.
  int stage_size() const { return 2 * ny + 3 * nsw; }
  using Point = FesdPoint<ny, nsw, nu>;
  // The OCP's functions are differentiated by AD: each must be a member template in T taking T
  // everywhere, or the values and the derivatives would silently use different functions.
  static_assert(!detail::HasNonTemplateRunningCost<Ocp>,
                "FesdMpcc: Ocp::running_cost must be a member template: template <class T> T running_cost(const "
                "VecT<T, nx>& x, const VecT<T, nu>& u[, const T& t]) const");
  static_assert(detail::HasRunningCost<Ocp, double, nx, nu> == detail::HasRunningCost<Ocp, detail::Ad2<nz>, nx, nu> &&
                    detail::HasTimedRunningCost<Ocp, double, nx, nu> ==
                        detail::HasTimedRunningCost<Ocp, detail::Ad2<nz>, nx, nu>,
                "FesdMpcc: Ocp::running_cost must take the clock as const T& t (it is differentiated)");

  FesdMpcc(const System& system, const Ocp& ocp, const Vec<nq>& q0, const Vec<nq>& v0, const FesdOptions& options)
      : system_(system), ocp_(ocp), options_(options), tableau_(radau_iia(options.stages)) {
    require_finite(q0, "FESD: initial configuration q0");
    require_finite(v0, "FESD: initial velocity v0");
    SALTUS_REQUIRE(options.control_intervals >= 1, "FESD: control_intervals must be >= 1, got ", options.control_intervals);
    SALTUS_REQUIRE(options.finite_elements >= 1, "FESD: finite_elements must be >= 1, got ", options.finite_elements);
    SALTUS_REQUIRE(std::isfinite(options.horizon) && options.horizon > 0.0, "FESD: the numerical horizon must be > 0, got ",
                   options.horizon);
    SALTUS_REQUIRE(options.element_length_freedom >= 0.0 && options.element_length_freedom <= 1.0,
                   "FESD: element_length_freedom (gamma_h) must lie in [0, 1], got ", options.element_length_freedom);
    SALTUS_REQUIRE(std::isfinite(options.speed_of_time_max) && options.speed_of_time_max >= 1.0,
                   "FESD: speed_of_time_max must be >= 1, got ", options.speed_of_time_max);
    SALTUS_REQUIRE(std::isfinite(options.step_equilibration_weight) && options.step_equilibration_weight >= 0.0,
                   "FESD: step_equilibration_weight must be >= 0 and finite, got ", options.step_equilibration_weight);
    SALTUS_REQUIRE(std::isfinite(options.speed_of_time_weight) && options.speed_of_time_weight >= 0.0,
                   "FESD: speed_of_time_weight must be >= 0 and finite, got ", options.speed_of_time_weight);
    SALTUS_REQUIRE(std::isfinite(options.contact_side_weight) && options.contact_side_weight >= 0.0,
                   "FESD: contact_side_weight must be >= 0 and finite, got ", options.contact_side_weight);
    for (double k : options.switching_scale)
      SALTUS_REQUIRE(std::isfinite(k) && k > 0.0, "FESD: switching_scale entries must be finite and > 0, got ", k);
    SALTUS_REQUIRE(options.clock == ClockConstraint::None ||
                       (std::isfinite(options.physical_horizon) && options.physical_horizon > 0.0),
                   "FESD: a clock constraint needs physical_horizon > 0, got ", options.physical_horizon);
    SALTUS_REQUIRE(options.control_lower.size() == 0 || options.control_lower.size() == nu,
                   "FESD: control_lower must have nu = ", nu, " entries, got ", options.control_lower.size());
    SALTUS_REQUIRE(options.control_upper.size() == 0 || options.control_upper.size() == nu,
                   "FESD: control_upper must have nu = ", nu, " entries, got ", options.control_upper.size());
    y0_.setZero();
    y0_.template head<nq>() = q0;
    y0_.template segment<nq>(nq) = v0;
    SALTUS_REQUIRE(std::isfinite(options.initial_time), "FESD: initial_time must be finite, got ", options.initial_time);
    y0_[System::clock_index] = options.initial_time;
    for (int i = 0; i < nc; ++i) {
      const double gap = system.scene().template gap<double>(i, q0);
      y0_[System::gap_state_index + i] = gap;
      SALTUS_REQUIRE(gap >= -options.gap_tolerance, "FESD: the initial state penetrates contact '",
                     system.scene().contact(i).name, "' (gap ", gap, " < -", options.gap_tolerance, ")");
    }
    n_ = options.control_intervals * interval_size();
    h0_ = options.horizon / (options.control_intervals * options.finite_elements);
    build_rows();
    build_structures();
    build_pairs();
  }

  // ---- layout -------------------------------------------------------------------------------
  int stages() const { return options_.stages; }
  int element_size() const { return 1 + options_.stages * stage_size(); }
  int interval_size() const { return 1 + nu + options_.finite_elements * element_size(); }
  int speed_index(int k) const { return k * interval_size(); }
  int control_index(int k) const { return speed_index(k) + 1; }
  int length_index(int k, int j) const { return control_index(k) + nu + j * element_size(); }
  int stage_index(int k, int j, int r) const { return length_index(k, j) + 1 + r * stage_size(); }
  int state_index(int k, int j, int r) const { return stage_index(k, j, r); }
  int derivative_index(int k, int j, int r) const { return stage_index(k, j, r) + ny; }
  int alpha_index(int k, int j, int r) const { return stage_index(k, j, r) + 2 * ny; }
  int lambda_p_index(int k, int j, int r) const { return alpha_index(k, j, r) + nsw; }
  int lambda_n_index(int k, int j, int r) const { return alpha_index(k, j, r) + 2 * nsw; }
  /// Index of the state at the start of element (k, j): the previous element's last stage, or -1
  /// for the very first element (the fixed initial state).
  int start_state_index(int k, int j) const {
    if (j > 0) return state_index(k, j - 1, options_.stages - 1);
    if (k > 0) return state_index(k - 1, options_.finite_elements - 1, options_.stages - 1);
    return -1;
  }
  int final_state_index() const {
    return state_index(options_.control_intervals - 1, options_.finite_elements - 1, options_.stages - 1);
  }
  double nominal_element_length() const { return h0_; }
  const System& system() const { return system_; }
  const FesdOptions& options() const { return options_; }
  const Eigen::Matrix<double, ny, 1>& initial_state() const { return y0_; }

  /// The discrete solution: the initial point, then every stage point in numerical time order.
  std::vector<Point> points(const Eigen::Ref<const Eigen::VectorXd>& x) const {
    std::vector<Point> out;
    Point p0;
    p0.y = y0_;
    p0.alpha.setConstant(0.5);
    p0.ode_weight = 1.0;
    p0.u = applied_input(x, 0, y0_[System::clock_index]);
    out.push_back(p0);
    double tau = 0.0;
    for (int k = 0; k < options_.control_intervals; ++k)
      for (int j = 0; j < options_.finite_elements; ++j) {
        const double h = x[length_index(k, j)];
        for (int r = 0; r < options_.stages; ++r) {
          Point p;
          p.interval = k;
          p.element = j;
          p.stage = r;
          p.tau = tau + tableau_.c[r] * h;
          p.y = x.template segment<ny>(state_index(k, j, r));
          p.alpha = x.template segment<nsw>(alpha_index(k, j, r));
          p.ode_weight = System::template ode_weight<double>(p.alpha);
          p.u = applied_input(x, k, p.y[System::clock_index]);
          out.push_back(p);
        }
        tau += h;
      }
    return out;
  }

  // ---- Mpcc --------------------------------------------------------------------------------
  int variable_count() const override { return n_; }
  int constraint_count() const override { return m_; }

  void bounds(Eigen::Ref<Eigen::VectorXd> xl, Eigen::Ref<Eigen::VectorXd> xu, Eigen::Ref<Eigen::VectorXd> gl,
              Eigen::Ref<Eigen::VectorXd> gu) const override {
    const double inf = std::numeric_limits<double>::infinity();
    xl.setConstant(-inf);
    xu.setConstant(inf);
    const double gamma = options_.switch_detection ? options_.element_length_freedom : 0.0;
    for (int k = 0; k < options_.control_intervals; ++k) {
      xl[speed_index(k)] = 1.0;
      xu[speed_index(k)] = options_.speed_of_time_max;
      for (int i = 0; i < nu; ++i) {
        if (options_.control_lower.size() == nu) xl[control_index(k) + i] = options_.control_lower[i];
        if (options_.control_upper.size() == nu) xu[control_index(k) + i] = options_.control_upper[i];
      }
      for (int j = 0; j < options_.finite_elements; ++j) {
        xl[length_index(k, j)] = (1.0 - gamma) * h0_;
        xu[length_index(k, j)] = (1.0 + gamma) * h0_;
        for (int r = 0; r < options_.stages; ++r) {
          const int a = alpha_index(k, j, r);
          for (int m = 0; m < nsw; ++m) {
            xl[a + m] = 0.0;
            xu[a + m] = 1.0;
            xl[a + nsw + m] = 0.0;
            xl[a + 2 * nsw + m] = 0.0;
          }
          for (int i = 0; i < nc; ++i)
            if (!system_.has_friction(i)) {
              xl[a + 3 * i + 2] = 1.0;            // alpha_3 = 1: no tangential switching
              xu[a + 2 * nsw + 3 * i + 2] = 0.0;  // lambda_n,3 = 0
            }
        }
      }
    }
    gl.setZero();
    gu.setZero();
    for (const auto& [row, lower, upper] : inequality_rows_) {
      gl[row] = lower;
      gu[row] = upper;
    }
  }

  void initial_point(Eigen::Ref<Eigen::VectorXd> x) const override {
    x.setZero();
    Vec<nsw> c0 = system_.template switching_functions<double>(y0_.template head<nq>(), y0_.template segment<nq>(nq));
    for (int m = 0; m < nsw; ++m) c0[m] *= switching_scale(m);
    Vec<nsw> a0;
    for (int m = 0; m < nsw; ++m) a0[m] = c0[m] > 0.0 ? 1.0 : (c0[m] < 0.0 ? 0.0 : 0.5);
    for (int k = 0; k < options_.control_intervals; ++k) {
      x[speed_index(k)] = 1.0;
      for (int i = 0; i < nu; ++i) {
        double u = 0.0;
        if (options_.control_lower.size() == nu) u = std::max(u, options_.control_lower[i]);
        if (options_.control_upper.size() == nu) u = std::min(u, options_.control_upper[i]);
        x[control_index(k) + i] = u;
      }
      for (int j = 0; j < options_.finite_elements; ++j) {
        x[length_index(k, j)] = h0_;
        for (int r = 0; r < options_.stages; ++r) {
          x.template segment<ny>(state_index(k, j, r)) = y0_;
          x.template segment<nsw>(alpha_index(k, j, r)) = a0;
          x.template segment<nsw>(lambda_p_index(k, j, r)) = c0.cwiseMax(0.0);
          x.template segment<nsw>(lambda_n_index(k, j, r)) = (-c0).cwiseMax(0.0);
        }
      }
    }
  }

  /// An initial point from a guess of the motion (NOSNOC's `initialize_with_ref`): every stage
  /// point gets the guessed state guess(t) = (q, v) (nx = 2 nq entries) at the physical time t its
  /// nominal position on the grid maps to, t = initial_time + r tau with r = physical_horizon /
  /// horizon under a clock constraint (else r = 1) and tau = (k N_fe + j + c_i) h0; the clock t,
  /// the running cost 0, the stage derivatives of that motion in numerical time (r v for q, r times
  /// the central difference (v(t + 1e-6 s) - v(t - 1e-6 s)) / 2e-6 s for v, r for the clock), the
  /// speed of time r clipped to [1, s_max] (r < 1 cannot be a speed of time; the derivatives keep
  /// r, so such a start is not consistent), the nominal element lengths h0, zero inputs (clipped to
  /// their bounds), and each stage's step functions and multipliers from the switching functions
  /// at the guessed state, as initial_point does at the initial state (alpha = 1 where c > 0, 0
  /// where c < 0, 1/2 at 0; lambda_p = max(c, 0), lambda_n = max(-c, 0); a frictionless contact's
  /// tangential alpha = 1 and lambda_n = 0, as its bounds fix them). The guess need not be
  /// dynamically consistent, nor start at (q0, v0) (the initial state is the constructor's; the
  /// guess is not called at initial_time itself): it is a starting point, not a constraint.
  /// `guess` is called with t in (initial_time, initial_time + r horizon] widened by 1e-6 s at
  /// both ends; it must return nx finite values there (InvalidArgument naming the time or the size
  /// otherwise; a dynamic-size vector is checked). x_out must have variable_count() entries
  /// (InvalidArgument otherwise); it is left unchanged when this throws.
  template <class Guess>
  void initial_point_from_guess(Eigen::Ref<Eigen::VectorXd> x_out, const Guess& guess) const {
    SALTUS_REQUIRE(x_out.size() == n_, "FESD: initial_point_from_guess needs ", n_, " entries, got ", x_out.size());
    Eigen::VectorXd x(n_);  // filled here, copied out once every guess value passed its checks
    initial_point(x);
    const double rate = options_.clock == ClockConstraint::None ? 1.0 : options_.physical_horizon / options_.horizon;
    const double speed = std::clamp(rate, 1.0, options_.speed_of_time_max);
    const auto state_at = [&](double t) {
      const auto raw = guess(t);  // a fixed- or dynamic-size vector: its size is checked here
      SALTUS_REQUIRE(raw.size() == nx, "FESD: initial_point_from_guess: the guess has ", raw.size(),
                     " entries at t = ", t, ", expected nx = 2 nq = ", nx);
      const Vec<nx> g = raw;
      SALTUS_REQUIRE(g.allFinite(), "FESD: initial_point_from_guess: the guess is not finite at t = ", t);
      return g;
    };
    constexpr double dt = 1e-6;  // central difference of the guessed velocity [s]
    for (int k = 0; k < options_.control_intervals; ++k) {
      x[speed_index(k)] = speed;
      for (int j = 0; j < options_.finite_elements; ++j)
        for (int r = 0; r < options_.stages; ++r) {
          const double tau = ((k * options_.finite_elements + j) + tableau_.c[r]) * h0_;
          const double t = options_.initial_time + rate * tau;
          const Vec<nx> g = state_at(t);
          const Vec<nq> accel = (state_at(t + dt).template tail<nq>() - state_at(t - dt).template tail<nq>()) / (2.0 * dt);
          Eigen::Matrix<double, ny, 1> y = Eigen::Matrix<double, ny, 1>::Zero();
          y.template head<nx>() = g;
          y[System::clock_index] = t;
          Eigen::Matrix<double, ny, 1> yd = Eigen::Matrix<double, ny, 1>::Zero();
          yd.template head<nq>() = rate * g.template tail<nq>();
          yd.template segment<nq>(nq) = rate * accel;
          yd[System::clock_index] = rate;
          if constexpr (nc > 0) {
            const Vec<nq> gq = g.template head<nq>(), gv = g.template tail<nq>();
            const Vec<nc> vn = system_.template normal_velocities<double>(gq, gv);
            for (int i = 0; i < nc; ++i) {
              y[System::gap_state_index + i] = system_.scene().template gap<double>(i, gq);
              yd[System::gap_state_index + i] = rate * vn[i];
            }
          }
          x.template segment<ny>(state_index(k, j, r)) = y;
          x.template segment<ny>(derivative_index(k, j, r)) = yd;
          // The guess's integrated gaps are gap(q) (set above), so either reading gives the same c.
          Vec<nsw> c =
              system_.template switching_functions<double>(Vec<nq>(g.template head<nq>()), Vec<nq>(g.template tail<nq>()));
          for (int m = 0; m < nsw; ++m) c[m] *= switching_scale(m);
          Vec<nsw> a;
          for (int m = 0; m < nsw; ++m) a[m] = c[m] > 0.0 ? 1.0 : (c[m] < 0.0 ? 0.0 : 0.5);
          for (int i = 0; i < nc; ++i)
            if (!system_.has_friction(i)) a[3 * i + 2] = 1.0;  // as the bounds fix it
          Vec<nsw> lambda_n = (-c).cwiseMax(0.0);
          for (int i = 0; i < nc; ++i)
            if (!system_.has_friction(i)) lambda_n[3 * i + 2] = 0.0;  // as the bounds fix it
          x.template segment<nsw>(alpha_index(k, j, r)) = a;
          x.template segment<nsw>(lambda_p_index(k, j, r)) = c.cwiseMax(0.0);
          x.template segment<nsw>(lambda_n_index(k, j, r)) = lambda_n;
        }
    }
    x_out = x;
  }

  double objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override {
    double f = x[final_state_index() + System::cost_index];
    const Eigen::Matrix<double, ny, 1> yf = x.template segment<ny>(final_state_index());
    if constexpr (detail::HasTerminalCost<Ocp, double, nx>)
      f += ocp_.template terminal_cost<double>(yf.template head<nx>(), yf[System::clock_index]);
    for (int k = 0; k < options_.control_intervals; ++k) {
      const double ds = x[speed_index(k)] - 1.0;
      f += options_.speed_of_time_weight * ds * ds;
      if (options_.switch_detection)
        for (int j = 0; j < options_.finite_elements; ++j) {
          const double dh = x[length_index(k, j)] - h0_;
          f += heuristic_weight() * dh * dh;
        }
      if (options_.contact_side_weight > 0.0)
        for (int j = 0; j < options_.finite_elements; ++j)
          for (int r = 0; r < options_.stages; ++r)
            for (int i = 0; i < nc; ++i) f += options_.contact_side_weight * x[alpha_index(k, j, r) + 3 * i];
    }
    return f;
  }

  void objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> g) const override {
    g.setZero();
    const int yf = final_state_index();
    g[yf + System::cost_index] = 1.0;
    if constexpr (detail::HasTerminalCost<Ocp, double, nx>) {
      constexpr int N = nx + 1;
      Eigen::Matrix<double, N, 1> w;
      w << x.template segment<nx>(yf), x[yf + System::clock_index];
      const auto a = detail::seed_first<N>(w);
      const detail::Ad1<N> f = ocp_.template terminal_cost<detail::Ad1<N>>(a.template head<nx>(), a[nx]);
      g.template segment<nx>(yf) += f.derivatives().template head<nx>();
      g[yf + System::clock_index] += f.derivatives()[nx];
    }
    for (int k = 0; k < options_.control_intervals; ++k) {
      g[speed_index(k)] += 2.0 * options_.speed_of_time_weight * (x[speed_index(k)] - 1.0);
      if (options_.switch_detection)
        for (int j = 0; j < options_.finite_elements; ++j)
          g[length_index(k, j)] += 2.0 * heuristic_weight() * (x[length_index(k, j)] - h0_);
      if (options_.contact_side_weight > 0.0)
        for (int j = 0; j < options_.finite_elements; ++j)
          for (int r = 0; r < options_.stages; ++r)
            for (int i = 0; i < nc; ++i) g[alpha_index(k, j, r) + 3 * i] += options_.contact_side_weight;
    }
  }

  void constraints(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> g) const override {
    jacobian_pass(x, &g, nullptr, nullptr);
  }
  const std::vector<SparseEntry>& jacobian_structure() const override { return jacobian_structure_; }
  void jacobian_values(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> values) const override {
    jacobian_pass(x, nullptr, &values, nullptr);
  }
  const std::vector<SparseEntry>& hessian_structure() const override { return hessian_structure_; }
  void hessian_values(const Eigen::Ref<const Eigen::VectorXd>& x, double objective_factor,
                      const Eigen::Ref<const Eigen::VectorXd>& multipliers, Eigen::Ref<Eigen::VectorXd> values) const override {
    hessian_pass(x, objective_factor, multipliers, &values, nullptr);
  }
  const std::vector<ComplementarityPair>& complementarity_pairs() const override { return pairs_; }

  std::string variable_name(int i) const override {
    const int k = i / interval_size();
    int rest = i - k * interval_size();
    if (rest == 0) return "s[" + std::to_string(k) + "]";
    if (rest <= nu) return "u[" + std::to_string(k) + "][" + std::to_string(rest - 1) + "]";
    rest -= 1 + nu;
    const int j = rest / element_size();
    rest -= j * element_size();
    const std::string el = "[" + std::to_string(k) + "," + std::to_string(j);
    if (rest == 0) return "h" + el + "]";
    rest -= 1;
    const int r = rest / stage_size();
    rest -= r * stage_size();
    const std::string at = el + "," + std::to_string(r) + "]";
    if (rest < ny) return "Y" + at + "[" + std::to_string(rest) + "]";
    if (rest < 2 * ny) return "K" + at + "[" + std::to_string(rest - ny) + "]";
    rest -= 2 * ny;
    if (rest < nsw) return "alpha" + at + "[" + std::to_string(rest) + "]";
    if (rest < 2 * nsw) return "lambda_p" + at + "[" + std::to_string(rest - nsw) + "]";
    return "lambda_n" + at + "[" + std::to_string(rest - 2 * nsw) + "]";
  }
  std::string constraint_name(int row) const override {
    if (row >= terminal_row_) return "terminal constraint " + std::to_string(row - terminal_row_);
    for (int k = 0; k < options_.control_intervals; ++k) {
      if (row == interval_row_[k]) return "sum of element lengths [" + std::to_string(k) + "]";
      if (row == interval_row_[k] + 1 && has_clock_row(k)) return "clock [" + std::to_string(k) + "]";
    }
    const auto it = std::upper_bound(stage_row_.begin(), stage_row_.end(), row);
    const int i = static_cast<int>(it - stage_row_.begin()) - 1;
    const int ns = options_.stages, nfe = options_.finite_elements;
    const std::string at = "[" + std::to_string(i / (ns * nfe)) + "," + std::to_string((i / ns) % nfe) + "," +
                           std::to_string(i % ns) + "]";
    const int off = row - stage_row_[i];
    if (off < ny) return "stage dynamics" + at + "[" + std::to_string(off) + "]";
    if (off < 2 * ny) return "collocation" + at + "[" + std::to_string(off - ny) + "]";
    if (off < 2 * ny + nsw) return "switching function" + at + "[" + std::to_string(off - 2 * ny) + "]";
    return "path constraint" + at + "[" + std::to_string(off - 2 * ny - nsw) + "]";
  }

 private:
  // ---- the applied input ---------------------------------------------------------------------
  template <class T>
  VecT<T, nu> input_law(const T& t, const VecT<T, nu>& decision) const {
    if constexpr (detail::HasInputLaw<Ocp, T, nu>) return ocp_.template input<T>(t, decision);
    else return decision;
  }
  Vec<nu> applied_input(const Eigen::Ref<const Eigen::VectorXd>& x, int k, double t) const {
    const Vec<nu> d = x.template segment<nu>(control_index(k));
    return input_law<double>(t, d);
  }

  // ---- the stage dynamics ---------------------------------------------------------------------
  // R = (K_q - s G_q, M(q) K_v - s G_v, K_t - s G_t, K_L - s G_L) with the field
  // G(z) = (Theta v, F(q, v, u, alpha), Theta, Theta l(x, u)), z = (q, v, t, u, alpha).
  // Written out by hand around the two AD kernels G(z) and M(q) K_v: s and K enter linearly
  // (their Jacobian entries and the (s, z) Hessian block come from grad G), so the second-order
  // AD runs over nz = 2 nq + 1 + nu + 3 nc directions, not over all ~2 ny + nz local variables.
  template <class T>
  VecT<T, ny> stage_field(const VecT<T, nz>& z) const {
    const VecT<T, nq> q = z.template segment<nq>(0);
    const VecT<T, nq> v = z.template segment<nq>(nq);
    const T& t = z[2 * nq];
    const VecT<T, nu> u = input_law<T>(t, VecT<T, nu>(z.template segment<nu>(2 * nq + 1)));
    const VecT<T, nsw> alpha = z.template segment<nsw>(2 * nq + 1 + nu);
    const T theta = System::template ode_weight<T>(alpha);
    const VecT<T, nq> force = system_.template generalised_force<T>(q, v, u, alpha);
    VecT<T, ny> gz;
    gz.template head<nq>() = theta * v;
    gz.template segment<nq>(nq) = force;
    gz[System::clock_index] = theta;
    T running(0.0);
    if constexpr (detail::HasTimedRunningCost<Ocp, T, nx, nu>)
      running = ocp_.template running_cost<T>(VecT<T, nx>(z.template head<nx>()), u, t);
    else if constexpr (detail::HasRunningCost<Ocp, T, nx, nu>)
      running = ocp_.template running_cost<T>(VecT<T, nx>(z.template head<nx>()), u);
    gz[System::cost_index] = T(theta * running);
    if constexpr (nc > 0) {
      const VecT<T, nc> vn = system_.template normal_velocities<T>(q, v);
      for (int i = 0; i < nc; ++i) gz[System::gap_state_index + i] = T(theta * vn[i]);
    }
    return gz;
  }
  /// M(q) K_v at w = (q, K_v).
  template <class T>
  VecT<T, nq> mass_times(const VecT<T, 2 * nq>& w) const {
    const MatT<T, nq, nq> mass = system_.scene().template mass_matrix<T>(VecT<T, nq>(w.template head<nq>()));
    return mass * VecT<T, nq>(w.template segment<nq>(nq));
  }
  Eigen::Matrix<double, nz, 1> field_local(const Eigen::Ref<const Eigen::VectorXd>& x, int k, int j, int r) const {
    Eigen::Matrix<double, nz, 1> z;
    z.template head<2 * nq + 1>() = x.template segment<2 * nq + 1>(state_index(k, j, r));
    z.template segment<nu>(2 * nq + 1) = x.template segment<nu>(control_index(k));
    z.template segment<nsw>(2 * nq + 1 + nu) = x.template segment<nsw>(alpha_index(k, j, r));
    return z;
  }
  // The global variable of the field's local slot a.
  int field_global(int k, int j, int r, int a) const {
    if (a < 2 * nq + 1) return state_index(k, j, r) + a;
    if (a < 2 * nq + 1 + nu) return control_index(k) + (a - 2 * nq - 1);
    return alpha_index(k, j, r) + (a - 2 * nq - 1 - nu);
  }
  Eigen::Matrix<double, 2 * nq, 1> mass_local(const Eigen::Ref<const Eigen::VectorXd>& x, int k, int j, int r) const {
    Eigen::Matrix<double, 2 * nq, 1> w;
    w << x.template segment<nq>(state_index(k, j, r)), x.template segment<nq>(derivative_index(k, j, r) + nq);
    return w;
  }
  int mass_global(int k, int j, int r, int a) const {
    return a < nq ? state_index(k, j, r) + a : derivative_index(k, j, r) + a;  // K_v starts at K + nq
  }

  // ---- path constraints at a stage: local (Y, u) ----------------------------------------------
  static constexpr int npw = ny + nu;
  template <class T>
  VecT<T, (np > 0 ? np : 1)> stage_path(const VecT<T, npw>& w) const {
    if constexpr (np > 0) {
      const VecT<T, nu> u = input_law<T>(w[System::clock_index], VecT<T, nu>(w.template segment<nu>(ny)));
      return ocp_.template path_constraints<T>(VecT<T, nx>(w.template head<nx>()), u);
    } else {
      return VecT<T, 1>::Zero();
    }
  }
  // ---- terminal constraints and cost: local (x, t) ----------------------------------------------
  static constexpr int ntw = nx + 1;
  template <class T>
  VecT<T, (nt > 0 ? nt : 1)> terminal_function(const VecT<T, ntw>& w) const {
    if constexpr (nt > 0) return ocp_.template terminal_constraints<T>(VecT<T, nx>(w.template head<nx>()), w[nx]);
    else return VecT<T, 1>::Zero();
  }
  int terminal_global(int a) const {
    return final_state_index() + (a < nx ? a : System::clock_index);
  }

  // ---- rows ----------------------------------------------------------------------------------
  // Row blocks in this order: per stage [dynamics ny][collocation ny][switching nsw][path np];
  // per control interval, after its stages: [element sum 1][clock 0 or 1]; then [terminal nt].
  int stage_row(int k, int j, int r) const { return stage_row_[(k * options_.finite_elements + j) * options_.stages + r]; }

  void build_rows() {
    int row = 0;
    stage_row_.clear();
    interval_row_.clear();
    for (int k = 0; k < options_.control_intervals; ++k) {
      for (int j = 0; j < options_.finite_elements; ++j)
        for (int r = 0; r < options_.stages; ++r) {
          stage_row_.push_back(row);
          row += 2 * ny + nsw + np;
        }
      interval_row_.push_back(row);
      row += 1 + (has_clock_row(k) ? 1 : 0);
    }
    terminal_row_ = row;
    row += nt;
    m_ = row;
    // Bounds of the non-equality rows.
    inequality_rows_.clear();
    for (int k = 0; k < options_.control_intervals; ++k) {
      const int ir = interval_row_[k];
      const double dt = options_.horizon / options_.control_intervals;
      inequality_rows_.push_back({ir, dt, dt});
      if (has_clock_row(k)) {
        const double tk = options_.initial_time + (options_.clock == ClockConstraint::Stagewise
                                                       ? options_.physical_horizon * (k + 1) / options_.control_intervals
                                                       : options_.physical_horizon);
        inequality_rows_.push_back({ir + 1, tk, tk});
      }
      if constexpr (np > 0) {
        const Vec<np> lo = ocp_.path_lower(), hi = ocp_.path_upper();
        for (int j = 0; j < options_.finite_elements; ++j)
          for (int r = 0; r < options_.stages; ++r)
            for (int i = 0; i < np; ++i) inequality_rows_.push_back({stage_row(k, j, r) + 2 * ny + nsw + i, lo[i], hi[i]});
      }
    }
    if constexpr (nt > 0) {
      const Vec<nt> lo = ocp_.terminal_lower(), hi = ocp_.terminal_upper();
      for (int i = 0; i < nt; ++i) inequality_rows_.push_back({terminal_row_ + i, lo[i], hi[i]});
    }
  }
  bool has_clock_row(int k) const {
    return options_.clock == ClockConstraint::Stagewise ||
           (options_.clock == ClockConstraint::Terminal && k == options_.control_intervals - 1);
  }
  /// The scale of switching function m (FesdOptions::switching_scale).
  double switching_scale(int m) const { return options_.switching_scale[static_cast<std::size_t>(m % 3)]; }
  double heuristic_weight() const { return options_.step_equilibration_weight; }
  /// Does switching function m switch at all (a frictionless contact's tangential one does not)?
  // Switching function m is a gap read from the integrated gap state (FesdOptions::integrated_gap).
  bool reads_integrated_gap(int m) const { return options_.integrated_gap && m % 3 == 0; }
  bool switching_active(int m) const { return system_.has_friction(m / 3) || m % 3 != 2; }
  /// Does switching function m have cross-complementarity (so its switches sit on boundaries)?
  /// The other active ones get the stage-wise pairs (build_pairs).
  bool cross_complementary(int m) const {
    return switching_active(m) && options_.switch_detection && (options_.velocity_switch_detection || m % 3 == 0);
  }

  // One pass over the constraint rows: values into g, Jacobian values into jac (in structure
  // order), or the structure into `structure` — the same loop, so the orders cannot drift apart.
  void jacobian_pass(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd>* g,
                     Eigen::Ref<Eigen::VectorXd>* jac, std::vector<SparseEntry>* structure) const {
    int e = 0;  // running entry index
    auto put = [&](int row, int col, double value) {
      if (structure) structure->push_back({row, col});
      if (jac) (*jac)[e] = value;
      ++e;
    };
    const int ns = options_.stages;
    for (int k = 0; k < options_.control_intervals; ++k) {
      for (int j = 0; j < options_.finite_elements; ++j) {
        const int ys = start_state_index(k, j);
        const double h = x[length_index(k, j)];
        for (int r = 0; r < ns; ++r) {
          const int row = stage_row(k, j, r);
          // dynamics (see stage_field)
          {
            const double sp = x[speed_index(k)];
            const Eigen::Matrix<double, nz, 1> z = field_local(x, k, j, r);
            const int kd = derivative_index(k, j, r);
            if (jac || structure) {
              const VecT<detail::Ad1<nz>, ny> gz = stage_field<detail::Ad1<nz>>(detail::seed_first<nz>(z));
              const VecT<detail::Ad1<2 * nq>, nq> mk = mass_times<detail::Ad1<2 * nq>>(detail::seed_first<2 * nq>(mass_local(x, k, j, r)));
              for (int i = 0; i < ny; ++i) {
                const bool v_row = i >= nq && i < 2 * nq;
                if (g) (*g)[row + i] = (v_row ? mk[i - nq].value() : x[kd + i]) - sp * gz[i].value();
                put(row + i, speed_index(k), -gz[i].value());
                for (int a = 0; a < nz; ++a) {
                  double d = -sp * gz[i].derivatives()[a];
                  if (v_row && a < nq) d += mk[i - nq].derivatives()[a];  // d(M K_v)/dq
                  put(row + i, field_global(k, j, r, a), d);
                }
                if (v_row)
                  for (int b = 0; b < nq; ++b) put(row + i, kd + nq + b, mk[i - nq].derivatives()[nq + b]);
                else
                  put(row + i, kd + i, 1.0);
              }
            } else {
              const VecT<double, ny> gz = stage_field<double>(z);
              const VecT<double, nq> mk = mass_times<double>(mass_local(x, k, j, r));
              for (int i = 0; i < ny; ++i) {
                const bool v_row = i >= nq && i < 2 * nq;
                (*g)[row + i] = (v_row ? mk[i - nq] : x[kd + i]) - sp * gz[i];
              }
            }
          }
          // collocation: Y_r - y_start - h sum_l a_rl K_l
          for (int i = 0; i < ny; ++i) {
            const int crow = row + ny + i;
            double sum_k = 0.0;
            for (int l = 0; l < ns; ++l) sum_k += tableau_.a(r, l) * x[derivative_index(k, j, l) + i];
            if (g) {
              const double start = ys < 0 ? y0_[i] : x[ys + i];
              (*g)[crow] = x[state_index(k, j, r) + i] - start - h * sum_k;
            }
            put(crow, state_index(k, j, r) + i, 1.0);
            if (ys >= 0) put(crow, ys + i, -1.0);
            put(crow, length_index(k, j), -sum_k);
            for (int l = 0; l < ns; ++l) put(crow, derivative_index(k, j, l) + i, -h * tableau_.a(r, l));
          }
          // switching: c(q, v) - lambda_p + lambda_n
          {
            const int srow = row + 2 * ny;
            const Vec<nx> wx = x.template segment<nx>(state_index(k, j, r));
            const int lp = lambda_p_index(k, j, r), ln = lambda_n_index(k, j, r);
            if (jac || structure) {
              const auto a = detail::seed_first<nx>(wx);
              const VecT<detail::Ad1<nx>, nsw> c = system_.template switching_functions<detail::Ad1<nx>>(
                  a.template head<nq>(), a.template segment<nq>(nq));
              for (int m = 0; m < nsw; ++m) {
                const double k_m = switching_scale(m);
                if (reads_integrated_gap(m)) {
                  const int gi = state_index(k, j, r) + System::gap_state_index + m / 3;
                  if (g) (*g)[srow + m] = k_m * x[gi] - x[lp + m] + x[ln + m];
                  put(srow + m, gi, k_m);
                } else {
                  if (g) (*g)[srow + m] = k_m * c[m].value() - x[lp + m] + x[ln + m];
                  for (int b = 0; b < nx; ++b) put(srow + m, state_index(k, j, r) + b, k_m * c[m].derivatives()[b]);
                }
                put(srow + m, lp + m, -1.0);
                put(srow + m, ln + m, 1.0);
              }
            } else {
              const Vec<nsw> c = system_.template switching_functions<double>(wx.template head<nq>(), wx.template segment<nq>(nq));
              for (int m = 0; m < nsw; ++m) {
                const int gi = state_index(k, j, r) + System::gap_state_index + m / 3;
                const double cm = reads_integrated_gap(m) ? x[gi] : c[m];
                (*g)[srow + m] = switching_scale(m) * cm - x[lp + m] + x[ln + m];
              }
            }
          }
          // path constraints
          if constexpr (np > 0) {
            const int prow = row + 2 * ny + nsw;
            Eigen::Matrix<double, npw, 1> pw;
            pw << x.template segment<ny>(state_index(k, j, r)), x.template segment<nu>(control_index(k));
            const auto a = detail::seed_first<npw>(pw);
            const VecT<detail::Ad1<npw>, np> p = stage_path<detail::Ad1<npw>>(a);
            for (int i = 0; i < np; ++i) {
              if (g) (*g)[prow + i] = p[i].value();
              for (int b = 0; b < npw; ++b)
                put(prow + i, b < ny ? state_index(k, j, r) + b : control_index(k) + (b - ny), p[i].derivatives()[b]);
            }
          }
        }
      }
      // sum of element lengths, clock
      const int ir = interval_row_[k];
      double sum_h = 0.0;
      for (int j = 0; j < options_.finite_elements; ++j) {
        sum_h += x[length_index(k, j)];
        put(ir, length_index(k, j), 1.0);
      }
      if (g) (*g)[ir] = sum_h;
      if (has_clock_row(k)) {
        const int yk = state_index(k, options_.finite_elements - 1, ns - 1) + System::clock_index;
        if (g) (*g)[ir + 1] = x[yk];
        put(ir + 1, yk, 1.0);
      }
    }
    if constexpr (nt > 0) {
      Eigen::Matrix<double, ntw, 1> tw;
      for (int a = 0; a < ntw; ++a) tw[a] = x[terminal_global(a)];
      const auto a = detail::seed_first<ntw>(tw);
      const VecT<detail::Ad1<ntw>, nt> tf = terminal_function<detail::Ad1<ntw>>(a);
      for (int i = 0; i < nt; ++i) {
        if (g) (*g)[terminal_row_ + i] = tf[i].value();
        for (int b = 0; b < ntw; ++b) put(terminal_row_ + i, terminal_global(b), tf[i].derivatives()[b]);
      }
    }
  }

  // Lower-triangle entry (the larger index is the row).
  static SparseEntry lower(int a, int b) { return a >= b ? SparseEntry{a, b} : SparseEntry{b, a}; }

  void hessian_pass(const Eigen::Ref<const Eigen::VectorXd>& x, double sigma, const Eigen::Ref<const Eigen::VectorXd>& mu,
                    Eigen::Ref<Eigen::VectorXd>* values, std::vector<SparseEntry>* structure) const {
    int e = 0;
    auto put = [&](int a, int b, double value) {
      if (structure) structure->push_back(lower(a, b));
      if (values) (*values)[e] = value;
      ++e;
    };
    const int ns = options_.stages;
    for (int k = 0; k < options_.control_intervals; ++k) {
      for (int j = 0; j < options_.finite_elements; ++j) {
        for (int r = 0; r < ns; ++r) {
          const int row = stage_row(k, j, r);
          // dynamics: sum_i mu_i d2 R_i = -s sum mu_i d2 G_i (z, z), -sum mu_i dG_i (s, z), and the
          // mass term mu_v' M(q) K_v on (q, K_v)
          {
            Eigen::Matrix<double, nz, nz> hz = Eigen::Matrix<double, nz, nz>::Zero();
            Eigen::Matrix<double, nz, 1> hs = Eigen::Matrix<double, nz, 1>::Zero();
            Eigen::Matrix<double, 2 * nq, 2 * nq> hm = Eigen::Matrix<double, 2 * nq, 2 * nq>::Zero();
            if (values) {
              const double sp = x[speed_index(k)];
              const VecT<detail::Ad2<nz>, ny> gz = stage_field<detail::Ad2<nz>>(detail::seed_second<nz>(field_local(x, k, j, r)));
              for (int i = 0; i < ny; ++i) {
                const double m = mu[row + i];
                if (m == 0.0) continue;
                for (int a = 0; a < nz; ++a) {
                  hz.row(a) -= (sp * m) * gz[i].derivatives()[a].derivatives().transpose();
                  hs[a] -= m * gz[i].derivatives()[a].value();
                }
              }
              const VecT<detail::Ad2<2 * nq>, nq> mk =
                  mass_times<detail::Ad2<2 * nq>>(detail::seed_second<2 * nq>(mass_local(x, k, j, r)));
              for (int i = 0; i < nq; ++i) {
                const double m = mu[row + nq + i];
                if (m == 0.0) continue;
                for (int a = 0; a < 2 * nq; ++a) hm.row(a) += m * mk[i].derivatives()[a].derivatives().transpose();
              }
            }
            for (int a = 0; a < nz; ++a)
              for (int b = 0; b <= a; ++b) put(field_global(k, j, r, a), field_global(k, j, r, b), hz(a, b));
            for (int a = 0; a < nz; ++a) put(field_global(k, j, r, a), speed_index(k), hs[a]);
            // (q, q) and (K_v, q) blocks of the mass term; (K_v, K_v) is zero (linear in K_v).
            for (int a = 0; a < 2 * nq; ++a)
              for (int b = 0; b < std::min(a + 1, nq); ++b) put(mass_global(k, j, r, a), mass_global(k, j, r, b), hm(a, b));
          }
          // collocation: d2/dh dK_l,i of -h a_rl K_l,i, weighted
          for (int i = 0; i < ny; ++i) {
            const double m = values ? mu[row + ny + i] : 0.0;
            for (int l = 0; l < ns; ++l) put(length_index(k, j), derivative_index(k, j, l) + i, -m * tableau_.a(r, l));
          }
          // switching functions on (q, v)
          {
            Eigen::Matrix<double, nx, nx> hl = Eigen::Matrix<double, nx, nx>::Zero();
            if (values) {
              const Vec<nx> wx = x.template segment<nx>(state_index(k, j, r));
              const auto a = detail::seed_second<nx>(wx);
              const VecT<detail::Ad2<nx>, nsw> c = system_.template switching_functions<detail::Ad2<nx>>(
                  a.template head<nq>(), a.template segment<nq>(nq));
              for (int m = 0; m < nsw; ++m) {
                const double w = switching_scale(m) * mu[row + 2 * ny + m];
                if (w == 0.0 || reads_integrated_gap(m)) continue;  // g enters linearly
                for (int p = 0; p < nx; ++p) hl.row(p) += w * c[m].derivatives()[p].derivatives().transpose();
              }
            }
            for (int p = 0; p < nx; ++p)
              for (int b = 0; b <= p; ++b) put(state_index(k, j, r) + p, state_index(k, j, r) + b, hl(p, b));
          }
          if constexpr (np > 0) {
            Eigen::Matrix<double, npw, npw> hl = Eigen::Matrix<double, npw, npw>::Zero();
            auto global = [&](int b) { return b < ny ? state_index(k, j, r) + b : control_index(k) + (b - ny); };
            if (values) {
              Eigen::Matrix<double, npw, 1> pw;
              pw << x.template segment<ny>(state_index(k, j, r)), x.template segment<nu>(control_index(k));
              const VecT<detail::Ad2<npw>, np> p = stage_path<detail::Ad2<npw>>(detail::seed_second<npw>(pw));
              for (int i = 0; i < np; ++i) {
                const double w = mu[row + 2 * ny + nsw + i];
                if (w == 0.0) continue;
                for (int a = 0; a < npw; ++a) hl.row(a) += w * p[i].derivatives()[a].derivatives().transpose();
              }
            }
            for (int a = 0; a < npw; ++a)
              for (int b = 0; b <= a; ++b) put(global(a), global(b), hl(a, b));
          }
        }
      }
      put(speed_index(k), speed_index(k), sigma * 2.0 * options_.speed_of_time_weight);
      if (options_.switch_detection)
        for (int j = 0; j < options_.finite_elements; ++j)
          put(length_index(k, j), length_index(k, j), sigma * 2.0 * heuristic_weight());
    }
    // terminal constraints and terminal cost on (x, t) of the final state
    {
      Eigen::Matrix<double, ntw, ntw> hl = Eigen::Matrix<double, ntw, ntw>::Zero();
      if (values) {
        Eigen::Matrix<double, ntw, 1> tw;
        for (int a = 0; a < ntw; ++a) tw[a] = x[terminal_global(a)];
        const auto a = detail::seed_second<ntw>(tw);
        if constexpr (nt > 0) {
          const VecT<detail::Ad2<ntw>, nt> tf = terminal_function<detail::Ad2<ntw>>(a);
          for (int i = 0; i < nt; ++i) {
            const double w = mu[terminal_row_ + i];
            if (w == 0.0) continue;
            for (int p = 0; p < ntw; ++p) hl.row(p) += w * tf[i].derivatives()[p].derivatives().transpose();
          }
        }
        if constexpr (detail::HasTerminalCost<Ocp, detail::Ad2<ntw>, nx>) {
          const detail::Ad2<ntw> f = ocp_.template terminal_cost<detail::Ad2<ntw>>(a.template head<nx>(), a[nx]);
          for (int p = 0; p < ntw; ++p) hl.row(p) += sigma * f.derivatives()[p].derivatives().transpose();
        }
      }
      if (nt > 0 || detail::HasTerminalCost<Ocp, double, nx>)
        for (int p = 0; p < ntw; ++p)
          for (int b = 0; b <= p; ++b) put(terminal_global(p), terminal_global(b), hl(p, b));
    }
  }

  void build_structures() {
    Eigen::VectorXd x(n_);
    initial_point(x);
    jacobian_structure_.clear();
    jacobian_pass(x, nullptr, nullptr, &jacobian_structure_);
    hessian_structure_.clear();
    Eigen::VectorXd mu = Eigen::VectorXd::Zero(m_);
    hessian_pass(x, 0.0, mu, nullptr, &hessian_structure_);
  }

  void build_pairs() {
    pairs_.clear();
    const int ns = options_.stages;
    for (int k = 0; k < options_.control_intervals; ++k)
      for (int j = 0; j < options_.finite_elements; ++j) {
        const std::string el = "[" + std::to_string(k) + "," + std::to_string(j) + "]";
        for (int m = 0; m < nsw; ++m) {
          if (!switching_active(m)) continue;
          const std::string sw = "[" + std::to_string(m) + "]";
          if (!cross_complementary(m)) {
            // Stage-wise pairs: with c = lambda_p - lambda_n given, their equalities
            // lambda_n alpha = sigma, lambda_p (1 - alpha) = sigma determine alpha (smoothable).
            for (int r = 0; r < ns; ++r) {
              const int a = alpha_index(k, j, r) + m;
              const std::string at = el + "[stage " + std::to_string(r) + "]" + sw;
              pairs_.push_back({{{{lambda_n_index(k, j, r) + m, 1.0}}, 0.0}, {{{a, 1.0}}, 0.0}, "lambda_n" + at + " _|_ alpha", true});
              pairs_.push_back({{{{lambda_p_index(k, j, r) + m, 1.0}}, 0.0}, {{{a, -1.0}}, 1.0}, "lambda_p" + at + " _|_ 1 - alpha", true});
            }
            continue;
          }
          AffineExpression sum_alpha, sum_one_minus;
          for (int r = 0; r < ns; ++r) {
            sum_alpha.terms.push_back({alpha_index(k, j, r) + m, 1.0});
            sum_one_minus.terms.push_back({alpha_index(k, j, r) + m, -1.0});
          }
          sum_one_minus.constant = ns;
          // Points: the previous element's end (when there is one), then this element's stages;
          // each given by its stage base index (where its Y starts).
          std::vector<std::pair<int, std::string>> points;
          const int ys = start_state_index(k, j);
          if (ys >= 0) points.push_back({ys, "start"});
          for (int r = 0; r < ns; ++r) points.push_back({stage_index(k, j, r), "stage " + std::to_string(r)});
          for (const auto& [base, label] : points) {
            const std::string at = el + "[" + label + "]" + sw;
            pairs_.push_back({{{{base + 2 * ny + 2 * nsw + m, 1.0}}, 0.0}, sum_alpha, "lambda_n" + at + " _|_ sum alpha"});
            pairs_.push_back({{{{base + 2 * ny + nsw + m, 1.0}}, 0.0}, sum_one_minus, "lambda_p" + at + " _|_ sum (1 - alpha)"});
          }
        }
      }
  }

  System system_;
  Ocp ocp_;
  FesdOptions options_;
  RadauIIA tableau_;
  Eigen::Matrix<double, ny, 1> y0_;
  int n_ = 0, m_ = 0;
  double h0_ = 0.0;
  std::vector<int> stage_row_, interval_row_;
  int terminal_row_ = 0;
  struct BoundRow {
    int row;
    double lower, upper;
  };
  std::vector<BoundRow> inequality_rows_;
  std::vector<SparseEntry> jacobian_structure_, hessian_structure_;
  std::vector<ComplementarityPair> pairs_;
};

}  // namespace saltus::timefreezing
