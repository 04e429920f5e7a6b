// Private: the homotopy of relaxed NLPs with its retries, warm starts, refinement and polishes
// (solve.hpp, "HOMOTOPY").
#pragma once

#include <saltus/timefreezing/mpcc/mpcc.hpp>
#include <saltus/timefreezing/mpcc/solution.hpp>
#include <saltus/timefreezing/mpcc/solver_options.hpp>

namespace saltus::timefreezing::detail {

/// The homotopy from `start` (checked by the caller, as the problem and the options); with
/// `with_multipliers` the start's multipliers are given (sizes m, n, n).
MpccSolution run_homotopy(const Mpcc& problem, const MpccStart& start, bool with_multipliers,
                          const MpccSolverOptions& options);

}  // namespace saltus::timefreezing::detail
