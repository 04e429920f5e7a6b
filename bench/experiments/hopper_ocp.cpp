// The flagship OCP, the hopper over three holes (scenes/hopper_holes.hpp; time-freezing paper
// Section 6), under the solver and formulation variants the issue asks to measure one by one.
//
//   hopper_ocp [--one-hole] [--json] [--only NAME] [--max-steps K] [--integrated-gap]
//              [--velocity-cross] [--gap-scale K] [--contact-side W]
//              [--element-length-freedom G]
//              [--warm-start primal|primal-dual] [--polish-below S] [--polish-max-iter K] [--max-iter K]
//              [--kappa K] [--ipopt NAME=VALUE]...
//
// --one-hole runs the variants on scenes::HopperOverOneHole instead: T = 1 s over the first hole,
// N = 8 of the flagship's 20 intervals, which meets the same wall (bench/experiments/README.md, "The one-hole
// test bed"); hop-guess (a three-hop guess) is skipped there, and `--one-hole --only hop-guess` is
// refused. On --one-hole every variant starts from that bed's own settings, which converge there
// (HopperOverOneHole: the contact-side selection 1e-2, so `side` is `default` there, primal-only
// warm starts, 11 steps; the two-phase variants' second phase keeps its own budget and weight); the
// one-hole measurements before bench/experiments/README.md's "The one-hole bed converges" ran with the
// flagship's, which are `--contact-side 0 --warm-start primal-dual --max-steps 10` now. The
// other flags: ocp_bench_support.hpp.
// --max-steps K overrides the homotopy's step budget (10; --one-hole: 11); --ipopt passes an Ipopt option to every
// solve (ocp_bench_support.hpp; the measurements of bench/experiments/README.md's hopper section use both).
//
// Every variant but hop-guess starts from the paper's initialisation (the start state at every stage point,
// zero torques; FesdMpcc::initial_point), on the paper's grid (N = 20, 3 elements, n_s = 2; N = 8
// with --one-hole), with
// sigma_0 = 1, kappa = 0.1, 10 steps (--one-hole: 11, primal-only starts, rho_c = 1e-2), 1500 Ipopt
// iterations per step, Ipopt tol 1e-8; one
// progress line per Ipopt solve on stderr. Columns, per variant:
//   conv          the homotopy converged (complementarity <= 1e-9 at a successful step)
//   steps         Ipopt solves run (continuation stages, homotopy steps, retries, polishes)
//   iters         total Ipopt iterations (per solve in the JSON)
//   compl         max_j |G_j H_j| at the returned point
//   path viol     largest violation of the 11 path rows at every stage point, at the FULL holes
//   target        max_i |q_i(T) - q_target,i|
//   J             objective (the integral of u'u over physical time plus the two penalties)
//   status        Ipopt's status of the last solve
//   seconds       wall time of the solve (one thread: run with OPENBLAS_NUM_THREADS=1)
// bench/experiments/README.md ("Hopper over three holes") has the table of a run and what it shows.
#include "scenes/hopper_holes.hpp"

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
  MpccSolverOptions::Relaxation relaxation = MpccSolverOptions::Relaxation::Smoothing;
  bool velocity_switch_detection = false;
  bool hole_continuation = true;
  /// N; 0: the scene's own (20 for the flagship, 8 for --one-hole); -2: half the scene's
  int control_intervals = 0;
  bool hop_guess = false;  ///< start from Ocp::hop_guess (the second initialisation) instead
  /// > 0: the default's homotopy runs this many steps (no polish), then `then` continues from its
  /// primal-dual solution from sigma = then_sigma_0 (< 0: the sigma the first homotopy stopped
  /// at; Penalty: rho_0 = 1 / then_sigma_0) on the grid with contact_side_weight =
  /// then_side_weight.
  int smoothing_steps = 0;
  double then_sigma_0 = 0.0;
  double contact_side_weight = 0.0;  ///< > 0: FesdOptions::regularisation.contact_side; 0: the scene's
  int stages = 2;                    ///< Radau IIA stages n_s
  MpccSolverOptions::Relaxation then = MpccSolverOptions::Relaxation::Penalty;
  double then_side_weight = 0.0;
  /// > 0: a continuation on a_n at sigma_0 (with_an_continuation): the hole continuation runs with
  /// this a_n, then one relaxed NLP per larger a_n of 50, 100, then the homotopy with a_n = 200.
  double first_auxiliary_acceleration = 0.0;
  /// With smoothing_steps: the continued homotopy reads the integrated gaps
  /// (FesdOptions::switching.integrated_gap; the first one reads gap(q)).
  bool then_integrated_gap = false;
};

std::vector<Variant> variants() {
  using R = MpccSolverOptions::Relaxation;
  return {
      {"default", "the default homotopy: smoothing, cross-complementarity on the gap, continuation on the holes"},
      {"paper", "the paper's formulation (NOSNOC): Scholtes, cross-complementarity on all, no continuation",
       R::Scholtes, true, false},
      {"no-continuation", "the default without the continuation on the holes", R::Smoothing, false, false},
      {"scholtes", "the default with the Scholtes inequalities instead of the smoothing", R::Scholtes, false, true},
      {"velocity-cross", "the default with cross-complementarity on the velocities too", R::Smoothing, true, true},
      {"penalty", "the default with the penalty (elastic) homotopy", R::Penalty, false, true},
      {"hop-guess", "second initialisation: the default from a kinematic three-hop guess, no continuation",
       R::Smoothing, false, false, 0, true},
      {"smoothing-then-penalty", "the default's continuation and first 4 steps (sigma 1 .. 1e-3), then the penalty from rho = 1e3",
       R::Smoothing, false, true, 0, false, 4, 1e-3},
      {"scholtes-side", "Scholtes inequalities on every pair (no smoothed velocity pair) with the contact-side selection 1e-2",
       R::Scholtes, false, true, 0, false, 0, 0.0, 1e-2},
      {"side", "the default with the contact-side selection 1e-2, or --contact-side W "
               "(FesdOptions::contact_side_weight)", R::Smoothing,
       false, true, 0, false, 0, 0.0, 1e-2},
      {"an-continuation", "the default with a continuation on a_n at sigma = 1: holes at a_n = 20, then 50, 100, 200",
       R::Smoothing, false, true, 0, false, 0, 0.0, 0.0, 2, R::Penalty, 0.0, 20.0},
      {"an-continuation-100", "the default with a continuation on a_n at sigma = 1: holes at a_n = 100, then 200",
       R::Smoothing, false, true, 0, false, 0, 0.0, 0.0, 2, R::Penalty, 0.0, 100.0},
      {"stages-3", "the default with Radau IIA n_s = 3", R::Smoothing, false, true, 0, false, 0, 0.0, 0.0, 3},
      {"stages-1", "the default with Radau IIA n_s = 1 (implicit Euler)", R::Smoothing, false, true, 0, false, 0, 0.0, 0.0, 1},
      {"half-intervals", "the default on half the scene's control intervals (twice as long each)", R::Smoothing, false,
       true, -2},
      {"smoothing-then-scholtes-side",
       "the default's continuation and first 4 steps (sigma 1 .. 1e-3), then Scholtes with the contact-side selection "
       "1e-2 from sigma = 1e-4",
       R::Smoothing, false, true, 0, false, 4, 1e-4, 0.0, 2, R::Scholtes, 1e-2},
      {"smoothing-then-scholtes",
       "the default's continuation and first 4 steps (sigma 1 .. 1e-3), then Scholtes inequalities on every pair "
       "(the velocity pairs no longer smoothed: a sticking foot need not creep) from sigma = 1e-4",
       R::Smoothing, false, true, 0, false, 4, 1e-4, 0.0, 2, R::Scholtes, 0.0},
      {"smoothing-then-side",
       "the default's continuation and first 4 steps (sigma 1 .. 1e-3), then the same smoothing with the contact-side "
       "selection 1e-2 from sigma = 1e-4",
       R::Smoothing, false, true, 0, false, 4, 1e-4, 0.0, 2, R::Smoothing, 1e-2},
      {"smoothing-then-side-same-sigma",
       "as smoothing-then-side, but the selection is switched on at the last solved sigma (1e-3): that NLP is solved "
       "again with the term, then the homotopy goes on",
       R::Smoothing, false, true, 0, false, 4, 1e-3, 0.0, 2, R::Smoothing, 1e-2},
      {"then-integrated-gap",
       "the default's continuation and first 4 steps (sigma 1 .. 1e-3) reading gap(q), then the same smoothing from "
       "sigma = 1e-3 reading the integrated gaps (FesdOptions::integrated_gap), polished as --polish-below says",
       R::Smoothing, false, true, 0, false, 4, 1e-3, 0.0, 2, R::Smoothing, 0.0, 0.0, true},
      {"wall-then-integrated-gap",
       "the default's whole homotopy (10 steps) reading gap(q), then one smoothing step at the sigma it stopped at "
       "reading the integrated gaps, polished as --polish-below says (use --polish-below 1)",
       R::Smoothing, false, true, 0, false, 10, -1.0, 0.0, 2, R::Smoothing, 0.0, 0.0, true},
  };
}

/// The continuation on a_n (Variant::first_auxiliary_acceleration): the hole continuation and the
/// first relaxed NLP with a_n = first, then one relaxed NLP per a_n of 50, 100 above `first` (each
/// from the last one's primal-dual solution), then the whole homotopy with the problem's a_n.
template <class Ocp>
TimeFreezingOcpResult<scenes::Hopper> with_an_continuation(double first, const Ocp& ocp, const FesdOptions& grid,
                                                            const MpccSolverOptions& s) {
  MpccSolverOptions one = s;
  one.homotopy.max_steps = 1;
  one.polish.enabled = false;
  const TimeFreezingSystem<scenes::Hopper> soft{scenes::Hopper{}, first};
  TimeFreezingOcpResult<scenes::Hopper> r =
      solve_time_freezing_ocp_by_continuation(soft, Ocp::hole_continuation(), ocp, Ocp::q0(), Ocp::v0(), grid, one);
  MpccSolution last = r.solution;
  std::vector<MpccHomotopyStep> earlier = r.continuation_steps;  // every solve before the homotopy
  earlier.insert(earlier.end(), last.steps.begin(), last.steps.end());
  for (double a_n : {50.0, 100.0, Ocp::auxiliary_acceleration}) {
    const bool final_stage = a_n == Ocp::auxiliary_acceleration;
    if (a_n <= first && !final_stage) continue;
    const FesdMpcc<scenes::Hopper, Ocp> problem(TimeFreezingSystem<scenes::Hopper>{scenes::Hopper{}, a_n}, ocp, Ocp::q0(),
                                                Ocp::v0(), grid);
    const MpccStart from{last.x, last.constraint_multipliers, last.bound_multipliers_lower, last.bound_multipliers_upper};
    MpccSolution next = solve_mpcc(problem, from, final_stage ? s : one);
    next.ipopt_iterations += last.ipopt_iterations;
    next.seconds += last.seconds;
    if (!final_stage) earlier.insert(earlier.end(), next.steps.begin(), next.steps.end());
    last = std::move(next);
    if (final_stage) {
      const auto pts = problem.points(last.x);
      r.points.assign(pts.begin(), pts.end());
    }
  }
  r.solution = std::move(last);
  r.continuation_steps = std::move(earlier);  // reported like the hole continuation's solves
  // The events and the recovered reference of the first stage do not describe the final points
  // (this benchmark reports neither): dropped rather than left stale.
  r.element_lengths.clear();
  r.frozen_phases.clear();
  r.switch_points.clear();
  r.reference = {};
  r.trajectory = {};
  return r;
}

template <class Ocp>
int run(const std::optional<bench::OcpBenchArgs>& args) {
  constexpr bool one_hole = std::is_same_v<Ocp, scenes::HopperOverOneHole>;
  const bool json = args->json;
  const std::string& only = args->only;
  if (one_hole && only == "hop-guess") {
    std::fprintf(stderr, "hopper_ocp: hop-guess is a three-hop guess over 2.5 s; it does not run with --one-hole\n");
    return 2;
  }
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  if (!bench::only_names_a_variant(only, variants(), "hopper_ocp")) return 2;
  if (!json)
    std::printf("%-24s %4s %5s %6s %9s %9s %9s %11s %-28s %8s\n", "variant", "conv", "steps", "iters", "compl",
                "path viol", "target", "J", "status", "seconds");
  for (const Variant& v : variants()) {
    if (!only.empty() && only != v.name) continue;
    if (one_hole && v.hop_guess) {
      std::fprintf(stderr, "== %s: skipped (its guess is three hops over 2.5 s, not the one-hole task)\n", v.name);
      continue;
    }
    std::fprintf(stderr, "== %s: %s\n", v.name, v.what);
    const Ocp ocp;
    MpccSolverOptions s = Ocp::solver();
    s.homotopy.relaxation = v.relaxation;
    s.progress = &std::cerr;
    args->apply(s);
    if (v.smoothing_steps > 0) {
      s.homotopy.max_steps = v.smoothing_steps;
      s.polish.enabled = false;
    }
    const int scene_intervals = Ocp::grid().grid.control_intervals;
    FesdOptions grid = Ocp::grid(v.control_intervals > 0 ? v.control_intervals
                                 : v.control_intervals == -2 ? scene_intervals / 2
                                                             : scene_intervals,
                                 3, v.stages);
    grid.switching.velocity_detection = v.velocity_switch_detection;
    // A variant without the selection keeps the scene's (the flagship: none; --one-hole: 1e-2).
    if (v.contact_side_weight > 0.0) grid.regularisation.contact_side = v.contact_side_weight;
    args->apply(grid);
    auto r = v.first_auxiliary_acceleration > 0.0 ? with_an_continuation(v.first_auxiliary_acceleration, ocp, grid, s)
             : v.hop_guess ? solve_time_freezing_ocp_from_guess(Ocp::system(), ocp, Ocp::q0(), Ocp::v0(), grid,
                                                                    &scenes::HopperOverThreeHoles::hop_guess, s)
                   : v.hole_continuation ? solve_time_freezing_ocp_by_continuation(Ocp::system(), Ocp::hole_continuation(),
                                                                                 ocp, Ocp::q0(), Ocp::v0(), grid, s)
                                       : solve_time_freezing_ocp(Ocp::system(), ocp, Ocp::q0(), Ocp::v0(), grid, s);
    if (v.smoothing_steps > 0 && !r.converged()) {  // r ran smoothing_steps steps without polish (above)
      FesdOptions then_grid = grid;
      then_grid.regularisation.contact_side = v.then_side_weight;
      if (v.then_integrated_gap) then_grid.switching.integrated_gap = true;
      const FesdMpcc<scenes::Hopper, Ocp> problem(Ocp::system(), ocp, Ocp::q0(), Ocp::v0(), then_grid);
      // then_sigma_0 < 0: from where the first homotopy stopped (its complementarity, = sigma).
      const double sigma_0 = v.then_sigma_0 < 0.0 ? r.solution.complementarity : v.then_sigma_0;
      r.solution = bench::continue_homotopy(problem, r.solution, s, v.then, sigma_0,
                                            (args->max_steps > 0 ? args->max_steps : 10) - v.smoothing_steps);
      const auto pts = problem.points(r.solution.x);
      r.points.assign(pts.begin(), pts.end());
    }
    const typename Ocp::Feasibility f = Ocp::feasibility(r.points);
    const std::string status = r.solution.steps.empty() ? "" : r.solution.steps.back().ipopt_status;
    std::vector<int> per_step;
    for (const MpccHomotopyStep& st : r.continuation_steps) per_step.push_back(st.ipopt_iterations);
    for (const MpccHomotopyStep& st : r.solution.steps) per_step.push_back(st.ipopt_iterations);
    const std::size_t solves = per_step.size();
    if (json)
      rows.push_back({{"variant", v.name}, {"what", v.what}, {"gap_scale", grid.switching.scale[0]}, {"contact_side_weight", grid.regularisation.contact_side}, {"element_length_freedom", grid.grid.element_length_freedom}, {"warm_start", s.warm_start}, {"control_intervals", grid.grid.control_intervals},
                      {"converged", r.converged()}, {"solves", solves},
                      {"ipopt_iterations", r.solution.ipopt_iterations}, {"iterations_per_solve", per_step},
                      {"complementarity", r.solution.complementarity}, {"max_path_violation", f.path_violation},
                      {"worst_path_constraint", f.worst_row >= 0 ? Ocp::path_names[f.worst_row] : ""},
                      {"target_error", f.target_error}, {"objective", r.solution.objective}, {"status", status},
                      {"message", r.solution.message}, {"seconds", r.solution.seconds}});
    else
      std::printf("%-24s %4s %5zu %6d %9.2e %9.2e %9.2e %11.4e %-28s %8.1f\n", v.name, r.converged() ? "yes" : "no",
                  solves, r.solution.ipopt_iterations, r.solution.complementarity, f.path_violation,
                  f.target_error, r.solution.objective, status.c_str(), r.solution.seconds);
    std::fflush(stdout);
  }
  if (json)
    std::cout << nlohmann::ordered_json{{one_hole ? "hopper_over_one_hole" : "hopper_over_three_holes", rows}}.dump(2)
              << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // --one-hole is this program's own flag; the others are the shared ones (ocp_bench_support.hpp).
  bool one_hole = false;
  std::vector<char*> rest = bench::take_own_flag(argc, argv, "--one-hole", one_hole);
  const std::optional<bench::OcpBenchArgs> args =
      bench::parse_ocp_bench_args(static_cast<int>(rest.size()), rest.data(), "hopper_ocp [--one-hole]");
  if (!args) return 2;
  return one_hole ? run<scenes::HopperOverOneHole>(args) : run<scenes::HopperOverThreeHoles>(args);
}
