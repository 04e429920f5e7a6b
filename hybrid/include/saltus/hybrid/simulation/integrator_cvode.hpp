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
// The state is corrected in the kinetic metric, the M(q)^{-1} metric on forces:
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
#pragma once

#include <saltus/hybrid/simulation/integrator.hpp>
#include <saltus/hybrid/dynamics/kinematics.hpp>
#include <saltus/hybrid/contact/linear_solve.hpp>

#include <boost/math/tools/roots.hpp>

#include <cvode/cvode.h>
#include <cvode/cvode_proj.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <limits>
#include <string>
#include <utility>

namespace saltus {

template <Scene S>
class CvodeIntegrator {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nc = S::nc, ng = 2 * S::nc + 1;
  static constexpr int max_rows = delassus_bound(std::max(1, 3 * S::nc));
  using State = VecT<double, nx>;

  /// options.kind must be CvodeBdf or CvodeAdams. Throws InvalidArgument on bad options,
  /// NumericalFailure if SUNDIALS cannot create its objects.
  explicit CvodeIntegrator(const IntegratorOptions& options) : options_(options) {
    SALTUS_DEMAND(options.kind == IntegratorKind::CvodeBdf || options.kind == IntegratorKind::CvodeAdams,
                  InvalidArgument, "CvodeIntegrator needs IntegratorKind::CvodeBdf or CvodeAdams, got '",
                  to_string(options.kind), "'");
    SALTUS_DEMAND(options.relative_tolerance > 0 && options.absolute_tolerance > 0, InvalidArgument,
                  "integrator tolerances must be > 0, got relative ", options.relative_tolerance, ", absolute ",
                  options.absolute_tolerance);
    SALTUS_DEMAND(options.max_step >= 0 && options.max_steps > 0, InvalidArgument,
                  "max_step must be >= 0 and max_steps > 0");
    try {
      create();
    } catch (...) {
      destroy();
      throw;
    }
  }
  ~CvodeIntegrator() { destroy(); }
  CvodeIntegrator(const CvodeIntegrator&) = delete;
  CvodeIntegrator& operator=(const CvodeIntegrator&) = delete;

  const IntegratorOptions& options() const { return options_; }
  bool is_bdf() const { return options_.kind == IntegratorKind::CvodeBdf; }

  /// Integrates sys from (t0, x) towards t_final (> t0, or < t0 backwards); x holds the state at
  /// the end (at an event: the state just before it, the last instant where every guard is
  /// >= 0). Appends one piece per internal step to `out` if non-null.
  SegmentEndOf<S> integrate(ModeSystem<S>& sys, double t0, State& x, double t_final, double simultaneity,
                            DenseOutput<nx>* out, bool detect_events = true) {
    SegmentEndOf<S> end;
    require_finite(x, "initial state of the segment");
    const double direction = t_final >= t0 ? 1.0 : -1.0;
    end.t = t0;
    // Nothing to integrate (CVODE would refuse with CV_TOO_CLOSE).
    if (std::abs(t_final - t0) <= 4 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(t0))) {
      end.t = t_final;
      return end;
    }
    sys_ = &sys;
    n_guards_ = detect_events ? sys.guards().count : 0;
    pending_ = nullptr;
    last_message_.clear();
    closed_rows_ = 0;
    for (int i = 0; i < nc; ++i) closed_rows_ += sys.mode()[i].closed() ? 1 : 0;
    const bool project = options_.project_constraints && closed_rows_ > 0;

    Eigen::Map<State>(N_VGetArrayPointer(y_)) = x;
    check(CVodeReInit(mem_, t0, y_), "CVodeReInit");
    check(CVodeSetStopTime(mem_, t_final), "CVodeSetStopTime");
    check(CVodeSetRootDirection(mem_, root_direction_.data()), "CVodeSetRootDirection");
    if (is_bdf()) check(CVodeSetProjFrequency(mem_, project ? 1 : 0), "CVodeSetProjFrequency");

    double t_prev = t0, t_ret = t0;
    x_prev_ = x;
    sys.rhs(t0, x_prev_, dx_prev_);
    while (true) {
      SALTUS_DEMAND(end.steps < options_.max_steps, NumericalFailure, "CVODE: integration of one segment exceeded ",
                    options_.max_steps, " steps at t = ", t_prev);
      const int flag = CVode(mem_, t_final, y_, &t_ret, CV_ONE_STEP);
      if (pending_) std::rethrow_exception(std::exchange(pending_, nullptr));
      check(flag, "CVode");
      ++end.steps;
      const Piece piece = step_piece(t_prev);
      if (flag == CV_ROOT_RETURN) {
        check(CVodeGetRootInfo(mem_, roots_found_.data()), "CVodeGetRootInfo");
        locate(sys, piece, t_prev, t_ret, simultaneity, end);
        Piece last = piece;
        last.t1 = end.t_first_crossing;
        if (out && last.t1 != last.t0) out->append(last);
        x = piece.value(end.t_first_crossing);
        end.at_guard = true;
        end.t = end.t_first_crossing;
        break;
      }
      const bool at_stop = flag == CV_TSTOP_RETURN || direction * (t_ret - t_final) >= 0;
      Piece step = piece;
      if (at_stop) step.t1 = t_final;
      if (out) out->append(step);
      t_prev = step.t1;
      if (at_stop) {
        x = step.value(t_final);  // not CVODE's y at tstop: its low-order interpolant (see above)
        end.t = t_final;
        break;
      }
    }
    long failures = 0;
    check(CVodeGetNumErrTestFails(mem_, &failures), "CVodeGetNumErrTestFails");
    end.rejected_steps = failures;
    if (options_.project_constraints && closed_rows_ > 0) project_state(sys.scene(), sys.mode(), x, nullptr);
    sys_ = nullptr;
    return end;
  }

  /// Projects x onto the closed contacts of `mode` (see the file comment); `error`, if non-null,
  /// is projected with the linearised operators. Exposed for tests.
  void project_state(const S& scene, const Mode<nc>& mode, State& x, State* error) {
    VecT<double, nq> q = x.template head<nq>(), v = x.template tail<nq>();
    const double scale = 1.0 + q.cwiseAbs().maxCoeff();
    int m = 0;
    for (int iteration = 0; iteration < 4; ++iteration) {
      evaluate_kinematics(scene, q, v, kin_);
      m = 0;
      for (int i = 0; i < nc; ++i) {
        if (!mode[i].closed()) continue;
        G_.row(m) = kin_.contacts[i].wn.transpose();
        residual_[m] = kin_.contacts[i].gap;
        ++m;
      }
      if (m == 0) return;
      constraint_step(m, residual_, dq_);
      q -= dq_;
      if (dq_.cwiseAbs().maxCoeff() <= 4 * std::numeric_limits<double>::epsilon() * scale) break;
    }
    evaluate_kinematics(scene, q, v, kin_);
    if (error) {  // position part with the final G
      for (int r = 0; r < m; ++r) residual_[r] = G_.row(r).dot(error->template head<nq>());
      constraint_step(m, residual_, dq_);
      error->template head<nq>() -= dq_;
    }
    int r = 0;
    for (int i = 0; i < nc; ++i) {
      if (!mode[i].closed()) continue;
      const auto& c = kin_.contacts[i];
      G_.row(r++) = c.wn.transpose();
      if (mode[i].mode == ContactMode::Stick)
        for (int k = 0; k < c.tangents; ++k) G_.row(r++) = c.Wt.col(k).transpose();
    }
    for (int k = 0; k < r; ++k) residual_[k] = G_.row(k).dot(v);
    constraint_step(r, residual_, dq_);
    v -= dq_;
    if (error) {
      for (int k = 0; k < r; ++k) residual_[k] = G_.row(k).dot(error->template tail<nq>());
      constraint_step(r, residual_, dq_);
      error->template tail<nq>() -= dq_;
    }
    x.template head<nq>() = q;
    x.template tail<nq>() = v;
  }

 private:
  using Piece = PolynomialPiece<nx>;
  using Rows = BoundedMatrix<double, Eigen::Dynamic, nq, max_rows, nq>;
  using Cols = BoundedMatrix<double, nq, Eigen::Dynamic, nq, max_rows>;
  using Solver = MinNormSolver<max_rows>;

  // d = M^{-1} G^T (G M^{-1} G^T)^+ b over the first m rows of G_ (evaluated at kin_): the
  // smallest correction in the kinetic metric with G d = b.
  void constraint_step(int m, const typename Solver::Vector& b, VecT<double, nq>& d) {
    d.setZero();
    if (m == 0) return;
    MinvGt_.resize(nq, m);
    for (int k = 0; k < m; ++k) {
      VecT<double, nq> col = G_.row(k).transpose();
      kin_.llt.solveInPlace(col);
      MinvGt_.col(k) = col;
    }
    auto& A = delassus_.matrix(m);
    A.noalias() = G_.topRows(m) * MinvGt_;
    delassus_.factorize();
    multiplier_ = b.head(m);
    delassus_.solve_in_place(multiplier_);
    d.noalias() = MinvGt_ * multiplier_;
  }

  // The dense output of the last step on [t_prev, t_n] (see the file comment): CVODE's Nordsieck
  // interpolant for q >= 4, the cubic Hermite interpolant for q <= 3. Updates x_prev_, dx_prev_.
  Piece step_piece(double t_prev) {
    Piece p;
    double h = 0.0, tn = 0.0;
    int q = 0;
    check(CVodeGetLastStep(mem_, &h), "CVodeGetLastStep");
    check(CVodeGetCurrentTime(mem_, &tn), "CVodeGetCurrentTime");
    check(CVodeGetLastOrder(mem_, &q), "CVodeGetLastOrder");
    SALTUS_DEMAND(q >= 1 && q <= Piece::max_degree, NumericalFailure, "CVODE: step order ", q,
                  " outside the dense output's degrees 1..", Piece::max_degree);
    p.t0 = t_prev;
    p.t1 = tn;
    if (q >= 4) {
      p.t_ref = tn;
      p.h = h;
      p.degree = q;
      double scale = 1.0;  // h^j / j!
      for (int j = 0; j <= q; ++j) {
        check(CVodeGetDky(mem_, tn, j, dky_), "CVodeGetDky");
        p.c.col(j) = scale * Eigen::Map<const State>(N_VGetArrayPointer(dky_));
        scale *= h / double(j + 1);
      }
      x_next_ = p.c.col(0);
      dx_next_ = p.c.col(1) / h;
    } else {
      check(CVodeGetDky(mem_, tn, 0, dky_), "CVodeGetDky");
      x_next_ = Eigen::Map<const State>(N_VGetArrayPointer(dky_));
      check(CVodeGetDky(mem_, tn, 1, dky_), "CVodeGetDky");
      dx_next_ = Eigen::Map<const State>(N_VGetArrayPointer(dky_));
      // p(theta) = x0 + g0 theta + (3d - 2g0 - g1) theta^2 + (g0 + g1 - 2d) theta^3 on [t_prev, t_n].
      const double step = tn - t_prev;
      p.t_ref = t_prev;
      p.h = step;
      p.degree = 3;
      const State d = x_next_ - x_prev_, g0 = step * dx_prev_, g1 = step * dx_next_;
      p.c.col(0) = x_prev_;
      p.c.col(1) = g0;
      p.c.col(2) = 3.0 * d - 2.0 * g0 - g1;
      p.c.col(3) = g0 + g1 - 2.0 * d;
    }
    x_prev_ = x_next_;
    dx_prev_ = dx_next_;
    return p;
  }

  // Polished roots of the guards (see the file comment); sets end.t_first_crossing and end.fired.
  void locate(ModeSystem<S>& sys, const Piece& piece, double t_prev, double t_root, double simultaneity,
              SegmentEndOf<S>& end) {
    const double forward = piece.t1 >= piece.t0 ? 1.0 : -1.0;
    const double tol = options_.root_tolerance * std::max(1.0, std::abs(t_root));
    auto stop = [tol](double a, double b) { return std::abs(b - a) <= tol; };
    std::array<double, ng> root{};
    double first = std::numeric_limits<double>::quiet_NaN();
    State xs;
    std::array<double, ng> gv{};
    auto guard = [&](int k, double t) {
      xs = piece.value(t);
      sys.guard_values(t, xs, gv);
      return gv[k];
    };
    // The root of guard k between t_pos (guard >= 0) and t_neg (guard < 0); the >= 0 side.
    auto polish = [&](int k, double t_pos, double g_pos, double t_neg, double g_neg) {
      if (g_pos == 0.0) return t_pos;
      std::uintmax_t iterations = 200;
      const bool increasing_t = t_neg > t_pos;
      const auto bracket = boost::math::tools::toms748_solve([&](double t) { return guard(k, t); },
                                                             increasing_t ? t_pos : t_neg, increasing_t ? t_neg : t_pos,
                                                             increasing_t ? g_pos : g_neg, increasing_t ? g_neg : g_pos,
                                                             stop, iterations);
      return increasing_t ? bracket.first : bracket.second;
    };
    const double t_step_end = piece.t1;
    for (int k = 0; k < n_guards_; ++k) {
      root[k] = std::numeric_limits<double>::quiet_NaN();
      const double g_start = guard(k, t_prev), g_end = guard(k, t_step_end);
      if (g_start >= 0.0 && g_end < 0.0) {
        root[k] = polish(k, t_prev, g_start, t_step_end, g_end);
      } else if (roots_found_[k] != 0) {
        // CVODE saw a dip inside the step: bracket it from CVODE's root backwards.
        const double g_root = guard(k, t_root);
        if (g_root >= 0.0) {
          root[k] = t_root;
        } else {
          double back = 100 * std::numeric_limits<double>::epsilon() * (std::abs(t_root) + std::abs(piece.h));
          double t_pos = t_root, g_pos = g_root;
          while (true) {
            t_pos = t_root - forward * back;
            if (forward * (t_pos - t_prev) <= 0) t_pos = t_prev;
            g_pos = guard(k, t_pos);
            if (g_pos >= 0.0 || t_pos == t_prev) break;
            back *= 4;
          }
          root[k] = g_pos >= 0.0 ? polish(k, t_pos, g_pos, t_root, g_root) : t_prev;
        }
      }
      if (std::isfinite(root[k]) && (!std::isfinite(first) || forward * (root[k] - first) < 0)) first = root[k];
    }
    SALTUS_DEMAND(std::isfinite(first), NumericalFailure, "CVODE reported a root at t = ", t_root,
                  " but no active guard crossed");
    // Guards CVODE did not report that cross within the simultaneity window after the first root.
    const double t_window = first + forward * simultaneity;
    for (int k = 0; k < n_guards_; ++k) {
      if (std::isfinite(root[k])) continue;
      const double g_first = guard(k, first), g_window = guard(k, t_window);
      if (g_first >= 0.0 && g_window < 0.0) root[k] = polish(k, first, g_first, t_window, g_window);
    }
    end.t_first_crossing = first;
    for (int k = 0; k < n_guards_; ++k)
      end.fired[k] = std::isfinite(root[k]) && std::abs(root[k] - first) <= simultaneity;
  }

  // ---- CVODE callbacks (C linkage through static members; exceptions stored, never thrown) ----
  static int rhs_callback(double t, N_Vector y, N_Vector ydot, void* self_ptr) {
    auto* self = static_cast<CvodeIntegrator*>(self_ptr);
    try {
      self->x_work_ = Eigen::Map<const State>(N_VGetArrayPointer(y));
      self->sys_->rhs(t, self->x_work_, self->xdot_work_);
      Eigen::Map<State>(N_VGetArrayPointer(ydot)) = self->xdot_work_;
      return 0;
    } catch (...) {
      self->pending_ = std::current_exception();
      return -1;
    }
  }
  static int root_callback(double t, N_Vector y, double* gout, void* self_ptr) {
    auto* self = static_cast<CvodeIntegrator*>(self_ptr);
    try {
      for (int k = 0; k < ng; ++k) gout[k] = 1.0;  // unused slots never cross
      if (self->n_guards_ == 0) return 0;
      self->x_work_ = Eigen::Map<const State>(N_VGetArrayPointer(y));
      self->sys_->guard_values(t, self->x_work_, self->guard_work_);
      for (int k = 0; k < self->n_guards_; ++k) gout[k] = self->guard_work_[k];
      return 0;
    } catch (...) {
      self->pending_ = std::current_exception();
      return -1;
    }
  }
  static int projection_callback(double, N_Vector y, N_Vector correction, double, N_Vector error, void* self_ptr) {
    auto* self = static_cast<CvodeIntegrator*>(self_ptr);
    try {
      const State before = Eigen::Map<const State>(N_VGetArrayPointer(y));
      State after = before;
      if (error) {
        State e = Eigen::Map<const State>(N_VGetArrayPointer(error));
        self->project_state(self->sys_->scene(), self->sys_->mode(), after, &e);
        Eigen::Map<State>(N_VGetArrayPointer(error)) = e;
      } else {
        self->project_state(self->sys_->scene(), self->sys_->mode(), after, nullptr);
      }
      Eigen::Map<State>(N_VGetArrayPointer(correction)) = after - before;
      return 0;
    } catch (...) {
      self->pending_ = std::current_exception();
      return -1;
    }
  }
  static void error_callback(int code, const char* module, const char* function, char* message, void* self_ptr) {
    auto* self = static_cast<CvodeIntegrator*>(self_ptr);
    if (code < 0) self->last_message_ = detail::concat(module, "::", function, ": ", message);
  }

  // ---- creation, checks ----
  void check(int flag, const char* call) const {
    if (flag >= 0) return;
    char* name = CVodeGetReturnFlagName(flag);  // malloc'ed by SUNDIALS
    const std::string flag_name = name ? name : "?";
    std::free(name);
    throw NumericalFailure(detail::concat("CVODE (", to_string(options_.kind), "): ", call, " failed with ", flag_name,
                                          " (", flag, ")", last_message_.empty() ? "" : ": ", last_message_));
  }
  template <class P>
  P created(P p, const char* what) {
    SALTUS_DEMAND(p != nullptr, NumericalFailure, "SUNDIALS could not create ", what);
    return p;
  }

  void create() {
    SALTUS_DEMAND(SUNContext_Create(nullptr, &context_) == 0, NumericalFailure, "SUNDIALS could not create its context");
    y_ = created(N_VNew_Serial(nx, context_), "an N_Vector");
    dky_ = created(N_VNew_Serial(nx, context_), "an N_Vector");
    N_VConst(0.0, y_);
    mem_ = created(CVodeCreate(is_bdf() ? CV_BDF : CV_ADAMS, context_), "the CVODE memory");
    check(CVodeSetErrHandlerFn(mem_, &CvodeIntegrator::error_callback, this), "CVodeSetErrHandlerFn");
    check(CVodeInit(mem_, &CvodeIntegrator::rhs_callback, 0.0, y_), "CVodeInit");
    check(CVodeSetUserData(mem_, this), "CVodeSetUserData");
    check(CVodeSStolerances(mem_, options_.relative_tolerance, options_.absolute_tolerance), "CVodeSStolerances");
    if (is_bdf()) {
      matrix_ = created(SUNDenseMatrix(nx, nx, context_), "a dense matrix");
      linear_solver_ = created(SUNLinSol_Dense(y_, matrix_, context_), "the dense linear solver");
      check(CVodeSetLinearSolver(mem_, linear_solver_, matrix_), "CVodeSetLinearSolver");
      check(CVodeSetProjFn(mem_, &CvodeIntegrator::projection_callback), "CVodeSetProjFn");
    } else {
      nonlinear_solver_ = created(SUNNonlinSol_FixedPoint(y_, 0, context_), "the fixed-point solver");
      check(CVodeSetNonlinearSolver(mem_, nonlinear_solver_), "CVodeSetNonlinearSolver");
      check(CVodeSetMaxOrd(mem_, PolynomialPiece<nx>::max_degree), "CVodeSetMaxOrd");
    }
    check(CVodeSetMaxStep(mem_, options_.max_step), "CVodeSetMaxStep");
    // One-step mode: CVODE's own per-call step limit would never be reached; integrate() counts.
    check(CVodeSetMaxNumSteps(mem_, -1), "CVodeSetMaxNumSteps");
    check(CVodeRootInit(mem_, ng, &CvodeIntegrator::root_callback), "CVodeRootInit");
    root_direction_.fill(-1);
    check(CVodeSetRootDirection(mem_, root_direction_.data()), "CVodeSetRootDirection");
    check(CVodeSetNoInactiveRootWarn(mem_), "CVodeSetNoInactiveRootWarn");
    G_.resize(max_rows, nq);
    residual_.resize(max_rows);
    multiplier_.resize(max_rows);
  }
  void destroy() {
    if (mem_) CVodeFree(&mem_);
    if (linear_solver_) SUNLinSolFree(linear_solver_);
    if (nonlinear_solver_) SUNNonlinSolFree(nonlinear_solver_);
    if (matrix_) SUNMatDestroy(matrix_);
    if (y_) N_VDestroy(y_);
    if (dky_) N_VDestroy(dky_);
    if (context_) SUNContext_Free(&context_);
    mem_ = nullptr;
    linear_solver_ = nullptr;
    nonlinear_solver_ = nullptr;
    matrix_ = nullptr;
    y_ = dky_ = nullptr;
    context_ = nullptr;
  }

  IntegratorOptions options_;
  SUNContext context_ = nullptr;
  void* mem_ = nullptr;
  N_Vector y_ = nullptr, dky_ = nullptr;
  SUNMatrix matrix_ = nullptr;
  SUNLinearSolver linear_solver_ = nullptr;
  SUNNonlinearSolver nonlinear_solver_ = nullptr;
  std::array<int, ng> root_direction_{}, roots_found_{};

  // Per-integrate state used by the callbacks.
  ModeSystem<S>* sys_ = nullptr;
  int n_guards_ = 0, closed_rows_ = 0;
  std::exception_ptr pending_;
  std::string last_message_;
  State x_work_ = State::Zero(), xdot_work_ = State::Zero();
  State x_prev_ = State::Zero(), dx_prev_ = State::Zero(), x_next_ = State::Zero(), dx_next_ = State::Zero();
  std::array<double, ng> guard_work_{};

  // Projection workspace.
  Kinematics<S> kin_;
  Rows G_;
  Cols MinvGt_;
  Solver delassus_;
  typename Solver::Vector residual_, multiplier_;
  VecT<double, nq> dq_ = VecT<double, nq>::Zero();
};

}  // namespace saltus
