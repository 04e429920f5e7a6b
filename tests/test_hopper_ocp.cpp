// The flagship OCP statement, the hopper over three holes (scenes/hopper_holes.hpp): its path
// constraints at postures whose values are known in closed form, the hole continuation level, the
// exact derivatives of its FESD MPCC under Ipopt's own second-order derivative checker, and the
// feasibility report the example and the benchmark print.
#include "scenes/hopper_holes.hpp"

#include <saltus/timefreezing/fesd.hpp>
#include <saltus/timefreezing/mpcc_solver.hpp>

#include "mpcc_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <numbers>
#include <vector>

namespace saltus::scenes {
namespace {

using Ocp = HopperOverThreeHoles;

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

}  // namespace
}  // namespace saltus::scenes
