// Construction of the refinement NLP: the grid from the guess, the initial-state check, the implied
// rows, the row layout, bounds, the initial point, the sparse structures and names.
#pragma once

#include <saltus/timefreezing/refinement/refinement_nlp_eval.hxx>

#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace saltus::timefreezing {

namespace detail {

/// ||g - K' c||_2 / ||g||_2 for the least-squares c (0 when g = 0): how far g is from the row space
/// of K (rows: the gradients already imposed).
inline double span_residual(const Eigen::MatrixXd& K, const Eigen::VectorXd& g) {
  const double norm = g.norm();
  if (norm == 0.0) return 0.0;
  if (K.rows() == 0) return 1.0;
  const Eigen::MatrixXd Kt = K.transpose();
  const Eigen::VectorXd c = Kt.completeOrthogonalDecomposition().solve(g);
  return (g - Kt * c).norm() / norm;
}

inline void append_row(Eigen::MatrixXd& K, const Eigen::VectorXd& g) {
  K.conservativeResize(K.rows() + 1, g.size());
  K.row(K.rows() - 1) = g.transpose();
}

}  // namespace detail

template <Scene S, class Ocp>
ScheduleRefinementNlp<S, Ocp>::ScheduleRefinementNlp(const S& scene, const Ocp& ocp, const OcpHorizon<S>& horizon,
                                                     const ScheduleGuess<S>& guess, const RefinementOptions& options)
    : scene_(scene),
      ocp_(ocp),
      horizon_(horizon),
      schedule_(validated(scene, guess.schedule)),
      options_(options),
      tableau_(radau_iia(options.grid.stages)) {
  validate_scene(scene);
  horizon.validate();
  options.validate();
  SALTUS_REQUIRE(guess.state && guess.input, "refinement: the guess needs a state and an input function");
  const int P = phase_count();
  SALTUS_REQUIRE(static_cast<int>(guess.event_times.size()) == P - 1, "refinement: ", P - 1,
                 " event times needed (one per event), got ", guess.event_times.size());
  double previous = horizon.initial_time;
  for (int b = 0; b + 1 < P; ++b) {
    const double t = guess.event_times[static_cast<std::size_t>(b)];
    SALTUS_REQUIRE(std::isfinite(t) && t >= previous && t <= horizon.final_time, "refinement: event ", b, " at t = ", t,
                   " is not finite, before the previous event (", previous, ") or after T = ", horizon.final_time);
    previous = t;
  }
  SALTUS_REQUIRE(options.grid.element_boundaries.empty() || static_cast<int>(options.grid.element_boundaries.size()) == P,
                 "refinement: grid.element_boundaries has ", options.grid.element_boundaries.size(),
                 " lists, the schedule ", P, " phases (one list per phase, or none)");
  check_initial_state();
  build_grid(guess);
  find_implied_phase_rows();
  restrict_event_ends();
  find_implied_guards();
  find_implied_terminal_rows();
  build_rows();
  build_structures();
}

template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::check_initial_state() const {
  const double tol = options_.initial_state_tolerance;
  const VecT<double, nq> q = horizon_.x0.template head<nq>(), v = horizon_.x0.template tail<nq>();
  Kinematics<S, double> kin;
  evaluate_kinematics<S, double>(scene_, q, v, kin);
  for (int i = 0; i < nc; ++i) {
    const auto& c = kin.contacts[i];
    const bool closed = schedule_.phases.front()[i].closed();
    SALTUS_REQUIRE(closed || c.gap >= -tol, "refinement: phase 0: the initial state penetrates open contact '",
                   scene_.contact(i).name, "' (gap ", c.gap, ")");
    SALTUS_REQUIRE(!closed || (std::abs(c.gap) <= tol && std::abs(c.zeta_n) <= tol), "refinement: phase 0: contact '",
                   scene_.contact(i).name, "' is closed in the first phase but the initial state has gap ", c.gap,
                   " and normal velocity ", c.zeta_n, " (both must be 0 within ", tol, ")");
  }
}

template <Scene S, class Ocp>
void ScheduleRefinementNlp<S, Ocp>::build_grid(const ScheduleGuess<S>& guess) {
  const int P = phase_count(), ns = tableau_.stages;
  std::vector<double> t(static_cast<std::size_t>(P + 1));
  t.front() = horizon_.initial_time;
  t.back() = horizon_.final_time;
  for (int b = 0; b + 1 < P; ++b) t[static_cast<std::size_t>(b + 1)] = guess.event_times[static_cast<std::size_t>(b)];
  for (int p = 0; p < P; ++p) {
    const double d = t[static_cast<std::size_t>(p + 1)] - t[static_cast<std::size_t>(p)];
    const std::vector<double>* given =
        options_.grid.element_boundaries.empty() ? nullptr : &options_.grid.element_boundaries[static_cast<std::size_t>(p)];
    const int N = given ? static_cast<int>(given->size()) - 1
                        : std::max(options_.grid.min_elements, int(std::ceil(d / options_.grid.max_element_duration - 1e-9)));
    phase_first_element_.push_back(static_cast<int>(element_phase_.size()));
    phase_elements_.push_back(N);
    if (given) {  // RefinementGrid::element_boundaries, held times N_p as the rule's fractions are
      for (int j = 0; j < N; ++j) {
        element_phase_.push_back(p);
        element_begin_scaled_.push_back(double(N) * (*given)[std::size_t(j)]);
        element_length_scaled_.push_back(double(N) * ((*given)[std::size_t(j + 1)] - (*given)[std::size_t(j)]));
      }
      validity_count_.push_back(count_validity(schedule_.phases[static_cast<std::size_t>(p)]));
      continue;
    }
    // N_p s_k and N_p (s_{k+1} - s_k) of RefinementGrid::end_clustering: exactly k and 1 when c = 0.
    const double c = options_.grid.end_clustering, pi = std::acos(-1.0);
    const auto chebyshev = [&](int k) { return 0.5 * double(N) * (1.0 - std::cos(pi * double(k) / double(N))); };
    for (int j = 0; j < N; ++j) {
      element_phase_.push_back(p);
      element_begin_scaled_.push_back((1.0 - c) * double(j) + c * chebyshev(j));
      element_length_scaled_.push_back((1.0 - c) + c * (chebyshev(j + 1) - chebyshev(j)));
    }
    validity_count_.push_back(count_validity(schedule_.phases[static_cast<std::size_t>(p)]));
  }
  element_base_ = P + 1 + P * nx;
  n_ = element_base_ + element_count() * (nu + ns * nx);
  guess_x_.setZero(n_);
  for (int p = 0; p <= P; ++p) guess_x_[time_index(p)] = t[static_cast<std::size_t>(p)];
  for (int p = 0; p < P; ++p) {
    const double t0 = t[static_cast<std::size_t>(p)], t1 = t[static_cast<std::size_t>(p + 1)];
    guess_x_.template segment<nx>(start_index(p)) = p == 0 ? horizon_.x0 : guess.state(p, t0);
    for (int e = first_element(p); e < first_element(p) + elements_in(p); ++e) {
      const double tm = t0 + (t1 - t0) * (element_begin_scaled_[std::size_t(e)] + 0.5 * element_length_scaled_[std::size_t(e)]) /
                                 double(elements_in(p));
      VecT<double, nu> u = guess.input(tm);
      for (int k = 0; k < nu; ++k) {
        if (horizon_.control_lower.size() == nu) u[k] = std::max(u[k], horizon_.control_lower[k]);
        if (horizon_.control_upper.size() == nu) u[k] = std::min(u[k], horizon_.control_upper[k]);
      }
      guess_x_.template segment<nu>(control_index(e)) = u;
      for (int r = 0; r < ns; ++r) guess_x_.template segment<nx>(stage_index(e, r)) = guess.state(p, t0 + (t1 - t0) * point_theta(e, r));
    }
  }
  for (int p = 0; p < P; ++p)
    SALTUS_REQUIRE(guess_x_.segment(start_index(p), nx).allFinite(), "refinement: the guess of phase ", p,
                   " is not finite at its start (t = ", t[static_cast<std::size_t>(p)], ")");
  for (int e = 0; e < element_count(); ++e)
    SALTUS_REQUIRE(guess_x_.segment(control_index(e), nu + ns * nx).allFinite(), "refinement: the guess of phase ",
                   phase_of(e), " is not finite (element ", e - first_element(phase_of(e)), ")");
}

template <Scene S, class Ocp>
int ScheduleRefinementNlp<S, Ocp>::count_validity_of(const Mode<nc>& mode, int i) const {
  if (!mode[i].closed()) return 1;
  return 1 + (scene_.contact(i).tangents() == 0 ? 0 : (mode[i].mode == ContactMode::Stick ? 2 : 1));
}

template <Scene S, class Ocp>
int ScheduleRefinementNlp<S, Ocp>::count_validity(const Mode<nc>& mode) const {
  int n = 0;
  for (int i = 0; i < nc; ++i) n += count_validity_of(mode, i);
  return n;
}

template <Scene S, class Ocp>
int ScheduleRefinementNlp<S, Ocp>::count_impulse_rows(const EventRows& ev) const {
  int n = 0;
  for (int i = 0; i < nc; ++i) {
    const ImpulseRole role = ev.impulse_mode[i].role;
    if (role == ImpulseRole::None) continue;
    n += 1 + (scene_.contact(i).tangents() == 0 ? 0 : (role == ImpulseRole::Stick ? 2 : 1));
  }
  return n;
}

}  // namespace saltus::timefreezing

#include <saltus/timefreezing/refinement/refinement_nlp_rows.hxx>
