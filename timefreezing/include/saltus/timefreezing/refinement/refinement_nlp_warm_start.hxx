// The dual warm start of a mesh round (RefinementMesh::dual_warm_start_split_fraction): the
// multipliers of the previous grid's solution carried over to a grid that refines it.
//
// Every element e' of the finer grid lies in one element e of the coarser grid of the same phase
// (split_elements cuts elements, it never moves a boundary), a fraction rho = L_e' / L_e of it.
// For Radau IIA collocation the multipliers behave as follows (the discrete adjoint: stationarity
// of the Lagrangian in the stage states; Hager 2000 for Runge-Kutta, the same algebra here):
//   - the collocation rows of an element's LAST stage carry the costate, lambda_{e,s} ~ p(t_e+h):
//     it is the next element's start state, so its row's multiplier is, up to O(h), the sum of the
//     next element's collocation multipliers: O(1) and independent of h;
//   - the rows of the other stages carry h b_r (f_x' p - l_x), O(h);
//   - a validity or path row at a stage point is a quadrature node of a distributed multiplier,
//     h b_r nu(t), O(h); an input's bound multiplier integrates over the element, O(h);
//   - the rows at an element's start point (the validity under the element's input) and the event,
//     duration and terminal rows are point conditions, O(1).
// So a child e' takes its parent's last-stage collocation multipliers as they are (the costate at
// the parent's end: first-order accurate over the parent), its other stage rows and its input's
// bound multipliers times rho, its start rows only when it starts where its parent starts (a child
// that starts inside its parent has start rows the coarser grid did not have: they start at 0,
// though the finer solution may hold them active), and the
// event, duration and terminal rows and the time and phase-start bounds as they are. A row the two
// grids do not share (a validity row imposed on one grid only: a phase's end rows moved to the last
// child) starts at 0. The transfer needs the same schedule and the same event and terminal rows
// (the implied rows are decided from the guess and may differ): otherwise there is none, and the
// round starts from the primal guess alone.
#pragma once

#include <saltus/timefreezing/refinement/refinement_nlp_build.hxx>

#include <cmath>
#include <optional>

namespace saltus::timefreezing {

template <Scene S, class Ocp>
int ScheduleRefinementNlp<S, Ocp>::parent_element(const ScheduleRefinementNlp& coarser, int e) const {
  const int p = phase_of(e);
  const double middle = element_begin_fraction(e) + 0.5 * element_length_fraction(e);
  const int first = coarser.first_element(p), last = first + coarser.elements_in(p) - 1;
  for (int c = first; c < last; ++c)
    if (middle < coarser.element_begin_fraction(c) + coarser.element_length_fraction(c)) return c;
  return last;
}

template <Scene S, class Ocp>
bool ScheduleRefinementNlp<S, Ocp>::shares_point_conditions(const ScheduleRefinementNlp& coarser) const {
  if (coarser.phase_count() != phase_count() || coarser.stages() != stages() ||
      coarser.imposed_terminal_rows_ != imposed_terminal_rows_ || coarser.events_.size() != events_.size())
    return false;
  for (std::size_t b = 0; b < events_.size(); ++b)
    if (coarser.events_[b].imposed_guards != events_[b].imposed_guards ||
        coarser.events_[b].row_count() != events_[b].row_count())
      return false;
  for (int p = 0; p < phase_count(); ++p)
    if (coarser.imposed_path_rows(p) != imposed_path_rows(p)) return false;
  return true;
}

template <Scene S, class Ocp>
std::optional<MpccStart> ScheduleRefinementNlp<S, Ocp>::warm_start_from(const ScheduleRefinementNlp& coarser,
                                                                        const MpccSolution& solution) const {
  if (!shares_point_conditions(coarser) || solution.constraint_multipliers.size() != coarser.constraint_count() ||
      solution.bound_multipliers_lower.size() != coarser.variable_count())
    return std::nullopt;
  const Eigen::VectorXd& lambda = solution.constraint_multipliers;
  MpccStart start;
  start.x.resize(n_);
  initial_point(start.x);
  start.constraint_multipliers.setZero(m_);
  start.bound_multipliers_lower.setZero(n_);
  start.bound_multipliers_upper.setZero(n_);
  const auto copy_bounds = [&](int to, int from, int count, double factor) {
    start.bound_multipliers_lower.segment(to, count) = factor * solution.bound_multipliers_lower.segment(from, count);
    start.bound_multipliers_upper.segment(to, count) = factor * solution.bound_multipliers_upper.segment(from, count);
  };
  copy_bounds(0, 0, phase_count() + 1 + phase_count() * nx, 1.0);  // the times and the phases' start states
  const int ns = stages();
  for (int e = 0; e < element_count(); ++e) {
    const int c = parent_element(coarser, e);
    const double rho = element_length_fraction(e) / coarser.element_length_fraction(c);
    const bool first_child = std::abs(element_begin_fraction(e) - coarser.element_begin_fraction(c)) <= 1e-12;
    copy_bounds(control_index(e), coarser.control_index(c), nu, rho);
    for (int r = first_child ? -1 : 0; r < ns; ++r) {
      const double factor = r < 0 || r == ns - 1 ? 1.0 : rho;  // file comment
      const int offset = validity_offset_in_rows(r);
      if (r >= 0)
        start.constraint_multipliers.template segment<nx>(point_row(e, r)) =
            factor * lambda.template segment<nx>(coarser.point_row(c, r));
      for (int k : imposed_validity(e, r)) {
        const int from = coarser.validity_row(c, r, k);
        if (from >= 0) start.constraint_multipliers[validity_row(e, r, k)] = (r < 0 ? 1.0 : rho) * lambda[from];
      }
      if (r < 0) continue;
      const int path = static_cast<int>(imposed_path_rows(phase_of(e)).size());
      const int to_path = point_row(e, r) + offset + static_cast<int>(imposed_validity(e, r).size());
      const int from_path = coarser.point_row(c, r) + offset + static_cast<int>(coarser.imposed_validity(c, r).size());
      start.constraint_multipliers.segment(to_path, path) = rho * lambda.segment(from_path, path);
    }
  }
  // the events', durations' and terminal rows, last and of the same layout on both grids
  const int tail = m_ - (events_.empty() ? duration_row_ : events_.front().first_row);
  start.constraint_multipliers.tail(tail) = lambda.tail(tail);
  return start;
}

}  // namespace saltus::timefreezing
