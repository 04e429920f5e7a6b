// The evaluation callbacks of the refinement NLP: local vectors, the derivative caches, and the
// Jacobian and Hessian written by one walk each over the rows (structure and values in the same
// order by construction).
#pragma once

#include <saltus/timefreezing/refinement/refinement_nlp_blocks.hxx>

#include <algorithm>
#include <cmath>
#include <type_traits>

namespace saltus::timefreezing {

namespace detail {

/// value and Jacobian of y = f(w) by forward AD (N directions).
template <int N, int M, class F>
void local_jacobian(F&& f, const Eigen::Matrix<double, N, 1>& w, Eigen::Matrix<double, M, 1>& value,
                    Eigen::Matrix<double, M, N>& jacobian) {
  const VecT<Ad1<N>, N> wd = seed_first<N>(w);
  const VecT<Ad1<N>, M> y = f(wd);
  for (int i = 0; i < M; ++i) {
    value[i] = y[i].value();
    jacobian.row(i) = y[i].derivatives().transpose();
  }
}

/// H = sum_i weights_i d2 f_i / dw2 by forward-over-forward AD.
template <int N, int M, class F>
void local_hessian(F&& f, const Eigen::Matrix<double, N, 1>& w, const Eigen::Matrix<double, M, 1>& weights,
                   Eigen::Matrix<double, N, N>& hessian) {
  const VecT<Ad2<N>, N> wd = seed_second<N>(w);
  const VecT<Ad2<N>, M> y = f(wd);
  hessian.setZero();
  for (int i = 0; i < M; ++i) {
    if (weights[i] == 0.0) continue;
    for (int a = 0; a < N; ++a) hessian.row(a) += weights[i] * y[i].derivatives()[a].derivatives().transpose();
  }
}

}  // namespace detail

template <Scene S, class Ocp>
double ScheduleRefinementNlp<S, Ocp>::point_theta(int e, int r) const {
  const std::size_t k = static_cast<std::size_t>(e);
  return (element_begin_scaled_[k] + (r < 0 ? 0.0 : tableau_.c[r] * element_length_scaled_[k])) / double(elements_in(phase_of(e)));
}

template <Scene S, class Ocp>
int ScheduleRefinementNlp<S, Ocp>::element_start_index(int e) const {
  const int p = phase_of(e);
  return e == first_element(p) ? start_index(p) : stage_index(e - 1, tableau_.stages - 1);
}

template <Scene S, class Ocp>
const std::vector<int>& ScheduleRefinementNlp<S, Ocp>::imposed_validity(int e, int r) const {
  const int p = phase_of(e);
  const PhaseValidity& v = phase_validity_rows_[static_cast<std::size_t>(p)];
  if (r < 0 && e == first_element(p)) return v.at_start;
  if (r == tableau_.stages - 1 && e == first_element(p) + elements_in(p) - 1) return v.at_end;
  return v.interior;
}

template <Scene S, class Ocp>
int ScheduleRefinementNlp<S, Ocp>::validity_row(int e, int r, int k) const {
  const std::vector<int>& imposed = imposed_validity(e, r);
  const auto it = std::find(imposed.begin(), imposed.end(), k);
  if (it == imposed.end()) return -1;
  return point_row(e, r) + validity_offset_in_rows(r) + static_cast<int>(it - imposed.begin());
}

template <Scene S, class Ocp>
VecT<double, ScheduleRefinementNlp<S, Ocp>::nw> ScheduleRefinementNlp<S, Ocp>::point_local(
    const Eigen::Ref<const Eigen::VectorXd>& x, int e, int r) const {
  VecT<double, nw> w;
  const int p = phase_of(e);
  w << x.template segment<nx>(point_state_index(e, r)), x.template segment<nu>(control_index(e)), x[time_index(p)],
      x[time_index(p + 1)];
  return w;
}

template <Scene S, class Ocp>
int ScheduleRefinementNlp<S, Ocp>::point_global(int e, int r, int a) const {
  if (a < nx) return point_state_index(e, r) + a;
  if (a < nx + nu) return control_index(e) + (a - nx);
  return time_index(phase_of(e) + (a - nx - nu));
}

template <Scene S, class Ocp>
VecT<double, ScheduleRefinementNlp<S, Ocp>::nwe> ScheduleRefinementNlp<S, Ocp>::event_local(
    const Eigen::Ref<const Eigen::VectorXd>& x, int b) const {
  VecT<double, nwe> w;
  const int last = first_element(b) + elements_in(b) - 1;
  w << x.template segment<nx>(phase_end_index(b)), x.template segment<nu>(control_index(last)), x[time_index(b + 1)];
  return w;
}

template <Scene S, class Ocp>
int ScheduleRefinementNlp<S, Ocp>::event_global(int b, int a) const {
  if (a < nx) return phase_end_index(b) + a;
  if (a < nx + nu) return control_index(first_element(b) + elements_in(b) - 1) + (a - nx);
  return time_index(b + 1);
}

template <Scene S, class Ocp>
VecT<double, ScheduleRefinementNlp<S, Ocp>::nwt> ScheduleRefinementNlp<S, Ocp>::terminal_local(
    const Eigen::Ref<const Eigen::VectorXd>& x) const {
  VecT<double, nwt> w;
  w << x.template segment<nx>(phase_end_index(phase_count() - 1)), x[time_index(phase_count())];
  return w;
}

template <Scene S, class Ocp>
int ScheduleRefinementNlp<S, Ocp>::terminal_global(int a) const {
  return a < nx ? phase_end_index(phase_count() - 1) + a : time_index(phase_count());
}

template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::update(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  if (cache_valid_ && cached_x_.size() == x.size() && cached_x_ == x) return;
  thread_local FlowWorkspace<S, detail::Ad1<nw>> stage_ws;
  thread_local FlowWorkspace<S, detail::Ad1<nwe>> event_ws;
  thread_local JumpWorkspace<S, detail::Ad1<nwe>> jump_ws;
  for (int e = 0; e < element_count(); ++e)
    for (int r = -1; r < tableau_.stages; ++r) {
      const double theta = point_theta(e, r);
      detail::local_jacobian<nw, stage_outputs>([&](const auto& w) { return stage_block(e, theta, w, stage_ws); },
                                                point_local(x, e, r), point_value_[point_slot(e, r)],
                                                point_jacobian_[point_slot(e, r)]);
    }
  for (int b = 0; b + 1 < phase_count(); ++b)
    detail::local_jacobian<nwe, event_outputs>([&](const auto& w) { return event_block(b, w, event_ws, jump_ws); },
                                               event_local(x, b), event_value_[static_cast<std::size_t>(b)],
                                               event_jacobian_[static_cast<std::size_t>(b)]);
  detail::local_jacobian<nwt, terminal_outputs>([&](const auto& w) { return terminal_block(w); }, terminal_local(x),
                                                terminal_value_, terminal_jacobian_);
  cached_x_ = x;
  cache_valid_ = true;
}

template <Scene S, class Ocp>
double ScheduleRefinementNlp<S, Ocp>::objective(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  update(x);
  double f = terminal_value_[nt];
  for (int e = 0; e < element_count(); ++e)
    for (int l = 0; l < tableau_.stages; ++l) f += tableau_.b[l] * point_value_[point_slot(e, l)][nx];
  return f;
}

template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                                                       Eigen::Ref<Eigen::VectorXd> gradient) const {
  update(x);
  gradient.setZero();
  for (int e = 0; e < element_count(); ++e)
    for (int l = 0; l < tableau_.stages; ++l)
      for (int a = 0; a < nw; ++a) gradient[point_global(e, l, a)] += tableau_.b[l] * point_jacobian_[point_slot(e, l)](nx, a);
  for (int a = 0; a < nwt; ++a) gradient[terminal_global(a)] += terminal_jacobian_(nt, a);
}

template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::constraints(const Eigen::Ref<const Eigen::VectorXd>& x,
                                                Eigen::Ref<Eigen::VectorXd> g) const {
  update(x);
  const int ns = tableau_.stages;
  for (int e = 0; e < element_count(); ++e) {
    const int p = phase_of(e);
    const std::vector<int>& path = imposed_path_rows(p);
    for (int r = -1; r < ns; ++r) {
      const std::vector<int>& validity = imposed_validity(e, r);
      int row = point_row(e, r);
      const auto& phi = point_value_[point_slot(e, r)];
      if (r >= 0)
        for (int i = 0; i < nx; ++i, ++row) {
          double s = x[stage_index(e, r) + i] - x[element_start_index(e) + i];
          for (int l = 0; l < ns; ++l) s -= tableau_.a(r, l) * point_value_[point_slot(e, l)][i];
          g[row] = s;
        }
      for (int k : validity) g[row++] = phi[nx + 1 + k];
      if (r >= 0)
        for (int k : path) g[row++] = phi[nx + 1 + max_validity + k];
    }
  }
  for (int b = 0; b + 1 < phase_count(); ++b) {
    const EventRows& ev = events_[static_cast<std::size_t>(b)];
    const auto& phi = event_value_[static_cast<std::size_t>(b)];
    int row = ev.first_row;
    for (std::size_t k = 0; k < ev.imposed_guards.size() + ev.released_sticking.size(); ++k) g[row++] = phi[static_cast<int>(k)];
    for (std::size_t k = 0; k < ev.approach_contacts.size(); ++k) g[row++] = phi[2 * nc + static_cast<int>(k)];
    for (int i = 0; i < nx; ++i) g[row++] = x[start_index(b + 1) + i] - phi[3 * nc + i];
    for (int k = 0; k < ev.impulse_rows; ++k) g[row++] = phi[3 * nc + nx + k];
    for (std::size_t k = 0; k < ev.separating_contacts.size(); ++k) g[row++] = phi[6 * nc + nx + static_cast<int>(k)];
  }
  for (int p = 0; p < phase_count(); ++p) g[duration_row_ + p] = x[time_index(p + 1)] - x[time_index(p)];
  for (std::size_t j = 0; j < imposed_terminal_rows_.size(); ++j)
    g[terminal_row_ + static_cast<int>(j)] = terminal_value_[imposed_terminal_rows_[j]];
}

/// emit(row, column, value) for every Jacobian entry, in a fixed order (values from the caches:
/// zeros before the first update, which is how the structure is walked).
template <Scene S, class Ocp>
template <class Emit>
void ScheduleRefinementNlp<S, Ocp>::walk_jacobian(Emit&& emit) const {
  const int ns = tableau_.stages;
  for (int e = 0; e < element_count(); ++e) {
    const int p = phase_of(e);
    for (int r = -1; r < ns; ++r) {
      int row = point_row(e, r);
      const auto& jr = point_jacobian_[point_slot(e, r)];
      if (r >= 0)
        for (int i = 0; i < nx; ++i, ++row) {
          emit(row, stage_index(e, r) + i, 1.0);
          emit(row, element_start_index(e) + i, -1.0);
          for (int l = 0; l < ns; ++l)
            for (int a = 0; a < nw; ++a) emit(row, point_global(e, l, a), -tableau_.a(r, l) * point_jacobian_[point_slot(e, l)](i, a));
        }
      for (int k : imposed_validity(e, r)) {
        for (int a = 0; a < nw; ++a) emit(row, point_global(e, r, a), jr(nx + 1 + k, a));
        ++row;
      }
      if (r >= 0)
        for (int k : imposed_path_rows(p)) {
          for (int a = 0; a < nw; ++a) emit(row, point_global(e, r, a), jr(nx + 1 + max_validity + k, a));
          ++row;
        }
    }
  }
  for (int b = 0; b + 1 < phase_count(); ++b) {
    const EventRows& ev = events_[static_cast<std::size_t>(b)];
    const auto& jb = event_jacobian_[static_cast<std::size_t>(b)];
    int row = ev.first_row;
    const auto rows_from = [&](int first_output, int count, double sign) {
      for (int k = 0; k < count; ++k, ++row)
        for (int a = 0; a < nwe; ++a) emit(row, event_global(b, a), sign * jb(first_output + k, a));
    };
    rows_from(0, static_cast<int>(ev.imposed_guards.size() + ev.released_sticking.size()), 1.0);
    rows_from(2 * nc, static_cast<int>(ev.approach_contacts.size()), 1.0);
    for (int i = 0; i < nx; ++i) emit(row + i, start_index(b + 1) + i, 1.0);
    rows_from(3 * nc, nx, -1.0);
    rows_from(3 * nc + nx, ev.impulse_rows, 1.0);
    rows_from(6 * nc + nx, static_cast<int>(ev.separating_contacts.size()), 1.0);
  }
  for (int p = 0; p < phase_count(); ++p) {
    emit(duration_row_ + p, time_index(p + 1), 1.0);
    emit(duration_row_ + p, time_index(p), -1.0);
  }
  for (std::size_t j = 0; j < imposed_terminal_rows_.size(); ++j)
    for (int a = 0; a < nwt; ++a)
      emit(terminal_row_ + static_cast<int>(j), terminal_global(a), terminal_jacobian_(imposed_terminal_rows_[j], a));
}

template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::jacobian_values(const Eigen::Ref<const Eigen::VectorXd>& x,
                                                    Eigen::Ref<Eigen::VectorXd> values) const {
  update(x);
  Eigen::Index k = 0;
  walk_jacobian([&](int, int, double v) { values[k++] = v; });
}

/// The weights of point (e, l)'s outputs in the Lagrangian sigma f + lambda' g.
template <Scene S, class Ocp>
VecT<double, ScheduleRefinementNlp<S, Ocp>::stage_outputs> ScheduleRefinementNlp<S, Ocp>::point_weights(
    int e, int l, double sigma, const Eigen::Ref<const Eigen::VectorXd>& lambda) const {
  VecT<double, stage_outputs> weight = VecT<double, stage_outputs>::Zero();
  const int p = phase_of(e), ns = tableau_.stages;
  int row = point_row(e, l);
  if (l >= 0) {
    for (int i = 0; i < nx; ++i)
      for (int r = 0; r < ns; ++r) weight[i] -= tableau_.a(r, l) * lambda[point_row(e, r) + i];
    weight[nx] = sigma * tableau_.b[l];
    row += nx;
  }
  for (int k : imposed_validity(e, l)) weight[nx + 1 + k] = lambda[row++];
  if (l >= 0)
    for (int k : imposed_path_rows(p)) weight[nx + 1 + max_validity + k] = lambda[row++];
  return weight;
}

/// The weights of event b's outputs in the Lagrangian.
template <Scene S, class Ocp>
VecT<double, ScheduleRefinementNlp<S, Ocp>::event_outputs> ScheduleRefinementNlp<S, Ocp>::event_weights(
    int b, const Eigen::Ref<const Eigen::VectorXd>& lambda) const {
  const EventRows& ev = events_[static_cast<std::size_t>(b)];
  VecT<double, event_outputs> weight = VecT<double, event_outputs>::Zero();
  int row = ev.first_row;
  for (std::size_t k = 0; k < ev.imposed_guards.size() + ev.released_sticking.size(); ++k)
    weight[static_cast<int>(k)] = lambda[row++];
  for (std::size_t k = 0; k < ev.approach_contacts.size(); ++k) weight[2 * nc + static_cast<int>(k)] = lambda[row++];
  for (int i = 0; i < nx; ++i) weight[3 * nc + i] = -lambda[row++];
  for (int k = 0; k < ev.impulse_rows; ++k) weight[3 * nc + nx + k] = lambda[row++];
  for (std::size_t k = 0; k < ev.separating_contacts.size(); ++k) weight[6 * nc + nx + static_cast<int>(k)] = lambda[row++];
  return weight;
}

/// emit(row, column, value) for every lower-triangle Hessian entry of the blocks, in a fixed order.
/// With lambda empty (size 0), the structure walk: no AD, zero values.
template <Scene S, class Ocp>
template <class Emit>
void ScheduleRefinementNlp<S, Ocp>::walk_hessian(const Eigen::Ref<const Eigen::VectorXd>& x, double sigma,
                                                 const Eigen::Ref<const Eigen::VectorXd>& lambda, Emit&& emit) const {
  const bool values = lambda.size() > 0;
  [[maybe_unused]] thread_local std::conditional_t<stages_time_invariant, int, FlowWorkspace<S, detail::Ad2<nw>>> stage_ws;
  thread_local FlowWorkspace<S, detail::Ad2<nwe>> event_ws;
  thread_local JumpWorkspace<S, detail::Ad2<nwe>> jump_ws;
  const auto emit_lower = [&](const auto& H, const auto& global) {
    for (int a = 0; a < H.rows(); ++a)
      for (int c = 0; c <= a; ++c) {
        const int ga = global(a), gc = global(c);
        emit(std::max(ga, gc), std::min(ga, gc), H(a, c));
      }
  };
  MatT<double, nw, nw> Hs = MatT<double, nw, nw>::Zero();
  for (int e = 0; e < element_count(); ++e)
    for (int l = -1; l < tableau_.stages; ++l) {
      if (values) {
        const double theta = point_theta(e, l);
        if constexpr (stages_time_invariant)
          stage_hessian(e, theta, point_local(x, e, l), point_weights(e, l, sigma, lambda), Hs);
        else
          detail::local_hessian<nw, stage_outputs>([&](const auto& w) { return stage_block(e, theta, w, stage_ws); },
                                                   point_local(x, e, l), point_weights(e, l, sigma, lambda), Hs);
      }
      emit_lower(Hs, [&](int a) { return point_global(e, l, a); });
    }
  MatT<double, nwe, nwe> He = MatT<double, nwe, nwe>::Zero();
  for (int b = 0; b + 1 < phase_count(); ++b) {
    if (values)
      detail::local_hessian<nwe, event_outputs>([&](const auto& w) { return event_block(b, w, event_ws, jump_ws); },
                                                event_local(x, b), event_weights(b, lambda), He);
    emit_lower(He, [&](int a) { return event_global(b, a); });
  }
  MatT<double, nwt, nwt> Ht = MatT<double, nwt, nwt>::Zero();
  if (values) {
    VecT<double, terminal_outputs> weight = VecT<double, terminal_outputs>::Zero();
    for (std::size_t j = 0; j < imposed_terminal_rows_.size(); ++j)
      weight[imposed_terminal_rows_[j]] = lambda[terminal_row_ + static_cast<int>(j)];
    weight[nt] = sigma;
    detail::local_hessian<nwt, terminal_outputs>([&](const auto& w) { return terminal_block(w); }, terminal_local(x),
                                                 weight, Ht);
  }
  emit_lower(Ht, [&](int a) { return terminal_global(a); });
}

template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::stage_hessian(int e, double theta, const VecT<double, nw>& w,
                                                  const VecT<double, stage_outputs>& weight,
                                                  MatT<double, nw, nw>& hessian) const {
  constexpr int nz = nx + nu;
  using A2 = detail::Ad2<nz>;
  thread_local FlowWorkspace<S, A2> ws;
  const double dh_dt = element_length_scaled_[static_cast<std::size_t>(e)] / double(elements_in(phase_of(e)));
  const double h = (w[nz + 1] - w[nz]) * dh_dt, t = w[nz] + theta * (w[nz + 1] - w[nz]);
  const VecT<A2, nz> z = detail::seed_second<nz>(VecT<double, nz>(w.template head<nz>()));
  const VecT<A2, stage_outputs> y = stage_values<A2>(e, theta, VecT<A2, nx>(z.template head<nx>()),
                                                     VecT<A2, nu>(z.template tail<nu>()), A2(1.0), A2(t), ws);
  hessian.setZero();
  VecT<double, nz> gradient_a = VecT<double, nz>::Zero();  // A' (the outputs scaled by h, at h = 1)
  for (int k = 0; k < stage_outputs; ++k) {
    if (weight[k] == 0.0) continue;
    const bool scaled = k <= nx;
    for (int a = 0; a < nz; ++a)
      hessian.row(a).template head<nz>() += (scaled ? h : 1.0) * weight[k] * y[k].derivatives()[a].derivatives().transpose();
    if (scaled) gradient_a += weight[k] * y[k].value().derivatives();
  }
  hessian.template block<nz, 1>(0, nz) = -dh_dt * gradient_a;
  hessian.template block<nz, 1>(0, nz + 1) = dh_dt * gradient_a;
  hessian.template block<1, nz>(nz, 0) = -dh_dt * gradient_a.transpose();
  hessian.template block<1, nz>(nz + 1, 0) = dh_dt * gradient_a.transpose();
}

template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::hessian_values(const Eigen::Ref<const Eigen::VectorXd>& x, double objective_factor,
                                                   const Eigen::Ref<const Eigen::VectorXd>& multipliers,
                                                   Eigen::Ref<Eigen::VectorXd> values) const {
  Eigen::Index k = 0;
  walk_hessian(x, objective_factor, multipliers, [&](int, int, double v) { values[k++] = v; });
}

}  // namespace saltus::timefreezing
