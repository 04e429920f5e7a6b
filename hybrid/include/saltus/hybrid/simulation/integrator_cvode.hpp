// The SUNDIALS CVODE backend (SUNDIALS 6.4): BDF (stiff, Newton iteration with a dense linear
// solver and CVODE's difference-quotient Jacobian) or Adams-Moulton (non-stiff, fixed-point
// iteration), with CVODE's own root finding on the guards of the mode and, for BDF, CVODE's
// projection onto the constraints of the closed contacts. Same contract as
// DormandPrinceIntegrator::integrate (integrator.hpp).
//
// Dense output. After every internal step of order q >= 4 the Nordsieck history
// z_j = h^j y^(j)(t_n) / j!, j = 0..q, is read through CVodeGetDky(t_n, j) (which returns
// y^(j)(t_n) = j! z_j / h^j) and stored as one PolynomialPiece with t_ref = t_n and
// theta = (t - t_n) / h: exactly CVODE's own interpolant on [t_n - h, t_n] (dense_output.hpp). A
// piece holds degree <= 5, so Adams runs with maximum order 5 instead of CVODE's default 12 (BDF's
// maximum is 5 anyway). At low order that interpolant is one order less accurate than the step:
// on the free fall or the sliding box (quadratic positions) Adams-Moulton of order 1, the
// trapezoidal rule, is exact, so CVODE stays at order 1 with long steps, and its linear
// interpolant is off by h^2 g / 8 (millimetres) between exact mesh values. For q <= 3 the piece is
// therefore the cubic Hermite interpolant of (y, y') at both ends of the step (y' from CVODE's
// history), exact for cubics, with error h^4 max|y''''| / 384.
//
// Events. One CVODE root function per active guard (CVodeRootInit with the largest guard count a
// mode of the scene can have, 2 nc + 1, so the root memory is allocated once; the slots a mode
// does not use return a constant 1), every direction -1 (a downward crossing, gamma from >= 0 to
// < 0). CVODE brackets a root to ttol = 100 uround (|t_n| + |h|), about 2e-14 relative, and
// returns the end of that bracket where the guard has already changed sign. That is accurate
// enough for the 1e-12 relative requirement, but it is a root of CVODE's interpolant (see the dense
// output above: at low order it can be far off) and it sits on the wrong side of the root: the
// simulator expects the last instant of the mode (the guard still >= 0, as Dormand-Prince
// delivers), and CVODE reports only the guards that change sign inside its final bracket, not
// those crossing within the simulator's `simultaneity` window. So CVODE's root only says that the
// step contains a crossing: every guard that is >= 0 at the start of the step and < 0 at its end
// is then located with TOMS 748 on the step's piece (the dense output) to
// root_tolerance * max(1, |t|), taking the side where the guard is still >= 0 (a guard CVODE
// reports that dips below zero and back inside the step is bracketed from CVODE's root backwards),
// and the other guards are checked for a crossing within `simultaneity` of the earliest root on
// that piece (extrapolated by at most `simultaneity` past t_n).
//
// Projection (IntegratorOptions::project_constraints). Closed contacts must keep
//     h_n(q) = 0,   w_n(q)^T v = 0,   and, sticking, W_t(q)^T v = 0.
// The state is corrected in the kinetic metric, the M(q)^{-1} metric on forces
// (ConstraintProjection, dynamics/constraints.hpp, shared with the numerical twin):
//     q <- q - M^{-1} G^T (G M^{-1} G^T)^+ h_n(q)      (G = rows w_n^T; Gauss-Newton, <= 4 iterations)
//     v <- v - M^{-1} J^T (J M^{-1} J^T)^+ J v         (J = rows w_n^T and, sticking, W_t^T)
// Why this metric rather than the Euclidean one: it does not depend on the units of the
// coordinates (metres against radians in the boxes), the velocity correction is the one a
// perfectly plastic constraint impulse would make (it never adds kinetic energy), and
// J M^{-1} J^T is the Delassus matrix, whose minimum-norm solve already handles redundant
// contacts (a box flat on four corners). The two stages are the usual position-then-velocity
// coordinate projection: the velocity constraint is enforced at the projected configuration,
// neglecting the O(correction^2) coupling through dJ/dq. Both are solved to round-off, not just
// to CVODE's epsProj. The local error estimate is projected with the same (linear) operators.
// CVODE accepts a projection function with BDF only ("Projection is only supported with BDF
// methods"): with Adams the state handed back at the end of a segment (event or final time) is
// projected, the steps in between are not.
//
// Failures. Every CVODE call is checked; a negative flag becomes NumericalFailure naming the
// flag (CVodeGetReturnFlagName) and CVODE's own message. An exception thrown inside a callback
// (the flow, the input law, the guards) cannot cross CVODE's C frames: it is stored, the callback
// returns -1 (unrecoverable), and the original exception is rethrown once CVode has returned.
//
// Allocation. The SUNContext, the CVODE memory, vectors, matrix and solvers are created once in
// the constructor; integrate() reinitialises them with CVodeReInit and allocates nothing itself
// (CVODE allocates nothing after its first initialisation either; the dense output vector
// grows as pieces are appended, as with Dormand-Prince).
//
// Files. This header declares CvodeIntegrator<S> and includes neither SUNDIALS nor Boost.Math;
// integrator_cvode.hxx defines its members (include it, or link an explicit instantiation
// `template class saltus::CvodeIntegrator<Scene>;` compiled in one .cpp that includes it). The
// SUNDIALS objects and calls, the flag checks and the callbacks' exception capture are
// scene-free: CvodeSession (cvode_session.hpp), compiled once in saltus_hybrid.
#pragma once

#include <saltus/hybrid/dynamics/constraints.hpp>
#include <saltus/hybrid/simulation/cvode_session.hpp>
#include <saltus/hybrid/simulation/integrator.hpp>

#include <algorithm>
#include <array>

namespace saltus {

template <Scene S>
class CvodeIntegrator final : private CvodeProblem {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nc = S::nc, ng = 2 * S::nc + 1;
  using State = VecT<double, nx>;

  /// options.kind must be CvodeBdf or CvodeAdams. Throws InvalidArgument on bad options,
  /// NumericalFailure if SUNDIALS cannot create its objects.
  explicit CvodeIntegrator(const IntegratorOptions& options);
  CvodeIntegrator(const CvodeIntegrator&) = delete;
  CvodeIntegrator& operator=(const CvodeIntegrator&) = delete;

  const IntegratorOptions& options() const { return options_; }
  bool is_bdf() const { return options_.kind == IntegratorKind::CvodeBdf; }

  /// Integrates sys from (t0, x) towards t_final (> t0, or < t0 backwards); x holds the state at
  /// the end (at an event: the state just before it, the last instant where every guard is
  /// >= 0). Appends one piece per internal step to `out` if non-null.
  SegmentEndOf<S> integrate(ModeSystem<S>& sys, double t0, State& x, double t_final, double simultaneity,
                            DenseOutput<nx>* out, bool detect_events = true);

  /// Projects x onto the closed contacts of `mode` (see the file comment); `error`, if non-null,
  /// is projected with the linearised operators. Exposed for tests.
  void project_state(const S& scene, const Mode<nc>& mode, State& x, State* error);

  /// m: an open contact's gap below -gap_tolerance is a penetration, hence a missed touchdown.
  /// Besides CVODE's sign-change roots, every step's dense output is scanned for touchdowns that
  /// dip and come back within the step, or start below zero (guard_scan.hxx). The simulator sets
  /// it to its impact options' gap tolerance.
  void set_gap_tolerance(double gap_tolerance) { gap_tolerance_ = gap_tolerance; }

 private:
  using Piece = PolynomialPiece<nx>;

  // The checks of the constructor's options, before the session is created.
  static const IntegratorOptions& validated(const IntegratorOptions& options);

  // The dense output of the last step on [t_prev, t_n] (see the file comment): CVODE's Nordsieck
  // interpolant for q >= 4, the cubic Hermite interpolant for q <= 3. Updates x_prev_, dx_prev_.
  Piece step_piece(double t_prev);

  // Polished roots of the guards (see the file comment); sets end.t_first_crossing and end.fired.
  // False when no guard fires (a touchdown's round-off sign change while leaving the surface).
  bool locate(ModeSystem<S>& sys, const Piece& piece, double t_prev, double t_root, double simultaneity,
              SegmentEndOf<S>& end);

  // ---- CvodeProblem: CVODE's callbacks, on the mode system of the running integrate() ----
  void rhs(double t, const double* x, double* xdot) override;
  void roots(double t, const double* x, double* g) override;  // unused slots: a constant 1
  void project(double t, const double* x, double* correction, double* error) override;

  IntegratorOptions options_;
  double gap_tolerance_ = 1e-9;
  CvodeSession session_;
  std::array<int, ng> root_direction_{}, roots_found_{};

  // Per-integrate state used by the callbacks.
  ModeSystem<S>* sys_ = nullptr;
  int n_guards_ = 0, closed_rows_ = 0;
  State x_work_ = State::Zero(), xdot_work_ = State::Zero();
  State x_prev_ = State::Zero(), dx_prev_ = State::Zero(), x_next_ = State::Zero(), dx_next_ = State::Zero();
  std::array<double, ng> guard_work_{};

  // The projection onto the closed contacts' constraints (dynamics/constraints.hpp).
  ConstraintProjection<S> projection_;
};

}  // namespace saltus
