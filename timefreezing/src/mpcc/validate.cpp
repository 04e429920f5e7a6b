#include "validate.hpp"

#include <cmath>
#include <limits>
#include <saltus/hybrid/vocabulary/errors.hpp>
#include <saltus/timefreezing/mpcc/solve.hpp>
#include <set>
#include <string>

namespace saltus::timefreezing {

namespace {

/// Bounds: not NaN, lower <= upper, not both at the same infinity; named by `kind` and name(i).
template <class Name>
void require_bounds(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, const char* kind, Name name) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < lower.size(); ++i) {
    SALTUS_REQUIRE(!std::isnan(lower[i]) && !std::isnan(upper[i]), "Mpcc: NaN bound of ", kind, " ", i, " (", name(i),
                   "): [", lower[i], ", ", upper[i], "]");
    SALTUS_REQUIRE(lower[i] <= upper[i], "Mpcc: lower bound > upper bound of ", kind, " ", i, " (", name(i),
                   "): ", lower[i], " > ", upper[i]);
    SALTUS_REQUIRE(lower[i] < inf && upper[i] > -inf, "Mpcc: infinite bounds of ", kind, " ", i, " (", name(i),
                   ") leave no value: [", lower[i], ", ", upper[i], "]");
  }
}

void require_structures(const Mpcc& problem) {
  const int n = problem.variable_count(), m = problem.constraint_count();
  const std::vector<SparseEntry>& jac = problem.jacobian_structure();
  for (std::size_t e = 0; e < jac.size(); ++e)
    SALTUS_REQUIRE(jac[e].row >= 0 && jac[e].row < m && jac[e].col >= 0 && jac[e].col < n,
                   "Mpcc: jacobian_structure() entry ", e, " (", jac[e].row, ", ", jac[e].col,
                   ") is out of range for a ", m, " x ", n, " Jacobian");
  const std::vector<SparseEntry>& hess = problem.hessian_structure();
  for (std::size_t e = 0; e < hess.size(); ++e) {
    SALTUS_REQUIRE(hess[e].row >= 0 && hess[e].row < n && hess[e].col >= 0 && hess[e].col < n,
                   "Mpcc: hessian_structure() entry ", e, " (", hess[e].row, ", ", hess[e].col,
                   ") is out of range for a ", n, " x ", n, " Hessian");
    SALTUS_REQUIRE(hess[e].row >= hess[e].col, "Mpcc: hessian_structure() entry ", e, " (", hess[e].row, ", ",
                   hess[e].col, ") is above the diagonal: the structure lists the lower triangle only (row >= column)");
  }
}

void require_pairs(const Mpcc& problem) {
  const int n = problem.variable_count();
  const std::vector<ComplementarityPair>& pairs = problem.complementarity_pairs();
  for (std::size_t j = 0; j < pairs.size(); ++j) {
    for (int side = 0; side < 2; ++side) {
      const AffineExpression& e = side == 0 ? pairs[j].left : pairs[j].right;
      const char* which = side == 0 ? "left" : "right";
      SALTUS_REQUIRE(!e.terms.empty(), "Mpcc: complementarity pair ", j, " (", pairs[j].name, "): the ", which,
                     " side has no variable (a constant side is not a complementarity constraint)");
      SALTUS_REQUIRE(std::isfinite(e.constant), "Mpcc: complementarity pair ", j, " (", pairs[j].name, "): the ", which,
                     " side's constant is not finite: ", e.constant);
      std::set<int> seen;
      for (const auto& [i, a] : e.terms) {
        SALTUS_REQUIRE(i >= 0 && i < n, "Mpcc: complementarity pair ", j, " (", pairs[j].name, "): the ", which,
                       " side has the variable index ", i, ", out of range for ", n, " variables");
        SALTUS_REQUIRE(std::isfinite(a), "Mpcc: complementarity pair ", j, " (", pairs[j].name, "): the ", which,
                       " side's coefficient of ", problem.variable_name(i), " is not finite: ", a);
        SALTUS_REQUIRE(seen.insert(i).second, "Mpcc: complementarity pair ", j, " (", pairs[j].name, "): the ", which,
                       " side lists the variable ", i, " (", problem.variable_name(i),
                       ") twice (each variable at most once per side)");
      }
    }
  }
}

}  // namespace

void validate_problem(const Mpcc& problem) {
  const int n = problem.variable_count(), m = problem.constraint_count();
  SALTUS_REQUIRE(n >= 1, "Mpcc: variable_count() must be >= 1, got ", n);
  SALTUS_REQUIRE(m >= 0, "Mpcc: constraint_count() must be >= 0, got ", m);
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  // NaN-filled: an implementation that leaves an entry unset is caught as a NaN bound.
  Eigen::VectorXd x_lower = Eigen::VectorXd::Constant(n, nan), x_upper = x_lower;
  Eigen::VectorXd g_lower = Eigen::VectorXd::Constant(m, nan), g_upper = g_lower;
  problem.bounds(x_lower, x_upper, g_lower, g_upper);
  require_bounds(x_lower, x_upper, "variable",
                 [&](Eigen::Index i) { return problem.variable_name(static_cast<int>(i)); });
  require_bounds(g_lower, g_upper, "constraint",
                 [&](Eigen::Index j) { return problem.constraint_name(static_cast<int>(j)); });
  Eigen::VectorXd x0 = Eigen::VectorXd::Constant(n, nan);
  problem.initial_point(x0);
  for (int i = 0; i < n; ++i)
    SALTUS_REQUIRE(std::isfinite(x0[i]), "Mpcc: initial point of variable ", i, " (", problem.variable_name(i),
                   ") is not finite: ", x0[i]);
  require_structures(problem);
  require_pairs(problem);
}

namespace detail {

void require_finite(const Eigen::VectorXd& v, const char* what, const Mpcc& problem, bool is_x) {
  for (Eigen::Index i = 0; i < v.size(); ++i)
    SALTUS_REQUIRE(std::isfinite(v[i]), what, "[", i, "]",
                   is_x ? " (" + problem.variable_name(static_cast<int>(i)) + ")" : std::string(), " = ", v[i],
                   " is not finite");
}

bool validate_start(const Mpcc& problem, const MpccStart& start) {
  const Eigen::Index n = problem.variable_count(), m = problem.constraint_count();
  SALTUS_REQUIRE(start.x.size() == n, "MpccStart::x: expected size ", n, ", got ", start.x.size());
  require_finite(start.x, "MpccStart::x", problem, true);
  const bool any_multipliers = start.constraint_multipliers.size() > 0 || start.bound_multipliers_lower.size() > 0 ||
                               start.bound_multipliers_upper.size() > 0;
  if (!any_multipliers) return false;
  SALTUS_REQUIRE(start.constraint_multipliers.size() == m, "MpccStart::constraint_multipliers: expected size ", m,
                 " (or all multipliers empty), got ", start.constraint_multipliers.size());
  SALTUS_REQUIRE(start.bound_multipliers_lower.size() == n, "MpccStart::bound_multipliers_lower: expected size ", n,
                 " (or all multipliers empty), got ", start.bound_multipliers_lower.size());
  SALTUS_REQUIRE(start.bound_multipliers_upper.size() == n, "MpccStart::bound_multipliers_upper: expected size ", n,
                 " (or all multipliers empty), got ", start.bound_multipliers_upper.size());
  require_finite(start.constraint_multipliers, "MpccStart::constraint_multipliers", problem, false);
  require_finite(start.bound_multipliers_lower, "MpccStart::bound_multipliers_lower", problem, true);
  require_finite(start.bound_multipliers_upper, "MpccStart::bound_multipliers_upper", problem, true);
  for (Eigen::Index i = 0; i < n; ++i)
    SALTUS_REQUIRE(start.bound_multipliers_lower[i] >= 0.0 && start.bound_multipliers_upper[i] >= 0.0,
                   "MpccStart: bound multipliers must be >= 0; variable ", i, " (",
                   problem.variable_name(static_cast<int>(i)), ") has z_L = ", start.bound_multipliers_lower[i],
                   ", z_U = ", start.bound_multipliers_upper[i]);
  return true;
}

}  // namespace detail

}  // namespace saltus::timefreezing
