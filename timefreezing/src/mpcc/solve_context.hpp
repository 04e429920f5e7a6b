// Private: what a homotopy step and a polish share of the solve_mpcc call they belong to.
#pragma once

#include <saltus/timefreezing/mpcc/solution.hpp>
#include <saltus/timefreezing/mpcc/solver_options.hpp>

#include "ipopt_session.hpp"
#include "mpcc_layout.hpp"
#include "relaxation.hpp"

namespace saltus::timefreezing::detail {

struct SolveContext {
  const MpccSolverOptions& options;
  MpccLayout& layout;         ///< the problem's layout (its constraint_violation has a workspace)
  const RelaxedNlp& relaxed;  ///< the homotopy's relaxed NLP
  IpoptSession& session;      ///< initialised; the steps' and polishes' Ipopt
  MpccSolution& solution;     ///< every solve is recorded in its steps and ipopt_iterations
  int step_max_iter;          ///< Ipopt max_iter of a homotopy step (ipopt.options may override ipopt.max_iter)
};

/// A step (or a polish) counts as successful: Solve_Succeeded, or with homotopy.accept_acceptable
/// Solved_To_Acceptable_Level, or Search_Direction_Becomes_Too_Small with the original constraint
/// violation <= homotopy.small_step_feasibility_tolerance.
inline bool successful(Ipopt::ApplicationReturnStatus status, double violation, const MpccSolverOptions& options) {
  if (status == Ipopt::Solve_Succeeded) return true;
  if (!options.homotopy.accept_acceptable) return false;
  return status == Ipopt::Solved_To_Acceptable_Level ||
         (status == Ipopt::Search_Direction_Becomes_Too_Small &&
          violation <= options.homotopy.small_step_feasibility_tolerance);
}

}  // namespace saltus::timefreezing::detail
