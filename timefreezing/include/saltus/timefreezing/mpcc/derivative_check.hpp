// Ipopt's own derivative checker on the relaxed NLP of an MPCC (mpcc.hpp): a test of a problem's
// hand-written or AD derivatives through exactly what the solver hands to Ipopt.
#pragma once

#include <Eigen/Core>
#include <saltus/timefreezing/mpcc/mpcc.hpp>
#include <string>

namespace saltus::timefreezing {

/// Output of Ipopt's derivative checker (check_derivatives).
struct DerivativeCheckReport {
  int errors = 0;            ///< entries Ipopt flagged ("Derivative checker detected N error(s).")
  std::string output;        ///< Ipopt's checker output: the flagged entries and the verdict
  std::string ipopt_status;  ///< status of the zero-iteration Ipopt run that hosted the check
};

/// Runs Ipopt's own derivative checker (derivative_test = second-order, forward differences) on
/// the Scholtes-relaxed NLP (sigma = 1) at exactly x (point_perturbation_radius = 0: Ipopt would
/// otherwise check at a random point within 10 of x): gradient of f, Jacobian of g and of the sign
/// and relaxation rows, Hessians of f, of every g_j and of every relaxation row. An entry is
/// flagged when |approx - exact| / max(|approx|, 1) >= tolerance; `perturbation` is relative,
/// perturbation * max(1, |x_i|). Nothing is printed.
/// @pre x has size n, is finite and within the bounds; perturbation > 0; tolerance > 0.
/// @throws InvalidArgument as solve_mpcc for the problem statement, and for x or the numbers.
/// @throws NumericalFailure when Ipopt's output holds no verdict (the check could not run, e.g.
///   a function could not be evaluated at x), with Ipopt's status and output.
DerivativeCheckReport check_derivatives(const Mpcc& problem, const Eigen::VectorXd& x, double perturbation = 1e-7,
                                        double tolerance = 1e-4);

}  // namespace saltus::timefreezing
