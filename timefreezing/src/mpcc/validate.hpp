// Private: the checks of solve_mpcc's and check_derivatives' arguments beyond validate_problem
// (solve.hpp) and MpccSolverOptions::validate.
#pragma once

#include <Eigen/Core>
#include <saltus/timefreezing/mpcc/mpcc.hpp>
#include <saltus/timefreezing/mpcc/solution.hpp>

namespace saltus::timefreezing::detail {

/// Throws InvalidArgument naming `what`[i] (and, with is_x, the variable's name) when an entry of v
/// is not finite.
void require_finite(const Eigen::VectorXd& v, const char* what, const Mpcc& problem, bool is_x);

/// Throws InvalidArgument when the start's sizes do not match the (validated) problem, an entry is
/// not finite, or a bound multiplier is negative. Returns whether it has multipliers.
bool validate_start(const Mpcc& problem, const MpccStart& start);

}  // namespace saltus::timefreezing::detail
