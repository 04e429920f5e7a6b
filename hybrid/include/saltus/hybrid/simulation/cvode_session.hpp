// The scene-free half of the CVODE backend (integrator_cvode.hpp): one SUNDIALS 6.4 CVODE
// session (SUNContext, N_Vectors, CVODE memory, dense matrix and linear solver or fixed-point
// nonlinear solver) behind an opaque pointer, compiled once in hybrid/src/cvode_session.cpp.
// This header includes no SUNDIALS header: only that .cpp does, so SUNDIALS is a link-only
// dependency of saltus_hybrid and never reaches a translation unit that uses the simulator.
//
// Callbacks: an abstract interface (CvodeProblem), implemented by CvodeIntegrator<S>, rather
// than C function pointers with a void* user_data. Reasons: the template never sees an N_Vector
// or a C signature (the session converts them to plain arrays of n doubles); the trampolines
// with C signatures, and the capture of an exception thrown inside a callback (it cannot cross
// CVODE's C frames: it is stored, the callback returns -1 and the exception is rethrown once
// CVode has returned), are written once here instead of once per scene; and the interface is
// type-checked. The cost, one virtual call per right-hand side, guard or projection evaluation,
// is negligible next to the evaluation itself (kinematics, a Cholesky factorisation of the mass
// matrix and a contact-force solve).
//
// Failures: every CVODE call is checked; a negative flag becomes NumericalFailure
//     "CVODE (<label>): <function> failed with <flag name> (<flag>)[: <CVODE's message>]"
// with the flag's name from CVodeGetReturnFlagName and the last message CVODE passed to its
// error handler since the last reinit(). A null object from a SUNDIALS constructor becomes
// NumericalFailure "SUNDIALS could not create <what>".
#pragma once

#include <memory>

namespace saltus {

/// What CVODE integrates, seen by the session. Every array holds the session's n doubles, except
/// the guard values (the root count given to CvodeSession::init_roots). Implementations may
/// throw: the session stores the exception, makes CVODE stop, and rethrows it from step().
class CvodeProblem {
 public:
  /// xdot = f(t, x).
  virtual void rhs(double t, const double* x, double* xdot) = 0;
  /// The root functions at (t, x), one per slot of init_roots.
  virtual void roots(double t, const double* x, double* g) = 0;
  /// CVODE's projection (BDF only, after set_projection): correction = P(x) - x; error, if
  /// non-null, is the local error estimate, to be projected in place.
  virtual void project(double t, const double* x, double* correction, double* error) = 0;

 protected:
  CvodeProblem() = default;
  CvodeProblem(const CvodeProblem&) = default;
  CvodeProblem& operator=(const CvodeProblem&) = default;
  ~CvodeProblem() = default;
};

/// One CVODE integrator of an n-dimensional ODE: BDF with Newton iteration and the dense linear
/// solver (difference-quotient Jacobian), or Adams-Moulton with fixed-point iteration. Each
/// member wraps the CVODE call of the same name; the object may not be copied or moved (CVODE
/// holds pointers to it and to the problem).
class CvodeSession {
 public:
  enum class Method { Bdf, Adams };
  /// How one CV_ONE_STEP call of CVode ended (its non-negative return flags).
  enum class StepEnd {
    Step,  ///< CV_SUCCESS: one internal step
    Stop,  ///< CV_TSTOP_RETURN: the stop time was reached
    Root,  ///< CV_ROOT_RETURN: a root function changed sign in the step
  };

  /// Creates the context, the state vectors, the CVODE memory (CVodeCreate, CVodeInit at t = 0,
  /// x = 0, with the problem's rhs) and the solvers of `method`. `label` names the session in
  /// error messages (the integrator kind). Throws NumericalFailure.
  CvodeSession(int n, Method method, const char* label, CvodeProblem& problem);
  ~CvodeSession();
  CvodeSession(const CvodeSession&) = delete;
  CvodeSession& operator=(const CvodeSession&) = delete;

  int size() const;
  Method method() const;

  // ---- settings ----
  void set_tolerances(double relative, double absolute);  ///< CVodeSStolerances
  void set_max_order(int order);                          ///< CVodeSetMaxOrd
  void set_max_step(double h);                            ///< CVodeSetMaxStep (0: unlimited)
  void set_max_num_steps(long steps);                     ///< CVodeSetMaxNumSteps (< 0: unlimited)
  void set_stop_time(double t);                           ///< CVodeSetStopTime
  /// CVodeRootInit with `count` root functions, evaluated by problem.roots.
  void init_roots(int count);
  void set_root_directions(const int* directions);  ///< CVodeSetRootDirection (count entries)
  void disable_inactive_root_warning();             ///< CVodeSetNoInactiveRootWarn
  /// CVodeSetProjFn with problem.project (BDF only: CVODE refuses it with Adams).
  void set_projection();
  void set_projection_frequency(long frequency);  ///< CVodeSetProjFrequency (0: off)

  // ---- integration ----
  /// CVodeReInit at (t0, x0); forgets the previous segment's pending exception and message.
  void reinit(double t0, const double* x0);
  /// One internal step towards t_out (CVode, CV_ONE_STEP). Rethrows an exception a callback
  /// stored; throws NumericalFailure on a CVODE failure. `t` receives CVODE's returned time.
  StepEnd step(double t_out, double& t);
  /// CVodeGetRootInfo after StepEnd::Root: one entry per root function.
  void root_info(int* found) const;
  /// CVodeGetDky: the k-th derivative of CVODE's interpolant at t, into out (n doubles).
  void dky(double t, int k, double* out) const;
  double last_step() const;     ///< CVodeGetLastStep
  double current_time() const;  ///< CVodeGetCurrentTime
  int last_order() const;       ///< CVodeGetLastOrder
  long error_test_failures() const;  ///< CVodeGetNumErrTestFails

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace saltus
