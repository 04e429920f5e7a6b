// The flagship OCP statements. The hopper over three holes (scenes/hopper_holes.hpp): its path
// constraints at postures whose values are known in closed form, the hole continuation level, the
// exact derivatives of its FESD MPCC under Ipopt's own second-order derivative checker, and the
// feasibility report the example and the benchmark print; its coarse grid, the one-hole bed
// (scenes::HopperOverOneHole), solved and checked as a structure. The plank-box flat landing
// (scenes/plank_box_landing.hpp): its start, target and rows, the derivative checker on its
// two-contact FESD MPCC with the scaled gap, and the optimal reference itself (its grid, solved,
// recovered, re-simulated and analysed).
#include "one_hole_checks.hpp"
#include "scenes/hopper_footsteps.hpp"
#include "scenes/hopper_holes.hpp"
#include "scenes/plank_box_landing.hpp"
#include "scenes/plank_box_tracking.hpp"

#include <saltus/hybrid/reference/resimulation.hpp>
#include <saltus/sensitivity/analysis/reference_analysis_io.hpp>
#include <saltus/timefreezing/discretisation/fesd.hpp>
#include <saltus/timefreezing/mpcc/mpcc_solver.hpp>
#include <saltus/timefreezing/drivers/optimal_control.hpp>
#include <saltus/timefreezing/refinement/mode_schedule.hpp>

#include "mpcc_support.hpp"
#include "support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

namespace saltus::scenes {
namespace {

using Ocp = HopperOverThreeHoles;
using saltus::testing::expect_invalid;

Vec<8> state(const Vec<4>& q) {
  Vec<8> x = Vec<8>::Zero();
  x.head<4>() = q;
  return x;
}

TEST(HopperOverThreeHoles, PathConstraintsAtKnownPostures) {
  const Ocp ocp;
  // The start: leg straight down, foot at (0, 0), knee at (0, 0.2).
  const Vec<11> c0 = ocp.path_constraints<double>(state(Ocp::q0()), Vec<2>::Zero());
  const Vec<11> expected0 = (Vec<11>() << 0, 0, 0, 0.4, 0, 0, 0.2, 0, 4, 36, 100).finished();
  EXPECT_LT((c0 - expected0).cwiseAbs().maxCoeff(), 1e-14) << c0.transpose();
  // The target stands on the ground right of the third hole: ((3 - 2.5) / 0.25)^2 = 4.
  const Vec<11> cT = ocp.path_constraints<double>(state(Ocp::q_target()), Vec<2>::Zero());
  EXPECT_NEAR(cT[10], 4.0, 1e-14);
  EXPECT_NEAR(cT[0], 3.0, 1e-14);
  // Hip 90 degrees forward, knee bent back by 90 degrees: thigh horizontal, shank straight down.
  const double pi = std::numbers::pi;
  const Vec<4> q(1.0, 0.4, pi / 2, -pi / 2);
  const Vec<11> c = ocp.path_constraints<double>(state(q), Vec<2>::Zero());
  EXPECT_NEAR(c[1], 1.2, 1e-14);  // foot x = x + l1
  EXPECT_NEAR(c[2], 1.2, 1e-14);  // knee x
  EXPECT_NEAR(c[6], 0.4, 1e-14);  // knee z = z
  EXPECT_NEAR(c[7], 0.2, 1e-14);  // foot z = z - l2
  EXPECT_NEAR(c[9], std::pow((1.2 - 1.5) / 0.25, 2) + std::pow(0.2 / 0.1, 2), 1e-13);
  // Bounds: the paper's numbers, the holes' rows at the continuation level.
  Ocp shallow;
  shallow.hole_level = 0.25;
  EXPECT_DOUBLE_EQ(ocp.path_lower()[8], 1.0);
  EXPECT_DOUBLE_EQ(shallow.path_lower()[9], 0.25);
  EXPECT_DOUBLE_EQ(ocp.path_upper()[4], 3 * pi / 8);
  EXPECT_DOUBLE_EQ(ocp.path_lower()[5], -pi / 2);
  EXPECT_DOUBLE_EQ(ocp.path_upper()[7], 0.2);
  EXPECT_TRUE(std::isinf(ocp.path_upper()[8]));
}

// A foot on the ground at the edge of a hole at level beta: x_c - sqrt(beta) a is on the boundary.
TEST(HopperOverThreeHoles, HoleLevelScalesTheExcludedEllipse) {
  for (double beta : {0.04, 0.25, 1.0}) {
    Ocp ocp;
    ocp.hole_level = beta;
    // Leg straight down: foot x = hip x.
    const Vec<4> q(1.5 - std::sqrt(beta) * 0.25, 0.4, 0.0, 0.0);
    const Vec<11> c = ocp.path_constraints<double>(state(q), Vec<2>::Zero());
    EXPECT_NEAR(c[9], ocp.path_lower()[9], 1e-13) << "beta " << beta;
  }
}

using saltus::testing::interior_point;

// Every term of the OCP (running cost gated by the clock, 11 path rows at every stage point with
// the ellipses, the terminal rows, the clock, speed of time and step equilibration) on one control
// interval with two finite elements: Ipopt's second-order checker finds no wrong entry.
TEST(HopperOverThreeHoles, IpoptDerivativeCheckerFindsNoError) {
  const timefreezing::FesdMpcc<Hopper, Ocp> problem(Ocp::system(), Ocp{}, Ocp::q0(), Ocp::v0(), Ocp::grid(1, 2, 2));
  EXPECT_EQ(problem.np, 11);
  EXPECT_EQ(problem.nt, 4);
  const timefreezing::DerivativeCheckReport report = timefreezing::check_derivatives(problem, interior_point(problem, 11));
  EXPECT_EQ(report.errors, 0) << report.output;
}

// The feasibility report reads the full holes whatever the level the problem was solved at.
TEST(HopperOverThreeHoles, FeasibilityReportNamesTheWorstRow) {
  struct P {
    Vec<10> y;
    Vec<2> u;
  };
  P start{Vec<10>::Zero(), Vec<2>::Zero()}, in_hole = start, end = start;
  start.y.head<4>() = Ocp::q0();
  in_hole.y.head<4>() = Vec<4>(1.5, 0.4, 0.0, 0.0);  // foot at the centre of hole 2: row value 0
  end.y.head<4>() = Ocp::q_target() + Vec<4>(0.0, 1e-3, 0.0, 0.0);
  const std::vector<P> path{start, in_hole, end};
  const Ocp::Feasibility f = Ocp::feasibility(path);
  EXPECT_NEAR(f.path_violation, 1.0, 1e-14);
  EXPECT_EQ(f.worst_row, 9);
  EXPECT_NEAR(f.target_error, 1e-3, 1e-15);
  const std::vector<P> clean{start, end};
  EXPECT_EQ(Ocp::feasibility(clean).worst_row, -1);
}

// The one-hole test bed (bench/experiments/hopper_ocp --one-hole): its own target, horizon, grid and hole
// continuation, the flagship's rows; its feasibility report measures the target error against its
// own target, and its FESD MPCC reads that target in the terminal rows.
/// The footsteps the holes leave: stances on x = 0, 1, 2, 3 (0.3, 0.45, 0.45, 0.3 s), flights of
/// 1/3 s between them.
HopperFootsteps holes_footsteps() {
  return {{0.0, 1.0, 2.0, 3.0}, {0.3, 0.3 + 1.0 / 3, 0.75 + 1.0 / 3, 0.75 + 2.0 / 3, 1.2 + 2.0 / 3, 1.2 + 1.0}};
}

// The footstep guess is kinematically consistent with its schedule: in each stance the foot stands
// on its foothold (gap 0, foot x = foothold) with the foot at rest; the poses are continuous at the
// events; it starts at q0 and ends at the target; reading its footsteps back gives them again.
TEST(HopperFootsteps, TheGuessStandsOnItsFootholdsAndReadsBack) {
  const Hopper hopper{};
  const HopperFootsteps steps = holes_footsteps();
  const auto g = footstep_guess(hopper, steps, Ocp::q0(), Ocp::q_target(), Ocp::horizon);
  EXPECT_EQ(timefreezing::describe(hopper, g.schedule),
            "foot:stick [release foot] foot:open [touchdown foot] foot:stick [release foot] foot:open [touchdown foot] "
            "foot:stick [release foot] foot:open [touchdown foot] foot:stick");
  EXPECT_LE((g.state(0, 0.0).head<4>() - Ocp::q0()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LE((g.state(6, Ocp::horizon).head<4>() - Ocp::q_target()).cwiseAbs().maxCoeff(), 1e-12);
  for (int k = 0; k < 7; k += 2) {
    const double t0 = k == 0 ? 0.0 : steps.event_times[std::size_t(k - 1)];
    const double t1 = k == 6 ? Ocp::horizon : steps.event_times[std::size_t(k)];
    for (double t : {t0, 0.5 * (t0 + t1), t1}) {
      const Vec<8> x = g.state(k, t);
      const Vec<2> foot = hopper.foot<double>(Vec<4>(x.head<4>()));
      EXPECT_NEAR(foot[0], steps.footholds[std::size_t(k / 2)], 1e-9) << "stance " << k / 2 << " at t = " << t;
      EXPECT_NEAR(foot[1], 0.0, 1e-9) << "stance " << k / 2 << " at t = " << t;
    }
  }
  for (std::size_t e = 0; e < steps.event_times.size(); ++e) {
    const double t = steps.event_times[e];
    const int k = static_cast<int>(e);
    EXPECT_LE((g.state(k, t).head<4>() - g.state(k + 1, t).head<4>()).cwiseAbs().maxCoeff(), 1e-9) << "event " << e;
  }
  const HopperFootsteps back = footsteps_of(hopper, g, Ocp::q0(), Ocp::q_target(), Ocp::horizon);
  ASSERT_EQ(back.footholds.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_NEAR(back.footholds[i], steps.footholds[i], 1e-9);
  ASSERT_EQ(back.event_times.size(), steps.event_times.size());
  for (std::size_t i = 0; i < steps.event_times.size(); ++i) EXPECT_EQ(back.event_times[i], steps.event_times[i]);
}

// footsteps_of merges consecutive closed phases into one stance (a slip then a stick), and bad
// footsteps, shapes and schedules are named.
TEST(HopperFootsteps, ClosedPhasesMergeAndBadInputIsNamed) {
  const Hopper hopper{};
  auto g = footstep_guess(hopper, holes_footsteps(), Ocp::q0(), Ocp::q_target(), Ocp::horizon);
  timefreezing::ScheduleGuess<Hopper> slip_then_stick = g;
  Mode<1> slip;
  slip[0] = ContactState::slip_planar(+1);
  slip_then_stick.schedule.phases.insert(slip_then_stick.schedule.phases.begin() + 2, slip);
  slip_then_stick.event_times.insert(slip_then_stick.event_times.begin() + 1, 0.5);
  const auto base = g.state;
  slip_then_stick.state = [base](int k, double t) { return base(k <= 1 ? k : k - 1, t); };
  const HopperFootsteps merged = footsteps_of(hopper, slip_then_stick, Ocp::q0(), Ocp::q_target(), Ocp::horizon);
  EXPECT_EQ(merged.footholds.size(), 4u);
  EXPECT_EQ(merged.event_times.size(), 6u);

  HopperFootsteps steps = holes_footsteps();
  steps.event_times.pop_back();
  expect_invalid([&] { (void)footstep_guess(hopper, steps, Ocp::q0(), Ocp::q_target(), Ocp::horizon); }, {"6 event times"});
  steps = holes_footsteps();
  std::swap(steps.event_times[1], steps.event_times[2]);
  expect_invalid([&] { (void)footstep_guess(hopper, steps, Ocp::q0(), Ocp::q_target(), Ocp::horizon); },
                 {"increase strictly"});
  HopperGaitShape long_leg;
  long_leg.stance_leg = 0.45;
  expect_invalid([&] { (void)footstep_guess(hopper, holes_footsteps(), Ocp::q0(), Ocp::q_target(), Ocp::horizon, long_leg); },
                 {"stance_leg"});
  // A schedule that ends in a flight lands for the last landing_stance seconds, or for the second
  // half of a flight shorter than twice that.
  timefreezing::ScheduleGuess<Hopper> flying = g;
  flying.schedule.phases.pop_back();
  flying.schedule.events.pop_back();
  flying.event_times.pop_back();
  const HopperFootsteps landed = footsteps_of(hopper, flying, Ocp::q0(), Ocp::q_target(), Ocp::horizon, 0.2);
  ASSERT_EQ(landed.event_times.size(), 6u);
  EXPECT_DOUBLE_EQ(landed.event_times.back(), Ocp::horizon - 0.2);
  EXPECT_EQ(landed.footholds.back(), 3.0);
  const double last_release = landed.event_times[4];
  const HopperFootsteps halved = footsteps_of(hopper, flying, Ocp::q0(), Ocp::q_target(), Ocp::horizon, 1.0);
  ASSERT_GT(2.0, Ocp::horizon - last_release);  // the flight is shorter than 2 landing_stance
  EXPECT_DOUBLE_EQ(halved.event_times.back(), Ocp::horizon - 0.5 * (Ocp::horizon - last_release));
  timefreezing::ScheduleGuess<Hopper> lifted = g;
  lifted.schedule.phases.erase(lifted.schedule.phases.begin());
  lifted.schedule.events.erase(lifted.schedule.events.begin());
  lifted.event_times.erase(lifted.event_times.begin());
  expect_invalid([&] { (void)footsteps_of(hopper, lifted, Ocp::q0(), Ocp::q_target(), Ocp::horizon); },
                 {"must start with the foot on the ground"});
}

TEST(HopperOverOneHole, TargetGridAndRowsAreTheShortTask) {
  using Short = HopperOverOneHole;
  EXPECT_EQ(Short::q_target(), Vec<4>(1.0, 0.4, 0.0, 0.0));
  EXPECT_EQ(Short{}.terminal_lower(), Short::q_target());
  EXPECT_EQ(Short{}.terminal_upper(), Short::q_target());
  const timefreezing::FesdOptions grid = Short::grid();
  EXPECT_EQ(grid.grid.control_intervals, 8);
  EXPECT_EQ(grid.grid.finite_elements, 3);
  EXPECT_EQ(grid.grid.horizon, 1.0);
  EXPECT_EQ(grid.clock.physical_horizon, 1.0);
  EXPECT_EQ(grid.grid.horizon / grid.grid.control_intervals, Ocp::grid().grid.horizon / Ocp::grid().grid.control_intervals);
  const std::vector<Short> levels = Short::hole_continuation();
  ASSERT_EQ(levels.size(), Ocp::hole_continuation().size());
  EXPECT_EQ(levels.back().hole_level, 1.0);
  EXPECT_EQ(Short{}.path_lower(), Ocp{}.path_lower());
  struct P {
    Vec<10> y;
    Vec<2> u;
  };
  P start{Vec<10>::Zero(), Vec<2>::Zero()}, end = start;
  start.y.head<4>() = Short::q0();
  end.y.head<4>() = Short::q_target();
  const std::vector<P> path{start, end};
  EXPECT_EQ(Short::feasibility(path).target_error, 0.0);
  EXPECT_EQ(Short::feasibility(path).worst_row, -1);
  EXPECT_EQ(Ocp::feasibility(path).target_error, 2.0);  // the flagship's target is x = 3
  const timefreezing::FesdMpcc<Hopper, Short> problem(Short::system(), Short{}, Short::q0(), Short::v0(),
                                                      Short::grid(1, 2, 2));
  EXPECT_EQ(problem.nt, 4);
  const int n = problem.variable_count(), m = problem.constraint_count();
  Eigen::VectorXd x_lower(n), x_upper(n), g_lower(m), g_upper(m);
  problem.bounds(x_lower, x_upper, g_lower, g_upper);
  int terminal_rows = 0;
  for (int j = 0; j < m; ++j) {
    const std::string name = problem.constraint_name(j);
    if (name.rfind("terminal constraint ", 0) != 0) continue;
    const int i = std::stoi(name.substr(20));
    EXPECT_EQ(g_lower[j], Short::q_target()[i]) << name;
    EXPECT_EQ(g_upper[j], Short::q_target()[i]) << name;
    ++terminal_rows;
  }
  EXPECT_EQ(terminal_rows, 4);
}

// The hopper's shorter task the issue asks for: the one-hole bed (scenes::HopperOverOneHole, T = 1 s,
// N = 8 of the flagship's 0.125 s intervals, over the first hole) with its own settings (its
// docstring: the contact-side selection, primal-only warm starts, 11 steps). Measured: converged
// at sigma = 1e-10, 5,373 Ipopt iterations, 153 s with another solve on the machine
// (bench/experiments/README.md, "The one-hole bed converges"); over the minute. The gait found: a hop
// and a bounce, a slide to the hole's near edge, a jump over it (lift-off at foot x = 0.246,
// touchdown at 0.951), a brief slip and a stop, a small hop to x = 1. Checked as a structure that
// another gait would also pass: every touchdown lands outside the hole, one flight crosses it,
// and no lift-off comes last (the target, fixed, puts the foot on the ground).
// The event-driven re-simulation under the optimal torques is printed, not bounded: it leaves the
// reference (measured 291 at t = 1: the hopper is unstable open loop, and the simulator's first
// event comes at t = 0.05, where the reference still sticks), bench/experiments/README.md says more.
// Known weakness of this check (bench/experiments/README.md, "Warm starts below a sigma"): the landing beyond
// the hole ends its element with the foot on the ground moving up (J_n v = +0.52 m/s after -3.6
// inside the element, a leg swing the coarse grid does not resolve); this optimum's recovery
// reads it as a touchdown, another optimum of the bed (primal-dual warm starts below sigma =
// 1e-6, docs/decisions/mpcc-warm-start-below.md) as an impact without a guard, which fails the one-guard assertion below.
TEST(HopperOverOneHole, CoarseGridConvergesAndJumpsTheHole) {
#if defined(SALTUS_TESTS_UNDER_SANITIZERS)
  GTEST_SKIP() << "about 2.5 minutes in Release: run in the release stage only";
#endif
  using Short = HopperOverOneHole;
  EXPECT_EQ(Short::grid().regularisation.contact_side, 1e-2);
  EXPECT_FALSE(Short::solver().warm_start);
  const auto r = timefreezing::solve_time_freezing_ocp_by_continuation(
      Short::system(), Short::hole_continuation(), Short{}, Short::q0(), Short::v0(), Short::grid(), Short::solver());
  ASSERT_TRUE(r.converged()) << r.solution.message;
  EXPECT_LE(r.solution.complementarity, 1e-9);
  const Short::Feasibility f = Short::feasibility(r.points);
  EXPECT_LE(f.path_violation, 1e-6);
  EXPECT_LE(f.target_error, 1e-6);
  testing::expect_one_hole_event_structure(r.trajectory.events);
  const PolishResult<Hopper> resim = polish(Hopper{}, r.reference);
  std::cout << "hopper over one hole: objective " << r.solution.objective << ", " << r.solution.ipopt_iterations
            << " Ipopt iterations, " << r.solution.seconds << " s; " << r.trajectory.events.size()
            << " recovered events; re-simulation distance " << resim.state_distance << " at t = "
            << resim.worst_sample_time << ", " << resim.trajectory.events.size() << " simulated events, the first:";
  for (std::size_t k = 0; k < std::min<std::size_t>(2, resim.trajectory.events.size()); ++k) {
    std::cout << " t = " << resim.trajectory.events[k].t;
    for (const Guard& g : resim.trajectory.events[k].guards()) std::cout << " " << to_string(g.kind);
  }
  std::cout << "\n";
}

// The start: both corners 5 cm above the level plank, the box parallel to it (path row 0); the
// target: 5 cm above the plank at x = 0.75, so its terminal rows are the bounds; the feasibility
// report reads both.
TEST(PlankBoxFlatLanding, StartTargetAndRowsAreTheStatement) {
  using Landing = PlankBoxFlatLanding;
  const Landing ocp;
  const PlankBox box;
  const Vec<4> q0 = Landing::q0();
  EXPECT_NEAR(box.gap<double>(PlankBox::left, q0), 0.05, 1e-15);
  EXPECT_NEAR(box.gap<double>(PlankBox::right, q0), 0.05, 1e-15);
  EXPECT_EQ(ocp.path_constraints<double>(state(q0), Vec<3>::Zero())[0], 0.0);
  Vec<8> target = Vec<8>::Zero();
  target.head<3>() = Landing::box_target();
  EXPECT_NEAR(box.gap<double>(PlankBox::left, Vec<4>(target.head<4>())), 0.05, 1e-15);
  EXPECT_NEAR(target[0], 0.75, 1e-15);
  const Vec<6> rows = ocp.terminal_constraints<double>(target, 1.5);
  EXPECT_EQ((rows - ocp.terminal_lower()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((ocp.terminal_upper() - ocp.terminal_lower()).cwiseAbs().maxCoeff(), 0.0);
  // A tilted box (theta - phi = 0.01) and a target missed by 2 mm are reported.
  struct P {
    Vec<10> y;
  };
  P start{Vec<10>::Zero()}, tilted = start, end = start;
  start.y.head<4>() = q0;
  tilted.y.head<4>() = q0 + Vec<4>(0.0, 0.0, 0.01, 0.0);
  end.y.head<8>() = target;
  end.y[1] += 2e-3;
  const std::vector<P> path{start, tilted, end};
  const Landing::Feasibility f = Landing::feasibility(path);
  EXPECT_NEAR(f.path_violation, 0.01, 1e-15);
  EXPECT_NEAR(f.target_error, 2e-3, 1e-15);
}

// Two contacts with friction, the gap scaled by 100, the parallel-box row, the six terminal rows,
// the clock and the speed of time: Ipopt's second-order checker finds no wrong entry.
TEST(PlankBoxFlatLanding, IpoptDerivativeCheckerFindsNoError) {
#if defined(SALTUS_TESTS_UNDER_SANITIZERS)
  GTEST_SKIP() << "42 s under ASan: release stage only (the FESD NLP's derivative code runs under the sanitizers in "
                  "Fesd.IpoptDerivativeCheckerFindsNoError and HopperOverThreeHoles.IpoptDerivativeCheckerFindsNoError)";
#endif
  using Landing = PlankBoxFlatLanding;
  const timefreezing::FesdMpcc<PlankBox, Landing> problem(Landing::system(), Landing{}, Landing::q0(), Landing::v0(),
                                                          Landing::grid(1, 2, 2));
  EXPECT_EQ(problem.np, 1);
  EXPECT_EQ(problem.nt, 6);
  const timefreezing::DerivativeCheckReport report = timefreezing::check_derivatives(problem, interior_point(problem, 13));
  EXPECT_EQ(report.errors, 0) << report.output;
}

// The flagship OCP on its own grid (15 control intervals, 2 elements, n_s = 2; the coarser grids
// tried, 10 and 12 intervals, stall in the homotopy, and 1 element per interval cannot move an
// element boundary): converged to complementarity 0 by the branch NLP, the box parallel to the
// plank and the target met; the recovered reference lands with both corners in ONE impact, slides,
// sticks and lifts off; the event-driven simulator under the optimal input finds the same events
// (its impact is the simultaneous impact of both corners) and stays close: measured 0.026 (the
// plank's rate, after the lift-off). The grid finishes the impact inside a flowing element whose
// clock runs 0.024 s meanwhile; x+ is read there at its own time (recover_trajectory,
// x_plus_time; read at the impact's time it was 0.065 away).
TEST(PlankBoxFlatLanding, OptimalReferenceLandsFlatAndAgreesWithTheEventDrivenSimulator) {
#if defined(SALTUS_TESTS_UNDER_SANITIZERS)
  GTEST_SKIP() << "about 100 s in Release: run in the release stage only";
#endif
  using Landing = PlankBoxFlatLanding;
  const auto r = timefreezing::solve_time_freezing_ocp(Landing::system(), Landing{}, Landing::q0(), Landing::v0(),
                                                       Landing::grid(), Landing::solver());
  ASSERT_TRUE(r.converged()) << r.solution.message;
  EXPECT_LE(r.solution.complementarity, 1e-9);
  const Landing::Feasibility f = Landing::feasibility(r.points);
  EXPECT_LE(f.path_violation, 1e-6);
  EXPECT_LE(f.target_error, 1e-6);
  // Landing (both corners in one impact), stop, lift-off.
  const auto& events = r.trajectory.events;
  ASSERT_EQ(events.size(), 3u);
  EXPECT_TRUE(events[0].impact());
  EXPECT_EQ(events[0].guards(), (std::vector<Guard>{{0, GuardKind::Touchdown}, {1, GuardKind::Touchdown}}));
  EXPECT_EQ(events[1].guards(), (std::vector<Guard>{{0, GuardKind::Stop}, {1, GuardKind::Stop}}));
  EXPECT_EQ(events[2].guards(), (std::vector<Guard>{{0, GuardKind::Release}, {1, GuardKind::Release}}));
  // The event-driven re-simulation under the optimal input.
  const PolishResult<PlankBox> resim = polish(PlankBox{}, r.reference);
  ASSERT_EQ(resim.trajectory.events.size(), events.size());
  EXPECT_EQ(resim.trajectory.events[0].guards().size(), 2u);
  EXPECT_NEAR(resim.trajectory.events[0].t, events[0].t, 1e-6);
  EXPECT_NEAR(resim.trajectory.events[1].t, events[1].t, 1e-2);  // measured 3.0e-3: a slip-stick inside an element
  EXPECT_NEAR(resim.trajectory.events[2].t, events[2].t, 1e-6);
  std::cout << "plank-box flagship: objective " << r.solution.objective << ", " << r.solution.ipopt_iterations
            << " Ipopt iterations, " << r.solution.seconds << " s; re-simulation distance " << resim.state_distance
            << " at t = " << resim.worst_sample_time << "\n";
  EXPECT_LT(resim.state_distance, 0.05);

  // The reference analysed (analyse_reference, as `plank_box --json` does with 100 runs):
  // the flat landing is a conewise event of two pieces (one per corner first), the stop of both
  // corners is one event with a saltation matrix, the lift-off at an input jump a fixed-time event
  // with a linear gain; the LQR design is stable, and 20
  // perturbed closed-loop runs keep the event sequence and shrink as the first-order closed loop
  // predicts. Measured with 100 runs: a(T) = 0.0302 (both bounds), 99 kept and shrank, first-order
  // discrepancy 5.7e-3; the 100th stalled in 17 micro-events at the landing (reported, not thrown).
  // With these 20: all kept and shrank, discrepancy 8.5e-4.
  const ReferenceAnalysis<PlankBox> a =
      analyse_reference(PlankBox{}, resim.trajectory, SimulationOptions{}, plank_box_tracking(20));
  const std::string dump = to_json(a).dump(2);  // the failure messages
  ASSERT_TRUE(a.completed()) << dump;
  ASSERT_EQ(a.events.size(), 3u) << dump;
  EXPECT_TRUE(a.events[0].conewise) << dump;
  EXPECT_EQ(a.events[0].pieces, 2) << dump;
  EXPECT_EQ(a.events[0].unrealisable_orders, 0) << dump;
  EXPECT_FALSE(a.events[1].conewise) << dump;
  // The lift-off is where the optimal input jumps (an element's end): the simulator fires both
  // releases at that breakpoint (Event::input_jump), a fixed-time event whose gain is linear.
  EXPECT_TRUE(resim.trajectory.events[2].input_jump);
  EXPECT_FALSE(a.events[2].conewise) << dump;
  const StabilityReport& check = *a.stability;
  EXPECT_EQ(check.verdict, StabilityVerdict::Stable) << dump;
  EXPECT_LE(check.lower_bound, check.upper_bound);
  EXPECT_LT(check.upper_bound, 1.0);
  const MonteCarloReport& mc = *a.monte_carlo;
  EXPECT_GE(mc.kept_event_sequence, 18) << dump;
  EXPECT_EQ(mc.shrank, mc.kept_event_sequence) << dump;
  EXPECT_LE(mc.max_log_discrepancy, 0.05) << dump;
  EXPECT_TRUE(a.agree) << dump;
  std::cout << "plank-box flagship reference: " << to_string(check.verdict) << ", a(T) = " << check.upper_bound << ", "
            << mc.kept_event_sequence << "/20 runs kept and shrank, "
            << "first-order discrepancy " << mc.max_log_discrepancy << "; analysis " << a.seconds.total << " s\n";
}

// The coarse grid the issue asks for: the shorter flat landing (scenes::PlankBoxShortLanding, T = 1 s,
// N = 10) in about a minute in Release (measured 57-67 s). Converged by the branch NLP (measured: 1,048 Ipopt
// iterations, complementarity 0); the recovered reference lands with both corners in ONE
// impact at t = 0.3 and lifts off with both at 0.6, still sliding (no stop on this short slide).
// Checked as a structure: one flat impact first, then only slip-stick changes, then the release of
// both corners (another optimum of this task, found under other rounding, also sticks: below).
// The event-driven simulator under the optimal input lands and lifts off at the same times; in
// between it lets corner 1 leave the plank for 4.4e-4 s at t = 0.512 (a release and a touchdown the
// FESD grid does not resolve), hence its two extra events and the distance there (measured 0.022,
// the box's angular rate at t = 0.5125).
// The path to this optimum depends on rounding: with the contact kinematics chained into the AD
// types (the same derivatives, rounded differently; docs/decisions/fesd-composed-kinematics.md) the
// homotopy converged with 400 iterations per step to another optimum (objective 52.0 against 61.5)
// that sticks at t = 0.564 s and lifts off at t = 0.7 s from rest, and absorbs its landing impact
// into a flowing element (re-simulation 0.069).
TEST(PlankBoxShortLanding, CoarseGridConvergesWithAFlatLandingAndALiftOff) {
#if defined(SALTUS_TESTS_UNDER_SANITIZERS)
  GTEST_SKIP() << "about a minute in Release: run in the release stage only";
#endif
  using Landing = PlankBoxShortLanding;
  const timefreezing::FesdOptions grid = Landing::grid();
  EXPECT_EQ(grid.grid.control_intervals, 10);
  EXPECT_EQ(grid.grid.horizon, 1.0);
  EXPECT_EQ(grid.clock.physical_horizon, 1.0);
  // Its target: 5 cm above the level plank at 0.55 m from the hinge, at rest; the feasibility
  // report reads this target, not the flagship's.
  const PlankBox box;
  const Vec<6> target = Landing{}.terminal_lower();
  EXPECT_NEAR(target[0], 0.55, 1e-15);
  EXPECT_NEAR(box.gap<double>(PlankBox::left, Vec<4>(target[0], target[1], target[2], 0.0)), 0.05, 1e-15);
  EXPECT_EQ(target.tail<3>(), Vec<3>::Zero());
  EXPECT_EQ(Landing{}.terminal_upper(), target);
  const auto r = timefreezing::solve_time_freezing_ocp(Landing::system(), Landing{}, Landing::q0(), Landing::v0(),
                                                       grid, Landing::solver());
  ASSERT_TRUE(r.converged()) << r.solution.message;
  EXPECT_LE(r.solution.complementarity, 1e-9);
  const Landing::Feasibility f = Landing::feasibility(r.points);
  EXPECT_LE(f.path_violation, 1e-6);
  EXPECT_LE(f.target_error, 1e-6);
  const auto& events = r.trajectory.events;
  std::ostringstream listed;  // the recovered events, for the failure messages
  for (const auto& ev : events) {
    listed << "\n  t = " << ev.t << (ev.impact() ? " impact" : "");
    for (const Guard& g : ev.guards()) listed << " " << g.contact << ":" << to_string(g.kind);
  }
  // Lands flat (one impact, both corners), then only slip-stick changes on the plank, then lifts
  // off with both corners at once.
  ASSERT_GE(events.size(), 2u) << listed.str();
  EXPECT_TRUE(events.front().impact()) << listed.str();
  EXPECT_EQ(events.front().guards(), (std::vector<Guard>{{0, GuardKind::Touchdown}, {1, GuardKind::Touchdown}}))
      << listed.str();
  for (std::size_t k = 1; k + 1 < events.size(); ++k) {
    EXPECT_FALSE(events[k].impact()) << listed.str();
    for (const Guard& g : events[k].guards())
      EXPECT_TRUE(g.kind == GuardKind::Stop || g.kind == GuardKind::SlipOnset) << listed.str();
  }
  EXPECT_FALSE(events.back().impact()) << listed.str();
  EXPECT_EQ(events.back().guards(), (std::vector<Guard>{{0, GuardKind::Release}, {1, GuardKind::Release}}))
      << listed.str();
  const PolishResult<PlankBox> resim = polish(PlankBox{}, r.reference);
  const auto& simulated = resim.trajectory.events;
  ASSERT_GE(simulated.size(), 2u);
  // The simulator's landing: one impact after which both corners are closed (which corner its
  // event location names first is a matter of rounding on a flat landing).
  EXPECT_TRUE(simulated.front().impact());
  EXPECT_TRUE(simulated.front().mode_after[0].closed() && simulated.front().mode_after[1].closed());
  EXPECT_NEAR(simulated.front().t, events.front().t, 1e-6);
  EXPECT_EQ(simulated.back().guards(), events.back().guards());
  EXPECT_NEAR(simulated.back().t, events.back().t, 1e-6);
  std::cout << "plank-box short landing: objective " << r.solution.objective << ", " << r.solution.ipopt_iterations
            << " Ipopt iterations, " << r.solution.seconds << " s; re-simulation distance " << resim.state_distance
            << " at t = " << resim.worst_sample_time << ", " << simulated.size() << " simulated events\n";
  EXPECT_LT(resim.state_distance, 0.05);  // measured 0.022 (above)
}

}  // namespace
}  // namespace saltus::scenes
