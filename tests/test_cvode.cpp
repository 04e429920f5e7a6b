// The CVODE backend (BDF and Adams): its agreement with Dormand-Prince, its projection onto the
// closed contacts, and its failures: every CVODE error becomes an exception naming the flag, every
// exception thrown inside a callback reaches the caller. The analytic cases run with every
// integrator in test_simulation.cpp.
#include "support.hpp"

#include "scenes/all_scenes.hpp"

#include <saltus/hybrid/simulation/integrator_cvode.hpp>

namespace saltus::testing {
namespace {

class Cvode : public ::testing::TestWithParam<IntegratorKind> {
 protected:
  SimulationOptions tight() const {
    SimulationOptions o;
    o.integrator.kind = GetParam();
    o.integrator.relative_tolerance = 1e-12;
    o.integrator.absolute_tolerance = 1e-13;
    return o;
  }
};

// Both CVODE variants agree with Dormand-Prince on a case without a closed form (the plank-box
// after landing: spring, damper and two sticking corners), up to t = 0.5: the landing and the
// sticking phase (both corners start slipping at t = 0.564).
TEST_P(Cvode, AgreesWithDormandPrinceOnThePlankBox) {
  scenes::PlankBox plank_box;
  const Vec<8> x0 = plank_box.flat_state();  // the box flat, 5 cm above the level plank
  // The actuated box holds its weight but 2 N: u = (0, m g - 2, 0).
  auto input = open_loop<scenes::PlankBox>([&](double) { return plank_box.lowering_input(); });
  SimulationOptions dopri_options = tight();
  dopri_options.integrator.kind = IntegratorKind::DormandPrince;
  Simulator<scenes::PlankBox> dopri(plank_box, dopri_options), cvode(plank_box, tight());
  const auto a = dopri.run(x0, 0.0, 0.5, input), b = cvode.run(x0, 0.0, 0.5, input);
  ASSERT_EQ(a.events.size(), b.events.size());
  for (std::size_t k = 0; k < a.events.size(); ++k) EXPECT_NEAR(a.events[k].t, b.events[k].t, 1e-9) << "event " << k;
  EXPECT_TRUE(matrices_near(b.final_state(), a.final_state(), 0.0, 1e-8));
}

INSTANTIATE_TEST_SUITE_P(Backends, Cvode, ::testing::Values(IntegratorKind::CvodeBdf, IntegratorKind::CvodeAdams),
                         [](const auto& info) { return std::string(info.param == IntegratorKind::CvodeBdf ? "Bdf" : "Adams"); });

// ---- projection ----------------------------------------------------------------------------

// The largest |gap|, |normal velocity| and (sticking) |tangential velocity| over the closed
// contacts of `mode` at x.
template <Scene S>
double constraint_violation(const S& scene, const Mode<S::nc>& mode, const VecT<double, 2 * S::nq>& x) {
  Kinematics<S> kin;
  evaluate_kinematics(scene, VecT<double, S::nq>(x.template head<S::nq>()), VecT<double, S::nq>(x.template tail<S::nq>()),
                      kin);
  double worst = 0.0;
  for (int i = 0; i < S::nc; ++i) {
    if (!mode[i].closed()) continue;
    const auto& c = kin.contacts[i];
    worst = std::max({worst, std::abs(c.gap), std::abs(c.zeta_n)});
    if (mode[i].mode == ContactMode::Stick)
      for (int k = 0; k < c.tangents; ++k) worst = std::max(worst, std::abs(c.zeta_t[k]));
  }
  return worst;
}

// The plank-box after landing: the box sticks on a plank that swings on its spring, so the
// contact constraints are curved (the gaps depend on the plank and box angles) and an
// integrator at a loose tolerance drifts off them. With projection (BDF: after every step) the
// gap and the constrained velocities stay zero to round-off at every step end and at the end.
TEST(CvodeProjection, KeepsTheClosedContactsOfTheSwingingPlankOnTheirConstraints) {
  scenes::PlankBox plank_box;
  const Vec<8> x0 = plank_box.flat_state();  // the box flat, 5 cm above the level plank
  // The actuated box holds its weight but 2 N: u = (0, m g - 2, 0).
  auto input = open_loop<scenes::PlankBox>([&](double) { return plank_box.lowering_input(); });
  auto worst_violation = [&](bool project) {
    SimulationOptions o;
    o.integrator.kind = IntegratorKind::CvodeBdf;
    o.integrator.relative_tolerance = 1e-5;
    o.integrator.absolute_tolerance = 1e-7;
    o.integrator.project_constraints = project;
    Simulator<scenes::PlankBox> sim(plank_box, o);
    const auto traj = sim.run(x0, 0.0, 0.5, input);
    EXPECT_GE(traj.events.size(), 1u);
    const auto& last = traj.segments.back();
    EXPECT_TRUE(last.mode[0].closed() && last.mode[1].closed()) << describe(plank_box, last.mode);
    double worst = constraint_violation(plank_box, last.mode, traj.final_state());
    for (const auto& piece : last.x.pieces())
      worst = std::max(worst, constraint_violation(plank_box, last.mode, piece.value(piece.t1)));
    return worst;
  };
  EXPECT_LE(worst_violation(true), 1e-12);
  // Without projection the same run drifts: the check above can fail.
  EXPECT_GT(worst_violation(false), 1e-10);
}

// A sliding point mass (Example 3's sliding phase): the gap stays 0 to 1e-12 with both variants
// (Adams projects the state handed back at the end of the segment).
TEST(CvodeProjection, KeepsTheSlidingPointMassOnTheTable) {
  scenes::PointMass mass;
  for (IntegratorKind kind : {IntegratorKind::CvodeBdf, IntegratorKind::CvodeAdams}) {
    SimulationOptions o;
    o.integrator.kind = kind;
    o.integrator.relative_tolerance = 1e-4;
    o.integrator.absolute_tolerance = 1e-6;
    Simulator<scenes::PointMass> sim(mass, o);
    auto input = open_loop<scenes::PointMass>([](double t) { return Vec<2>(7.0 * std::cos(3 * t), 0.0); });
    const auto traj = sim.run(Vec<4>(0.0, 0.0, 0.3, 0.0), 0.0, 1.0, input);
    ASSERT_TRUE(traj.segments.back().mode[0].closed()) << to_string(kind);
    EXPECT_LE(std::abs(traj.final_state()[1]), 1e-12) << to_string(kind);
    EXPECT_LE(std::abs(traj.final_state()[3]), 1e-12) << to_string(kind);
  }
}

// ---- failures ------------------------------------------------------------------------------

TEST(CvodeFailures, BadOptionsAreRejected) {
  IntegratorOptions o;
  o.kind = IntegratorKind::CvodeBdf;
  o.relative_tolerance = -1e-6;
  EXPECT_THROW(CvodeIntegrator<scenes::BouncingBall>{o}, InvalidArgument);
  o.relative_tolerance = 1e-6;
  o.absolute_tolerance = 0.0;
  EXPECT_THROW(CvodeIntegrator<scenes::BouncingBall>{o}, InvalidArgument);
  o.absolute_tolerance = 1e-8;
  o.kind = IntegratorKind::DormandPrince;
  EXPECT_THROW(CvodeIntegrator<scenes::BouncingBall>{o}, InvalidArgument);
  scenes::BouncingBall ball;
  SimulationOptions so;
  so.integrator.kind = IntegratorKind::CvodeAdams;
  so.integrator.absolute_tolerance = -1.0;
  EXPECT_THROW(Simulator<scenes::BouncingBall>(ball, so), InvalidArgument);
}

// Tolerances below round-off: CVODE stops with CV_TOO_MUCH_ACC, surfaced with its name.
TEST(CvodeFailures, ACvodeErrorBecomesANumericalFailureNamingTheFlag) {
  scenes::BouncingBall ball;
  SimulationOptions o;
  o.integrator.kind = IntegratorKind::CvodeBdf;
  o.integrator.relative_tolerance = 1e-22;
  o.integrator.absolute_tolerance = 1e-30;
  Simulator<scenes::BouncingBall> sim(ball, o);
  try {
    sim.run(Vec<2>(1.0, 0.0), 0.0, 1.0, zero_input<scenes::BouncingBall>());
    FAIL() << "expected a NumericalFailure";
  } catch (const NumericalFailure& e) {
    EXPECT_NE(std::string(e.what()).find("CV_TOO_MUCH_ACC"), std::string::npos) << e.what();
  }
}

TEST(CvodeFailures, AnExceptionInsideTheFlowReachesTheCaller) {
  scenes::PointMass mass;
  for (IntegratorKind kind : {IntegratorKind::CvodeBdf, IntegratorKind::CvodeAdams}) {
    SimulationOptions o;
    o.integrator.kind = kind;
    Simulator<scenes::PointMass> sim(mass, o);
    auto input = open_loop<scenes::PointMass>([](double t) {
      if (t > 0.2) throw std::domain_error("input law undefined after t = 0.2");
      return Vec<2>(0.0, 0.0);
    });
    EXPECT_THROW(sim.run(Vec<4>(0.0, 1.0, 0.0, 0.0), 0.0, 1.0, input), std::domain_error) << to_string(kind);
    auto nan_input = open_loop<scenes::PointMass>([](double t) { return Vec<2>(t > 0.1 ? std::nan("") : 0.0, 0.0); });
    EXPECT_THROW(sim.run(Vec<4>(0.0, 1.0, 0.0, 0.0), 0.0, 1.0, nan_input), NumericalFailure) << to_string(kind);
  }
}

TEST(CvodeFailures, TheStepLimitIsEnforced) {
  scenes::BouncingBall ball;
  SimulationOptions o;
  o.integrator.kind = IntegratorKind::CvodeAdams;
  o.integrator.max_steps = 3;
  Simulator<scenes::BouncingBall> sim(ball, o);
  EXPECT_THROW(sim.run(Vec<2>(1.0, 0.0), 0.0, 1.0, zero_input<scenes::BouncingBall>()), NumericalFailure);
}

}  // namespace
}  // namespace saltus::testing
