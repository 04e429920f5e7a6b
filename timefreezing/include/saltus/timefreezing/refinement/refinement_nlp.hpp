// The refinement NLP: a smooth multi-phase OCP whose mode schedule is FIXED (mode_schedule.hpp),
// built on the hybrid core's own flows, guards and jump maps, collocated with Radau IIA.
//
// PHASES. Phase p = 0..P-1 runs in the mode m_p of the schedule from t_p to t_{p+1}
// (t_0 = t0 and t_P = T fixed, the event times t_1..t_{P-1} variables with t_{p+1} - t_p >=
// min_phase_duration >= 0). It has N_p elements of equal length h_p = (t_{p+1} - t_p) / N_p, each
// a Radau IIA step with n_s stages and one piecewise-constant input (decision) u_e. The flow is
// the hybrid core's flow of the mode (dynamics/flow.hpp: the contact forces of the closed contacts
// from the Delassus system, so that a closed contact is held at the ACCELERATION level,
// J a + kappa = 0): with f_m the flow of mode m,
//     X_{e,r} - X_{e,start} - h_p sum_l a_rl f_m(X_{e,l}, u(t_{e,l}, u_e)) = 0     (collocation)
// for every stage r of element e; X_{e,start} is the previous element's last stage or, for the
// phase's first element, the phase's start state X_p (a variable). The closed contacts' position
// and velocity conditions are NOT imposed at the stage points: they hold at the phase's start
// (the event before it imposes the gap, its jump map puts the velocity on the contact) and the
// flow keeps them to the collocation's accuracy. (Imposing them at every stage point as well
// over-determines a discretisation of a gap nonlinear in q, the cause of the rank-deficient branch
// NLPs of FESD: fesd.hpp, "INTEGRATED GAP".)
//
// MODE VALIDITY at every stage point and at every element's start under the element's input (the
// input jumps there; inequality rows >= 0), from the flow's contact forces:
//     open contact:             h_n(q)                    (no penetration; minus
//                               RefinementOptions::flight_clearance times a hump in the phase
//                               fraction s: 4 s (1 - s), or (256/27) s^3 (1 - s) after a release)
//                               at the start of a phase that a release begins, instead:
//                               h_n'' = w_n' a + kappa_n  (the released contact accelerates away
//                               under the phase's first input; see RELEASE CONSISTENCY)
//     closed contact:           lambda_n                  (no pull; minus RefinementOptions::normal_force_margin
//                               where the schedule keeps the contact closed past the phase's end,
//                               minus RefinementOptions::stance_load times 4 s (1 - s) where it
//                               releases it there)
//     sticking planar contact:  mu lambda_n - lambda_t,  mu lambda_n + lambda_t   (in the cone;
//                               mu times 1 - RefinementOptions::stick_cone_margin, default 1)
//     slipping planar contact:  s zeta_t                  (the slip keeps its sign s; minus
//                               RefinementOptions::slip_speed_margin, ramped to 0 at a slip
//                               onset or a stop of the contact)
// With these and the events below, the refined motion satisfies the complementarity conditions of
// contact and Coulomb friction EXACTLY at every stage point, by construction: each contact is in
// one branch (open: lambda = 0 by the flow; closed: gap = 0 by the phase start and the flow), and
// the branch's sign conditions are these rows. mode_validity_violation reports their largest
// violation at the solution.
//
// EVENTS (the boundary between phase p and p + 1, at x- = the last stage of phase p, u- = its last
// input, t = t_{p+1}), with the hybrid core's event physics:
//     touchdown of i:   h_n,i(q-) = 0 and zeta_n,i(x-) <= -RefinementOptions::touchdown_speed
//                       (approaching; at least that fast)
//     release of i:     lambda_n,i(x-, u-) = 0   (the flow of m_p); released from stick also
//                       lambda_t,i(x-, u-) = 0 (the cone rows, dropped at x-, would leave it free)
//     stop of i:        zeta_t,i(x-) = 0
//     slip onset of i:  lambda_t,i(x-, u-) + s mu lambda_n,i(x-, u-) = 0   (s: the slip sign of
//                       m_{p+1}; friction opposes the slip)
//     state:            X_{p+1} = Delta(x-)   (the jump map of the impulse mode of m_{p+1} at an
//                       event with a touchdown, dynamics/jump_map.hpp; identity otherwise)
//     at an impact:     Lambda_n,i >= 0 for every contact taking an impulse; a sticking impulse in
//                       the cone, mu Lambda_n -+ Lambda_t >= 0; a slipping contact leaves with its
//                       sign, s zeta_t(x+) >= 0; a contact closed before and open after separates,
//                       zeta_n(x+) >= 0.
// A simultaneous event has all its guards at one boundary.
//
// IMPLIED ROWS. A row that the others imply must not be imposed twice (LICQ, and with
// discretisation drift even feasibility): (a) an equality path row whose gradient, at the guess's
// middle of a phase, lies in the span of the gap gradients of the phase's closed contacts and that
// depends on neither v nor u (the plank-box's theta - phi = 0 while both corners are closed) is
// not imposed inside that phase; (b) a guard whose gradient in (x-, u-), at the guess's x-, lies
// in the span of the rows already imposed there (the equality path rows at x-, the guards before
// it) is not imposed (the plank-box's second corner touching down while theta - phi = 0 holds).
// (d) closed frictional contacts of one sub-mode whose tangent rows W_t' are parallel at the guess
// (the plank-box's two corners on the plank) form a friction group: their slip-sign rows are one
// condition (only the first contact's is imposed), and the flow splits a sticking group's friction
// by equal utilisation (flow.hpp), so its per-contact cones are one condition too: the first
// contact's cone rows read the group's totals, mu sum lambda_n -+ sum lambda_t >= 0 (slip starts
// when no split is left), and the others' cone rows are implied.
// (c) the gap >= 0 row of an open contact whose gap gradient lies in the span of the closed
// contacts' gap gradients and the gradients of the equality path rows (no v, u dependence) is
// implied as gap = 0 (the plank-box's corner kept on the plank by theta - phi = 0 while the other
// corner is closed): not imposed, it would be weakly active at every stage point.
// (e) an equality terminal row that the last phase's closed contacts (h_n = 0, zeta_n = 0) and the
// terminal rows kept before it imply in gradient and in value (the hopper's z(T) = 0.4 with the leg
// straight is the foot's gap = 0): not imposed (refinement_nlp_terminal.hxx).
// "In the span": relative least-squares residual <= RefinementOptions::implied_row_tolerance.
// implied_rows() lists them; the readings (mode_validity_violation, path_violation,
// terminal_violation) include them.
//
// EVENT ENDS. At a phase's last stage point the guard of an event replaces the validity row it
// makes active (touchdown: gap = 0 for gap >= 0; release: lambda_n = 0 for lambda_n >= 0 and a
// stick's cone, a slide keeping its sign row; stop: zeta_t = 0 for s zeta_t >= 0; slip onset: the
// cone); at the next phase's start point
// (its first element's start under its input) the rows that continuity or the impulse rows already
// fix go (after a slip onset the slip sign, after an impact the slip sign of the contacts taking an
// impulse and the gap of the contacts it throws off; after a release the gap, whose row there is
// the release consistency below); at the very first
// point the gaps of x0, which no variable moves. Otherwise each would be a second, dependent row
// active at the same point (LICQ), and a drift of the collocation could make it infeasible.
//
// RELEASE CONSISTENCY. The input is constant per element, so it may jump at a release: the guard
// lambda_n(x-, u-) = 0 holds under the ending phase's last input u-, while the flight starts under
// its own first input u+. If the released contact's free normal acceleration under u+ were
// negative, the contact would not open (the event-driven simulator, following the reference's
// input, closes it again an instant later with zero approach speed: a grazing re-touch). So the
// open contact's row at the released phase's start point (x+ = x-, u+) is h_n'' >= 0, the normal
// acceleration of the phase's open-contact flow. Under a continuous input it is 0 (lambda_n = 0
// makes the free and the constrained acceleration equal), so it costs nothing where u is smooth.
//
// RELEASE AT AN INPUT JUMP (RefinementOptions::releases_at_input_jumps). The release guard
// lambda_n(x-, u-) = 0 asks the stance's last input to unload the contact. Where the optimum
// wants the force up to the lift-off (a push-off), the mesh then cuts the stance's last element
// ever shorter and its input all but unloads the foot in it. With the option, the release guard
// is not a row: the stance's validity rows are kept at x- (lambda_n(x-, u-) >= 0, a sticking
// contact in its cone) and the flight's start row h_n''(x-, u+) >= 0 (RELEASE CONSISTENCY) says
// that under the flight's first input the contact separates. For one released contact, with the
// Delassus matrix positive, h_n''(open, u+) >= 0 is the same as lambda_n(closed, x-, u+) <= 0, so
// the acceleration-level mode selection under u+ opens it: the release happens at the input's
// jump, a time event. With several released at once (the plank-box's two corners), h'' >= 0 for
// each with lambda = 0 solves the contact LCP under u+, which has one solution for a P-matrix.
// Under a continuous input both rows meet at lambda_n = 0, the guard's release.
//
// COST AND CONSTRAINTS of the OCP struct (the one the time-freezing solver takes,
// formulation/ocp concepts in fesd.hpp): the running cost in physical time by the Radau
// quadrature, sum_e h_p sum_l b_l l(x_{e,l}, u_e[, t_{e,l}]); the terminal cost and terminal rows
// at (X_final, T); path rows at every stage point; input bounds on every u_e.
//
// DERIVATIVES. Three local blocks carry all nonlinearity: the stage block at a stage point,
// w = (x, u_e, t_p, t_{p+1}) -> (h f, h l, validity, path); the event block, w = (x-, u-, t) ->
// (guards, approach, x+, impulse validity, separation); the terminal block, w = (x_P, T) ->
// (terminal rows, terminal cost). Their Jacobians are forward AD (ad::Dual over w), their
// Hessians weighted by the multipliers forward-over-forward AD, through the hybrid core's flow,
// Delassus solve and jump map (linear_solve.hpp: derivatives reuse the value's factorisation).
// Everything else is linear and written out.
#pragma once

#include <saltus/ad/autodiff.hpp>
#include <saltus/hybrid/dynamics/flow.hpp>
#include <saltus/hybrid/dynamics/jump_map.hpp>
#include <saltus/timefreezing/discretisation/fesd.hpp>
#include <saltus/timefreezing/discretisation/radau.hpp>
#include <saltus/timefreezing/mpcc/mpcc.hpp>
#include <saltus/timefreezing/mpcc/solution.hpp>
#include <saltus/timefreezing/refinement/refinement_options.hpp>
#include <saltus/timefreezing/refinement/schedule_guess.hpp>

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace saltus::timefreezing {

/// A row that the refinement does not impose because the others imply it (file comment).
struct ImpliedRow {
  int phase = -1;           ///< (a) the phase of an implied path row; -1 for a guard or a terminal row
  int event = -1;           ///< (b) the event of an implied guard; -1 for a path or terminal row
  int index = 0;            ///< the path row's index, the guard's position in the event, or the terminal row's index
  std::string description;  ///< e.g. "path row 0 in phase 1", "touchdown C_R at event 0"
  double residual = 0.0;    ///< the relative least-squares residual that decided it
  bool terminal = false;    ///< (e) a terminal row (phase and event -1, index its terminal row)
};

/// The refinement NLP of one schedule (file comment). Immutable after construction except for its
/// derivative caches (mutable: not to be shared between threads).
template <Scene S, class Ocp>
class ScheduleRefinementNlp final : public Mpcc {
 public:
  static constexpr int nq = S::nq, nu = S::nu, nc = S::nc, nx = 2 * S::nq;
  static constexpr int np = path_constraint_count<Ocp>();
  static constexpr int nt = terminal_constraint_count<Ocp>();
  static constexpr int max_validity = 3 * nc;
  /// Stage block: w = (x, u, t_p, t_{p+1}); outputs (h f [nx], h l [1], validity, path [np]).
  static constexpr int nw = nx + nu + 2;
  static constexpr int stage_outputs = nx + 1 + max_validity + np;
  /// Whether the stage block depends on time only through h (no input law in t, no running cost in
  /// t): its outputs are then h F(x, u) (collocation, running cost) and G(x, u) (validity, path), and
  /// the Hessian is taken over (x, u) alone (stage_hessian).
  static constexpr bool stages_time_invariant =
      !HasInputLaw<Ocp, double, nu> && !HasTimedRunningCost<Ocp, double, nx, nu>;
  /// Event block: w = (x-, u-, t); outputs (guards, approach, x+, impulse validity, separation).
  static constexpr int nwe = nx + nu + 1;
  static constexpr int event_outputs = 2 * nc + nc + nx + 3 * nc + nc;
  /// Terminal block: w = (x, T); outputs (terminal rows [nt], terminal cost [1]).
  static constexpr int nwt = nx + 1;
  static constexpr int terminal_outputs = nt + 1;

  /// @throws InvalidArgument for a schedule that is not one of the scene (validated()), a horizon
  ///   that does not validate, bad options, a guess with non-finite values or event times outside
  ///   [t0, T] or decreasing, an initial state that contradicts the first phase's mode (a closed
  ///   contact not at gap 0 and normal velocity 0 within options.initial_state_tolerance, an open
  ///   one penetrating), naming the phase and the condition.
  ScheduleRefinementNlp(const S& scene, const Ocp& ocp, const OcpHorizon<S>& horizon, const ScheduleGuess<S>& guess,
                        const RefinementOptions& options);

  // ---- Mpcc (a plain NLP: no pairs) ------------------------------------------------------------
  int variable_count() const override { return n_; }
  int constraint_count() const override { return m_; }
  void bounds(Eigen::Ref<Eigen::VectorXd> x_lower, Eigen::Ref<Eigen::VectorXd> x_upper,
              Eigen::Ref<Eigen::VectorXd> g_lower, Eigen::Ref<Eigen::VectorXd> g_upper) const override;
  void initial_point(Eigen::Ref<Eigen::VectorXd> x) const override;
  double objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override;
  void objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> gradient) const override;
  void constraints(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> g) const override;
  const std::vector<SparseEntry>& jacobian_structure() const override { return jacobian_structure_; }
  void jacobian_values(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> values) const override;
  const std::vector<SparseEntry>& hessian_structure() const override { return hessian_structure_; }
  void hessian_values(const Eigen::Ref<const Eigen::VectorXd>& x, double objective_factor,
                      const Eigen::Ref<const Eigen::VectorXd>& multipliers,
                      Eigen::Ref<Eigen::VectorXd> values) const override;
  const std::vector<ComplementarityPair>& complementarity_pairs() const override { return no_pairs_; }
  std::string variable_name(int i) const override;
  std::string constraint_name(int j) const override;

  // ---- layout --------------------------------------------------------------------------------
  int phase_count() const { return static_cast<int>(schedule_.phases.size()); }
  int element_count() const { return static_cast<int>(element_phase_.size()); }
  int stages() const { return tableau_.stages; }
  int elements_in(int p) const { return phase_elements_[static_cast<std::size_t>(p)]; }
  /// Element e's start and length as fractions of its phase's duration (RefinementGrid::end_clustering),
  /// held times N_p so that the uniform grid's fractions are j / N_p and 1 / N_p to the last bit.
  double element_begin_fraction(int e) const { return element_begin_scaled_[std::size_t(e)] / elements_in(phase_of(e)); }
  double element_length_fraction(int e) const { return element_length_scaled_[std::size_t(e)] / elements_in(phase_of(e)); }
  /// The fraction of its phase at stage point (element e, point r): (B_e + c_r L_e) / N_p, B_e / N_p
  /// for the start (r = -1), with B_e, L_e the element's start and length times N_p.
  double point_theta(int e, int r) const;
  /// t0 + (t1 - t0) B_e / N_p: element e's start in a phase that runs over [t0, t1] [s].
  double element_start_time(int e, double t0, double t1) const {
    return t0 + (t1 - t0) * element_begin_scaled_[std::size_t(e)] / double(elements_in(phase_of(e)));
  }
  int first_element(int p) const { return phase_first_element_[static_cast<std::size_t>(p)]; }
  int phase_of(int e) const { return element_phase_[static_cast<std::size_t>(e)]; }
  int time_index(int p) const { return p; }  ///< t_p, p = 0..P
  int start_index(int p) const { return phase_count() + 1 + p * nx; }
  int control_index(int e) const { return element_base_ + e * (nu + tableau_.stages * nx); }
  int stage_index(int e, int r) const { return control_index(e) + nu + r * nx; }
  int element_start_index(int e) const;
  int phase_end_index(int p) const { return stage_index(first_element(p) + elements_in(p) - 1, tableau_.stages - 1); }
  const ModeSchedule<nc>& schedule() const { return schedule_; }
  const Ocp& ocp() const { return ocp_; }
  const RefinementOptions& options() const { return options_; }
  const S& scene() const { return scene_; }
  const RadauIIA& tableau() const { return tableau_; }
  const std::vector<ImpliedRow>& implied_rows() const { return implied_; }
  /// The path rows imposed at the stage points of phase p (all np of them unless some are implied).
  const std::vector<int>& imposed_path_rows(int p) const { return phase_path_rows_[static_cast<std::size_t>(p)]; }

  // ---- reading a solution ---------------------------------------------------------------------
  /// The largest violation of the mode-validity conditions at x, >= 0: every condition of the mode
  /// at every collocation point (the implied ones included), the imposed ones at every element's
  /// start under its input, and the impact rows (file comment).
  double mode_validity_violation(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  /// The largest violation of the path rows at x (all of them, the implied ones included).
  double path_violation(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  /// The largest violation of the terminal rows at x (all of them, the implied ones included:
  /// the collocation's drift from the manifold that implies them).
  double terminal_violation(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  /// The largest |h_n| and |zeta_n| of the closed contacts over every point of x: how far the
  /// collocation drifts from the contact manifold that the flow holds at the acceleration level
  /// (file comment: the position and velocity conditions are imposed once, at the phase's start);
  /// of the order of the collocation's error, h^(2 n_s - 1).
  double contact_drift(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  /// Per element, the local error of its collocation step at x [state units]: the largest
  /// |X_{e,end} - y(t_e + h_e)| over the state's entries, y the exact flow of the phase's mode from
  /// y(t_e) = X_{e,start} under the element's input (classical Runge-Kutta with step doubling until
  /// its own error estimate is below 1 % of the distance or 1e-13, Richardson-extrapolated; at most
  /// 8192 steps). The re-simulation's per-phase distance is these errors carried through the
  /// phase's flow. A zero-length element has local error 0. Where the flow fails at every step
  /// count (NumericalFailure: the Runge-Kutta steps run into a non-finite or singular state, as from
  /// an element whose collocation is far from its flow: the hopper's coarse first solves), the
  /// element's local error is +infinity and the mesh refinement splits it the most. Throws what
  /// the flow throws otherwise (NonSpdMassMatrix).
  std::vector<double> element_local_errors(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  /// The validity values at point (e, r) of x in the order of the file comment (count:
  /// validity_count); r = -1 is the element's start under its input, r = 0..n_s-1 its stages.
  std::vector<double> validity_values(const Eigen::Ref<const Eigen::VectorXd>& x, int e, int r) const;
  int validity_count(int p) const { return validity_count_[static_cast<std::size_t>(p)]; }
  /// How many validity values contact i has in `mode` (open 1; closed 1, + 2 sticking, + 1 slipping
  /// with friction).
  int count_validity_of(const Mode<nc>& mode, int contact) const;
  /// The validity values imposed as rows at point (e, r): the phase's (all of them unless some are
  /// implied), less, at the phase's start and end points, those of the contacts whose guard fires
  /// at the event there (file comment, "EVENT ENDS").
  const std::vector<int>& imposed_validity(int e, int r) const;
  /// The row of validity value k at point (e, r), or -1 when that value is implied (not a row).
  int validity_row(int e, int r, int k) const;
  /// The applied input of element e (after the OCP's input law, at the element's start).
  VecT<double, S::nu> applied_input(const Eigen::Ref<const Eigen::VectorXd>& x, int e) const;
  /// A start for this NLP from `solution`, the solution of `coarser`: an NLP of the same schedule on
  /// a grid that this one refines (every element of this grid inside one of coarser's, as
  /// split_elements makes it). The returned start has x = this NLP's initial point
  /// (variable_count()), the constraint multipliers (constraint_count()) and the lower and upper
  /// bound multipliers (variable_count() each) carried over (refinement_nlp_warm_start.hxx: the
  /// costate rows as they are, the O(h) rows in proportion to the element's length).
  /// Precondition, NOT checked: this grid refines coarser's (an element is mapped to the coarser
  /// element that holds its middle; a grid that moves element boundaries gets multipliers of the
  /// wrong element). nullopt when the two NLPs do not share their point conditions (another
  /// schedule or stage count, other event, path or terminal rows imposed) or the solution's
  /// vectors do not have coarser's sizes. Throws nothing of its own.
  std::optional<MpccStart> warm_start_from(const ScheduleRefinementNlp& coarser, const MpccSolution& solution) const;
  /// The contact forces of point (e, r) at x (the flow of the phase's mode).
  std::array<ContactForce<double>, S::nc> contact_forces(const Eigen::Ref<const Eigen::VectorXd>& x, int e, int r) const;
  /// The impulses of event b at x (zero without an impact).
  std::array<ContactForce<double>, S::nc> impulses(const Eigen::Ref<const Eigen::VectorXd>& x, int b) const;

 private:
  struct EventRows {  // the rows of event b and what they mean
    ImpactMode<nc> impulse_mode{};
    bool impact = false;
    std::vector<Guard> imposed_guards;   // after dropping the implied ones
    // released from stick: lambda_t = 0 as well (the whole force vanishes; a slipping contact's
    // lambda_t = -s mu lambda_n vanishes with lambda_n), rows after the guards
    std::vector<int> released_sticking;
    std::vector<int> approach_contacts;  // touchdowns: zeta_n <= 0
    std::vector<int> separating_contacts;
    int impulse_rows = 0;
    int first_row = 0;
    int row_count() const {
      return static_cast<int>(imposed_guards.size() + released_sticking.size() + approach_contacts.size() +
                              separating_contacts.size()) +
             nx + impulse_rows;
    }
  };

  // the dual warm start (refinement_nlp_warm_start.hxx)
  int parent_element(const ScheduleRefinementNlp& coarser, int e) const;  // coarser's element containing e
  bool shares_point_conditions(const ScheduleRefinementNlp& coarser) const;

  // construction (refinement_nlp_build.hxx)
  void build_grid(const ScheduleGuess<S>& guess);
  void check_initial_state() const;
  void find_implied_phase_rows();
  void find_implied_guards();
  void find_implied_terminal_rows();
  template <class T>
  VecT<T, 2 * S::nc> held_contact_values(const VecT<T, nx>& x) const;  // per contact (h_n, zeta_n)
  struct TerminalLinearisation {  // the terminal block and the held contact values at w, with their Jacobians
    VecT<double, terminal_outputs> value;
    MatT<double, terminal_outputs, nwt> jacobian;
    VecT<double, 2 * S::nc> held_value;
    MatT<double, 2 * S::nc, nx> held_jacobian;
  };
  TerminalLinearisation linearise_terminal(const VecT<double, nwt>& w) const;
  bool project_on_held_manifold(const VecT<double, nwt>& w, const std::vector<int>& held, const std::vector<int>& kept,
                                VecT<double, nx>& x) const;
  void build_rows();
  void build_structures();
  int count_validity(const Mode<nc>& mode) const;
  int count_impulse_rows(const EventRows& ev) const;

  // the local blocks (refinement_nlp_blocks.hxx)
  template <class T>
  VecT<T, stage_outputs> stage_block(int e, double theta, const VecT<T, nw>& w, FlowWorkspace<S, T>& ws) const;
  /// The stage block's outputs from (x, u, h, t) (stage_block computes h, t and u from w).
  template <class T>
  VecT<T, stage_outputs> stage_values(int e, double theta, const VecT<T, nx>& x, const VecT<T, nu>& u, const T& h,
                                      const T& t, FlowWorkspace<S, T>& ws) const;
  /// H = sum_k weight_k d2 out_k / dw2 at a stage point when stages_time_invariant: with
  /// L = h A(x, u) + B(x, u) (A the weighted collocation and running-cost outputs over h, B the
  /// rest) and h linear in (t_p, t_{p+1}), d2L/dz2 = h A'' + B'', d2L/dz dt = (dh/dt) A', d2L/dt2 = 0
  /// (z = (x, u)): forward-over-forward AD over the nx + nu entries of z instead of all nw,
  /// ((nx + nu + 1) / (nw + 1))^2 of the work (0.72 for the hopper).
  void stage_hessian(int e, double theta, const VecT<double, nw>& w, const VecT<double, stage_outputs>& weight,
                     MatT<double, nw, nw>& hessian) const;
  template <class T>
  VecT<T, event_outputs> event_block(int b, const VecT<T, nwe>& w, FlowWorkspace<S, T>& fws,
                                     JumpWorkspace<S, T>& jws) const;
  template <class T>
  VecT<T, terminal_outputs> terminal_block(const VecT<T, nwt>& w) const;
  template <class T>
  VecT<T, S::nu> input_law(const T& t, const VecT<T, S::nu>& decision) const;
  template <class T>
  void write_validity(int p, double theta, const FlowWorkspace<S, T>& ws, VecT<T, stage_outputs>& out) const;
  double normal_margin(int p, int i, double theta) const;
  double slip_margin(int p, int i, double theta) const;
  double clearance(int p, int i, double theta) const;
  bool released_at_start(int p, int i) const;  // contact i closed in phase p - 1, opened by a release

  // local vectors and their globals. A point (e, r): r = -1 the element's start (its start state
  // under its own input: validity rows only), r = 0..n_s-1 its stages.
  VecT<double, nw> point_local(const Eigen::Ref<const Eigen::VectorXd>& x, int e, int r) const;
  int point_global(int e, int r, int a) const;
  int point_state_index(int e, int r) const { return r < 0 ? element_start_index(e) : stage_index(e, r); }
  std::size_t point_slot(int e, int r) const { return static_cast<std::size_t>(e * (tableau_.stages + 1) + r + 1); }
  VecT<double, nwe> event_local(const Eigen::Ref<const Eigen::VectorXd>& x, int b) const;
  int event_global(int b, int a) const;
  VecT<double, nwt> terminal_local(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  int terminal_global(int a) const;
  /// The first row of point (e, r): a start's validity rows; a stage's collocation, validity, path rows.
  int point_row(int e, int r) const { return point_row_[point_slot(e, r)]; }
  int validity_offset_in_rows(int r) const { return r < 0 ? 0 : nx; }

  // derivative caches (refinement_nlp_eval.hxx)
  void update(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  template <class Emit>
  void walk_jacobian(Emit&& emit) const;
  VecT<double, stage_outputs> point_weights(int e, int l, double sigma, const Eigen::Ref<const Eigen::VectorXd>& lambda) const;
  VecT<double, event_outputs> event_weights(int b, const Eigen::Ref<const Eigen::VectorXd>& lambda) const;
  template <class Emit>
  void walk_hessian(const Eigen::Ref<const Eigen::VectorXd>& x, double sigma,
                    const Eigen::Ref<const Eigen::VectorXd>& lambda, Emit&& emit) const;

  S scene_;
  Ocp ocp_;
  OcpHorizon<S> horizon_;
  ModeSchedule<nc> schedule_;
  RefinementOptions options_;
  RadauIIA tableau_;
  int n_ = 0, m_ = 0, element_base_ = 0;
  std::vector<int> phase_elements_, phase_first_element_, element_phase_, validity_count_;
  std::vector<double> element_begin_scaled_, element_length_scaled_;  // fractions of the phase times N_p
  std::vector<std::vector<int>> phase_path_rows_;      // per phase: the path rows imposed at its stages
  struct PhaseValidity {  // the validity values imposed as rows: inside the phase, at its start, at its end
    std::vector<int> interior, at_start, at_end;
  };
  std::vector<PhaseValidity> phase_validity_rows_;
  // per phase and contact: the leader of its friction group (itself when alone; -1 when open or
  // frictionless): closed frictional contacts of one sub-mode whose tangent rows are parallel
  std::vector<std::array<int, nc>> friction_leader_;
  void restrict_event_ends();
  void find_friction_groups(int p, const Kinematics<S, double>& kin);
  std::vector<int> point_row_;
  std::vector<EventRows> events_;
  int duration_row_ = 0, terminal_row_ = 0;
  std::vector<int> imposed_terminal_rows_;  // the terminal rows imposed, in order (the others implied)
  std::vector<ImpliedRow> implied_;
  Eigen::VectorXd guess_x_;  // the initial point, built from the guess
  std::vector<SparseEntry> jacobian_structure_, hessian_structure_;
  std::vector<ComplementarityPair> no_pairs_;
  // caches at the last x
  mutable Eigen::VectorXd cached_x_;
  mutable bool cache_valid_ = false;
  mutable std::vector<VecT<double, stage_outputs>> point_value_;       // per point slot
  mutable std::vector<MatT<double, stage_outputs, nw>> point_jacobian_;
  mutable std::vector<VecT<double, event_outputs>> event_value_;
  mutable std::vector<MatT<double, event_outputs, nwe>> event_jacobian_;
  mutable VecT<double, terminal_outputs> terminal_value_;
  mutable MatT<double, terminal_outputs, nwt> terminal_jacobian_;
};

}  // namespace saltus::timefreezing
