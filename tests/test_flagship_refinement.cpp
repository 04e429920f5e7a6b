// The flagship scenes' mode-schedule refinement, each compiled once in its own library: the
// plank-box's (scenes/plank_box_landing.hpp, saltus_plank_box_refinement): discovery and refinement
// of its short landing on a coarse grid; the hopper's (scenes/hopper_holes_refinement.hpp,
// saltus_hopper_refinement, for the three-hole OCP type): the whole chain, discovery, refinement
// and analysis, on the one-hole bed. A release-stage suite: tests/CMakeLists.txt leaves it out of
// the sanitizer build, which then compiles neither this program nor the refinement units (the
// refinement's code paths run under the sanitizers in tests/test_refinement.cpp, on the guiding
// example's scene).
#include "one_hole_checks.hpp"
#include "scenes/hopper_holes_refinement.hpp"
#include "scenes/hopper_tracking.hpp"
#include "scenes/plank_box_landing.hpp"

#include <saltus/sensitivity/analysis/reference_analysis.hpp>
#include <saltus/timefreezing/refinement/discovery.hpp>
#include <saltus/timefreezing/refinement/mode_schedule.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <sstream>
#include <vector>

namespace saltus::scenes {
namespace {

// The plank-box's discovery and refinement on a coarse grid (the short landing that
// tests/test_flagship_ocps.cpp solves in PlankBoxShortLanding.CoarseGridConvergesWithAFlatLandingAndALiftOff).
// Discovery reads the first relaxed solution (sigma = 1e-2) with sigma-scaled tolerances
// (DiscoveryOptions::reading, 0.1 sigma m and sigma m/s): "land flat, slide, lift off"; read with
// the exact tolerances (the default) the same solution has no contact at all (the landed box rests 1e-4 m above the plank, creeping up at
// a few mm/s) and its refinement is a hover (objective 97.3). The refinement of that schedule
// (elements of 0.02 s, Radau IIA n_s = 3) is exact in its modes and rows; the left corner carries
// zero normal force over part of the slide at the optimum (its validity row lambda_n >= 0 active),
// so the event-driven re-simulation releases and retouches it there (unplanned events, counted),
// and its distance (3.7e-5 here, 3.9e-6 at 0.01 s) stays above the 1e-6 of "refined".
TEST(PlankBoxShortLanding, DiscoveryAndRefinementOnACoarseGrid) {
  using Landing = PlankBoxShortLanding;
  const PlankBox scene{};
  timefreezing::DiscoveryOptions options;
  options.agreeing_steps = 1;
  options.reading.gap_per_sigma = 0.1;
  options.reading.velocity_per_sigma = 1.0;
  const auto discovery = timefreezing::discover_schedule(scene, Landing::system(), Landing{}, Landing::q0(),
                                                         Landing::v0(), Landing::grid(), Landing::solver(), options);
  ASSERT_TRUE(discovery.schedule_found) << discovery.message;
  EXPECT_EQ(discovery.steps.size(), 1u);
  EXPECT_EQ(timefreezing::describe(scene, discovery.discovered.guess.schedule),
            "C_L:open C_R:open [touchdown C_L + touchdown C_R] C_L:slip+ C_R:slip+ [release C_L + release C_R] "
            "C_L:open C_R:open");
  timefreezing::DiscoveryOptions exact = options;
  exact.reading.gap_per_sigma = exact.reading.velocity_per_sigma = 0.0;
  const auto floating = timefreezing::discover_schedule(scene, Landing::system(), Landing{}, Landing::q0(),
                                                        Landing::v0(), Landing::grid(), Landing::solver(), exact);
  ASSERT_TRUE(floating.schedule_found) << floating.message;
  EXPECT_EQ(timefreezing::describe(scene, floating.discovered.guess.schedule), "C_L:open C_R:open");

  const auto r = timefreezing::refine_schedule(scene, Landing{}, Landing::refinement_horizon(),
                                               discovery.discovered.guess, Landing::refinement());
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_LE(r.mode_validity_violation, 1e-9);
  EXPECT_LE(r.path_violation, 1e-6);
  EXPECT_LE(r.terminal_violation, 1e-6);
  EXPECT_LT(r.objective, discovery.relaxed.solution.objective);  // 38.6 against 58.6
  EXPECT_LE(r.phase_resim_max_error, 1e-4) << r.message;
  EXPECT_LE(r.open_loop.max_error, 1e-4) << r.open_loop.note;
}

// The one-hole bed's OCP is the three-hole OCP with the target (1, 0.4, 0, 0) (HopperOverThreeHoles::
// target), so that its discovery and refinement run on the three-hole type's compiled code; the
// three-hole task keeps its own target.
TEST(HopperOverOneHole, IsTheThreeHoleOcpWithAnotherTarget) {
  using Short = HopperOverOneHole;
  EXPECT_EQ(HopperOverThreeHoles{}.target, HopperOverThreeHoles::q_target());
  EXPECT_EQ(HopperOverThreeHoles{}.terminal_lower(), Vec<4>(3.0, 0.4, 0.0, 0.0));
  EXPECT_EQ(Short{}.target, Short::q_target());
  const HopperOverThreeHoles rows = Short::on_three_hole_rows();
  EXPECT_EQ(rows.terminal_lower(), Vec<4>(1.0, 0.4, 0.0, 0.0));
  EXPECT_EQ(rows.terminal_upper(), Vec<4>(1.0, 0.4, 0.0, 0.0));
  EXPECT_EQ(rows.hole_level, 1.0);
  EXPECT_EQ(Short::on_three_hole_rows(0.5).hole_level, 0.5);
  EXPECT_EQ(rows.path_lower(), Short{}.path_lower());
  EXPECT_EQ(rows.path_upper(), Short{}.path_upper());
  const std::vector<HopperOverThreeHoles> levels = HopperOverThreeHoles::hole_continuation(Short::q_target());
  const std::vector<Short> short_levels = Short::hole_continuation();
  ASSERT_EQ(levels.size(), short_levels.size());
  for (std::size_t k = 0; k < levels.size(); ++k) {
    EXPECT_EQ(levels[k].hole_level, short_levels[k].hole_level);
    EXPECT_EQ(levels[k].terminal_lower(), short_levels[k].terminal_lower());
  }
  EXPECT_EQ(HopperOverThreeHoles::hole_continuation().back().target, HopperOverThreeHoles::q_target());
  const timefreezing::OcpHorizon<Hopper> horizon = hopper_refinement_horizon(Short::horizon);
  EXPECT_EQ(horizon.final_time, 1.0);
  EXPECT_EQ(hopper_refinement_horizon().final_time, HopperOverThreeHoles::horizon);
  EXPECT_THROW((void)hopper_refinement_horizon(0.0), InvalidArgument);
}

// The whole chain on the one-hole bed (T = 1 s, target (1, 0.4, 0, 0), N = 8; HopperOverOneHole)
// in 32 s on an idle machine (measured below): run_hopper_chain, the
// code of examples/hopper.cpp --json and of the Python binding, with hopper_chain_options(OneHole),
// the three-hole chain's settings (docs/refinement.md, "Hopper over three holes") but for three:
//  - discovery: the hole continuation and two homotopy steps (sigma = 1, 0.1) with the one-hole
//    bed's grid and solver (contact-side selection, primal-only warm starts), on the three-hole
//    OCP type with the one-hole target (nothing else compiled);
//  - refinement: the three-hole options (n_s = 4, elements of at most 0.05 s, ...) but the mesh
//    refined to local error 2e-7 instead of 2e-8 (the per-phase re-simulation check needs 1e-6:
//    measured 2.8e-7; at 1e-6 it failed with 1.4e-6; at 2e-8 the refinement took 64 s instead of
//    32-35 s, both beside another build);
//  - analysis: the LQR design (R = I) and its stability check as the flagship's, 30 Monte Carlo runs
//    at eps = 1e-6 (not 200) and no deviation times (60 of them cost the batch about 11 s).
// Measured (release, one thread; docs/refinement.md, "The whole chain on the one-hole bed"): alone on
// the machine 31.9 s, discovery 11.9 s, refinement 16.6 s (4 mesh rounds, 169 elements, 183 Ipopt
// iterations), analysis 3.3 s; beside other work up to 62 s; none of the variants measured there
// was faster. Footholds 0, 0.246, 0.750, 1 from the discovered
// slides; refined objective 39.20 (the relaxed 13.27), mode validity 7e-13, per-phase
// re-simulation 2.8e-7; a hop in place (lift-off 0.40 s, touchdown at foot x 0.2498, on the hole's
// edge), the jump over the hole (0.55 s to 0.75 s, touchdown at x = 0.834), a hop to x = 1
// (touchdown 0.92 s); the LQR design stable (a(T) <= 0.969), 20 of 30 runs keep the event sequence
// (the other 10 bounce at the touchdown beyond the hole) and all shrink, first-order to 7.5e-4.
// Checked as a structure that another gait would also pass (as HopperOverOneHole.
// CoarseGridConvergesAndJumpsTheHole in test_flagship_ocps.cpp): every touchdown lands outside the
// hole, one flight crosses it, no lift-off comes last.
TEST(HopperOverOneHole, WholeChainDiscoveryRefinementAnalysis) {
  using Short = HopperOverOneHole;
  const HopperOverThreeHoles ocp = Short::on_three_hole_rows();
  const HopperChainOptions options = hopper_chain_options(HopperTask::OneHole);  // the settings above
  EXPECT_EQ(options.local_error_tolerance, 2e-7);
  EXPECT_EQ(options.runs, 30);
  EXPECT_EQ(options.perturbation_size, 1e-6);  // as the flagship's: the touchdowns' saltation norms
  EXPECT_EQ(options.deviation_times, 0);
  const HopperChain chain = run_hopper_chain(options);
  const timefreezing::DiscoveryResult<Hopper>& discovery = chain.discovery;
  ASSERT_TRUE(discovery.schedule_found) << discovery.message;
  EXPECT_EQ(discovery.continuation_steps.size(), HopperOverThreeHoles::hole_continuation().size());
  const HopperFootsteps& footsteps = chain.footsteps;
  ASSERT_GE(footsteps.footholds.size(), 2u);
  EXPECT_EQ(footsteps.footholds.back(), 1.0);  // the target's foothold

  ASSERT_TRUE(chain.refined.has_value()) << chain.refinement_failure;
  const timefreezing::RefinementResult<Hopper>& r = *chain.refined;
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_EQ(r.stage, "refined") << r.message;
  EXPECT_LE(r.mode_validity_violation, 1e-9);
  EXPECT_LE(r.path_violation, 1e-6);
  EXPECT_LE(r.terminal_violation, 1e-6);
  EXPECT_LE(r.phase_resim_max_error, 1e-6) << r.stage;
  EXPECT_EQ(r.phase_resimulation.size(), r.schedule.phases.size());
  for (const auto& phase : r.phase_resimulation) EXPECT_EQ(phase.unplanned_events, 0) << phase.note;
  // The runtime target, not the three-hole task's x = 3: the reference ends at (1, 0.4, 0, 0).
  const auto& traj = r.trajectory;
  const int last = static_cast<int>(traj.segments.size()) - 1;
  EXPECT_NEAR(traj.t_end(), 1.0, 1e-12);
  EXPECT_LE((traj.state(last, traj.t_end()).head<4>() - Short::q_target()).cwiseAbs().maxCoeff(), 1e-6);

  const auto& events = traj.events;
  testing::expect_one_hole_event_structure(events);

  ASSERT_TRUE(chain.analysis.has_value());
  const ReferenceAnalysis<Hopper>& a = *chain.analysis;
  ASSERT_TRUE(a.completed()) << a.failure;
  EXPECT_EQ(a.events.size(), events.size());
  ASSERT_TRUE(a.stability.has_value());
  EXPECT_EQ(a.stability->verdict, StabilityVerdict::Stable);
  ASSERT_TRUE(a.monte_carlo.has_value());
  const MonteCarloReport& batch = *a.monte_carlo;
  std::ostringstream why;
  for (const std::string& s : batch.failure_reasons) why << "\n  failed: " << s;
  for (const std::string& s : batch.departures) why << "\n  departed: " << s;
  EXPECT_EQ(batch.runs, 30);
  EXPECT_GE(batch.kept_event_sequence, 10) << why.str();  // measured 20
  EXPECT_EQ(batch.grew, 0) << why.str();
  EXPECT_LE(batch.max_log_discrepancy, 0.05) << why.str();
  EXPECT_TRUE(a.agree) << why.str();

  std::cout << "hopper over one hole, whole chain: discovery " << discovery.seconds << " s (" << discovery.message
            << "), refinement " << r.seconds << " s (" << r.stage << ", objective " << r.objective << ", "
            << r.element_times.size() - 1 << " elements, " << r.ipopt_iterations << " Ipopt iterations, re-simulation "
            << r.phase_resim_max_error << "), analysis " << a.seconds.total << " s ("
            << to_string(a.stability->verdict) << ", a(T) <= " << a.stability->upper_bound << ", "
            << batch.kept_event_sequence << " of " << batch.runs << " runs kept the events, discrepancy "
            << batch.max_log_discrepancy << "); events:" << testing::list_one_hole_events(events) << "\n";
}

}  // namespace
}  // namespace saltus::scenes
