// The CVODE session (cvode_session.hpp): the only translation unit of Saltus that includes
// SUNDIALS headers.
#include <saltus/hybrid/simulation/cvode_session.hpp>

#include <saltus/hybrid/vocabulary/errors.hpp>

#include <cvode/cvode.h>
#include <cvode/cvode_proj.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <cstdlib>
#include <exception>
#include <string>
#include <type_traits>
#include <utility>

namespace saltus {

// The problem's callbacks take double arrays: SUNDIALS must be built with double precision.
static_assert(std::is_same_v<sunrealtype, double>, "Saltus needs SUNDIALS built with double precision");

struct CvodeSession::Impl {
  Impl(int size, Method m, const char* name, CvodeProblem& p) : n(size), method(m), label(name), problem(p) {}
  ~Impl() {
    if (mem) CVodeFree(&mem);
    if (linear_solver) SUNLinSolFree(linear_solver);
    if (nonlinear_solver) SUNNonlinSolFree(nonlinear_solver);
    if (matrix) SUNMatDestroy(matrix);
    if (y) N_VDestroy(y);
    if (dky) N_VDestroy(dky);
    if (context) SUNContext_Free(&context);
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  void check(int flag, const char* call) const {
    if (flag >= 0) return;
    char* name = CVodeGetReturnFlagName(flag);  // malloc'ed by SUNDIALS
    const std::string flag_name = name ? name : "?";
    std::free(name);
    throw NumericalFailure(detail::concat("CVODE (", label, "): ", call, " failed with ", flag_name, " (", flag, ")",
                                          last_message.empty() ? "" : ": ", last_message));
  }
  template <class P>
  static P created(P p, const char* what) {
    SALTUS_CHECK_NUMERICS(p != nullptr, "SUNDIALS could not create ", what);
    return p;
  }

  // ---- CVODE callbacks (C signatures; exceptions stored, never thrown through CVODE) ----
  static int rhs_callback(sunrealtype t, N_Vector y, N_Vector ydot, void* data) {
    auto* self = static_cast<Impl*>(data);
    try {
      self->problem.rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
      return 0;
    } catch (...) {
      self->pending = std::current_exception();
      return -1;
    }
  }
  static int root_callback(sunrealtype t, N_Vector y, sunrealtype* gout, void* data) {
    auto* self = static_cast<Impl*>(data);
    try {
      self->problem.roots(t, N_VGetArrayPointer(y), gout);
      return 0;
    } catch (...) {
      self->pending = std::current_exception();
      return -1;
    }
  }
  static int projection_callback(sunrealtype t, N_Vector y, N_Vector correction, sunrealtype, N_Vector error,
                                 void* data) {
    auto* self = static_cast<Impl*>(data);
    try {
      self->problem.project(t, N_VGetArrayPointer(y), N_VGetArrayPointer(correction),
                            error ? N_VGetArrayPointer(error) : nullptr);
      return 0;
    } catch (...) {
      self->pending = std::current_exception();
      return -1;
    }
  }
  static void error_callback(int code, const char* module, const char* function, char* message, void* data) {
    auto* self = static_cast<Impl*>(data);
    if (code < 0) self->last_message = detail::concat(module, "::", function, ": ", message);
  }

  const int n;
  const Method method;
  const std::string label;
  CvodeProblem& problem;
  SUNContext context = nullptr;
  void* mem = nullptr;
  N_Vector y = nullptr, dky = nullptr;
  SUNMatrix matrix = nullptr;
  SUNLinearSolver linear_solver = nullptr;
  SUNNonlinearSolver nonlinear_solver = nullptr;
  std::exception_ptr pending;
  std::string last_message;
};

CvodeSession::CvodeSession(int n, Method method, const char* label, CvodeProblem& problem)
    : impl_(std::make_unique<Impl>(n, method, label, problem)) {
  // On a throw below, impl_ (already constructed) frees whatever was created.
  Impl& s = *impl_;
  SALTUS_CHECK_NUMERICS(SUNContext_Create(nullptr, &s.context) == 0, "SUNDIALS could not create its context");
  s.y = Impl::created(N_VNew_Serial(n, s.context), "an N_Vector");
  s.dky = Impl::created(N_VNew_Serial(n, s.context), "an N_Vector");
  N_VConst(0.0, s.y);
  s.mem = Impl::created(CVodeCreate(method == Method::Bdf ? CV_BDF : CV_ADAMS, s.context), "the CVODE memory");
  s.check(CVodeSetErrHandlerFn(s.mem, &Impl::error_callback, &s), "CVodeSetErrHandlerFn");
  s.check(CVodeInit(s.mem, &Impl::rhs_callback, 0.0, s.y), "CVodeInit");
  s.check(CVodeSetUserData(s.mem, &s), "CVodeSetUserData");
  if (method == Method::Bdf) {
    s.matrix = Impl::created(SUNDenseMatrix(n, n, s.context), "a dense matrix");
    s.linear_solver = Impl::created(SUNLinSol_Dense(s.y, s.matrix, s.context), "the dense linear solver");
    s.check(CVodeSetLinearSolver(s.mem, s.linear_solver, s.matrix), "CVodeSetLinearSolver");
  } else {
    s.nonlinear_solver = Impl::created(SUNNonlinSol_FixedPoint(s.y, 0, s.context), "the fixed-point solver");
    s.check(CVodeSetNonlinearSolver(s.mem, s.nonlinear_solver), "CVodeSetNonlinearSolver");
  }
}

CvodeSession::~CvodeSession() = default;

int CvodeSession::size() const { return impl_->n; }
CvodeSession::Method CvodeSession::method() const { return impl_->method; }

void CvodeSession::set_tolerances(double relative, double absolute) {
  impl_->check(CVodeSStolerances(impl_->mem, relative, absolute), "CVodeSStolerances");
}
void CvodeSession::set_max_order(int order) { impl_->check(CVodeSetMaxOrd(impl_->mem, order), "CVodeSetMaxOrd"); }
void CvodeSession::set_max_step(double h) { impl_->check(CVodeSetMaxStep(impl_->mem, h), "CVodeSetMaxStep"); }
void CvodeSession::set_max_num_steps(long steps) {
  impl_->check(CVodeSetMaxNumSteps(impl_->mem, steps), "CVodeSetMaxNumSteps");
}
void CvodeSession::set_stop_time(double t) { impl_->check(CVodeSetStopTime(impl_->mem, t), "CVodeSetStopTime"); }
void CvodeSession::init_roots(int count) {
  impl_->check(CVodeRootInit(impl_->mem, count, &Impl::root_callback), "CVodeRootInit");
}
void CvodeSession::set_root_directions(const int* directions) {
  // CVODE reads the array only (it copies it), but declares it non-const.
  impl_->check(CVodeSetRootDirection(impl_->mem, const_cast<int*>(directions)), "CVodeSetRootDirection");
}
void CvodeSession::disable_inactive_root_warning() {
  impl_->check(CVodeSetNoInactiveRootWarn(impl_->mem), "CVodeSetNoInactiveRootWarn");
}
void CvodeSession::set_projection() {
  impl_->check(CVodeSetProjFn(impl_->mem, &Impl::projection_callback), "CVodeSetProjFn");
}
void CvodeSession::set_projection_frequency(long frequency) {
  impl_->check(CVodeSetProjFrequency(impl_->mem, frequency), "CVodeSetProjFrequency");
}

void CvodeSession::reinit(double t0, const double* x0) {
  Impl& s = *impl_;
  s.pending = nullptr;
  s.last_message.clear();
  double* y = N_VGetArrayPointer(s.y);
  for (int i = 0; i < s.n; ++i) y[i] = x0[i];
  s.check(CVodeReInit(s.mem, t0, s.y), "CVodeReInit");
}

CvodeSession::StepEnd CvodeSession::step(double t_out, double& t) {
  Impl& s = *impl_;
  const int flag = CVode(s.mem, t_out, s.y, &t, CV_ONE_STEP);
  if (s.pending) std::rethrow_exception(std::exchange(s.pending, nullptr));
  s.check(flag, "CVode");
  if (flag == CV_ROOT_RETURN) return StepEnd::Root;
  if (flag == CV_TSTOP_RETURN) return StepEnd::Stop;
  return StepEnd::Step;
}

void CvodeSession::root_info(int* found) const {
  impl_->check(CVodeGetRootInfo(impl_->mem, found), "CVodeGetRootInfo");
}

void CvodeSession::dky(double t, int k, double* out) const {
  const Impl& s = *impl_;
  s.check(CVodeGetDky(s.mem, t, k, s.dky), "CVodeGetDky");
  const double* d = N_VGetArrayPointer(s.dky);
  for (int i = 0; i < s.n; ++i) out[i] = d[i];
}

double CvodeSession::last_step() const {
  double h = 0.0;
  impl_->check(CVodeGetLastStep(impl_->mem, &h), "CVodeGetLastStep");
  return h;
}
double CvodeSession::current_time() const {
  double t = 0.0;
  impl_->check(CVodeGetCurrentTime(impl_->mem, &t), "CVodeGetCurrentTime");
  return t;
}
int CvodeSession::last_order() const {
  int q = 0;
  impl_->check(CVodeGetLastOrder(impl_->mem, &q), "CVodeGetLastOrder");
  return q;
}
long CvodeSession::error_test_failures() const {
  long failures = 0;
  impl_->check(CVodeGetNumErrTestFails(impl_->mem, &failures), "CVodeGetNumErrTestFails");
  return failures;
}

}  // namespace saltus
