// The plank-box's flagship OCP, the flat landing (scenes/plank_box_landing.hpp), under the
// formulation variants measured one by one (bench/experiments/README.md, "Plank-box flat landing").
//
//   plank_box_ocp [--short] [--json] [--only NAME] [--max-steps K] [--integrated-gap] [--velocity-cross]
//                 [--gap-scale K] [--contact-side W]
//                 [--element-length-freedom G]
//                 [--warm-start primal|primal-dual] [--kappa K]
//                 [--polish-below S] [--polish-max-iter K] [--max-iter K] [--ipopt NAME=VALUE]...
//
// --short runs the variants on scenes::PlankBoxShortLanding instead (the coarse-grid test's task:
// T = 1 s, N = 10, target 0.55 m, with its own solver limits).
//
// Every variant starts from the contact-implicit initialisation (the start state at every stage
// point, zero inputs) on the default grid (N = 15, 2 elements, n_s = 2) with the default homotopy
// (smoothing from sigma_0 = 1e-2, kappa = 0.1, 10 steps of at most 1500 Ipopt iterations); one
// progress line per Ipopt solve on stderr. Columns as bench/experiments/hopper_ocp.cpp's; `flat` is the largest
// |theta - phi| over the stage points [rad]. The flags: ocp_bench_support.hpp; they are applied
// after each variant's own settings, so --integrated-gap overrides `gap-of-q` and
// `before-2026-12-01`, and --polish-below the `*late-polish` variants.
// The JSON's "landing": the first event of the recovered trajectory (recover_trajectory) with a
// touchdown guard: {t, impact (false: a touchdown at zero normal velocity; an impact absorbed
// into a flowing element is read as an impact, recover_trajectory's docstring), guards (2: both
// corners at once), box_vz_before [m/s]}; null without one.
#include "scenes/plank_box_landing.hpp"

#include <saltus/timefreezing/drivers/optimal_control.hpp>

#include "ocp_bench_support.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <cstring>
#include <iostream>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

namespace {

using namespace saltus;
using namespace saltus::timefreezing;

struct Variant {
  const char* name;
  const char* what;
  double flatness_tolerance = 0.0;
  /// > 0: the smoothing homotopy runs this many steps (no polish), then `then` continues from its
  /// primal-dual solution from sigma = then_sigma_0 (Penalty: rho_0 = 1 / then_sigma_0) on the
  /// grid with contact_side_weight = then_side_weight.
  int smoothing_steps = 0;
  double then_sigma_0 = 0.0;
  bool scholtes = false;             ///< the Scholtes inequalities instead of the smoothing
  double contact_side_weight = 0.0;  ///< FesdOptions::regularisation.contact_side
  MpccSolverOptions::Relaxation then = MpccSolverOptions::Relaxation::Penalty;
  double then_side_weight = 0.0;
  /// The gap switching functions read gap(q) (FesdOptions::switching.integrated_gap = false; the default
  /// reads the integrated gaps since 2026-12-01).
  bool gap_of_q = false;
  /// The polish of the default before 2026-12-01: only after the homotopy's last step, 100
  /// iterations (MpccSolverOptions::Polish::below = 0, max_iter = 100).
  bool late_polish = false;
};

std::vector<Variant> variants() {
  return {
      {"default", "plank_box --json: theta - phi = 0 at every stage point"},
      {"flat-1e-4", "|theta - phi| <= 1e-4 instead of the equality", 1e-4},
      {"free-angle", "no flatness requirement (|theta - phi| <= 1: never active)", 1.0},
      {"smoothing-then-penalty", "the default's first 4 smoothing steps (1e-2 .. 1e-5), then the penalty from rho = 1e5",
       0.0, 4, 1e-5},
      {"smoothing-then-penalty-100", "the default's first 4 smoothing steps, then the penalty from rho = 100", 0.0, 4,
       1e-2},
      {"side", "the default with the contact-side selection 1e-2, or --contact-side W "
               "(FesdOptions::contact_side_weight)", 0.0, 0, 0.0,
       false, 1e-2},
      {"scholtes-side", "Scholtes inequalities on every pair (no smoothed velocity pair) with the contact-side selection 1e-2",
       0.0, 0, 0.0, true, 1e-2},
      {"smoothing-then-scholtes-side",
       "the default's first 4 smoothing steps (1e-2 .. 1e-5), then Scholtes with the contact-side selection 1e-2 from "
       "1e-6",
       0.0, 4, 1e-6, false, 0.0, MpccSolverOptions::Relaxation::Scholtes, 1e-2},
      {"smoothing-then-scholtes",
       "the default's first 4 smoothing steps (1e-2 .. 1e-5), then Scholtes inequalities on every pair (the velocity "
       "pairs no longer smoothed: a sticking corner need not creep) from 1e-6",
       0.0, 4, 1e-6, false, 0.0, MpccSolverOptions::Relaxation::Scholtes, 0.0},
      {"smoothing-then-side",
       "the default's first 3 smoothing steps (1e-2 .. 1e-4), then the same smoothing with the contact-side "
       "selection 1e-2 from 1e-5 (alpha_gap is free in the touchdown element: the impact ran the clock)",
       0.0, 3, 1e-5, false, 0.0, MpccSolverOptions::Relaxation::Smoothing, 1e-2},
      {"gap-of-q", "the default reading gap(q) instead of the integrated gaps (same polish)", 0.0, 0, 0.0, false, 0.0,
       MpccSolverOptions::Relaxation::Penalty, 0.0, true},
      {"before-2026-12-01",
       "the default of before 2026-12-01: gap(q), the polish only after the last step (100 iterations)", 0.0, 0, 0.0,
       false, 0.0, MpccSolverOptions::Relaxation::Penalty, 0.0, true, true},
      {"integrated-gap-late-polish",
       "the default with the polish only after the last step (100 iterations): the integrated gaps alone", 0.0, 0,
       0.0, false, 0.0, MpccSolverOptions::Relaxation::Penalty, 0.0, false, true},
  };
}

}  // namespace

template <class Ocp>
int run(const std::optional<bench::OcpBenchArgs>& args) {
  const bool json = args->json;
  const std::string& only = args->only;
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  if (!bench::only_names_a_variant(only, variants(), "plank_box_ocp")) return 2;
  if (!json)
    std::printf("%-24s %4s %5s %6s %9s %9s %9s %11s %-28s %8s\n", "variant", "conv", "steps", "iters", "compl", "flat",
                "target", "J", "status", "seconds");
  for (const Variant& v : variants()) {
    if (!only.empty() && only != v.name) continue;
    std::fprintf(stderr, "== %s: %s\n", v.name, v.what);
    Ocp ocp;
    ocp.flatness_tolerance = v.flatness_tolerance;
    MpccSolverOptions s = Ocp::solver();
    if (v.scholtes) s.homotopy.relaxation = MpccSolverOptions::Relaxation::Scholtes;
    s.progress = &std::cerr;
    if (v.late_polish) {
      s.polish.below = 0.0;
      s.polish.max_iter = 100;
    }
    FesdOptions grid = Ocp::grid();
    if (v.gap_of_q) grid.switching.integrated_gap = false;
    grid.regularisation.contact_side = v.contact_side_weight;
    args->apply(s);
    args->apply(grid);
    TimeFreezingOcpResult<scenes::PlankBox> r;
    if (v.smoothing_steps > 0) {
      const FesdMpcc<scenes::PlankBox, Ocp> problem(Ocp::system(), ocp, Ocp::q0(), Ocp::v0(), grid);
      MpccStart start;
      start.x.resize(problem.variable_count());
      problem.initial_point(start.x);
      MpccSolverOptions first = s;
      first.homotopy.max_steps = v.smoothing_steps;
      first.polish.enabled = false;
      const MpccSolution a = solve_mpcc(problem, start, first);
      FesdOptions then_grid = grid;
      then_grid.regularisation.contact_side = v.then_side_weight;
      const FesdMpcc<scenes::PlankBox, Ocp> then_problem(Ocp::system(), ocp, Ocp::q0(), Ocp::v0(), then_grid);
      r.solution = bench::continue_homotopy(then_problem, a, s, v.then, v.then_sigma_0,
                                            s.homotopy.max_steps - v.smoothing_steps);
      const auto pts = then_problem.points(r.solution.x);
      r.points.assign(pts.begin(), pts.end());
    } else {
      r = solve_time_freezing_ocp(Ocp::system(), ocp, Ocp::q0(), Ocp::v0(), grid, s);
    }
    const typename Ocp::Feasibility f = Ocp::feasibility(r.points);
    // The landing as the recovered trajectory reads it (recover_trajectory): one impact whose
    // guards are both corners' touchdowns, or two, or a touchdown without impact.
    nlohmann::ordered_json landing = nullptr;
    const HybridTrajectory<scenes::PlankBox> traj = recover_trajectory(Ocp::system(), r.points, grid.grid.stages);
    for (const auto& ev : traj.events) {
      bool touchdown = false;
      for (const Guard& g : ev.guards()) touchdown = touchdown || g.kind == GuardKind::Touchdown;
      if (!touchdown) continue;
      landing = {{"t", ev.t}, {"impact", ev.impact()}, {"guards", ev.guards().size()},
                 {"box_vz_before", ev.x_minus[5]}};
      break;
    }
    const std::string status = r.solution.steps.empty() ? "" : r.solution.steps.back().ipopt_status;
    std::vector<int> per_step;
    for (const MpccHomotopyStep& st : r.solution.steps) per_step.push_back(st.ipopt_iterations);
    if (json)
      rows.push_back({{"variant", v.name}, {"what", v.what}, {"converged", r.converged()},
                      {"solves", per_step.size()}, {"ipopt_iterations", r.solution.ipopt_iterations},
                      {"iterations_per_solve", per_step}, {"complementarity", r.solution.complementarity},
                      {"flatness", f.path_violation}, {"target_error", f.target_error},
                      {"objective", r.solution.objective}, {"status", status}, {"message", r.solution.message},
                      {"worst_pair", r.solution.worst_pair}, {"landing", landing}, {"seconds", r.solution.seconds}});
    else
      std::printf("%-24s %4s %5zu %6d %9.2e %9.2e %9.2e %11.4e %-28s %8.1f\n", v.name, r.converged() ? "yes" : "no",
                  per_step.size(), r.solution.ipopt_iterations, r.solution.complementarity, f.path_violation,
                  f.target_error, r.solution.objective, status.c_str(), r.solution.seconds);
    std::fflush(stdout);
  }
  constexpr bool short_landing = std::is_same_v<Ocp, scenes::PlankBoxShortLanding>;
  if (json)
    std::cout << nlohmann::ordered_json{{short_landing ? "plank_box_short_landing" : "plank_box_flat_landing", rows}}.dump(2)
              << "\n";
  return 0;
}

int main(int argc, char** argv) {
  // --short is this program's own flag; the others are the shared ones (ocp_bench_support.hpp).
  bool short_landing = false;
  std::vector<char*> rest = bench::take_own_flag(argc, argv, "--short", short_landing);
  const std::optional<bench::OcpBenchArgs> args =
      bench::parse_ocp_bench_args(static_cast<int>(rest.size()), rest.data(), "plank_box_ocp [--short]");
  if (!args) return 2;
  return short_landing ? run<scenes::PlankBoxShortLanding>(args) : run<scenes::PlankBoxFlatLanding>(args);
}
