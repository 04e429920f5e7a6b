// Readings of a refinement NLP's point: mode validity, path and terminal violations, forces,
// impulses, inputs.
#pragma once

#include <saltus/timefreezing/refinement/refinement_nlp_rows.hxx>

#include <limits>

namespace saltus::timefreezing {

inline void RefinementOptions::validate() const {
  // The refined trajectory holds each element's collocation polynomial (degree n_s) as one dense-output piece.
  constexpr int max_stages = PolynomialPiece<1>::max_degree;
  SALTUS_REQUIRE(grid.stages >= 1 && grid.stages <= max_stages, "refinement: grid.stages must be in 1 .. ", max_stages,
                 " (the refined trajectory's dense output holds polynomials of degree <= ", max_stages, "), got ",
                 grid.stages);
  SALTUS_REQUIRE(std::isfinite(grid.max_element_duration) && grid.max_element_duration > 0.0,
                 "refinement: grid.max_element_duration must be finite and > 0, got ", grid.max_element_duration);
  SALTUS_REQUIRE(grid.min_elements >= 1, "refinement: grid.min_elements must be >= 1, got ", grid.min_elements);
  SALTUS_REQUIRE(grid.end_clustering >= 0.0 && grid.end_clustering <= 1.0,
                 "refinement: grid.end_clustering must be in [0, 1], got ", grid.end_clustering);
  for (std::size_t p = 0; p < grid.element_boundaries.size(); ++p) {
    const std::vector<double>& s = grid.element_boundaries[p];
    bool increasing = s.size() >= 2 && s.front() == 0.0 && s.back() == 1.0;
    for (std::size_t k = 1; increasing && k < s.size(); ++k) increasing = std::isfinite(s[k]) && s[k] > s[k - 1];
    SALTUS_REQUIRE(increasing, "refinement: grid.element_boundaries of phase ", p,
                   " must increase strictly from 0 to 1 (at least one element), got ", s.size(), " values");
  }
  SALTUS_REQUIRE(std::isfinite(mesh.local_error_tolerance) && mesh.local_error_tolerance >= 0.0,
                 "refinement: mesh.local_error_tolerance must be >= 0, got ", mesh.local_error_tolerance);
  SALTUS_REQUIRE(mesh.max_rounds >= 0, "refinement: mesh.max_rounds must be >= 0, got ", mesh.max_rounds);
  SALTUS_REQUIRE(mesh.max_iter >= 0, "refinement: mesh.max_iter must be >= 0, got ", mesh.max_iter);
  SALTUS_REQUIRE(mesh.max_split >= 2, "refinement: mesh.max_split must be >= 2, got ", mesh.max_split);
  SALTUS_REQUIRE(mesh.safety > 0.0 && mesh.safety <= 1.0, "refinement: mesh.safety must lie in (0, 1], got ", mesh.safety);
  SALTUS_REQUIRE(std::isfinite(mesh.warm_start_mu) && mesh.warm_start_mu > 0.0,
                 "refinement: mesh.warm_start_mu must be > 0, got ", mesh.warm_start_mu);
  SALTUS_REQUIRE(mesh.dual_warm_start_split_fraction >= 0.0 && mesh.dual_warm_start_split_fraction <= 1.0,
                 "refinement: mesh.dual_warm_start_split_fraction must lie in [0, 1], got ",
                 mesh.dual_warm_start_split_fraction);
  SALTUS_REQUIRE(std::isfinite(mesh.dual_warm_start_mu) && mesh.dual_warm_start_mu > 0.0,
                 "refinement: mesh.dual_warm_start_mu must be > 0, got ", mesh.dual_warm_start_mu);
  SALTUS_REQUIRE(std::isfinite(ipopt.tol) && ipopt.tol > 0.0, "refinement: ipopt.tol must be > 0, got ", ipopt.tol);
  SALTUS_REQUIRE(ipopt.max_iter >= 0, "refinement: ipopt.max_iter must be >= 0, got ", ipopt.max_iter);
  SALTUS_REQUIRE(edits.max_edits >= 0, "refinement: edits.max_edits must be >= 0, got ", edits.max_edits);
  SALTUS_REQUIRE(edits.max_iter >= 0, "refinement: edits.max_iter must be >= 0, got ", edits.max_iter);
  SALTUS_REQUIRE(std::isfinite(edits.active_tolerance) && edits.active_tolerance >= 0.0,
                 "refinement: edits.active_tolerance must be >= 0, got ", edits.active_tolerance);
  SALTUS_REQUIRE(std::isfinite(edits.multiplier_threshold) && edits.multiplier_threshold >= 0.0,
                 "refinement: edits.multiplier_threshold must be >= 0, got ", edits.multiplier_threshold);
  SALTUS_REQUIRE(std::isfinite(edits.vanishing_duration) && edits.vanishing_duration >= 0.0,
                 "refinement: edits.vanishing_duration must be >= 0, got ", edits.vanishing_duration);
  SALTUS_REQUIRE(std::isfinite(min_phase_duration) && min_phase_duration >= 0.0,
                 "refinement: min_phase_duration must be >= 0, got ", min_phase_duration);
  SALTUS_REQUIRE(stick_cone_margin >= 0.0 && stick_cone_margin < 1.0,
                 "refinement: stick_cone_margin must lie in [0, 1), got ", stick_cone_margin);
  SALTUS_REQUIRE(std::isfinite(slip_speed_margin) && slip_speed_margin >= 0.0,
                 "refinement: slip_speed_margin must be finite and >= 0 [m/s], got ", slip_speed_margin);
  SALTUS_REQUIRE(std::isfinite(normal_force_margin) && normal_force_margin >= 0.0,
                 "refinement: normal_force_margin must be finite and >= 0 [N], got ", normal_force_margin);
  SALTUS_REQUIRE(std::isfinite(stance_load) && stance_load >= 0.0,
                 "refinement: stance_load must be finite and >= 0 [N], got ", stance_load);
  SALTUS_REQUIRE(std::isfinite(touchdown_load) && touchdown_load >= 0.0,
                 "refinement: touchdown_load must be finite and >= 0 [N], got ", touchdown_load);
  SALTUS_REQUIRE(std::isfinite(touchdown_speed) && touchdown_speed >= 0.0,
                 "refinement: touchdown_speed must be finite and >= 0 [m/s], got ", touchdown_speed);
  SALTUS_REQUIRE(std::isfinite(flight_clearance) && flight_clearance >= 0.0,
                 "refinement: flight_clearance must be finite and >= 0 [m], got ", flight_clearance);
  SALTUS_REQUIRE(std::isfinite(contact_stabilisation) && contact_stabilisation >= 0.0,
                 "refinement: contact_stabilisation must be finite and >= 0 [1/s], got ", contact_stabilisation);
  SALTUS_REQUIRE(implied_row_tolerance > 0.0 && implied_row_tolerance < 1.0,
                 "refinement: implied_row_tolerance must lie in (0, 1), got ", implied_row_tolerance);
  SALTUS_REQUIRE(std::isfinite(implied_terminal_value_tolerance) && implied_terminal_value_tolerance > 0.0,
                 "refinement: implied_terminal_value_tolerance must be > 0, got ", implied_terminal_value_tolerance);
  SALTUS_REQUIRE(std::isfinite(checks.mode_validity) && checks.mode_validity >= 0.0,
                 "refinement: checks.mode_validity must be >= 0, got ", checks.mode_validity);
  SALTUS_REQUIRE(std::isfinite(checks.phase_resimulation) && checks.phase_resimulation >= 0.0,
                 "refinement: checks.phase_resimulation must be >= 0, got ", checks.phase_resimulation);
  SALTUS_REQUIRE(std::isfinite(checks.resimulation_window) && checks.resimulation_window >= 0.0,
                 "refinement: checks.resimulation_window must be >= 0 [s], got ", checks.resimulation_window);
  SALTUS_REQUIRE(std::isfinite(initial_state_tolerance) && initial_state_tolerance >= 0.0,
                 "refinement: initial_state_tolerance must be >= 0, got ", initial_state_tolerance);
}

template <Scene S, class Ocp>
std::vector<double> ScheduleRefinementNlp<S, Ocp>::validity_values(const Eigen::Ref<const Eigen::VectorXd>& x, int e,
                                                                   int r) const {
  update(x);
  const auto& phi = point_value_[point_slot(e, r)];
  const int nv = validity_count(phase_of(e));
  return std::vector<double>(phi.data() + nx + 1, phi.data() + nx + 1 + nv);
}

template <Scene S, class Ocp>
double ScheduleRefinementNlp<S, Ocp>::mode_validity_violation(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  update(x);
  double worst = 0.0;
  for (int e = 0; e < element_count(); ++e)
    for (int r = -1; r < tableau_.stages; ++r) {
      const std::vector<double> v = validity_values(x, e, r);
      if (r >= 0)  // a collocation point: every condition of the mode, implied or imposed
        for (double value : v) worst = std::max(worst, -value);
      else  // an element's start under its input: the conditions imposed there
        for (int k : imposed_validity(e, r)) worst = std::max(worst, -v[static_cast<std::size_t>(k)]);
    }
  for (std::size_t b = 0; b < events_.size(); ++b) {
    const EventRows& ev = events_[b];
    const auto& phi = event_value_[b];
    for (std::size_t k = 0; k < ev.approach_contacts.size(); ++k)
      worst = std::max(worst, phi[2 * nc + static_cast<int>(k)] + options_.touchdown_speed);
    for (int k = 0; k < ev.impulse_rows; ++k) worst = std::max(worst, -phi[3 * nc + nx + k]);
    for (std::size_t k = 0; k < ev.separating_contacts.size(); ++k)
      worst = std::max(worst, -phi[6 * nc + nx + static_cast<int>(k)]);
  }
  return worst;
}

template <Scene S, class Ocp>
double ScheduleRefinementNlp<S, Ocp>::contact_drift(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  double worst = 0.0;
  Kinematics<S, double> kin;
  for (int e = 0; e < element_count(); ++e) {
    const Mode<nc>& mode = schedule_.phases[static_cast<std::size_t>(phase_of(e))];
    for (int r = -1; r < tableau_.stages; ++r) {
      const VecT<double, nx> xs = x.template segment<nx>(point_state_index(e, r));
      evaluate_kinematics<S, double>(scene_, VecT<double, nq>(xs.template head<nq>()), VecT<double, nq>(xs.template tail<nq>()), kin);
      for (int i = 0; i < nc; ++i)
        if (mode[i].closed()) worst = std::max({worst, std::abs(kin.contacts[i].gap), std::abs(kin.contacts[i].zeta_n)});
    }
  }
  return worst;
}

template <Scene S, class Ocp>
double ScheduleRefinementNlp<S, Ocp>::path_violation(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  double worst = 0.0;
  if constexpr (np > 0) {
    update(x);
    const VecT<double, np> lo = ocp_.path_lower(), hi = ocp_.path_upper();
    for (const auto& phi : point_value_)
      for (int k = 0; k < np; ++k) {
        const double v = phi[nx + 1 + max_validity + k];
        worst = std::max({worst, lo[k] - v, v - hi[k]});
      }
  }
  return worst;
}

template <Scene S, class Ocp>
double ScheduleRefinementNlp<S, Ocp>::terminal_violation(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  double worst = 0.0;
  if constexpr (nt > 0) {
    update(x);
    const VecT<double, nt> lo = ocp_.terminal_lower(), hi = ocp_.terminal_upper();
    for (int k = 0; k < nt; ++k) worst = std::max({worst, lo[k] - terminal_value_[k], terminal_value_[k] - hi[k]});
  }
  return worst;
}

template <Scene S, class Ocp>
VecT<double, S::nu> ScheduleRefinementNlp<S, Ocp>::applied_input(const Eigen::Ref<const Eigen::VectorXd>& x, int e) const {
  const int p = phase_of(e);
  const double t = element_start_time(e, x[time_index(p)], x[time_index(p + 1)]);
  return input_law<double>(t, VecT<double, nu>(x.template segment<nu>(control_index(e))));
}

template <Scene S, class Ocp>
std::array<ContactForce<double>, S::nc> ScheduleRefinementNlp<S, Ocp>::contact_forces(
    const Eigen::Ref<const Eigen::VectorXd>& x, int e, int r) const {
  FlowWorkspace<S, double> ws;
  (void)stage_block<double>(e, point_theta(e, r), point_local(x, e, r), ws);
  return ws.force;
}

template <Scene S, class Ocp>
std::array<ContactForce<double>, S::nc> ScheduleRefinementNlp<S, Ocp>::impulses(const Eigen::Ref<const Eigen::VectorXd>& x,
                                                                               int b) const {
  std::array<ContactForce<double>, nc> out{};
  if (!events_[static_cast<std::size_t>(b)].impact) return out;
  FlowWorkspace<S, double> fws;
  JumpWorkspace<S, double> jws;
  (void)event_block<double>(b, event_local(x, b), fws, jws);
  return jws.impulse;
}

template <Scene S, class Ocp>
std::vector<double> ScheduleRefinementNlp<S, Ocp>::element_local_errors(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  std::vector<double> out(static_cast<std::size_t>(element_count()), 0.0);
  FlowWorkspace<S, double> ws;
  ws.constraint_stabilisation = options_.contact_stabilisation;  // the phases' flow, as the collocation's
  for (int e = 0; e < element_count(); ++e) {
    const int p = phase_of(e);
    const Mode<nc>& mode = schedule_.phases[static_cast<std::size_t>(p)];
    const double t_p = x[time_index(p)], t_q = x[time_index(p + 1)];
    const double h = (t_q - t_p) * element_length_scaled_[std::size_t(e)] / double(elements_in(p));
    if (!(h > 0.0)) continue;
    const double t_a = element_start_time(e, t_p, t_q);
    const VecT<double, nu> decision = x.template segment<nu>(control_index(e));
    const VecT<double, nx> start = x.template segment<nx>(element_start_index(e));
    const VecT<double, nx> end = x.template segment<nx>(stage_index(e, tableau_.stages - 1));
    const auto f = [&](double t, const VecT<double, nx>& y) {
      evaluate_flow<S, double>(scene_, mode, y, input_law<double>(t, decision), ws);
      return VecT<double, nx>(ws.xdot);
    };
    // classical Runge-Kutta, `steps` equal steps over the element; false where the flow fails
    // (a step into a singular or non-finite state: the element's motion is far from its flow)
    const auto rk4 = [&](int steps, VecT<double, nx>& y) {
      y = start;
      const double dt = h / steps;
      try {
        for (int k = 0; k < steps; ++k) {
          const double t = t_a + dt * k;
          const VecT<double, nx> k1 = f(t, y), k2 = f(t + dt / 2, y + dt / 2 * k1), k3 = f(t + dt / 2, y + dt / 2 * k2),
                                 k4 = f(t + dt, y + dt * k3);
          y += dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
        }
      } catch (const NumericalFailure&) {
        return false;
      }
      return y.allFinite();
    };
    // step doubling from 8 steps until two successive results agree to 1 % of the error (Richardson);
    // no two successive results up to 8192 steps: the error is reported as infinite
    out[std::size_t(e)] = std::numeric_limits<double>::infinity();
    VecT<double, nx> coarse, fine;
    bool have_coarse = false;
    for (int steps = 8; steps <= 8192; steps *= 2) {
      if (!rk4(steps, fine)) {
        have_coarse = false;
        continue;
      }
      if (have_coarse) {
        const double estimate = (fine - coarse).cwiseAbs().maxCoeff() / 15.0;  // of `fine` (order 4)
        out[std::size_t(e)] = (fine + (fine - coarse) / 15.0 - end).cwiseAbs().maxCoeff();
        if (estimate <= std::max(1e-2 * (fine - end).cwiseAbs().maxCoeff(), 1e-13)) break;
      }
      coarse = fine;
      have_coarse = true;
    }
  }
  return out;
}

}  // namespace saltus::timefreezing
