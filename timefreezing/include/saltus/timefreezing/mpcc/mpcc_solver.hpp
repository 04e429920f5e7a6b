// The MPCC solver in one include: the homotopy of relaxed NLPs on Ipopt with its branch-NLP polish
// (solve.hpp, where the method is described), its options (solver_options.hpp), its results
// (solution.hpp) and Ipopt's derivative checker on the relaxed NLP (derivative_check.hpp).
#pragma once

#include <saltus/timefreezing/mpcc/derivative_check.hpp>
#include <saltus/timefreezing/mpcc/mpcc.hpp>
#include <saltus/timefreezing/mpcc/solution.hpp>
#include <saltus/timefreezing/mpcc/solve.hpp>
#include <saltus/timefreezing/mpcc/solver_options.hpp>
