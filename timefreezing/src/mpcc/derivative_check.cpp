#include <cmath>
#include <cstdlib>
#include <saltus/hybrid/vocabulary/errors.hpp>
#include <saltus/timefreezing/mpcc/derivative_check.hpp>
#include <saltus/timefreezing/mpcc/solve.hpp>

#include "ipopt_adapter.hpp"
#include "ipopt_session.hpp"
#include "mpcc_layout.hpp"
#include "relaxation.hpp"
#include "validate.hpp"

namespace saltus::timefreezing {

DerivativeCheckReport check_derivatives(const Mpcc& problem, const Eigen::VectorXd& x, double perturbation,
                                        double tolerance) {
  validate_problem(problem);
  SALTUS_REQUIRE(perturbation > 0.0 && std::isfinite(perturbation),
                 "check_derivatives: perturbation must be > 0 and finite, got ", perturbation);
  SALTUS_REQUIRE(tolerance > 0.0 && std::isfinite(tolerance),
                 "check_derivatives: tolerance must be > 0 and finite, got ", tolerance);
  const detail::MpccLayout layout(problem);
  SALTUS_REQUIRE(x.size() == layout.variable_count(), "check_derivatives: x: expected size ", layout.variable_count(),
                 ", got ", x.size());
  detail::require_finite(x, "check_derivatives: x", problem, true);
  for (Eigen::Index i = 0; i < x.size(); ++i)
    SALTUS_REQUIRE(x[i] >= layout.x_lower()[i] && x[i] <= layout.x_upper()[i], "check_derivatives: x[", i, "] (",
                   problem.variable_name(static_cast<int>(i)), ") = ", x[i], " is outside its bounds [",
                   layout.x_lower()[i], ", ", layout.x_upper()[i], "] (Ipopt would check elsewhere)");
  detail::RelaxedNlp relaxed(layout, MpccSolverOptions::Relaxation::Scholtes);
  relaxed.set_sigma(1.0);
  const Ipopt::SmartPtr<detail::ReformulatedNlp> nlp = new detail::ReformulatedNlp(layout, relaxed.nlp());
  nlp->set_start(x);

  detail::IpoptSession session(0);
  // The checker prints its flagged entries at J_WARNING and its verdict at J_SUMMARY or
  // J_WARNING, all in category J_NLP (IpTNLPAdapter.cpp, CheckDerivatives, 3.11.9).
  session.capture->SetPrintLevel(Ipopt::J_NLP, Ipopt::J_WARNING);
  session.set_string("derivative_test", "second-order");
  session.set_number("derivative_test_perturbation", perturbation);
  session.set_number("derivative_test_tol", tolerance);
  session.set_string("derivative_test_print_all", "no");
  // Without this Ipopt checks at a random point within 10 of x (clipped to the bounds).
  session.set_number("point_perturbation_radius", 0.0);
  session.set_integer("max_iter", 0);
  session.set_number("bound_relax_factor", 0.0);
  session.initialize();
  const Ipopt::ApplicationReturnStatus status = session.app->OptimizeTNLP(Ipopt::GetRawPtr(nlp));

  DerivativeCheckReport report;
  report.output = session.capture->text();
  report.ipopt_status = detail::status_name(status);
  // Verdicts as printed by TNLPAdapter::CheckDerivatives (3.11.9):
  //   "\nNo errors detected by derivative checker.\n\n"
  //   "\nDerivative checker detected %d error(s).\n\n"
  static const std::string none = "No errors detected by derivative checker.";
  static const std::string some = "Derivative checker detected ";
  if (report.output.find(none) != std::string::npos) return report;
  const std::size_t at = report.output.find(some);
  SALTUS_CHECK_NUMERICS(at != std::string::npos,
                        "check_derivatives: Ipopt's derivative checker gave no verdict (status ", report.ipopt_status,
                        "); Ipopt said: ", report.output);
  report.errors = std::atoi(report.output.c_str() + at + some.size());
  return report;
}

}  // namespace saltus::timefreezing
