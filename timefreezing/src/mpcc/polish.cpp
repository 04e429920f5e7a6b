#include "polish.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ostream>
#include <sstream>

#include "branch.hpp"
#include "progress.hpp"

namespace saltus::timefreezing::detail {

namespace {

using Clock = std::chrono::steady_clock;

/// Ipopt's status of a branch solve and whether it returned an iterate.
struct BranchSolve {
  Ipopt::ApplicationReturnStatus status = Ipopt::Solve_Succeeded;
  bool solved = false;
};

/// Solves the (not infeasible) branch NLP from `from` with the polish's iteration limit; records
/// the iterations and the status in `step`.
BranchSolve solve_branch(SolveContext& c, const BranchNlp& branch, const Ipopt::SmartPtr<ReformulatedNlp>& nlp,
                         const PrimalDual& from, double sigma, MpccHomotopyStep& step) {
  nlp->set_start(from.x, branch_start_multipliers(branch, c.layout, c.relaxed, from, sigma), from.z_lower,
                 from.z_upper);
  c.session.set_string("warm_start_init_point", c.options.warm_start ? "yes" : "no");
  c.session.set_integer("max_iter", c.options.polish.max_iter);
  BranchSolve result;
  result.status = c.session.app->OptimizeTNLP(Ipopt::GetRawPtr(nlp));
  c.session.set_integer("max_iter", c.step_max_iter);
  // A branch with more equalities than free variables, or one Ipopt refuses, is a failed guess,
  // not a wrong problem statement.
  if (result.status != Ipopt::Not_Enough_Degrees_Of_Freedom && result.status != Ipopt::Invalid_Problem_Definition)
    c.session.throw_on_setup_error(result.status);
  step.ipopt_iterations = c.session.iterations();
  step.ipopt_status = status_name(result.status);
  result.solved = nlp->has_result();
  return result;
}

/// The acceptance of a solved branch (solve.hpp, "POLISHING"): sets step.ipopt_succeeded and, for
/// a refusal, writes why to `note`. step's complementarity, objective and violation are set.
void judge(const SolveContext& c, const PrimalDual& from, double sigma, const BranchSolve& solve,
           MpccHomotopyStep& step, std::ostringstream& note) {
  const MpccSolverOptions& o = c.options;
  const bool solved = solve.solved && successful(solve.status, step.constraint_violation, o);
  // The relaxed optimum lies below the MPCC's by about sum_j w_j |G_j H_j| (the pairs' weights in
  // the relaxed Lagrangian times the relaxation the polish removes): allowed, twice over, plus
  // the margin.
  const double from_objective = c.layout.problem().objective(from.x);
  double expected_increase = 0.0;
  for (int j = 0; j < c.layout.pair_count(); ++j)
    expected_increase += std::abs(c.relaxed.pair_weight(from.lambda, j, sigma) * c.layout.side_value(2 * j, from.x) *
                                  c.layout.side_value(2 * j + 1, from.x));
  const double objective_limit =
      from_objective + 2.0 * expected_increase + o.polish.objective_increase * std::max(1.0, std::abs(from_objective));
  const bool objective_ok = step.objective <= objective_limit;  // false for NaN
  step.ipopt_succeeded = solved && step.constraint_violation <= o.polish.feasibility_tolerance &&
                         step.complementarity <= o.homotopy.complementarity_tolerance && objective_ok;
  if (!solved)
    note << "Ipopt: " << step.ipopt_status;
  else if (step.constraint_violation > o.polish.feasibility_tolerance)
    note << "constraint violation " << step.constraint_violation << " > " << o.polish.feasibility_tolerance;
  else if (step.complementarity > o.homotopy.complementarity_tolerance)
    note << "complementarity " << step.complementarity << " > " << o.homotopy.complementarity_tolerance;
  else if (!objective_ok)
    note << "objective " << step.objective << " > " << objective_limit << " (the step's " << from_objective
         << " + polish.objective_increase)";
}

/// The step of a polish before its solve: its index, sigma and the guess's counts.
MpccHomotopyStep polish_record(int k, double sigma, const BranchGuess& guess) {
  MpccHomotopyStep step;
  step.index = k;
  step.sigma = sigma;
  step.polish = true;
  step.biactive = guess.biactive;
  step.by_trend = guess.by_trend;
  for (int z : guess.zero_side) ++(z != 0 ? step.right_zero : step.left_zero);
  return step;
}

}  // namespace

std::optional<PolishResult> polish_step(SolveContext& c, const PrimalDual& from, int k, double sigma,
                                        const Eigen::VectorXd& previous_x, double previous_sigma) {
  const Clock::time_point start = Clock::now();
  const bool trend = previous_x.size() > 0 && previous_sigma > sigma;
  const BranchGuess guess = choose_branches(c.layout, from.x, std::sqrt(c.options.homotopy.complementarity_tolerance),
                                            trend ? &previous_x : nullptr, trend ? sigma / previous_sigma : 0.1);
  MpccHomotopyStep step = polish_record(k, sigma, guess);
  const BranchNlp branch = make_branch_nlp(c.layout, guess.zero_side);
  Ipopt::SmartPtr<ReformulatedNlp> nlp;
  BranchSolve solve;
  std::ostringstream note;
  note.precision(3);
  if (branch.infeasible()) {
    step.ipopt_status = "Not_Solved";
    note << "branch infeasible by its bounds: " << branch.why;
  } else {
    nlp = new ReformulatedNlp(c.layout, branch.nlp);
    solve = solve_branch(c, branch, nlp, from, sigma, step);
  }
  const Eigen::VectorXd& x = solve.solved ? nlp->result().x : from.x;
  step.complementarity = c.layout.complementarity(x);
  step.objective = c.layout.problem().objective(x);
  step.constraint_violation = c.layout.constraint_violation(x, &step.worst_violation);
  if (!branch.infeasible()) judge(c, from, sigma, solve, step, note);
  step.note = note.str();
  step.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  c.solution.ipopt_iterations += step.ipopt_iterations;
  c.solution.steps.push_back(step);
  if (c.options.progress)
    *c.options.progress << format_polish(step, branch.fixed_variables, branch.equality_rows, branch.inequality_rows,
                                         step.constraint_violation > c.options.polish.feasibility_tolerance)
                        << std::flush;
  if (!step.ipopt_succeeded) return std::nullopt;
  std::ostringstream summary;
  summary << "; polished from homotopy step " << k << " (sigma = " << sigma << ") by a branch NLP with "
          << step.left_zero << " pairs G = 0, " << step.right_zero << " pairs H = 0 (" << step.biactive << " biactive)";
  return PolishResult{nlp->result(), summary.str()};
}

}  // namespace saltus::timefreezing::detail
