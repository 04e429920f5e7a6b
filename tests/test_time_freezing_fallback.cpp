// The time-freezing simulation engine on easy problems (simulate_time_freezing's fallback,
// SimulationFallback; the whole battery: bench/time_freezing_battery): NOSNOC's bouncing-ball grid
// with a stiff auxiliary dynamics, a slide whose gap drifts without the contact-side selection, a
// rod landing flat while sliding (two contacts at once) against the event-driven simulator, and a
// frozen phase cut by the horizon's end, Painleve's rod taking its impact without collision in frozen
// time. Each against its closed form.
#include "scenes/point_mass.hpp"
#include "scenes/rod.hpp"
#include "scenes/time_freezing_examples.hpp"

#include <saltus/hybrid/simulation/simulator.hpp>
#include <saltus/timefreezing/drivers/simulate.hpp>
#if !defined(SALTUS_TESTS_UNDER_SANITIZERS)
#include <saltus/timefreezing/header_only.hpp>  // the time-freezing machinery of PainleveRod

#include "painleve_rod.hpp"
#endif

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace saltus::timefreezing {
namespace {

using scenes::PointMass;

constexpr double g = 9.81;

/// N control intervals of N_fe elements with n_s = 2 over the numerical horizon T.
FesdOptions grid_of(int N, int N_fe, double T) {
  FesdOptions o;
  o.grid.stages = 2;
  o.grid.control_intervals = N;
  o.grid.finite_elements = N_fe;
  o.grid.horizon = T;
  return o;
}

/// NOSNOC's bouncing-ball grid: 10 control intervals of 0.3, 2 elements each, n_s = 2.
FesdOptions bouncing_ball_grid() { return grid_of(10, 2, 3.0); }

/// The physical time at numerical time T of a point mass that lands at t1 with normal speed v1 and
/// then rests: the frozen phase takes v1 / a_n of numerical time, the rest runs the clock at
/// a_n / (a_n + g) (the Filippov combination theta (-g) + (1 - theta) a_n = 0).
double time_at_rest(double T, double t1, double v1, double a_n) { return t1 + (T - t1 - v1 / a_n) * a_n / (a_n + g); }

// The point mass dropped from rest at 0.8 m with a_n = 100 on NOSNOC's bouncing-ball grid: the
// touchdown (t = 0.404), the frozen phase (0.040 of numerical time) and the rest after it fall in
// control interval 1, three modes for two elements; its homotopy stalls (Infeasible_Problem_Detected
// at sigma ~ 0.026). The fallback solves that interval again on a finer grid.
TEST(TimeFreezingFallback, BouncingBallGridWithAStiffAuxiliaryDynamics) {
#if defined(SALTUS_TESTS_UNDER_SANITIZERS)
  GTEST_SKIP() << "18 s in Release, several minutes under the sanitizers: release stage only (the driver's "
                  "code paths run in this file's other tests there)";
#endif
  const TimeFreezingSystem<PointMass> system(PointMass(), 100.0);
  const Vec<2> q0(0.0, 0.8), v0 = Vec<2>::Zero();
  const double t1 = std::sqrt(2.0 * 0.8 / g), v1 = std::sqrt(2.0 * g * 0.8);
  TimeFreezingSimulationOptions without;
  without.fallback.enabled = false;
  const auto failed = simulate_time_freezing(system, q0, v0, bouncing_ball_grid(), NoObjective{}, {}, without);
  EXPECT_FALSE(failed.converged());
  EXPECT_NE(failed.solution.message.find("control interval 1"), std::string::npos) << failed.solution.message;
  EXPECT_TRUE(failed.fallback_log.empty());

  for (double contact_side : {0.0, 1e-2}) {
    FesdOptions grid = bouncing_ball_grid();
    grid.regularisation.contact_side = contact_side;
    const auto sim = simulate_time_freezing(system, q0, v0, grid);
    ASSERT_TRUE(sim.converged()) << sim.solution.message;
    ASSERT_EQ(sim.fallback_log.size(), 1u) << contact_side;
    EXPECT_EQ(sim.fallbacks, 1);
    EXPECT_NE(sim.fallback_log[0].find("interval 1 (not converged): solved on "), std::string::npos)
        << sim.fallback_log[0];
    ASSERT_EQ(sim.finite_elements.size(), 10u);
    EXPECT_GE(sim.finite_elements[1], 4);  // measured 8 (the 4 elements' impact element ran its clock back)
    EXPECT_EQ(sim.finite_elements[0], 2);
    const auto& y = sim.final_state();
    EXPECT_NEAR(y[1], 0.0, 1e-9);
    EXPECT_NEAR(y[3], 0.0, 1e-9);
    EXPECT_NEAR(y[4], time_at_rest(3.0, t1, v1, 100.0), 1e-9);  // measured 1e-14
    // The frozen run's record ends at the impact's outcome or says it does not (FrozenPhase::cut);
    // the recovered impact event's x+ is the outcome either way.
    ASSERT_EQ(sim.frozen_phases.size(), 1u);
    EXPECT_NEAR(sim.frozen_phases[0].time, t1, 1e-9);
    if (!sim.frozen_phases[0].cut) EXPECT_NEAR(sim.frozen_phases[0].x_plus[3], 0.0, 1e-9);
    ASSERT_EQ(sim.trajectory.events.size(), 1u);
    EXPECT_TRUE(sim.trajectory.events[0].impact());
    EXPECT_NEAR(sim.trajectory.events[0].t, t1, 1e-9);
    EXPECT_NEAR(sim.trajectory.events[0].x_plus[3], 0.0, 1e-9);
  }
}

// NOSNOC's frictional landing without the contact-side selection: every homotopy converges, but
// the gap drifts to -1.0e-5 while the mass slides (its step function is free where the gap is
// exactly zero), and the stop is 1.0e-5 off. The fallback sees the penetration and solves those
// intervals again with the selection.
TEST(TimeFreezingFallback, ADriftingGapIsSolvedAgainWithTheContactSideSelection) {
#if defined(SALTUS_TESTS_UNDER_SANITIZERS)
  GTEST_SKIP() << "11 s in Release, several minutes under the sanitizers: release stage only (the driver's "
                  "code paths run in this file's other tests there)";
#endif
  using Landing = scenes::FrictionalLanding;
  FesdOptions grid = Landing::grid();
  grid.regularisation.contact_side = 0.0;
  TimeFreezingSimulationOptions without;
  without.fallback.enabled = false;
  const auto drifted = simulate_time_freezing(Landing::system(), Landing::q0(), Landing::v0(), grid, NoObjective{}, {}, without);
  ASSERT_TRUE(drifted.converged());
  EXPECT_LT(drifted.final_state()[1], -1e-6);  // measured -1.0e-5
  const auto sim = simulate_time_freezing(Landing::system(), Landing::q0(), Landing::v0(), grid);
  ASSERT_TRUE(sim.converged()) << sim.solution.message;
  ASSERT_FALSE(sim.fallback_log.empty());
  EXPECT_NE(sim.fallback_log[0].find("a contact penetrated by"), std::string::npos) << sim.fallback_log[0];
  EXPECT_NE(sim.fallback_log[0].find("contact-side selection on"), std::string::npos) << sim.fallback_log[0];
  EXPECT_NEAR(sim.final_state()[0], Landing::stop, 1e-9);
  EXPECT_GT(sim.final_state()[1], -1e-8);
}

// A horizon that ends during the impact's frozen phase: the mass from 0.8 m with a_n = 20
// touches down at tau = 0.404 and its frozen phase would last 0.198 of numerical time; the
// horizon ends at 0.5. The record is flagged as cut (its x_plus still approaches the table); a
// horizon past the impact gives an uncut record whose x_plus is the outcome, v2 = 0.
TEST(TimeFreezingFallback, AFrozenPhaseCutByTheHorizonSaysSo) {
  const TimeFreezingSystem<PointMass> system(PointMass(), 20.0);
  FesdOptions grid = grid_of(2, 2, 0.5);
  grid.regularisation.contact_side = 1e-2;
  const double v1 = std::sqrt(2.0 * g * 0.8);
  const auto cut = simulate_time_freezing(system, Vec<2>(0.0, 0.8), Vec<2>::Zero(), grid);
  ASSERT_TRUE(cut.converged()) << cut.solution.message;
  ASSERT_EQ(cut.frozen_phases.size(), 1u);
  EXPECT_TRUE(cut.frozen_phases[0].cut);
  // The auxiliary dynamics pushed at a_n for 0.5 - 0.404 of numerical time.
  EXPECT_NEAR(cut.frozen_phases[0].x_plus[3], -v1 + 20.0 * (0.5 - std::sqrt(2.0 * 0.8 / g)), 1e-6);
  grid.grid.horizon = 1.0;
  const auto whole = simulate_time_freezing(system, Vec<2>(0.0, 0.8), Vec<2>::Zero(), grid);
  ASSERT_TRUE(whole.converged()) << whole.solution.message;
  ASSERT_EQ(whole.frozen_phases.size(), 1u);
  EXPECT_FALSE(whole.frozen_phases[0].cut);
  EXPECT_NEAR(whole.frozen_phases[0].x_plus[3], 0.0, 1e-9);
}

// NOSNOC's falling_rod case, two contacts landing at once: the rod (scenes::Rod, mu = 0.2) dropped
// flat from 0.3 m while sliding at 1 m/s. Closed form (rod.hpp): touchdown of both ends at
// t1 = sqrt(2 h / g), v_x+ = 1 - mu sqrt(2 g h), then the slide at mu g to rest; theta stays 0.
// Against it and against the event-driven simulator of the same scene.
TEST(TimeFreezingFallback, RodLandsFlatWhileSlidingAsTheEventDrivenSimulatorSays) {
#if defined(SALTUS_TESTS_UNDER_SANITIZERS)
  GTEST_SKIP() << "20-70 s in Release, several minutes under the sanitizers: release stage only (the driver's "
                  "code paths run in this file's other tests there)";
#endif
  using scenes::Rod;
  const double h = 0.3, v0 = 1.0, mu = 0.2, a_n = 100.0;
  const TimeFreezingSystem<Rod> system(Rod(), a_n);
  FesdOptions grid = grid_of(5, 2, 1.0);
  grid.regularisation.contact_side = 1e-2;
  const auto sim = simulate_time_freezing(system, Vec<3>(0.0, h, 0.0), Vec<3>(v0, 0.0, 0.0), grid);
  ASSERT_TRUE(sim.converged()) << sim.solution.message;
  const double t1 = std::sqrt(2.0 * h / g), v1 = std::sqrt(2.0 * g * h), vt = v0 - mu * v1;
  const double stop = v0 * t1 + vt * vt / (2.0 * mu * g);
  const auto& y = sim.final_state();
  EXPECT_NEAR(y[0], stop, 1e-8);
  EXPECT_NEAR(y[1], 0.0, 1e-9);
  EXPECT_NEAR(y[2], 0.0, 1e-9);
  EXPECT_NEAR(y.segment<3>(3).cwiseAbs().maxCoeff(), 0.0, 1e-9);
  ASSERT_FALSE(sim.trajectory.events.empty());
  const auto& impact = sim.trajectory.events[0];
  EXPECT_TRUE(impact.impact());
  EXPECT_NEAR(impact.t, t1, 1e-9);
  EXPECT_NEAR(impact.x_plus[3], vt, 1e-8);                        // v_x+
  EXPECT_NEAR(impact.x_plus.segment<2>(4).norm(), 0.0, 1e-8);     // v_y+, omega+
  for (const auto& f : sim.frozen_phases) EXPECT_FALSE(f.cut);
  // The event-driven simulator of the same motion: the simultaneous impact, the stop.
  SimulationOptions options;
  options.integrator.relative_tolerance = 1e-12;
  options.integrator.absolute_tolerance = 1e-13;
  const Rod rod;
  Simulator<Rod> simulator(rod, options);
  Vec<6> x0;
  x0 << 0.0, h, 0.0, v0, 0.0, 0.0;
  const auto exact = simulator.run(x0, 0.0, y[6]);
  ASSERT_FALSE(exact.events.empty());
  EXPECT_NEAR(exact.events[0].t, impact.t, 1e-9);
  EXPECT_NEAR((exact.events[0].x_plus - impact.x_plus).cwiseAbs().maxCoeff(), 0.0, 1e-8);
  EXPECT_NEAR((exact.final_state() - y.head<6>()).cwiseAbs().maxCoeff(), 0.0, 1e-8);
}

// The impact that straddles a control interval's end: the mass from 0.8 m with a_n = 20 on the
// bouncing-ball grid touches down at tau = 0.404 and its frozen phase would end at 0.602, past the
// interval's end at 0.6; the next interval's first element finishes the impact while its clock
// runs. The frozen run's record ends at 0.6 with v2 = -0.039 and says so (cut); the recovered
// impact event's x+ is the outcome, v2 = 0, at the touchdown's time.
TEST(TimeFreezingFallback, AnImpactAcrossAControlIntervalsEndIsCutInItsRecordOnly) {
  const TimeFreezingSystem<PointMass> system(PointMass(), 20.0);
  const double t1 = std::sqrt(2.0 * 0.8 / g), v1 = std::sqrt(2.0 * g * 0.8);
  const auto sim = simulate_time_freezing(system, Vec<2>(0.0, 0.8), Vec<2>::Zero(), bouncing_ball_grid());
  ASSERT_TRUE(sim.converged()) << sim.solution.message;
  ASSERT_EQ(sim.frozen_phases.size(), 1u);
  const auto& phase = sim.frozen_phases[0];
  EXPECT_TRUE(phase.cut);
  EXPECT_NEAR(phase.tau_end, 0.6, 1e-12);
  EXPECT_NEAR(phase.x_plus[3], -v1 + 20.0 * (0.6 - t1), 1e-6);  // -0.0389
  ASSERT_EQ(sim.trajectory.events.size(), 1u);
  EXPECT_NEAR(sim.trajectory.events[0].t, t1, 1e-9);
  EXPECT_NEAR(sim.trajectory.events[0].x_plus[3], 0.0, 1e-12);
  EXPECT_NEAR(sim.final_state()[4], time_at_rest(3.0, t1, v1, 20.0), 1e-9);
}

#if !defined(SALTUS_TESTS_UNDER_SANITIZERS)
// Painleve's inconsistent configuration: the rod of tests/painleve_rod.hpp (mu = 2) at 45 degrees,
// its lower end on the table sliding at -1 m/s, where no normal force keeps the end on the table.
// The auxiliary dynamics integrate the impact without collision in frozen time (slip under
// a_n (J_n + mu J_t) until the slip stops, then the Filippov sliding on v_t = 0 until the normal
// velocity is zero again); its closed form (Genot and Brogliato 1999,
// dynamics/impact_without_collision.hpp): P = (3/8, 5/8) N s, v+ = (-3/8, 3/8, 3 sqrt(2) / 4).
// The first control interval holds the slip, the stick and the rest that follows: the fallback
// solves it on a finer grid. Against the closed form, and against the event-driven simulator's
// resolution of the same state on scenes::Rod with mu = 2 (the same rod; its upper end stays
// 0.7 m above the table). Not scenes::Rod for time-freezing as well: its upper end's normal
// velocity starts on its switching surface too (J_n v = 0 at rest), and FESD's switch detection
// of that open contact's velocity functions stalls the homotopy on 4 and 8 elements (measured).
// The TF machinery of the test-local rod is compiled here (header-only) in the release build
// only, where the test runs.
TEST(TimeFreezingFallback, PainlevesRodTakesTheImpactWithoutCollisionInFrozenTime) {
  using saltus::testing::PainleveRod;
  const double mu = 2.0, c = std::sqrt(0.5);
  const PainleveRod rod(mu);
  const Vec<3> q0(0.5 * c, 0.5 * c, M_PI / 4), v0(-1.0, 0.0, 0.0);
  ASSERT_NEAR(rod.gap<double>(0, q0), 0.0, 1e-15);
  const TimeFreezingSystem<PainleveRod> system(rod, 100.0);
  FesdOptions grid = grid_of(4, 2, 0.2);
  grid.regularisation.contact_side = 1e-2;
  const auto sim = simulate_time_freezing(system, q0, v0, grid);
  ASSERT_TRUE(sim.converged()) << sim.solution.message;
  ASSERT_FALSE(sim.fallback_log.empty());
  EXPECT_NE(sim.fallback_log[0].find("interval 0 (not converged): solved on 8 finite elements"), std::string::npos)
      << sim.fallback_log[0];
  const Vec<3> v_plus(-0.375, 0.375, 3.0 * std::sqrt(2.0) / 4.0);
  ASSERT_FALSE(sim.frozen_phases.empty());
  const auto& phase = sim.frozen_phases[0];
  EXPECT_FALSE(phase.cut);
  EXPECT_NEAR(phase.time, 0.0, 1e-12);
  EXPECT_NEAR((phase.x_plus.tail<3>() - v_plus).cwiseAbs().maxCoeff(), 0.0, 1e-8);  // measured 5.8e-10
  // The event-driven simulator, Painleve's resolution turned on, to the run's own final time.
  SimulationOptions options;
  options.integrator.relative_tolerance = 1e-12;
  options.integrator.absolute_tolerance = 1e-13;
  options.painleve.resolution = InconsistentContactResolution::ImpactWithoutCollision;
  scenes::RodParameters p;
  p.mu = mu;
  const scenes::Rod same_rod(p);
  Simulator<scenes::Rod> simulator(same_rod, options);
  Vec<6> x0;
  x0 << q0, v0;
  const auto& y = sim.final_state();
  const auto exact = simulator.run(x0, 0.0, y[6]);
  ASSERT_FALSE(exact.events.empty());
  EXPECT_NEAR(exact.events[0].t, 0.0, 1e-12);
  EXPECT_NEAR((exact.events[0].x_plus.tail<3>() - phase.x_plus.tail<3>()).cwiseAbs().maxCoeff(), 0.0, 1e-8);
  // The collocation's error over the rest of the horizon (the end sticking while the rod turns).
  EXPECT_NEAR((exact.final_state() - y.head<6>()).cwiseAbs().maxCoeff(), 0.0, 1e-5)  // measured 1.8e-6
      << "final state " << (exact.final_state() - y.head<6>()).cwiseAbs().maxCoeff();
}
#endif

// When no attempt succeeds: the bouncing-ball grid's touchdown interval (three modes in two
// elements) with the selection on and no finer grid allowed (max_refinements = 0) has one attempt
// left, the selection turned off on the same two elements, which fails as well. The run goes on
// from the least bad attempt, says so in the log and the message, and is not converged. The same
// interval as the whole horizon (one control interval) gets the fallback too.
TEST(TimeFreezingFallback, WhenNoAttemptSucceedsTheRunSaysSoAndGoesOn) {
  const TimeFreezingSystem<PointMass> system(PointMass(), 100.0);
  const double t0 = 0.3;  // the bouncing-ball grid's interval 1: from the free fall's state at tau = 0.3
  FesdOptions grid = grid_of(1, 2, 0.3);
  grid.regularisation.contact_side = 1e-2;
  grid.clock.initial_time = t0;
  const Vec<2> q0(0.0, 0.8 - 0.5 * g * t0 * t0), v0(0.0, -g * t0);
  TimeFreezingSimulationOptions options;
  options.fallback.max_refinements = 0;
  const auto failed = simulate_time_freezing(system, q0, v0, grid, NoObjective{}, {}, options);
  EXPECT_FALSE(failed.converged());
  ASSERT_EQ(failed.fallback_log.size(), 1u);
  EXPECT_NE(failed.fallback_log[0].find("interval 0 (not converged): no attempt of the fallback succeeded; kept "),
            std::string::npos)
      << failed.fallback_log[0];
  EXPECT_NE(failed.solution.message.find("the run goes on from"), std::string::npos) << failed.solution.message;
  EXPECT_EQ(failed.fallbacks, 0);
  options.fallback.max_refinements = 2;
  const auto solved = simulate_time_freezing(system, q0, v0, grid, NoObjective{}, {}, options);
  ASSERT_TRUE(solved.converged()) << solved.solution.message;
  EXPECT_EQ(solved.fallbacks, 1);
  EXPECT_NEAR(solved.final_state()[3], 0.0, 1e-9);  // at rest on the table after the impact
  EXPECT_NEAR(solved.final_state()[1], 0.0, 1e-9);
}

TEST(TimeFreezingFallback, RefusesBadFallbackOptions) {
  const TimeFreezingSystem<PointMass> system(PointMass(), 20.0);
  const auto refused = [&](auto set, const std::string& what) {
    TimeFreezingSimulationOptions options;
    set(options.fallback);
    try {
      simulate_time_freezing(system, Vec<2>(0.0, 0.8), Vec<2>::Zero(), bouncing_ball_grid(), NoObjective{}, {}, options);
      ADD_FAILURE() << what << " was accepted";
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  refused([](SimulationFallback& f) { f.max_refinements = -1; }, "max_refinements");
  refused([](SimulationFallback& f) { f.max_refinements = 7; }, "max_refinements");
  refused([](SimulationFallback& f) { f.penetration_tolerance = -1.0; }, "penetration_tolerance");
  refused([](SimulationFallback& f) { f.contact_side_weight = 0.0; }, "contact_side_weight");
}

}  // namespace
}  // namespace saltus::timefreezing
