// Stick/slip changes that the contact geometry makes delicate:
//  - redundant sticking contacts (the plank-box resting flat on both corners): the friction split
//    gives every contact the same utilisation ||lambda_t|| / (mu lambda_n) (flow.hpp), so slip
//    starts at both corners together when the total load leaves the cone, and never cycles;
//  - a slip onset of a single contact (the hopper pushing off): the new slip's stop guard sits
//    at zero at the onset and must not send the contact back to stick at the same instant.
#include "support.hpp"

#include "scenes/all_scenes.hpp"

#include <saltus/hybrid/dynamics/derivatives.hpp>

namespace saltus::testing {
namespace {

using PB = scenes::PlankBox;
using H = scenes::Hopper;

/// The box resting flat on the plank, off-centre so the corners carry different normal loads,
/// pushed sideways by F_x.
Vec<8> flat_box_state(const PB& pb, double box_x, double plank_angle) {
  const auto& p = pb.parameters();
  Vec<8> x = Vec<8>::Zero();
  x[3] = plank_angle;
  x[2] = plank_angle;  // box parallel to the plank
  // Box centre at distance box_x along the plank, resting on its top face.
  const double up = 0.5 * (p.box_height + p.plank_thickness);
  x[0] = box_x * std::cos(plank_angle) - up * std::sin(plank_angle);
  x[1] = box_x * std::sin(plank_angle) + up * std::cos(plank_angle);
  return x;
}

TEST(RedundantFriction, StickingCornersShareTheFrictionInProportionToTheirLoads) {
  PB pb;
  const double mu = pb.parameters().mu;
  const Vec<8> x = flat_box_state(pb, 0.7, 0.02);
  for (int k = 0; k < 2; ++k) ASSERT_NEAR(pb.gap<double>(k, Vec<4>(x.head<4>())), 0.0, 1e-14);
  Mode<2> stick;
  stick[0] = ContactState::stick();
  stick[1] = ContactState::stick();
  // A sideways push and a torque that loads the right corner more than the left.
  const Vec<3> u(1.5, 0.0, 0.4);
  FlowWorkspace<PB> ws;
  evaluate_flow(pb, stick, x, u, ws);
  ASSERT_LT(ws.delassus.rank(), ws.assembly.rows) << "the tangent rows of a flat box coincide";
  const auto& fl = ws.force[0];
  const auto& fr = ws.force[1];
  ASSERT_GT(fl.normal, 0.0);
  ASSERT_GT(fr.normal, 0.0);
  EXPECT_GT(std::abs(fl.normal - fr.normal), 0.1 * (fl.normal + fr.normal)) << "a case with unequal loads";
  const double util_l = std::abs(fl.tangent[0]) / (mu * fl.normal), util_r = std::abs(fr.tangent[0]) / (mu * fr.normal);
  EXPECT_NEAR(util_l, util_r, 1e-12 * std::max(1.0, util_l));
  // The constraints still hold: zero normal and tangential accelerations at both corners.
  for (int i = 0; i < 2; ++i) {
    const auto& c = ws.kin.contacts[i];
    EXPECT_NEAR(c.wn.dot(ws.acceleration) + c.kappa_n, 0.0, 1e-12);
    EXPECT_NEAR(c.Wt.col(0).dot(ws.acceleration) + c.kappa_t[0], 0.0, 1e-12);
  }
}

// Baumgarte's stabilisation (FlowWorkspace::constraint_stabilisation): off the contact manifold a
// sticking corner's normal and tangential velocities obey zeta_n' = -2 a zeta_n - a^2 h_n and
// zeta_t' = -a zeta_t; with a = 0 both accelerations are zero, and the open corner is untouched.
TEST(ConstraintStabilisation, ADriftedStickDecaysAtTheBaumgarteRate) {
  PB pb;
  Vec<8> x = flat_box_state(pb, 0.7, 0.02);
  x[1] += 2e-3;                                       // both corners 2 mm above the plank
  x.tail<4>() << 0.05, -0.03, 0.2, 0.1;               // and moving: drifted in velocity too
  Mode<2> mode;
  mode[0] = ContactState::stick();                    // corner 1 open: one full-rank stick
  const Vec<3> u(1.5, 0.0, 0.4);
  for (const double alpha : {0.0, 30.0}) {
    FlowWorkspace<PB> ws;
    ws.constraint_stabilisation = alpha;
    evaluate_flow(pb, mode, x, u, ws);
    const auto& c = ws.kin.contacts[0];
    ASSERT_GT(std::abs(c.gap), 1e-3);
    ASSERT_GT(std::abs(c.zeta_n), 1e-3);
    ASSERT_GT(std::abs(c.zeta_t[0]), 1e-3);
    const double scale = alpha * alpha * std::abs(c.gap) + alpha * std::abs(c.zeta_n) + 1.0;
    EXPECT_NEAR(c.wn.dot(ws.acceleration) + c.kappa_n, -2.0 * alpha * c.zeta_n - alpha * alpha * c.gap, 1e-12 * scale);
    EXPECT_NEAR(c.Wt.col(0).dot(ws.acceleration) + c.kappa_t[0], -alpha * c.zeta_t[0], 1e-12 * scale);
    EXPECT_EQ(ws.force[1].normal, 0.0);
  }
  FlowWorkspace<PB> off, on;
  on.constraint_stabilisation = 30.0;
  const Vec<8> x_on = flat_box_state(pb, 0.7, 0.02);  // on the manifold (at rest): the same flow
  evaluate_flow(pb, mode, x_on, u, off);
  evaluate_flow(pb, mode, x_on, u, on);
  EXPECT_LT((on.xdot - off.xdot).cwiseAbs().maxCoeff(), 1e-11);
}

TEST(RedundantFriction, FlowJacobianOfTheFlatStickMatchesCentralDifferences) {
  // The split changes the forces, never the accelerations of a sticking box: x' stays smooth, and
  // its AD Jacobian (through the weighted minimum-norm solve) matches central differences.
  PB pb;
  const Vec<8> x = flat_box_state(pb, 0.65, 0.01);
  Mode<2> stick;
  stick[0] = ContactState::stick();
  stick[1] = ContactState::stick();
  const Vec<3> u(0.8, -1.0, 0.1);
  DerivativeWorkspace<PB> dws;
  Vec<8> f;
  Mat<8, 8> A;
  Mat<8, 3> B;
  flow_jacobian(pb, stick, x, u, dws, f, A, B);
  FlowWorkspace<PB> ws;
  const Mat<8, 8> A_fd = central_jacobian<8, 8>([&](const Vec<8>& y) { return flow(pb, stick, y, u, ws); }, x, 1e-6);
  const Mat<8, 3> B_fd = central_jacobian<8, 3>([&](const Vec<3>& w) { return flow(pb, stick, x, w, ws); }, u, 1e-6);
  EXPECT_TRUE(matrices_near(A, A_fd, 1e-6, 1e-6));
  EXPECT_TRUE(matrices_near(B, B_fd, 1e-6, 1e-6));
}

TEST(RedundantFriction, PlankBoxSlipsOnBothCornersAtOnceAndSettles) {
  PB pb;
  const Vec<8> x0 = pb.flat_state();
  auto input = open_loop<PB>([&](double) { return pb.lowering_input(); });
  SimulationOptions o;
  o.integrator.relative_tolerance = 1e-12;
  o.integrator.absolute_tolerance = 1e-13;
  Simulator<PB> sim(pb, o);
  const auto traj = sim.run(x0, 0.0, 1.0, input);
  ASSERT_EQ(traj.status, SimulationStatus::Completed);
  ASSERT_GE(traj.events.size(), 2u);
  bool joint_slip_onset = false;
  for (const auto& ev : traj.events) {
    EXPECT_LE(ev.transitions.size(), 3u) << "at t = " << ev.t;
    int onsets = 0;
    for (const Guard& g : ev.guards()) onsets += g.kind == GuardKind::SlipOnset;
    if (onsets == 2) {
      joint_slip_onset = true;
      EXPECT_EQ(ev.mode_after[0].mode, ContactMode::Slip);
      EXPECT_EQ(ev.mode_after[1].mode, ContactMode::Slip);
    }
    EXPECT_NE(onsets, 1) << "one corner alone cannot start slipping while the other sticks (t = " << ev.t << ")";
  }
  EXPECT_TRUE(joint_slip_onset);
}

TEST(SlipOnset, HopperPushOffSlipsThenLiftsOffWithoutCycling) {
  H hopper;
  // Crouched landing, then a stiff push towards a stretched leg from t = 0.3 (examples/hopper.cpp).
  InputLaw<H> controller = [](double t, const Vec<8>& x, const Mode<1>&) {
    const bool push = t >= 0.3;
    const double hip = push ? 0.15 : 0.4, knee = push ? -0.3 : -0.8, kp = push ? 150.0 : 40.0, kd = push ? 3.0 : 2.0;
    return Vec<2>(kp * (hip - x[2]) - kd * x[6], kp * (knee - x[3]) - kd * x[7]);
  };
  Vec<8> x0;
  x0 << 0.0, 0.0, 0.4, -0.8, 0.3, 0.0, 0.0, 0.0;
  x0[1] = 0.05 - hopper.foot(Vec<4>(x0.head<4>()))[1];
  SimulationOptions o;
  o.integrator.relative_tolerance = 1e-11;
  o.integrator.absolute_tolerance = 1e-12;
  o.breakpoints = {0.3};
  Simulator<H> sim(hopper, o);
  const auto traj = sim.run(x0, 0.0, 0.5, controller);
  ASSERT_EQ(traj.events.size(), 3u);
  EXPECT_EQ(traj.events[0].mode_after[0].mode, ContactMode::Stick);
  EXPECT_EQ(traj.events[1].guards().at(0).kind, GuardKind::SlipOnset);
  ASSERT_EQ(traj.events[1].transitions.size(), 1u) << "the new slip is not sent back to stick";
  EXPECT_EQ(traj.events[1].mode_after[0].mode, ContactMode::Slip);
  EXPECT_EQ(traj.events[2].guards().at(0).kind, GuardKind::Release);
  EXPECT_FALSE(traj.events[2].mode_after[0].closed());
  // After the onset the slip speeds up along its direction: the foot's tangential velocity half
  // way through the slip phase has the sign of the slip direction.
  const double t_mid = 0.5 * (traj.events[1].t + traj.events[2].t);
  const Vec<8> x_mid = traj.state(2, t_mid);
  Kinematics<H> kin;
  evaluate_kinematics(hopper, Vec<4>(x_mid.head<4>()), Vec<4>(x_mid.tail<4>()), kin);
  EXPECT_GT(kin.contacts[0].zeta_t[0] * traj.events[1].mode_after[0].slip_direction[0], 0.0);
}

// A release whose contact has drifted below the gap tolerance during the stance (integration
// error; dopri5 does not project) must open the contact and not close it again at the same
// instant: the point mass slides with friction at gap -2e-9 (tolerance 1e-9) under a rising
// thrust u2 = 2 g t, so lambda_n = m g - u2 reaches zero at t = 0.5; afterwards it rises with
// y'' = 2 g (t - 0.5): y(1) = -2e-9 + g / 24, and it keeps sliding: x'' = 0 in flight.
// Before the release guard was exempted, the chain cycled open <-> slip and threw.
TEST(Release, ContactBelowTheGapToleranceOpensWithoutCycling) {
  scenes::PointMassParameters p;
  p.friction = Friction::Planar;
  p.mu = 0.3;
  const scenes::PointMass mass(p);
  constexpr double g = 9.81;
  SimulationOptions o;
  o.integrator.relative_tolerance = 1e-12;
  o.integrator.absolute_tolerance = 1e-13;
  o.breakpoints = {0.5};
  Simulator<scenes::PointMass> sim(mass, o);
  Mode<1> slip;
  slip[0] = ContactState::slip_planar(+1);  // sliding to the right (the slip direction)
  const Vec<4> x0(0.0, -2e-9, 1.0, 0.0);
  const auto law = open_loop<scenes::PointMass>([](double t) { return Vec<2>(0.0, 2 * g * t); });
  const auto traj = sim.run(x0, slip, 0.0, 1.0, law);
  ASSERT_EQ(traj.events.size(), 1u);
  const auto& ev = traj.events[0];
  EXPECT_EQ(ev.guards().at(0).kind, GuardKind::Release);
  EXPECT_EQ(ev.transitions.size(), 1u) << "the released contact was closed again";
  EXPECT_NEAR(ev.t, 0.5, 1e-9);
  EXPECT_FALSE(traj.segments.back().mode[0].closed());
  // Friction mu m g (1 - 2t) decelerates the slide until the release: v(0.5) = 1 - mu g / 4.
  const double vx = 1.0 - p.mu * g * 0.25;
  const double x_release = 0.5 - p.mu * g * (0.125 - 1.0 / 24.0);
  const Vec<4> x1 = traj.final_state();
  EXPECT_NEAR(x1[1], -2e-9 + g / 24.0, 1e-9);
  EXPECT_NEAR(x1[3], g / 4.0, 1e-9);
  EXPECT_NEAR(x1[2], vx, 1e-9);
  EXPECT_NEAR(x1[0], x_release + 0.5 * vx, 1e-9);
}

// A release by an input jump: the point mass rests on the ground under a thrust u_y = g / 2 that
// jumps to 2 g at the breakpoint t = 0.5. Under the new input the closed contact would pull
// (lambda_n = m g - 2 m g < 0): the contact releases AT the breakpoint, with no sign change of
// lambda_n inside a step, and the mass rises with y'' = g: y(1) = g / 8.
TEST(Release, AnInputJumpReleasesAtTheBreakpoint) {
  const scenes::PointMass mass;
  constexpr double g = 9.81;
  SimulationOptions o;
  o.integrator.relative_tolerance = 1e-12;
  o.integrator.absolute_tolerance = 1e-13;
  o.breakpoints = {0.5};
  Simulator<scenes::PointMass> sim(mass, o);
  const auto law = open_loop<scenes::PointMass>([](double t) { return Vec<2>(0.0, t < 0.5 ? 0.5 * g : 2 * g); });
  const auto traj = sim.run(Vec<4>::Zero(), 0.0, 1.0, law);
  ASSERT_EQ(traj.events.size(), 1u);
  EXPECT_EQ(traj.events[0].guards().at(0).kind, GuardKind::Release);
  EXPECT_EQ(traj.events[0].t, 0.5);
  EXPECT_TRUE(traj.events[0].input_jump);
  EXPECT_FALSE(traj.segments.back().mode[0].closed());
  EXPECT_NEAR(traj.final_state()[1], g / 8.0, 1e-10);
  EXPECT_NEAR(traj.final_state()[3], g / 2.0, 1e-10);
}

}  // namespace
}  // namespace saltus::testing
