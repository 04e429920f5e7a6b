// Finite elements with switch detection (FESD; Nurkanović et al., "Finite Elements with Switch
// Detection for Direct Optimal Control of Nonsmooth Systems") for the time-freezing system: the
// discretisation of the OCP in numerical time (time-freezing paper, Nurkanović, Albrecht,
// Brogliato, Diehl, Automatica 2023, eq. 33, discretised as eq. 35) as an MPCC with exact sparse
// derivatives (mpcc/mpcc.hpp), for the solver in mpcc/mpcc_solver.hpp.
//
// GRID. N control intervals of equal numerical length T~/N (T~ = options.grid.horizon); each holds
// N_fe finite elements of free lengths h_kj with sum_j h_kj = T~/N and (1 - gamma_h) h0 <= h_kj <=
// (1 + gamma_h) h0, h0 = T~/(N N_fe) (options.switching.detection = false fixes h_kj = h0: the
// standard Radau time-stepping). Each element is a Radau IIA collocation step with n_s stages
// (radau.hpp); the last stage is the element's end point, which starts the next element.
//
// VARIABLES, per control interval k: the speed of time s_k in [1, s_max] (eq. 35g; fixed at 1
// when s_max = 1), the control u_k (piecewise constant); per element: h_kj; per stage r:
//     Y (ny = 2 nq + 2 + nc: q, v, t, L, g)   the stage state (g: the integrated gaps),
//     K (ny)                                  the stage derivative,
//     alpha (3 nc)                            the step functions of the switching functions,
//     lambda_p, lambda_n (3 nc)               their multipliers.
//
// ROWS, per stage: the stage dynamics and the collocation (ny each), the switching rows (3 nc), the
// OCP's path rows (np); per control interval: the sum of its element lengths, and the clock row
// under a clock constraint; then the OCP's terminal rows (nt). The math: fesd_stage_rows.hxx.
// COMPLEMENTARITY (all sides affine): stage-wise pairs on the fixed grid, cross-complementarity
// (switches only on element boundaries) with switch detection: fesd_complementarity.hxx.
// OBJECTIVE: the running cost L(T~) over physical time (eq. 29), the terminal cost, the heuristic
// step equilibration (fesd_step_equilibration.hxx), the speed-of-time weight and the contact-side
// selection (fesd_objective.hxx).
// DERIVATIVES: forward AD on small local kernels, assembled into the sparse structure built once
// (fesd_jacobian.hxx, fesd_hessian.hxx).
//
// Declared here, defined in the .hxx files beside it (fesd.hxx includes them all): a program that
// includes this header links FesdMpcc<S, Ocp> from the translation unit that instantiates it
// (saltus/timefreezing/instantiate.hpp), or includes <saltus/timefreezing/header_only.hpp>.
#pragma once

#include <saltus/ad/autodiff.hpp>
#include <saltus/timefreezing/discretisation/fesd_options.hpp>
#include <saltus/timefreezing/discretisation/fesd_point.hpp>
#include <saltus/timefreezing/discretisation/radau.hpp>
#include <saltus/timefreezing/discretisation/sparse_sink.hpp>
#include <saltus/timefreezing/formulation/ocp.hpp>
#include <saltus/timefreezing/formulation/time_freezing_system.hpp>
#include <saltus/timefreezing/mpcc/mpcc.hpp>

#include <Eigen/Core>

#include <functional>
#include <string>
#include <vector>

namespace saltus::timefreezing {

namespace detail {
template <int N>
using Ad1 = ad::Dual<double, N>;
template <int N>
using Ad2 = ad::Dual<ad::Dual<double, N>, N>;
/// First-order seeds: value w_k, direction k.
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
}  // namespace detail

/// A guess of the motion for FesdMpcc::initial_point_from_guess: (q, v) (nx = 2 nq entries) at
/// physical time t [s]. A lambda or function returning a fixed-size Vec<2 nq> converts to it.
using MotionGuess = std::function<Eigen::VectorXd(double)>;

/// The FESD-discretised time-freezing OCP as an MPCC (file comment). Ocp provides, optionally,
/// what formulation/ocp.hpp lists (running and terminal costs, an input law, path and terminal
/// constraints with their bounds); NoObjective: a simulation.
/// Throws InvalidArgument for bad options or a non-finite or penetrating initial state.
template <Scene S, class Ocp = NoObjective>
class FesdMpcc final : public Mpcc {
 public:
  using System = TimeFreezingSystem<S>;
  static constexpr int nq = S::nq, nu = S::nu, nc = S::nc;
  static constexpr int nx = 2 * nq;
  static constexpr int ny = System::ny;
  static constexpr int nsw = System::n_switch;
  static constexpr int np = path_constraint_count<Ocp>();
  static constexpr int nt = terminal_constraint_count<Ocp>();
  /// Local variables of the stage field G (fesd_stage_rows.hxx): z = (q, v, t, u, alpha).
  static constexpr int nz = 2 * nq + 1 + nu + nsw;
  using Point = FesdPoint<ny, nsw, nu>;
  // The OCP's functions are differentiated by AD: each must be a member template in T taking T
  // everywhere, or the values and the derivatives would silently use different functions.
  static_assert(!HasNonTemplateRunningCost<Ocp>,
                "FesdMpcc: Ocp::running_cost must be a member template: template <class T> T running_cost(const "
                "VecT<T, nx>& x, const VecT<T, nu>& u[, const T& t]) const");
  static_assert(HasRunningCost<Ocp, double, nx, nu> == HasRunningCost<Ocp, detail::Ad2<nz>, nx, nu> &&
                    HasTimedRunningCost<Ocp, double, nx, nu> == HasTimedRunningCost<Ocp, detail::Ad2<nz>, nx, nu>,
                "FesdMpcc: Ocp::running_cost must take the clock as const T& t (it is differentiated)");

  /// The MPCC of `ocp` on `system` from (q0, v0) at physical time options.clock.initial_time.
  /// Throws InvalidArgument: grid sizes below 1, a horizon or weights not finite and positive
  /// (nonnegative for weights), gamma_h outside [0, 1], s_max < 1, switching scales not > 0, a
  /// clock constraint without physical_horizon > 0, control bounds of a size other than 0 or nu,
  /// q0 or v0 not finite, an initial gap below -options.bounds.gap_tolerance.
  FesdMpcc(const System& system, const Ocp& ocp, const Vec<nq>& q0, const Vec<nq>& v0, const FesdOptions& options);

  // ---- layout (fesd_layout.hxx): per interval [s][u][element 0]...; per element [h][stage 0]...;
  // per stage [Y][K][alpha][lambda_p][lambda_n] -------------------------------------------------
  int stage_size() const;    ///< 2 ny + 3 nsw
  int stages() const;        ///< n_s
  int element_size() const;  ///< 1 + n_s stage_size()
  int interval_size() const; ///< 1 + nu + N_fe element_size()
  int speed_index(int k) const;
  int control_index(int k) const;
  int length_index(int k, int j) const;
  int stage_index(int k, int j, int r) const;
  int state_index(int k, int j, int r) const;
  int derivative_index(int k, int j, int r) const;
  int alpha_index(int k, int j, int r) const;
  int lambda_p_index(int k, int j, int r) const;
  int lambda_n_index(int k, int j, int r) const;
  /// Index of the state at the start of element (k, j): the previous element's last stage, or -1
  /// for the very first element (the fixed initial state).
  int start_state_index(int k, int j) const;
  int final_state_index() const;
  double nominal_element_length() const;  ///< h0
  const System& system() const;
  const FesdOptions& options() const;
  const Eigen::Matrix<double, ny, 1>& initial_state() const;  ///< (q0, v0, t0, 0, gap(q0))

  /// The discrete solution (fesd_points.hxx): the initial point, then every stage point in
  /// numerical time order, with its applied input. x has variable_count() entries.
  std::vector<Point> points(const Eigen::Ref<const Eigen::VectorXd>& x) const;

  // ---- Mpcc ----------------------------------------------------------------------------------
  int variable_count() const override;
  int constraint_count() const override;
  void bounds(Eigen::Ref<Eigen::VectorXd> xl, Eigen::Ref<Eigen::VectorXd> xu, Eigen::Ref<Eigen::VectorXd> gl,
              Eigen::Ref<Eigen::VectorXd> gu) const override;
  /// The initial state at every stage point, s = 1, zero inputs (clipped to their bounds), h = h0,
  /// step functions and multipliers from the switching functions at the initial state
  /// (fesd_initial_point.hxx).
  void initial_point(Eigen::Ref<Eigen::VectorXd> x) const override;
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
  /// otherwise). x_out must have variable_count() entries (InvalidArgument otherwise); it is left
  /// unchanged when this throws.
  void initial_point_from_guess(Eigen::Ref<Eigen::VectorXd> x_out, const MotionGuess& guess) const;
  double objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override;
  void objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> g) const override;
  void constraints(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> g) const override;
  const std::vector<SparseEntry>& jacobian_structure() const override;
  void jacobian_values(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> values) const override;
  const std::vector<SparseEntry>& hessian_structure() const override;
  void hessian_values(const Eigen::Ref<const Eigen::VectorXd>& x, double objective_factor,
                      const Eigen::Ref<const Eigen::VectorXd>& multipliers,
                      Eigen::Ref<Eigen::VectorXd> values) const override;
  const std::vector<ComplementarityPair>& complementarity_pairs() const override;
  /// "s[k]", "u[k][i]", "h[k,j]", "Y[k,j,r][i]", "K...", "alpha...", "lambda_p...", "lambda_n...".
  std::string variable_name(int i) const override;
  /// "stage dynamics[k,j,r][i]", "collocation...", "switching function...", "path constraint...",
  /// "sum of element lengths [k]", "clock [k]", "terminal constraint i".
  std::string constraint_name(int row) const override;

 private:
  // ---- the applied input and the local kernels (fesd_stage_rows.hxx) ---------------------------
  template <class T>
  VecT<T, nu> input_law(const T& t, const VecT<T, nu>& decision) const;
  Vec<nu> applied_input(const Eigen::Ref<const Eigen::VectorXd>& x, int k, double t) const;
  template <class T>
  VecT<T, ny> stage_field(const VecT<T, nz>& z) const;
  template <class T>
  VecT<T, nq> mass_times(const VecT<T, 2 * nq>& w) const;
  Eigen::Matrix<double, nz, 1> field_local(const Eigen::Ref<const Eigen::VectorXd>& x, int k, int j, int r) const;
  int field_global(int k, int j, int r, int a) const;
  Eigen::Matrix<double, 2 * nq, 1> mass_local(const Eigen::Ref<const Eigen::VectorXd>& x, int k, int j, int r) const;
  int mass_global(int k, int j, int r, int a) const;
  static constexpr int npw = ny + nu;  ///< local variables of the path rows: (Y, u)
  template <class T>
  VecT<T, (np > 0 ? np : 1)> stage_path(const VecT<T, npw>& w) const;
  int path_global(int k, int j, int r, int b) const;
  static constexpr int ntw = nx + 1;  ///< local variables of the terminal rows and cost: (x, t)
  template <class T>
  VecT<T, (nt > 0 ? nt : 1)> terminal_function(const VecT<T, ntw>& w) const;
  int terminal_global(int a) const;

  // ---- rows and switching functions (fesd_layout.hxx) -----------------------------------------
  void check_options() const;
  int stage_row(int k, int j, int r) const;
  void build_rows();
  bool has_clock_row(int k) const;
  double switching_scale(int m) const;    ///< options.switching.scale of function m
  bool reads_integrated_gap(int m) const;  ///< function m is a gap read from the integrated gap state
  bool switching_active(int m) const;      ///< false for a frictionless contact's tangential function
  bool cross_complementary(int m) const;   ///< function m's switches sit on element boundaries

  // ---- the constraint rows and their Jacobian (fesd_stage_rows.hxx, fesd_jacobian.hxx) ---------
  void jacobian_pass(const Eigen::Ref<const Eigen::VectorXd>& x, detail::JacobianSink& sink) const;
  void dynamics_rows(const Eigen::Ref<const Eigen::VectorXd>& x, int k, int j, int r, detail::JacobianSink& sink) const;
  void collocation_rows(const Eigen::Ref<const Eigen::VectorXd>& x, int k, int j, int r,
                        detail::JacobianSink& sink) const;
  void switching_rows(const Eigen::Ref<const Eigen::VectorXd>& x, int k, int j, int r, detail::JacobianSink& sink) const;
  void path_rows(const Eigen::Ref<const Eigen::VectorXd>& x, int k, int j, int r, detail::JacobianSink& sink) const;
  void interval_rows(const Eigen::Ref<const Eigen::VectorXd>& x, int k, detail::JacobianSink& sink) const;
  void terminal_rows(const Eigen::Ref<const Eigen::VectorXd>& x, detail::JacobianSink& sink) const;

  // ---- the Lagrangian Hessian (fesd_hessian.hxx) ----------------------------------------------
  void hessian_pass(const Eigen::Ref<const Eigen::VectorXd>& x, double sigma, const Eigen::Ref<const Eigen::VectorXd>& mu,
                    detail::HessianSink& sink) const;
  void dynamics_hessian(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& mu, int k,
                        int j, int r, detail::HessianSink& sink) const;
  void collocation_hessian(const Eigen::Ref<const Eigen::VectorXd>& mu, int k, int j, int r,
                           detail::HessianSink& sink) const;
  void switching_hessian(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& mu, int k,
                         int j, int r, detail::HessianSink& sink) const;
  void path_hessian(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& mu, int k,
                    int j, int r, detail::HessianSink& sink) const;
  void terminal_hessian(const Eigen::Ref<const Eigen::VectorXd>& x, double sigma,
                        const Eigen::Ref<const Eigen::VectorXd>& mu, detail::HessianSink& sink) const;
  void build_structures();

  // ---- the objective's regularisation (fesd_objective.hxx, fesd_step_equilibration.hxx) ---------
  double step_equilibration(const Eigen::Ref<const Eigen::VectorXd>& x, int k, double f) const;
  void step_equilibration_gradient(const Eigen::Ref<const Eigen::VectorXd>& x, int k, Eigen::Ref<Eigen::VectorXd> g) const;
  void step_equilibration_hessian(int k, double sigma, detail::HessianSink& sink) const;
  double contact_side_selection(const Eigen::Ref<const Eigen::VectorXd>& x, int k, double f) const;
  void contact_side_selection_gradient(int k, Eigen::Ref<Eigen::VectorXd> g) const;

  // ---- complementarity pairs (fesd_complementarity.hxx) ---------------------------------------
  void build_pairs();
  void stagewise_pairs(int k, int j, int m);
  void cross_pairs(int k, int j, int m);

  // ---- initial points (fesd_initial_point.hxx) -------------------------------------------------
  /// alpha, lambda_p, lambda_n of a stage point from its scaled switching functions c.
  void set_switching_start(Eigen::Ref<Eigen::VectorXd> x, int k, int j, int r, const Vec<nsw>& c) const;
  Vec<nx> guessed_state(const MotionGuess& guess, double t) const;
  void set_stage_from_guess(Eigen::Ref<Eigen::VectorXd> x, int k, int j, int r, const MotionGuess& guess,
                            double rate) const;

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
