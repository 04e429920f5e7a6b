// The plank-box's mode-schedule refinement (scenes/plank_box_landing.hpp, compiled once in the
// library saltus_plank_box_refinement): discovery and refinement of its short landing on a coarse
// grid. A release-stage suite: tests/CMakeLists.txt leaves it out of the sanitizer build, which then
// compiles neither this program nor the plank-box's refinement unit (the refinement's code paths run
// under the sanitizers in tests/test_refinement.cpp, on the guiding example's scene).
#include "scenes/plank_box_landing.hpp"

#include <saltus/timefreezing/refinement/discovery.hpp>
#include <saltus/timefreezing/refinement/mode_schedule.hpp>

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace saltus::scenes
