// The members of CvodeIntegrator<S> (integrator_cvode.hpp, where the method is described),
// defined out of the class body so that an explicit instantiation declaration
// (`extern template class saltus::CvodeIntegrator<Scene>;`) keeps a translation unit that sees
// it from compiling them again. Include this file where CvodeIntegrator<S> is instantiated.
#pragma once

#include <saltus/hybrid/simulation/guard_scan.hxx>
#include <saltus/hybrid/simulation/integrator_cvode.hpp>

#include <boost/math/tools/roots.hpp>

#include <cmath>
#include <cstdint>
#include <limits>

namespace saltus {

template <Scene S>
const IntegratorOptions& CvodeIntegrator<S>::validated(const IntegratorOptions& options) {
  SALTUS_REQUIRE(options.kind == IntegratorKind::CvodeBdf || options.kind == IntegratorKind::CvodeAdams, "CvodeIntegrator needs IntegratorKind::CvodeBdf or CvodeAdams, got '",
                to_string(options.kind), "'");
  SALTUS_REQUIRE(options.relative_tolerance > 0 && options.absolute_tolerance > 0, 
                "integrator tolerances must be > 0, got relative ", options.relative_tolerance, ", absolute ",
                options.absolute_tolerance);
  SALTUS_REQUIRE(options.max_step >= 0 && options.max_steps > 0, 
                "max_step must be >= 0 and max_steps > 0");
  return options;
}

// The session (created in the member initialiser, after the checks) creates the context, the
// vectors, the CVODE memory and the solvers; a throw below destroys it again.
template <Scene S>
CvodeIntegrator<S>::CvodeIntegrator(const IntegratorOptions& options)
    : options_(validated(options)),
      session_(nx, options.kind == IntegratorKind::CvodeBdf ? CvodeSession::Method::Bdf : CvodeSession::Method::Adams,
               to_string(options.kind), *this) {
  session_.set_tolerances(options_.relative_tolerance, options_.absolute_tolerance);
  if (is_bdf()) {
    session_.set_projection();
  } else {
    session_.set_max_order(PolynomialPiece<nx>::max_degree);
  }
  session_.set_max_step(options_.max_step);
  // One-step mode: CVODE's own per-call step limit would never be reached; integrate() counts.
  session_.set_max_num_steps(-1);
  session_.init_roots(ng);
  root_direction_.fill(-1);
  session_.set_root_directions(root_direction_.data());
  session_.disable_inactive_root_warning();
}

template <Scene S>
SegmentEndOf<S> CvodeIntegrator<S>::integrate(ModeSystem<S>& sys, double t0, State& x, double t_final,
                                              double simultaneity, DenseOutput<nx>* out, bool detect_events) {
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
  closed_rows_ = 0;
  for (int i = 0; i < nc; ++i) closed_rows_ += sys.mode()[i].closed() ? 1 : 0;
  const bool project = options_.project_constraints && closed_rows_ > 0;

  session_.reinit(t0, x.data());  // also forgets the previous segment's stored exception and message
  session_.set_stop_time(t_final);
  session_.set_root_directions(root_direction_.data());
  if (is_bdf()) session_.set_projection_frequency(project ? 1 : 0);

  double t_prev = t0, t_ret = t0;
  x_prev_ = x;
  sys.rhs(t0, x_prev_, dx_prev_);
  using Values = typename ModeSystem<S>::GuardValues;
  Values ga{}, ra{};
  if (n_guards_ > 0) sys.guard_values(t0, x, ga, &ra);
  const auto scan = detail::GuardScanSettings::of(options_, gap_tolerance_, simultaneity);
  while (true) {
    SALTUS_CHECK_NUMERICS(end.steps < options_.max_steps, "CVODE: integration of one segment exceeded ",
                  options_.max_steps, " steps at t = ", t_prev);
    // Rethrows an exception stored by a callback, then turns a CVODE failure into NumericalFailure.
    const CvodeSession::StepEnd flag = session_.step(t_final, t_ret);
    ++end.steps;
    const Piece piece = step_piece(t_prev);
    if (flag == CvodeSession::StepEnd::Root) session_.root_info(roots_found_.data());
    // A root CVODE reports may be a touchdown guard's round-off sign change of a contact that is
    // leaving the surface (guard_scan.hxx, case 1): locate() then finds no event and the step
    // is taken as an ordinary one.
    if (flag == CvodeSession::StepEnd::Root && locate(sys, piece, t_prev, t_ret, simultaneity, end)) {
      Piece last = piece;
      last.t1 = end.t_first_crossing;
      if (out && last.t1 != last.t0) out->append(last);
      x = piece.value(end.t_first_crossing);
      end.at_guard = true;
      end.t = end.t_first_crossing;
      break;
    }
    const bool at_stop = flag == CvodeSession::StepEnd::Stop || direction * (t_ret - t_final) >= 0;
    Piece step = piece;
    if (at_stop) step.t1 = t_final;
    // What CVODE's sign-change roots cannot see: a touchdown dipping and back within the step, or
    // starting below zero (guard_scan.hxx).
    if (n_guards_ > 0 && direction > 0 && step.t1 > step.t0) {
      auto state_at = [&step](double t, State& y) { y = step.value(t); };
      if (detail::scan_step_for_events(sys, state_at, step.t0, step.t1, ga, ra, scan, end)) {
        Piece last = step;
        last.t1 = end.t_first_crossing;
        if (out && last.t1 != last.t0) out->append(last);
        x = step.value(end.t_first_crossing);
        end.at_guard = true;
        end.t = end.t_first_crossing;
        break;
      }
    }
    if (out) out->append(step);
    t_prev = step.t1;
    if (at_stop) {
      x = step.value(t_final);  // not CVODE's y at tstop: its low-order interpolant (see above)
      end.t = t_final;
      break;
    }
  }
  end.rejected_steps = session_.error_test_failures();
  if (options_.project_constraints && closed_rows_ > 0) project_state(sys.scene(), sys.mode(), x, nullptr);
  sys_ = nullptr;
  return end;
}

template <Scene S>
void CvodeIntegrator<S>::project_state(const S& scene, const Mode<nc>& mode, State& x, State* error) {
  projection_.project(scene, mode, x, nullptr, nullptr, error);
}

template <Scene S>
typename CvodeIntegrator<S>::Piece CvodeIntegrator<S>::step_piece(double t_prev) {
  Piece p;
  const double h = session_.last_step(), tn = session_.current_time();
  const int q = session_.last_order();
  SALTUS_CHECK_NUMERICS(q >= 1 && q <= Piece::max_degree, "CVODE: step order ", q,
                " outside the dense output's degrees 1..", Piece::max_degree);
  p.t0 = t_prev;
  p.t1 = tn;
  State dky;
  if (q >= 4) {
    p.t_ref = tn;
    p.h = h;
    p.degree = q;
    double scale = 1.0;  // h^j / j!
    for (int j = 0; j <= q; ++j) {
      session_.dky(tn, j, dky.data());
      p.c.col(j) = scale * dky;
      scale *= h / double(j + 1);
    }
    x_next_ = p.c.col(0);
    dx_next_ = p.c.col(1) / h;
  } else {
    session_.dky(tn, 0, x_next_.data());
    session_.dky(tn, 1, dx_next_.data());
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

template <Scene S>
bool CvodeIntegrator<S>::locate(ModeSystem<S>& sys, const Piece& piece, double t_prev, double t_root,
                                double simultaneity, SegmentEndOf<S>& end) {
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
    if (sys.guards()[k].kind == GuardKind::Touchdown && g_end < 0.0 && g_end >= -gap_tolerance_) {
      // Within the tolerance below zero: an event only if the contact approaches (guard_scan.hxx).
      xs = piece.value(t_step_end);
      std::array<double, ng> rates{};
      sys.guard_values(t_step_end, xs, gv, &rates);
      if (rates[k] >= 0.0) continue;
    }
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
  if (!std::isfinite(first)) return false;
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
  return true;
}

// ---- CvodeProblem (called by the session inside CVode; it stores what they throw) ----

template <Scene S>
void CvodeIntegrator<S>::rhs(double t, const double* x, double* xdot) {
  x_work_ = Eigen::Map<const State>(x);
  sys_->rhs(t, x_work_, xdot_work_);
  Eigen::Map<State>{xdot} = xdot_work_;
}

template <Scene S>
void CvodeIntegrator<S>::roots(double t, const double* x, double* g) {
  for (int k = 0; k < ng; ++k) g[k] = 1.0;  // unused slots never cross
  if (n_guards_ == 0) return;
  x_work_ = Eigen::Map<const State>(x);
  sys_->guard_values(t, x_work_, guard_work_);
  for (int k = 0; k < n_guards_; ++k) g[k] = guard_work_[k];
}

template <Scene S>
void CvodeIntegrator<S>::project(double, const double* x, double* correction, double* error) {
  const State before = Eigen::Map<const State>(x);
  State after = before;
  if (error) {
    State e = Eigen::Map<const State>(error);
    project_state(sys_->scene(), sys_->mode(), after, &e);
    Eigen::Map<State>{error} = e;
  } else {
    project_state(sys_->scene(), sys_->mode(), after, nullptr);
  }
  Eigen::Map<State>{correction} = after - before;
}

}  // namespace saltus
