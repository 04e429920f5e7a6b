// Definitions of refinement.hpp: the solve, the edits, the readings, the re-simulation. Compiled
// once per scene and OCP (timefreezing/instantiate.hxx) or included by a program that instantiates
// it itself.
#pragma once

#include <saltus/timefreezing/refinement/phase_resimulation.hxx>
#include <saltus/timefreezing/refinement/schedule_edits.hxx>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ostream>
#include <sstream>

namespace saltus::timefreezing {

namespace detail {

/// One Ipopt solve of the refinement NLP from its initial point, or from `start` (primal-dual,
/// warm_start_init_point): the MPCC solver with no pairs is one Ipopt solve of the plain NLP (its
/// homotopy has nothing to relax or polish).
inline MpccSolution solve_refinement_nlp(const Mpcc& nlp, const RefinementIpopt& o, const MpccStart* start = nullptr) {
  MpccSolverOptions s;
  s.homotopy.max_steps = 1;
  s.polish.enabled = false;
  s.ipopt.tol = o.tol;
  s.ipopt.max_iter = o.max_iter;
  s.ipopt.print_level = o.print_level;
  // Exact mode validity needs Ipopt's bound_relax_factor = 0 (a solver default,
  // MpccSolverOptions::IpoptSettings): Ipopt's own 1e-8 relative relaxation of every bound leaves
  // validity rows at -1e-8 .. -1e-7 (the plank-box's slide at h = 0.05: 7.7e-8 with it, 1.2e-13
  // with 0). The user's options come after and may set it again.
  s.ipopt.options = o.options;
  return start ? solve_mpcc(nlp, *start, s) : solve_mpcc(nlp, s);
}

template <Scene S, class Ocp>
void read_solution(const S& scene, const ScheduleRefinementNlp<S, Ocp>& nlp, const MpccSolution& sol,
                   RefinementResult<S>& out) {
  // Ipopt meets the ordering rows t_p <= t_{p+1} to its constraint tolerance, so a phase that
  // wants to vanish can end a few 1e-12 s before it starts (measured: -2.5e-12 s on the plank-box
  // after a "vanish" edit, where the trajectory's segment then had t_end < t_begin and every
  // sampling of it threw): such a phase is read as of zero length.
  Eigen::VectorXd x = sol.x;
  for (int p = 0; p < nlp.phase_count(); ++p)
    x[nlp.time_index(p + 1)] = std::max(x[nlp.time_index(p + 1)], x[nlp.time_index(p)]);
  out.schedule = nlp.schedule();
  out.event_times.clear();
  for (int p = 1; p < nlp.phase_count(); ++p) out.event_times.push_back(x[nlp.time_index(p)]);
  out.trajectory = refined_trajectory(scene, nlp, x, out.element_times);
  out.objective = sol.objective;
  out.constraint_violation = sol.constraint_violation;
  out.mode_validity_violation = nlp.mode_validity_violation(x);
  out.path_violation = nlp.path_violation(x);
  out.terminal_violation = nlp.terminal_violation(x);
  out.contact_drift = nlp.contact_drift(x);
  out.implied_rows = nlp.implied_rows();
  out.element_local_errors = nlp.element_local_errors(x);
  const std::vector<double>& local = out.element_local_errors;
  out.local_error = local.empty() ? 0.0 : *std::max_element(local.begin(), local.end());
}

inline RefinementSolve solve_record(const std::string& schedule, const MpccSolution& sol) {
  RefinementSolve r;
  r.schedule = schedule;
  r.succeeded = !sol.steps.empty() && sol.steps.back().ipopt_succeeded;
  r.ipopt_status = sol.steps.empty() ? "no solve" : sol.steps.back().ipopt_status;
  r.objective = sol.objective;
  r.constraint_violation = sol.constraint_violation;
  r.ipopt_iterations = sol.ipopt_iterations;
  r.seconds = sol.seconds;
  return r;
}

/// "name (multiplier)" of the `count` rows of `nlp` with the largest |multipliers|, largest first.
inline std::vector<std::string> largest_multipliers(const Mpcc& nlp, const Eigen::VectorXd& multipliers, int count) {
  std::vector<int> rows(static_cast<std::size_t>(multipliers.size()));
  for (int j = 0; j < multipliers.size(); ++j) rows[static_cast<std::size_t>(j)] = j;
  const auto n = std::min<std::ptrdiff_t>(count, std::ssize(rows));
  std::partial_sort(rows.begin(), rows.begin() + n, rows.end(),
                    [&](int a, int b) { return std::abs(multipliers[a]) > std::abs(multipliers[b]); });
  std::vector<std::string> out;
  for (std::ptrdiff_t k = 0; k < n; ++k) {
    std::ostringstream line;
    line << nlp.constraint_name(rows[std::size_t(k)]) << " (" << multipliers[rows[std::size_t(k)]] << ")";
    out.push_back(line.str());
  }
  return out;
}

inline void progress_line(std::ostream* os, const RefinementSolve& s) {
  if (!os) return;
  *os << "refinement: " << (s.succeeded ? "solved" : "failed") << " (" << s.ipopt_status << ", " << s.ipopt_iterations
      << " iterations, " << s.seconds << " s" << (s.warm_started ? ", from the previous multipliers" : "")
      << "), objective " << s.objective << ", violation " << s.constraint_violation << ": " << s.schedule << "\n";
  if (!s.succeeded && !s.largest_multipliers.empty()) {
    *os << "refinement:   largest multipliers:";
    for (const std::string& m : s.largest_multipliers) *os << " " << m << ";";
    *os << "\n";
  }
}

/// The solve of one schedule: builds the NLP, solves it (from the guess, or with the multipliers
/// of `coarser`'s solution `coarse` carried over when both are given and the NLPs share their point
/// conditions: ScheduleRefinementNlp::warm_start_from), records it. Returns the NLP and the solution.
template <Scene S, class Ocp>
std::pair<std::unique_ptr<ScheduleRefinementNlp<S, Ocp>>, MpccSolution> solve_schedule(
    const S& scene, const Ocp& ocp, const OcpHorizon<S>& horizon, const ScheduleGuess<S>& guess,
    const RefinementOptions& options, RefinementResult<S>& out, const ScheduleRefinementNlp<S, Ocp>* coarser = nullptr,
    const MpccSolution* coarse = nullptr) {
  auto nlp = std::make_unique<ScheduleRefinementNlp<S, Ocp>>(scene, ocp, horizon, guess, options);
  const std::optional<MpccStart> start =
      coarser && coarse ? nlp->warm_start_from(*coarser, *coarse) : std::optional<MpccStart>{};
  RefinementIpopt ipopt = options.ipopt;
  if (start)  // a primal-dual start: the round's barrier start (its first mu_init) is RefinementMesh::dual_warm_start_mu
    for (IpoptOption& o : ipopt.options)
      if (o.name == "mu_init") {
        o.value = options.mesh.dual_warm_start_mu;
        break;
      }
  MpccSolution sol = solve_refinement_nlp(*nlp, ipopt, start ? &*start : nullptr);
  RefinementSolve record = solve_record(describe(scene, nlp->schedule()), sol);
  record.warm_started = start.has_value();
  record.largest_multipliers = largest_multipliers(*nlp, sol.constraint_multipliers, 5);
  progress_line(options.progress, record);
  out.solves.push_back(record);
  out.ipopt_iterations += sol.ipopt_iterations;
  return {std::move(nlp), std::move(sol)};
}

/// The edit loop of refinement.hpp: from a converged solve, propose an edit, solve the edited
/// schedule, keep it when it converges to a lower cost; stop at the first edit that does not.
template <Scene S, class Ocp>
void edit_schedule(const S& scene, const Ocp& ocp, const OcpHorizon<S>& horizon, const RefinementOptions& options,
                   std::unique_ptr<ScheduleRefinementNlp<S, Ocp>>& nlp, MpccSolution& sol, RefinementResult<S>& out) {
  for (int round = 0;; ++round) {
    const std::optional<ScheduleEdit> edit = propose_edit(*nlp, sol.x, sol.constraint_multipliers, options.edits);
    if (!edit) {
      out.schedule_check_passed = true;
      return;
    }
    if (round >= options.edits.max_edits) {
      out.message += "; an edit is still proposed (" + edit->kind + " in phase " + std::to_string(edit->phase) +
                     ") after " + std::to_string(round) + " edits";
      return;
    }
    const std::optional<ScheduleGuess<S>> guess = edited_guess(scene, out.trajectory, nlp->schedule(), *edit);
    if (!guess) {
      out.message += "; the proposed " + edit->kind + " edit of phase " + std::to_string(edit->phase) +
                     " leaves no valid schedule, not tried";
      return;
    }
    ScheduleEdit record = *edit;
    record.schedule_after = describe(scene, guess->schedule);
    if (options.progress) *options.progress << "refinement: edit " << record.kind << " in phase " << record.phase << " at t = " << record.t << "\n";
    RefinementOptions edited_options = options;
    edited_options.ipopt.max_iter = std::min(options.ipopt.max_iter, options.edits.max_iter);
    edited_options.grid.element_boundaries.clear();  // the edited schedule has other phases
    auto [edited_nlp, edited_sol] = solve_schedule(scene, ocp, horizon, *guess, edited_options, out);
    const bool better = out.solves.back().succeeded && edited_sol.constraint_violation <= 1e-6 &&
                        edited_sol.objective < sol.objective - 1e-9 * std::max(1.0, std::abs(sol.objective));
    if (!better) {
      record.kind += " (rejected: " + (out.solves.back().succeeded ? std::string("no lower cost") : out.solves.back().ipopt_status) + ")";
      out.edits.push_back(record);
      // Passed when the edit the multipliers asked for solved without lowering the cost; an edit
      // whose solve failed leaves the question open.
      out.schedule_check_passed = out.solves.back().succeeded;
      if (!out.solves.back().succeeded)
        out.message += "; the proposed " + edit->kind + " edit of phase " + std::to_string(edit->phase) + " did not solve (" +
                       out.solves.back().ipopt_status + ")";
      return;
    }
    out.edits.push_back(record);
    nlp = std::move(edited_nlp);
    sol = std::move(edited_sol);
    read_solution(scene, *nlp, sol, out);
  }
}

/// "refined", or "converged, checks failed: ..." naming each failed check and its figures.
template <Scene S>
std::string checked_stage(const RefinementResult<S>& r, const RefinementChecks& checks) {
  std::ostringstream failed;
  if (!(r.mode_validity_violation <= checks.mode_validity))
    failed << "; mode validity " << r.mode_validity_violation << " > " << checks.mode_validity;
  bool phases_pass = r.phase_resim_max_error <= checks.phase_resimulation;
  for (const PhaseResimulation& p : r.phase_resimulation) phases_pass = phases_pass && p.passes(checks.phase_resimulation);
  if (!phases_pass) {
    failed << "; per-phase re-simulation " << r.phase_resim_max_error << " (tolerance " << checks.phase_resimulation << ")";
    for (const PhaseResimulation& p : r.phase_resimulation)
      if (!p.passes(checks.phase_resimulation))
        failed << " (phase " << p.phase << ": " << p.max_error << (p.note.empty() ? "" : ", " + p.note) << ")";
  }
  const std::string f = failed.str();
  return f.empty() ? "refined" : "converged, checks failed: " + f.substr(2);
}

}  // namespace detail

}  // namespace saltus::timefreezing

// The mesh rounds call solve_schedule and read_solution above.
#include <saltus/timefreezing/refinement/mesh_refinement.hxx>

namespace saltus::timefreezing {

template <Scene S, class Ocp>
RefinementResult<S> refine_schedule(const S& scene, const Ocp& ocp, const OcpHorizon<S>& horizon,
                                    const ScheduleGuess<S>& guess, const RefinementOptions& options,
                                    const SimulationOptions& simulation) {
  const auto start = std::chrono::steady_clock::now();
  RefinementResult<S> out;
  auto [nlp, sol] = detail::solve_schedule(scene, ocp, horizon, guess, options, out);
  detail::read_solution(scene, *nlp, sol, out);
  out.converged = out.solves.back().succeeded && sol.constraint_violation <= 1e-6;
  if (!out.converged) {
    out.stage = "not converged";
    out.message = "Ipopt: " + out.solves.back().ipopt_status + ", worst row: " +
                  (sol.steps.empty() ? std::string("?") : sol.steps.back().worst_violation);
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
  }
  out.message = "converged";
  detail::edit_schedule(scene, ocp, horizon, options, nlp, sol, out);
  detail::refine_mesh(scene, ocp, horizon, options, nlp, sol, out);
  out.phase_resimulation = resimulate_phases(scene, out.trajectory, out.schedule, out.element_times, simulation,
                                             options.checks.resimulation_window);
  for (const PhaseResimulation& r : out.phase_resimulation)  // NaN (a failed simulation) propagates
    out.phase_resim_max_error = std::isnan(r.max_error) ? r.max_error : std::max(out.phase_resim_max_error, r.max_error);
  out.open_loop = resimulate_open_loop(scene, out.trajectory, out.element_times, simulation);
  out.stage = detail::checked_stage(out, options.checks);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace saltus::timefreezing
