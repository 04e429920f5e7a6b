// Private: the polish of a successful homotopy step by its branch NLP (solve.hpp, "POLISHING").
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>

#include "ipopt_adapter.hpp"
#include "solve_context.hpp"

namespace saltus::timefreezing::detail {

/// An accepted polish: the branch NLP's primal-dual solution (lambda of the branch's rows, of which
/// the first m are the problem's) and the summary the solution's message ends with.
struct PolishResult {
  PrimalDual point;
  std::string summary;
};

/// The polish of the successful step `from` (the relaxed NLP's primal-dual solution of homotopy
/// step k at sigma): the branch NLP of the branch rule's guess (with the trend from previous_x at
/// previous_sigma when there is one and previous_sigma > sigma), solved from `from`, judged, and
/// recorded as a step of context.solution (with its progress line). nullopt when it is not
/// accepted.
std::optional<PolishResult> polish_step(SolveContext& context, const PrimalDual& from, int k, double sigma,
                                        const Eigen::VectorXd& previous_x, double previous_sigma);

}  // namespace saltus::timefreezing::detail
