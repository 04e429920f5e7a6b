#include <saltus/timefreezing/mpcc/solve.hpp>

#include "homotopy.hpp"
#include "validate.hpp"

namespace saltus::timefreezing {

MpccSolution solve_mpcc(const Mpcc& problem, const MpccSolverOptions& options) {
  validate_problem(problem);
  MpccStart start;
  start.x.resize(problem.variable_count());
  problem.initial_point(start.x);
  return solve_mpcc(problem, start, options);
}

MpccSolution solve_mpcc(const Mpcc& problem, const MpccStart& start, const MpccSolverOptions& options) {
  options.validate();
  validate_problem(problem);
  const bool with_multipliers = detail::validate_start(problem, start);
  return detail::run_homotopy(problem, start, with_multipliers, options);
}

}  // namespace saltus::timefreezing
