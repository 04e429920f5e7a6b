// The flagship OCP, the hopper over three holes (scenes/hopper_holes.hpp; time-freezing paper
// Section 6), under the solver and formulation variants the issue asks to measure one by one.
//
//   hopper_ocp [--json] [--only NAME]
//
// Every variant starts from the paper's initialisation (the start state at every stage point,
// zero torques; FesdMpcc::initial_point) and runs the homotopy of solve_mpcc; one progress line
// per homotopy step on stderr. Columns, per variant:
//   conv          the homotopy converged (complementarity <= 1e-9 at a successful step)
//   steps         Ipopt solves run (homotopy steps, retries and polish attempts)
//   iters         total Ipopt iterations, and per solve
//   compl         max_j |G_j H_j| at the returned point
//   path viol     largest violation of the 11 path rows at every stage point, at the FULL holes
//   target        max_i |q_i(T) - q_target,i|
//   J             objective (the integral of u'u over physical time plus the two penalties)
//   status        Ipopt's status of the last solve
//   seconds       wall time of the solve (one thread: run with OPENBLAS_NUM_THREADS=1)
// bench/README.md ("Hopper over three holes") has the table of a run and what it shows.
#include "scenes/hopper_holes.hpp"

#include <saltus/timefreezing/simulation.hpp>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

namespace {

using namespace saltus;
using namespace saltus::timefreezing;
using Ocp = scenes::HopperOverThreeHoles;

struct Variant {
  const char* name;
  const char* what;
  int control_intervals = 20;
  MpccSolverOptions::Relaxation relaxation = MpccSolverOptions::Relaxation::Scholtes;
  double sigma_0 = 1.0;
  double tol = 1e-8;
  const char* mu_strategy = "adaptive";
  double hole_level = 1.0;
};

std::vector<Variant> variants() {
  using R = MpccSolverOptions::Relaxation;
  return {
      {"paper", "Scholtes sigma_0 = 1, kappa = 0.1, Ipopt tol 1e-8, N = 20 (Ocp::solver)"},
      {"paper-tol-1e-10", "the same with Ipopt tol 1e-10", 20, R::Scholtes, 1.0, 1e-10},
      {"penalty", "elastic: rho_k sum G H in the objective, rho_0 = 1", 20, R::Penalty},
      {"monotone-mu", "Ipopt mu_strategy = monotone", 20, R::Scholtes, 1.0, 1e-8, "monotone"},
      {"no-holes", "hole_level 0 (the holes' rows always hold): the start of a continuation on the holes", 20,
       R::Scholtes, 1.0, 1e-8, "adaptive", 0.0},
      {"no-holes-N10", "no holes, N = 10", 10, R::Scholtes, 1.0, 1e-8, "adaptive", 0.0},
      {"no-holes-N10-sigma-0.1", "no holes, N = 10, sigma_0 = 0.1", 10, R::Scholtes, 0.1, 1e-8, "adaptive", 0.0},
      {"no-holes-N10-sigma-0.01", "no holes, N = 10, sigma_0 = 0.01", 10, R::Scholtes, 0.01, 1e-8, "adaptive", 0.0},
  };
}

}  // namespace

int main(int argc, char** argv) {
  bool json = false;
  std::string only;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--json") == 0) json = true;
    else if (std::strcmp(argv[i], "--only") == 0 && i + 1 < argc) only = argv[++i];
    else {
      std::fprintf(stderr, "usage: hopper_ocp [--json] [--only NAME]\n");
      return 2;
    }
  }
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  if (!json)
    std::printf("%-24s %4s %5s %6s %9s %9s %9s %11s %-28s %8s\n", "variant", "conv", "steps", "iters", "compl",
                "path viol", "target", "J", "status", "seconds");
  for (const Variant& v : variants()) {
    if (!only.empty() && only != v.name) continue;
    std::fprintf(stderr, "== %s: %s\n", v.name, v.what);
    Ocp ocp;
    ocp.hole_level = v.hole_level;
    MpccSolverOptions s = Ocp::solver();
    s.relaxation = v.relaxation;
    s.sigma_0 = v.sigma_0;
    s.tol = v.tol;
    s.mu_strategy = v.mu_strategy;
    s.progress = &std::cerr;
    const auto r = solve_time_freezing_ocp(Ocp::system(), ocp, Ocp::q0(), Ocp::v0(), Ocp::grid(v.control_intervals), s);
    const Ocp::Feasibility f = Ocp::feasibility(r.points);
    const std::string status = r.solution.steps.empty() ? "" : r.solution.steps.back().ipopt_status;
    std::vector<int> per_step;
    for (const MpccHomotopyStep& st : r.solution.steps) per_step.push_back(st.ipopt_iterations);
    if (json)
      rows.push_back({{"variant", v.name}, {"what", v.what}, {"control_intervals", v.control_intervals},
                      {"converged", r.converged()}, {"solves", r.solution.steps.size()},
                      {"ipopt_iterations", r.solution.ipopt_iterations}, {"iterations_per_solve", per_step},
                      {"complementarity", r.solution.complementarity}, {"max_path_violation", f.path_violation},
                      {"worst_path_constraint", f.worst_row >= 0 ? Ocp::path_names[f.worst_row] : ""},
                      {"target_error", f.target_error}, {"objective", r.solution.objective}, {"status", status},
                      {"message", r.solution.message}, {"seconds", r.solution.seconds}});
    else
      std::printf("%-24s %4s %5zu %6d %9.2e %9.2e %9.2e %11.4e %-28s %8.1f\n", v.name, r.converged() ? "yes" : "no",
                  r.solution.steps.size(), r.solution.ipopt_iterations, r.solution.complementarity, f.path_violation,
                  f.target_error, r.solution.objective, status.c_str(), r.solution.seconds);
    std::fflush(stdout);
  }
  if (json) std::cout << nlohmann::ordered_json{{"hopper_over_three_holes", rows}}.dump(2) << "\n";
  return 0;
}
