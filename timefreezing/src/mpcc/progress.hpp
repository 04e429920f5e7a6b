// Private: the progress lines of solve_mpcc (MpccSolverOptions::progress), one per Ipopt solve.
#pragma once

#include <saltus/timefreezing/mpcc/solution.hpp>
#include <string>

namespace saltus::timefreezing::detail {

/// "mpcc step   k[ retry r] sigma|rho ...  compl ...  f ...  viol ...  iter ...  status  seconds",
/// with "  worst: <row>" for a failed step; newline-terminated.
std::string format_step(const MpccHomotopyStep& step, bool penalty);

/// "mpcc polish   k  G=0 .. H=0 .. biactive .. trend .. (fixed .., rows .. =, .. >=)  compl ...",
/// with "  failed: <note>" and, when `infeasible`, "  worst: <row>"; newline-terminated.
std::string format_polish(const MpccHomotopyStep& step, int fixed_variables, int equality_rows, int inequality_rows,
                          bool infeasible);

}  // namespace saltus::timefreezing::detail
