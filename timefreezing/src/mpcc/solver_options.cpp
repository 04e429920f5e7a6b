#include <cmath>
#include <saltus/hybrid/vocabulary/errors.hpp>
#include <saltus/timefreezing/mpcc/solver_options.hpp>

namespace saltus::timefreezing {

std::vector<IpoptOption> MpccSolverOptions::IpoptSettings::solver_defaults() {
  constexpr double push = 1e-9;
  return {{"mu_strategy", std::string("adaptive")},
          {"mu_oracle", std::string("quality-function")},
          {"bound_relax_factor", 0.0},
          {"warm_start_bound_push", push},
          {"warm_start_bound_frac", push},
          {"warm_start_slack_bound_push", push},
          {"warm_start_slack_bound_frac", push},
          {"warm_start_mult_bound_push", 1e-6},
          {"mumps_mem_percent", 1000}};
}

void MpccSolverOptions::validate() const {
  const Homotopy& h = homotopy;
  SALTUS_REQUIRE(std::isfinite(h.sigma_0) && h.sigma_0 > 0.0,
                 "MpccSolverOptions::homotopy.sigma_0 must be > 0 and finite, got ", h.sigma_0);
  SALTUS_REQUIRE(h.kappa > 0.0 && h.kappa < 1.0, "MpccSolverOptions::homotopy.kappa must be in (0, 1), got ", h.kappa);
  SALTUS_REQUIRE(h.complementarity_tolerance >= 0.0 && std::isfinite(h.complementarity_tolerance),
                 "MpccSolverOptions::homotopy.complementarity_tolerance must be >= 0 and finite, got ",
                 h.complementarity_tolerance);
  SALTUS_REQUIRE(h.complementarity_refinement >= 0.0 && h.complementarity_refinement <= h.complementarity_tolerance,
                 "MpccSolverOptions::homotopy.complementarity_refinement must be in [0, complementarity_tolerance = ",
                 h.complementarity_tolerance, "], got ", h.complementarity_refinement);
  SALTUS_REQUIRE(h.max_steps >= 1, "MpccSolverOptions::homotopy.max_steps must be >= 1, got ", h.max_steps);
  SALTUS_REQUIRE(h.max_step_retries >= 0, "MpccSolverOptions::homotopy.max_step_retries must be >= 0, got ",
                 h.max_step_retries);
  SALTUS_REQUIRE(h.small_step_feasibility_tolerance >= 0.0,
                 "MpccSolverOptions::homotopy.small_step_feasibility_tolerance must be >= 0, got ",
                 h.small_step_feasibility_tolerance);
  SALTUS_REQUIRE(ipopt.tol > 0.0 && std::isfinite(ipopt.tol),
                 "MpccSolverOptions::ipopt.tol must be > 0 and finite, got ", ipopt.tol);
  SALTUS_REQUIRE(ipopt.max_iter >= 0, "MpccSolverOptions::ipopt.max_iter must be >= 0, got ", ipopt.max_iter);
  SALTUS_REQUIRE(ipopt.print_level >= 0 && ipopt.print_level <= 12,
                 "MpccSolverOptions::ipopt.print_level must be in [0, 12], got ", ipopt.print_level);
  for (const IpoptOption& option : ipopt.options)
    SALTUS_REQUIRE(!option.name.empty(), "MpccSolverOptions::ipopt.options: an option has an empty name");
  SALTUS_REQUIRE(polish.below >= 0.0 && std::isfinite(polish.below),
                 "MpccSolverOptions::polish.below must be >= 0 and finite, got ", polish.below);
  SALTUS_REQUIRE(polish.feasibility_tolerance >= 0.0 && std::isfinite(polish.feasibility_tolerance),
                 "MpccSolverOptions::polish.feasibility_tolerance must be >= 0 and finite, got ",
                 polish.feasibility_tolerance);
  SALTUS_REQUIRE(polish.max_iter >= 0, "MpccSolverOptions::polish.max_iter must be >= 0, got ", polish.max_iter);
  SALTUS_REQUIRE(polish.objective_increase >= 0.0 && std::isfinite(polish.objective_increase),
                 "MpccSolverOptions::polish.objective_increase must be >= 0 and finite, got ",
                 polish.objective_increase);
}

}  // namespace saltus::timefreezing
