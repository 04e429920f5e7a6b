// The mesh refinement of refinement.hpp ("MESH REFINEMENT"): split the elements whose local error
// exceeds the tolerance, solve again on the finer grid from the previous solution.
#pragma once

#include <saltus/timefreezing/refinement/refinement.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <ostream>

namespace saltus::timefreezing::detail {

/// The element boundaries of `nlp`'s grid with every element whose local error exceeds
/// mesh.local_error_tolerance split into k equal parts (RefinementMesh::max_split); fills the
/// round's record. Phase fractions as RefinementGrid::element_boundaries.
template <Scene S, class Ocp>
std::vector<std::vector<double>> split_elements(const ScheduleRefinementNlp<S, Ocp>& nlp, const Eigen::VectorXd& x,
                                                const std::vector<double>& errors, const RefinementMesh& mesh,
                                                MeshRound& round) {
  const double tol = mesh.local_error_tolerance, exponent = 1.0 / (nlp.stages() + 1);
  std::vector<std::vector<double>> boundaries(static_cast<std::size_t>(nlp.phase_count()));
  for (int p = 0; p < nlp.phase_count(); ++p) {
    std::vector<double>& s = boundaries[static_cast<std::size_t>(p)];
    s.push_back(0.0);
    for (int e = nlp.first_element(p); e < nlp.first_element(p) + nlp.elements_in(p); ++e) {
      const double err = errors[static_cast<std::size_t>(e)], begin = nlp.element_begin_fraction(e);
      const double length = nlp.element_length_fraction(e);
      if (err > round.largest_local_error) {
        round.largest_local_error = err;
        round.worst_phase = p;
        round.worst_time = nlp.element_start_time(e, x[nlp.time_index(p)], x[nlp.time_index(p + 1)]);
      }
      int k = 1;
      if (err > tol) {
        // clamped as a double: an infinite error (the flow failed over the element) splits the most
        k = int(std::clamp(std::ceil(std::pow(err / (mesh.safety * tol), exponent)), 2.0, double(mesh.max_split)));
        ++round.elements_split;
      }
      for (int j = 1; j < k; ++j) s.push_back(begin + length * double(j) / double(k));
      s.push_back(e + 1 == nlp.first_element(p) + nlp.elements_in(p) ? 1.0 : begin + length);
    }
    round.elements += static_cast<int>(s.size()) - 1;
  }
  return boundaries;
}

/// A guess that reproduces a solution of `nlp` on any grid of the same schedule: the states from
/// the refined trajectory's dense output (each element's collocation polynomial), the decisions of
/// the element that contains t. (Primal only: the multipliers of a coarser grid have other rows.)
template <Scene S, class Ocp>
ScheduleGuess<S> solution_guess(const ScheduleRefinementNlp<S, Ocp>& nlp, const Eigen::VectorXd& x,
                                const RefinementResult<S>& result) {
  constexpr int nu = S::nu;
  struct Held {
    HybridTrajectory<S> trajectory;
    std::vector<double> starts;               // element start times
    std::vector<VecT<double, nu>> decisions;  // per element
  };
  auto held = std::make_shared<Held>();
  held->trajectory = result.trajectory;
  for (int e = 0; e < nlp.element_count(); ++e) {
    const int p = nlp.phase_of(e);
    held->starts.push_back(nlp.element_start_time(e, x[nlp.time_index(p)], x[nlp.time_index(p + 1)]));
    held->decisions.push_back(x.template segment<nu>(nlp.control_index(e)));
  }
  ScheduleGuess<S> g;
  g.schedule = nlp.schedule();
  g.event_times = result.event_times;
  g.state = [held](int p, double t) {
    const Segment<S>& seg = held->trajectory.segments[static_cast<std::size_t>(p)];
    return VecT<double, 2 * S::nq>(held->trajectory.state(p, std::clamp(t, seg.t_begin, seg.t_end)));
  };
  g.input = [held](double t) {
    const auto it = std::upper_bound(held->starts.begin(), held->starts.end(), t);
    const std::size_t e = it == held->starts.begin() ? 0 : std::size_t(it - held->starts.begin()) - 1;
    return held->decisions[e];
  };
  return g;
}

/// The rounds of the mesh refinement, from the converged solve (nlp, sol) whose reading is in
/// `out` (its element_local_errors among it); on return nlp, sol and `out` hold the last solve that
/// succeeded.
template <Scene S, class Ocp>
void refine_mesh(const S& scene, const Ocp& ocp, const OcpHorizon<S>& horizon, const RefinementOptions& options,
                 std::unique_ptr<ScheduleRefinementNlp<S, Ocp>>& nlp, MpccSolution& sol, RefinementResult<S>& out) {
  const RefinementMesh& mesh = options.mesh;
  for (int k = 0; mesh.local_error_tolerance > 0.0; ++k) {
    MeshRound round;
    const std::vector<std::vector<double>> boundaries =
        split_elements(*nlp, sol.x, out.element_local_errors, mesh, round);
    if (round.elements_split == 0) return;
    if (k >= mesh.max_rounds) {
      out.message += "; local error " + std::to_string(round.largest_local_error) + " > " +
                     std::to_string(mesh.local_error_tolerance) + " after " + std::to_string(k) + " mesh rounds";
      return;
    }
    if (options.progress)
      *options.progress << "refinement: mesh round " << k + 1 << ": largest local error " << round.largest_local_error
                        << " (phase " << round.worst_phase << ", t = " << round.worst_time << "), "
                        << round.elements_split << " of " << nlp->element_count() << " elements split, "
                        << round.elements << " elements\n";
    RefinementOptions finer = options;
    finer.grid.element_boundaries = boundaries;
    finer.ipopt.max_iter = std::min(options.ipopt.max_iter, mesh.max_iter);
    // MUMPS ordered by AMD: its automatic choice of an ordering, on these larger NLPs, made the rounds
    // differ from run to run (RefinementMesh, "reproducible"); the user's options come after.
    const bool duals = round.elements_split <= mesh.dual_warm_start_split_fraction * double(nlp->element_count());
    finer.ipopt.options.insert(finer.ipopt.options.begin(),
                               {IpoptOption{"mu_init", mesh.warm_start_mu}, IpoptOption{"mumps_pivot_order", 0}});
    const ScheduleGuess<S> guess = solution_guess(*nlp, sol.x, out);
    auto [finer_nlp, finer_sol] = duals ? solve_schedule(scene, ocp, horizon, guess, finer, out, nlp.get(), &sol)
                                        : solve_schedule(scene, ocp, horizon, guess, finer, out);
    round.dual_warm_start = duals && out.solves.back().warm_started;
    round.solved = out.solves.back().succeeded && finer_sol.constraint_violation <= 1e-6;
    out.mesh_rounds.push_back(round);
    if (!round.solved) {
      out.message += "; mesh round " + std::to_string(k + 1) + " did not solve (" + out.solves.back().ipopt_status +
                     "), the previous grid's solution is kept";
      return;
    }
    nlp = std::move(finer_nlp);
    sol = std::move(finer_sol);
    read_solution(scene, *nlp, sol, out);
  }
}

}  // namespace saltus::timefreezing::detail
