#include "progress.hpp"

#include <cstdio>

namespace saltus::timefreezing::detail {

std::string format_step(const MpccHomotopyStep& s, bool penalty) {
  char line[320];
  std::snprintf(line, sizeof line,
                "mpcc step %3d%-10s %s %9.3e  compl %9.3e  f % .10e  viol %9.3e  iter %5d  %-34s %8.3f s", s.index,
                s.retry > 0 ? (" retry " + std::to_string(s.retry)).c_str() : "", penalty ? "rho  " : "sigma",
                penalty ? 1.0 / s.sigma : s.sigma, s.complementarity, s.objective, s.constraint_violation,
                s.ipopt_iterations, s.ipopt_status.c_str(), s.seconds);
  // A failed step says where its iterate is infeasible (the wall of a homotopy: dynamics, a path
  // row, a bound).
  return std::string(line) + (!s.ipopt_succeeded && !s.worst_violation.empty() ? "  worst: " + s.worst_violation : "") +
         "\n";
}

std::string format_polish(const MpccHomotopyStep& s, int fixed_variables, int equality_rows, int inequality_rows,
                          bool infeasible) {
  char line[400];
  std::snprintf(line, sizeof line,
                "mpcc polish %3d  G=0 %d H=0 %d biactive %d trend %d (fixed %d, rows %d =, %d >=)  "
                "compl %9.3e  f % .10e  viol %9.3e  iter %5d  %-34s %8.3f s",
                s.index, s.left_zero, s.right_zero, s.biactive, s.by_trend, fixed_variables, equality_rows,
                inequality_rows, s.complementarity, s.objective, s.constraint_violation, s.ipopt_iterations,
                s.ipopt_status.c_str(), s.seconds);
  // The note can be long (a branch's reason to be infeasible names variables): appended as is.
  // The worst row only where it says something: not for a polish refused for its objective alone.
  return std::string(line) + (s.note.empty() ? "" : "  failed: " + s.note) +
         (infeasible && !s.worst_violation.empty() ? "  worst: " + s.worst_violation : "") + "\n";
}

}  // namespace saltus::timefreezing::detail
