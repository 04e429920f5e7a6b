// The jump gain of an impact without collision (SimulationOptions::painleve) against its numerical
// twin: the rod of tests/painleve_rod.hpp pushed into the release that ends Painleve's
// indeterminacy, where the release guard's transition is the impact without collision. Its
// velocity jump is the stick jump map of the contact (dynamics/impact_without_collision.hpp), so
// the analytic gain differentiates that map at the release; the twin re-simulates perturbed
// motions through the event, each taking its own impact without collision.
#include "painleve_rod.hpp"
#include "support.hpp"

#include <saltus/sensitivity/header_only.hpp>  // the test-local rod

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace saltus::testing {
namespace {

TEST(ImpactWithoutCollisionGain, TheReleaseIntoAnImpactWithoutCollisionMatchesTheTwin) {
  const PushedRod rod(2.0);
  SimulationOptions options;
  options.integrator.relative_tolerance = 1e-13;
  options.integrator.absolute_tolerance = 1e-13;
  options.painleve.resolution = InconsistentContactResolution::ImpactWithoutCollision;
  const double c = std::sqrt(0.5);
  Vec<6> x0;
  x0 << 0.5 * c, 0.5 * c, M_PI / 4, -1.0, 0.0, 0.0;  // the end sliding at -1 m/s, W_nn - mu s W_nt = -1/2
  const InputLaw<PushedRod> push = [](double t, const Vec<6>&, const Mode<1>&) {
    return Vec<2>(0.0, PushedRod::g + 2.0 - 100.0 * t);
  };
  Simulator<PushedRod> sim(rod, options);
  const auto traj = sim.run(x0, Mode<1>{ContactState::slip_planar(-1)}, 0.0, 0.03, push);
  ASSERT_GE(traj.events.size(), 1u);
  const auto& ev = traj.events.front();
  ASSERT_EQ(ev.transitions.size(), 1u);
  ASSERT_TRUE(ev.transitions.front().impact_without_collision);
  ASSERT_EQ(ev.guards().front().kind, GuardKind::Release);

  JumpGainSolver<PushedRod> solver(rod);
  const JumpGain<PushedRod> analytic = solver.compute(ev, traj.input);
  EXPECT_LE(analytic.jump_map_residual, 1e-12) << "the stick jump map does not reproduce x+";
  NumericalJumpGainOptions twin;
  twin.simulation = options;
  const NumericalJumpGain<PushedRod> numeric = numerical_jump_gain(rod, traj, 0, twin);
  const Eigen::MatrixXd GzB = analytic.G_z * numeric.basis;
  const double scale = std::max({GzB.cwiseAbs().maxCoeff(), numeric.G_z_basis.cwiseAbs().maxCoeff(),
                                 analytic.G_v.cwiseAbs().maxCoeff()});
  const double gz_error = (GzB - Eigen::MatrixXd(numeric.G_z_basis)).cwiseAbs().maxCoeff() / scale;
  const double gv_error = (analytic.G_v - numeric.G_v).cwiseAbs().maxCoeff() / scale;
  const Eigen::RowVectorXd dtB = analytic.dt_dz * numeric.basis;
  const double dt_scale = std::max({dtB.cwiseAbs().maxCoeff(), numeric.dt_basis.cwiseAbs().maxCoeff(),
                                    analytic.dt_dv.cwiseAbs().maxCoeff()});
  const double dt_error = std::max((dtB - Eigen::RowVectorXd(numeric.dt_basis)).cwiseAbs().maxCoeff(),
                                   (analytic.dt_dv - numeric.dt_dv).cwiseAbs().maxCoeff()) /
                          dt_scale;
  std::printf("impact without collision at t = %.9f s: admissible rank %d, relative errors G_z B %.2e, G_v %.2e, "
              "dt %.2e (scale %.3g; replays %d)\n",
              ev.t, static_cast<int>(numeric.basis.cols()), gz_error, gv_error, dt_error, scale, numeric.replays);
  EXPECT_LE(gz_error, 1e-6) << "analytic G_z B:\n" << GzB << "\nnumerical:\n" << numeric.G_z_basis;
  EXPECT_LE(gv_error, 1e-6) << "analytic G_v:\n" << analytic.G_v << "\nnumerical:\n" << numeric.G_v;
  EXPECT_LE(dt_error, 1e-6);
  EXPECT_EQ(numeric.replays, 0);
}

}  // namespace
}  // namespace saltus::testing
