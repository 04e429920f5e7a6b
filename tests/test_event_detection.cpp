// No silent wrong result from the event detection: touchdowns after flights shorter than a step
// (a rocking block near its accumulation of impacts), a guard that dips below zero and back
// within one step (a point mass skimming a table), the accumulation of impacts that alternate
// between two contacts (Zeno, detected on all touchdowns), the no-penetration invariant over
// every scene's reference motions, and an inconsistent initial mode (a Painleve rod) refused with
// the contact named. Each case has its closed-form value.
#include "painleve_rod.hpp"
#include "support.hpp"

#include "scenes/all_scenes.hpp"
#include "scenes/references.hpp"

#include <saltus/hybrid/header_only.hpp>
#include <saltus/hybrid/vocabulary/trajectory_io.hpp>
#include <saltus/hybrid/vocabulary/trajectory_report.hpp>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>

namespace saltus::testing {
namespace {

constexpr double g = 9.81;

// A uniform rectangular block in the vertical plane, q = (x, y, theta) of its centre [m, m,
// rad], both bottom corners as planar-friction contacts; no inputs.
class RockingBlock {
 public:
  static constexpr int nq = 3, nu = 0, nc = 2;
  RockingBlock(double width, double height, double mu)
      : w_(width), h_(height), corners_{ContactSpec{"left", Friction::Planar, mu, 0.0},
                                        ContactSpec{"right", Friction::Planar, mu, 0.0}} {}
  const ContactSpec& contact(int i) const { return corners_[i]; }
  double width() const { return w_; }
  double height() const { return h_; }
  template <class T>
  MatT<T, nq, nq> mass_matrix(const VecT<T, nq>&) const {
    MatT<T, nq, nq> M = MatT<T, nq, nq>::Zero();
    M(0, 0) = M(1, 1) = T(1.0);
    M(2, 2) = T((w_ * w_ + h_ * h_) / 12.0);
    return M;
  }
  template <class T>
  VecT<T, nq> bias(const VecT<T, nq>&, const VecT<T, nq>&) const {
    return VecT<T, nq>(T(0), T(g), T(0));
  }
  template <class T>
  MatT<T, nq, nu> input_matrix(const VecT<T, nq>&) const {
    return MatT<T, nq, nu>::Zero();
  }
  // Corner i at body coordinates (-+w/2, -h/2).
  template <class T>
  VecT<T, 2> corner(int i, const VecT<T, nq>& q) const {
    using std::cos;
    using std::sin;
    const double bx = i == 0 ? -w_ / 2 : w_ / 2, by = -h_ / 2;
    return VecT<T, 2>(q[0] + cos(q[2]) * bx - sin(q[2]) * by, q[1] + sin(q[2]) * bx + cos(q[2]) * by);
  }
  template <class T>
  T gap(int i, const VecT<T, nq>& q) const {
    return corner(i, q)[1];
  }
  template <class T>
  VecT<T, 2> tangent_position(int i, const VecT<T, nq>& q) const {
    return VecT<T, 2>(corner(i, q)[0], T(0));
  }
  /// At rest on the left corner, tilted by `tilt` (rad) so that the right corner is lifted.
  Vec<6> resting_on_left_corner(double tilt) const {
    // Centre = left corner + R(tilt) (w/2, h/2), left corner at the origin.
    const double cx = std::cos(tilt) * w_ / 2 - std::sin(tilt) * h_ / 2;
    const double cy = std::sin(tilt) * w_ / 2 + std::cos(tilt) * h_ / 2;
    Vec<6> x = Vec<6>::Zero();
    x << cx, cy, tilt, 0, 0, 0;
    return x;
  }
  /// Housner's ratio of the angular velocities after and before an impact on a corner of a
  /// uniform block (e_n = 0, no slip): 1 - (3/2) sin^2(alpha), alpha = atan(w / h).
  double housner_ratio() const {
    const double s = std::sin(std::atan(w_ / h_));
    return 1.0 - 1.5 * s * s;
  }

 private:
  double w_, h_;
  std::array<ContactSpec, 2> corners_;
};

InputLaw<RockingBlock> no_input() {
  return [](double, const Vec<6>&, const Mode<2>&) { return Vec<0>(); };
}

struct RockingCase {
  IntegratorKind kind;
  double rtol;
};

class RockingBlockSettles : public ::testing::TestWithParam<RockingCase> {};

// Issue cases 1 and 2: a tall block (0.2 m x 0.6 m, mu = 2) released on one corner, tilted by
// 0.05 rad, rocks with impacts alternating between its corners; the intervals between impacts
// shrink by Housner's ratio 0.85. The run ends with status Zeno at the accumulation time, never
// below the ground.
TEST_P(RockingBlockSettles, ZenoOfAlternatingCornersNeverBelowTheGround) {
  const RockingBlock block(0.2, 0.6, 2.0);
  SimulationOptions o;
  o.integrator.kind = GetParam().kind;
  o.integrator.relative_tolerance = GetParam().rtol;
  o.integrator.absolute_tolerance = GetParam().rtol * 1e-2;
  Simulator<RockingBlock> sim(block, o);
  const auto traj = sim.run(block.resting_on_left_corner(0.05), 0.0, 5.0);  // nu = 0: no input law
  ASSERT_EQ(traj.status, SimulationStatus::Zeno) << "events: " << traj.events.size();
  // The scan keeps every check point above -gap_tolerance; between check points the dense output
  // may sit lower by its own error (about the absolute tolerance: 1.1e-9 at rtol 1e-8 with BDF).
  EXPECT_GE(lowest_gap(block, traj, true), -(o.impact.gap_tolerance + 10 * o.integrator.absolute_tolerance));
  EXPECT_GE(lowest_gap(block, traj, false), -1e-8);
  // The touchdowns alternate between the corners, and the intervals shrink towards Housner's
  // ratio (the rocking is not small against the block's slenderness angle, so the first ratios
  // differ from it).
  std::vector<double> times;
  std::vector<int> corner;
  std::ostringstream summary;
  for (const auto& ev : traj.events) {
    summary << ev.t << ":";
    for (const auto& gd : ev.guards()) summary << ' ' << to_string(gd.kind) << gd.contact;
    summary << " -> " << describe(block, ev.mode_after) << "\n";
    for (const auto& gd : ev.guards())
      if (gd.kind == GuardKind::Touchdown) {
        times.push_back(ev.t);
        corner.push_back(gd.contact);
        break;
      }
  }
  ASSERT_GE(times.size(), 10u) << summary.str();
  const std::size_t m = times.size();
  const double ratio = (times[m - 1] - times[m - 2]) / (times[m - 2] - times[m - 3]);
  EXPECT_NEAR(ratio, block.housner_ratio(), 2e-3) << summary.str();
  // The predicted accumulation lies within the geometric tail of the last interval.
  const double tail = (times[m - 1] - times[m - 2]) * ratio / (1 - ratio);
  EXPECT_GT(traj.zeno_time, times.back() + 0.5 * tail);
  EXPECT_LT(traj.zeno_time, times.back() + 1.5 * tail);
  for (std::size_t k = 1; k < m; ++k) EXPECT_NE(corner[k], corner[k - 1]) << "touchdown " << k << "\n" << summary.str();
}

INSTANTIATE_TEST_SUITE_P(Integrators, RockingBlockSettles,
                         ::testing::Values(RockingCase{IntegratorKind::DormandPrince, 1e-8},
                                           RockingCase{IntegratorKind::DormandPrince, 1e-12},
                                           RockingCase{IntegratorKind::CvodeBdf, 1e-8},
                                           RockingCase{IntegratorKind::CvodeBdf, 1e-12},
                                           RockingCase{IntegratorKind::CvodeAdams, 1e-10}),
                         [](const auto& info) {
                           return std::string(to_string(info.param.kind) == std::string("dopri5") ? "Dopri5"
                                              : info.param.kind == IntegratorKind::CvodeBdf   ? "CvodeBdf"
                                                                                              : "CvodeAdams") +
                                  "_rtol" + std::to_string(static_cast<int>(-std::log10(info.param.rtol)));
                         });

// Issue case 9: a block 0.2 m x 0.4 m (mu = 0.8) tilted by 0.1 rad rocks with ratio 0.7 per
// impact and ends in a detected accumulation, not in a chain that does not settle.
TEST(RockingBlock, SquatBlockReachesItsAccumulationWithHousnersRatio) {
  const RockingBlock block(0.2, 0.4, 0.8);
  EXPECT_NEAR(block.housner_ratio(), 0.7, 1e-12);
  Simulator<RockingBlock> sim(block, SimulationOptions{});
  const auto traj = sim.run(block.resting_on_left_corner(0.1), 0.0, 5.0, no_input());
  ASSERT_EQ(traj.status, SimulationStatus::Zeno);
  EXPECT_GE(lowest_gap(block, traj, true), -1e-9);
  // Angular velocities just before consecutive impacts shrink by the ratio.
  const auto& e = traj.events;
  ASSERT_GE(e.size(), 4u);
  for (std::size_t k = 1; k < 4; ++k) EXPECT_NEAR(e[k].x_minus[5] / e[k - 1].x_minus[5], -0.7, 1e-6) << k;
}

// Issue case 7: a unit point mass at vx = 1 above a table (mu = 0.5, e_n = 0) under a thrust
// that makes its free height y(t) = 0.5 (t - 1)^2 + delta. For delta < 0 it touches the table at
// t* = 1 - sqrt(-2 delta) with vy = -sqrt(-2 delta), the inelastic impact slides (friction
// impulse mu sqrt(-2 delta)), and the net upward force lifts it off at once:
// y(t) = 0.5 (t - t*)^2, x(t) = t* + (1 - mu s)(t - t*) after it, s = sqrt(-2 delta).
// For delta >= 0 (grazing the table at t = 1, or missing it) the motion is the free parabola and
// there is no event (a jump gain at a grazing touch is refused: test_jump_gains.cpp).
class SkimmingPointMass : public ::testing::TestWithParam<double> {};

TEST_P(SkimmingPointMass, TouchdownInsideOneStepIsFound) {
  const double delta = GetParam();
  scenes::PointMassParameters p;
  p.friction = Friction::Planar;
  p.mu = 0.5;
  const scenes::PointMass mass(p);
  const InputLaw<scenes::PointMass> thrust = [](double, const Vec<4>&, const Mode<1>&) {
    return Vec<2>(0.0, g + 1.0);
  };
  Vec<4> x0;
  x0 << 0.0, 0.5 + delta, 1.0, -1.0;
  const double T = 2.0;
  Simulator<scenes::PointMass> sim(mass, SimulationOptions{});
  const auto traj = sim.run(x0, 0.0, T, thrust);
  EXPECT_EQ(traj.status, SimulationStatus::Completed);
  Vec<4> expected;
  if (delta < 0) {
    const double s = std::sqrt(-2 * delta), ts = 1 - s;
    ASSERT_EQ(traj.events.size(), 1u);
    EXPECT_NEAR(traj.events[0].t, ts, 1e-10);
    expected << ts + (1 - p.mu * s) * (T - ts), 0.5 * (T - ts) * (T - ts), 1 - p.mu * s, T - ts;
  } else {
    expected << T, 0.5 * (T - 1) * (T - 1) + delta, 1.0, T - 1;
    EXPECT_TRUE(traj.events.empty());  // grazing (delta = 0) or missing the table
  }
  EXPECT_LT((traj.final_state() - expected).cwiseAbs().maxCoeff(), 1e-9) << traj.final_state().transpose();
  EXPECT_GE(lowest_gap(mass, traj, true), -1e-9);
}

INSTANTIATE_TEST_SUITE_P(Depths, SkimmingPointMass, ::testing::Values(-1e-3, -1e-4, -1e-6, -1e-8, 0.0, 1e-8),
                         [](const auto& info) {
                           const double d = info.param;
                           if (d == 0) return std::string("grazing");
                           return std::string(d < 0 ? "below_1e" : "above_1e") +
                                  std::to_string(static_cast<int>(std::round(-std::log10(std::abs(d)))));
                         });

// Case 4 of the guard scan (simulation/guard_scan.hxx): a release guard that dips below zero and
// back within one step. The point mass rests on the frictionless table under the thrust
// u_y(t) = m g - 6 + A cos(2 pi (t + 1/2)) N: the normal force lambda_n = 6 - A cos(...) goes
// negative when cos(2 pi (t + 1/2)) > 6 / A, so for A = 8 the mass leaves the table at
// t_r + k, t_r = 1/2 - arccos(3/4) / (2 pi), and lands again before the next release. At rest
// the flow is constant and the integrator's steps grow past the thrust's period: every release
// after a landing falls inside one step (before case 4 the second one was missed). For A = 6 the
// normal force touches zero once per period without going below it: a grazing release, no event.
class RestingPointMassUnderThrust : public ::testing::TestWithParam<IntegratorKind> {};

TEST_P(RestingPointMassUnderThrust, ReleaseDipInsideOneStepIsFound) {
  const scenes::PointMass mass;
  const double m = mass.parameters().mass, grav = mass.parameters().gravity;
  auto thrust = [m, grav](double amplitude) -> InputLaw<scenes::PointMass> {
    return [=](double t, const Vec<4>&, const Mode<1>&) {
      return Vec<2>(0.0, m * grav - 6.0 + amplitude * std::cos(2.0 * std::numbers::pi * (t + 0.5)));
    };
  };
  SimulationOptions options;
  options.integrator.kind = GetParam();
  Simulator<scenes::PointMass> sim(mass, options);
  const auto hops = sim.run(Vec<4>::Zero(), 0.0, 3.2, thrust(8.0));
  ASSERT_EQ(hops.status, SimulationStatus::Completed);
  const double t_r = 0.5 - std::acos(0.75) / (2.0 * std::numbers::pi);
  std::vector<double> releases;
  for (const auto& e : hops.events)
    for (const auto& g : e.guards())
      if (g.kind == GuardKind::Release) releases.push_back(e.t);
  ASSERT_EQ(releases.size(), 3u) << "releases expected at " << t_r << " + k";
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(releases[k], t_r + k, 1e-9) << "release " << k;
  EXPECT_EQ(hops.events.size(), 6u);  // three releases, three landings

  const auto grazing = sim.run(Vec<4>::Zero(), 0.0, 3.2, thrust(6.0));
  ASSERT_EQ(grazing.status, SimulationStatus::Completed);
  EXPECT_TRUE(grazing.events.empty()) << grazing.events.size() << " events, the first at " << grazing.events[0].t;
  EXPECT_LT(grazing.final_state().cwiseAbs().maxCoeff(), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Backends, RestingPointMassUnderThrust,
                         ::testing::Values(IntegratorKind::DormandPrince, IntegratorKind::CvodeBdf),
                         [](const auto& info) {
                           return std::string(info.param == IntegratorKind::DormandPrince ? "dopri5" : "cvode_bdf");
                         });

TEST(GuardScan, GuardSamplesOutsideTheirRangeAreRefused) {
  const scenes::PointMass mass;
  SimulationOptions options;
  options.integrator.guard_samples = 15;
  Simulator<scenes::PointMass> sim(mass, options);
  const InputLaw<scenes::PointMass> none = [](double, const Vec<4>&, const Mode<1>&) { return Vec<2>::Zero(); };
  EXPECT_THROW(sim.run(Vec<4>(0.0, 1.0, 0.0, 0.0), 0.0, 1.0, none), InvalidArgument);
}

// Issue case 3: over every scene's reference motions, no open contact is below -gap_tolerance
// at any point of the dense output, and no closed one drifts below 1e-8.
TEST(NoPenetration, EveryReferenceMotionStaysAboveTheGround) {
  auto check = [](const auto& ref) {
    SCOPED_TRACE(ref.name);
    EXPECT_GE(lowest_gap(ref.scene, ref.trajectory, true), -ref.options.impact.gap_tolerance);
    EXPECT_GE(lowest_gap(ref.scene, ref.trajectory, false), -1e-8);
  };
  const auto example3 = references::example3();
  check(example3);
  // Its frictionless sliding segment is reported as closed, not as a slip.
  EXPECT_EQ(describe(example3.scene, example3.trajectory.segments.at(1).mode), "table:closed");
  check(references::point_mass_with_friction());
  check(references::hopper());
  check(references::hopper_push_off());
  check(references::plank_box());
  // The elastic ball to its accumulation.
  scenes::BouncingBallParameters bp;
  bp.restitution = 0.8;
  const scenes::BouncingBall ball(bp);
  Simulator<scenes::BouncingBall> sim(ball, SimulationOptions{});
  Vec<2> x0(1.0, 0.0);
  const auto traj = sim.run(x0, 0.0, 5.0, [](double, const Vec<2>&, const Mode<1>&) { return Vec<0>(); });
  EXPECT_EQ(traj.status, SimulationStatus::Zeno);
  EXPECT_GE(lowest_gap(ball, traj, true), -1e-9);
}

// The rest criterion works with the default zeno_bounces: a ball with e_n = 0.7 dropped from
// 1 m comes to rest (status completed, at rest on the floor at T).
TEST(RestCriterion, BouncingBallComesToRestWithDefaultOptions) {
  scenes::BouncingBallParameters bp;
  bp.restitution = 0.7;
  const scenes::BouncingBall ball(bp);
  SimulationOptions o;
  o.rest_velocity = 0.05;
  Simulator<scenes::BouncingBall> sim(ball, o);
  const auto traj = sim.run(Vec<2>(1.0, 0.0), 0.0, 5.0, [](double, const Vec<2>&, const Mode<1>&) { return Vec<0>(); });
  EXPECT_EQ(traj.status, SimulationStatus::Completed);
  EXPECT_NEAR(traj.final_state()[0], 0.0, 1e-9);
  EXPECT_NEAR(traj.final_state()[1], 0.0, 1e-9);
}

// Issue case 4: the rod at 45 degrees, its end on the ground sliding at 1 m/s towards -x (away
// from under its centre), mu = 2, no rotation. With the end slipping, the normal acceleration of
// the end is -g + (N / m) (1 + 3 c (c - mu s)) = -g - N / (2 m) (c = s = 1/sqrt 2): only N = -2 m g
// keeps the contact, so the slipping mode is inconsistent and the run refuses it, naming the
// contact and the negative force. Sliding towards +x the same mode is consistent.
TEST(InitialMode, PainleveSlipWithNegativeNormalForceIsRefused) {
  const PainleveRod rod(2.0);
  const double c = std::sqrt(0.5);
  Vec<6> x0;
  x0 << 0.5 * c, 0.5 * c, M_PI / 4, -1.0, 0.0, 0.0;
  Simulator<PainleveRod> sim(rod, SimulationOptions{});
  auto no_u = [](double, const Vec<6>&, const Mode<1>&) { return Vec<0>(); };
  const Mode<1> slipping_back{ContactState::slip_planar(-1)};
  try {
    (void)sim.run(x0, slipping_back, 0.0, 0.1, no_u);
    FAIL() << "the inconsistent initial mode was accepted";
  } catch (const InvalidArgument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("'end'"), std::string::npos) << what;
    EXPECT_NE(what.find("normal force"), std::string::npos) << what;
  }
  // A slip direction against the sliding velocity, and a stick while sliding, are refused too.
  EXPECT_THROW((void)sim.run(x0, Mode<1>{ContactState::slip_planar(1)}, 0.0, 0.1, no_u), InvalidArgument);
  EXPECT_THROW((void)sim.run(x0, Mode<1>{ContactState::stick()}, 0.0, 0.1, no_u), InvalidArgument);
  // A closed contact above the ground, and an open one below it.
  Vec<6> above = x0;
  above[1] += 1e-3;
  EXPECT_THROW((void)sim.run(above, Mode<1>{ContactState::stick()}, 0.0, 0.1, no_u), InvalidArgument);
  Vec<6> below = x0;
  below[1] -= 1e-3;
  EXPECT_THROW((void)sim.run(below, Mode<1>{ContactState::open()}, 0.0, 0.1, no_u), InvalidArgument);
  // Sliding towards +x: 1 + 3 c (c + mu s) > 0, a positive force; the run goes ahead.
  Vec<6> forward = x0;
  forward[3] = 1.0;
  const auto traj = sim.run(forward, Mode<1>{ContactState::slip_planar(1)}, 0.0, 0.05, no_u);
  EXPECT_EQ(traj.status, SimulationStatus::Completed);
}

// Issue case 5: the rod at 45 degrees, its end sliding at 1 m/s towards -x with zero normal
// velocity while the rod turns at -8 rad/s (the centre's velocity follows). With the end
// slipping, the acceleration-level problem is y = d lambda + b with d = 1 + 3 c (c - mu s) =
// -1/2 (per unit mass) and b = -g + (L/2) s theta'^2 = -9.81 + 16 sqrt(1/2) > 0: two solutions,
// lift-off (lambda = 0, y = b) and a contact force lambda = 2 b with y = 0. Both are found and
// reported; the default is the solver's (lift-off), MostClosed takes the other.
TEST(ModeSelection, PainleveIndeterminacyReportsBothSolutions) {
  const PainleveRod rod(2.0);
  const double c = std::sqrt(0.5), w = -8.0;
  Vec<6> x;
  // End velocity: (xG' + (L/2) s w, yG' - (L/2) c w) = (-1, 0).
  x << 0.5 * c, 0.5 * c, M_PI / 4, -1.0 - 0.5 * c * w, 0.5 * c * w, w;
  const Vec<0> u;
  ModeSelector<PainleveRod> selector(rod);
  const Mode<1> taken = selector.select(x, u, {true});
  const auto& report = selector.uniqueness();
  ASSERT_TRUE(report.checked);
  EXPECT_EQ(report.solutions, 2);
  EXPECT_FALSE(taken[0].closed()) << "the default is the solver's solution: lift-off";
  const double b = -g + 0.5 * c * w * w;
  EXPECT_NEAR(selector.solution().y[0], b, 1e-9 * b);
  bool closed_alternative = false;
  for (int k = 0; k < report.solutions; ++k) closed_alternative = closed_alternative || report.modes[k][0].closed();
  EXPECT_TRUE(closed_alternative);
  ModeSelectionOptions prefer_contact;
  prefer_contact.ambiguity = AmbiguityChoice::MostClosed;
  ModeSelector<PainleveRod> other(rod, prefer_contact);
  const Mode<1> with_force = other.select(x, u, {true});
  ASSERT_TRUE(with_force[0].closed());
  EXPECT_EQ(with_force[0].slip_direction[0], -1.0);
  EXPECT_NEAR(other.solution().lambda[0], 2 * b, 1e-9 * b);
  // Unique when the end slides the other way (d = 1 + 3 c (c + mu s) > 0, a P-matrix).
  Vec<6> forward = x;
  forward[3] = 1.0 - 0.5 * c * w;
  (void)selector.select(forward, u, {true});
  EXPECT_EQ(selector.uniqueness().solutions, 1);
  // The simulator reports the ambiguity of its initial mode selection.
  Simulator<PainleveRod> sim(rod, SimulationOptions{});
  const auto traj = sim.run(x, 0.0, 0.01);
  EXPECT_EQ(traj.statistics.ambiguous_selections, 1);
}

// A contact at tangential rest whose Delassus matrix couples its normal and tangential rows: the
// rod at theta = 45 degrees at rest, its end on the ground, mu = 4, pushed at its centre by
// u = (-3, g + 1). Per unit mass D = [1 + 3c^2, -3cs; -3cs, 1 + 3s^2] = [2.5, -1.5; -1.5, 2.5]
// and b = (u_y - g, u_x) = (1, -3). Three modes solve the acceleration-level problem:
// open (lambda = 0, y = b), stick (lambda = -D^{-1} b = (1/2, 3/2), inside the cone), and slip
// towards -x (lambda_t = mu lambda_n: y_n = 2.5 lambda_n - 1.5 mu lambda_n + 1 = 0, lambda_n = 2/7,
// y_t = -1.5 lambda_n + 2.5 lambda_t - 3 = -4/7 < 0). The enumeration finds all three, and the
// persistent choice keeps the mode the contact is in.
TEST(ModeSelection, ACoupledContactAtTangentialRestReportsItsThreeModes) {
  const PushedRod rod(4.0);
  const double c = std::sqrt(0.5);
  Vec<6> x;
  x << 0.5 * c, 0.5 * c, M_PI / 4, 0.0, 0.0, 0.0;
  const Vec<2> u(-3.0, g + 1.0);
  ModeSelector<PushedRod> selector(rod);
  const Mode<1> stick{ContactState::stick()}, open{ContactState::open()}, slip_back{ContactState::slip_planar(-1)};
  const Mode<1> kept = selector.select(x, u, {true}, {}, &stick);
  const auto& report = selector.uniqueness();
  ASSERT_TRUE(report.checked);
  ASSERT_EQ(report.solutions, 3);
  std::array<bool, 3> seen{};
  for (int k = 0; k < 3; ++k) {
    seen[0] = seen[0] || report.modes[k] == open;
    seen[1] = seen[1] || report.modes[k] == stick;
    seen[2] = seen[2] || report.modes[k] == slip_back;
  }
  EXPECT_TRUE(seen[0] && seen[1] && seen[2]);
  ASSERT_EQ(kept, stick) << "persistent: the contact stays in stick";
  EXPECT_NEAR(selector.solution().lambda[0], 0.5, 1e-12);
  EXPECT_NEAR(selector.solution().lambda[1], 1.5, 1e-12);
  EXPECT_NEAR(selector.solution().y[0], 0.0, 1e-12);
  EXPECT_EQ(selector.select(x, u, {true}, {}, &slip_back), slip_back);
  EXPECT_NEAR(selector.solution().lambda[0], 2.0 / 7.0, 1e-12);
  EXPECT_NEAR(selector.solution().lambda[1], 8.0 / 7.0, 1e-12);
  EXPECT_NEAR(selector.solution().y[1], -4.0 / 7.0, 1e-12);
  EXPECT_EQ(selector.select(x, u, {true}, {}, &open), open);
  EXPECT_NEAR(selector.solution().y[0], 1.0, 1e-12);
  // With mu = 1 the stick force (1/2, 3/2) leaves the cone and no slip holds: lift-off alone.
  const PushedRod smooth(1.0);
  ModeSelector<PushedRod> unique(smooth);
  EXPECT_EQ(unique.select(x, u, {true}, {}, &stick), open);
  EXPECT_TRUE(unique.uniqueness().checked);
  EXPECT_EQ(unique.uniqueness().solutions, 1);
}

// The same rod dropped onto its end (e_n = 0, at 1 m/s) under the push u = (-6, g + 1): the impact
// sticks (its impulse turns the rod at about -1 rad/s, which adds (L/2) theta'^2 (s, c) to b:
// b = (1.37, -5.63), stick force (1.25, 3.0) inside the cone), and at the acceleration level the
// end may stay in stick or lift off. The simulator keeps the impact's post-impact mode, stick, and
// reports the ambiguity; the solver's choice lifts off.
TEST(Simulation, AfterAnImpactIntoStickTheContactStaysWhereLiftOffIsPossibleToo) {
  const PushedRod rod(4.0);
  const double c = std::sqrt(0.5);
  Vec<6> x0;
  x0 << 0.5 * c, 0.5 * c + 0.01, M_PI / 4, 0.0, -1.0, 0.0;
  const InputLaw<PushedRod> push = [](double, const Vec<6>&, const Mode<1>&) { return Vec<2>(-6.0, g + 1.0); };
  SimulationOptions options;
  Simulator<PushedRod> sim(rod, options);
  const auto traj = sim.run(x0, 0.0, 0.05, push);
  ASSERT_GE(traj.events.size(), 1u);
  const auto& touchdown = traj.events.front();
  ASSERT_TRUE(touchdown.impact());
  EXPECT_EQ(touchdown.mode_after[0], ContactState::stick());
  EXPECT_GT(touchdown.transitions.back().selection_solutions, 1);
  EXPECT_GE(traj.statistics.ambiguous_selections, 1);
  EXPECT_EQ(traj.events.size(), 1u) << "the end stays in stick";
  options.selection.ambiguity = AmbiguityChoice::Solver;
  Simulator<PushedRod> solver_sim(rod, options);
  const auto solvers = solver_sim.run(x0, 0.0, 0.05, push);
  ASSERT_GE(solvers.events.size(), 1u);
  EXPECT_FALSE(solvers.events.front().mode_after[0] == ContactState::stick());
}


// ---- Painleve's inconsistent configuration and the impact without collision -------------------
// (dynamics/impact_without_collision.hpp). The rod of PainleveRod at 45 degrees, its end sliding
// at v_t = -1 m/s with zero normal velocity, mu = 2: per unit mass the end's Delassus matrix is
// W = J M^-1 J^T = [1 + 3c^2, -3cs; -3cs, 1 + 3s^2] = [2.5, -1.5; -1.5, 2.5] (c = s = 1/sqrt 2),
// the slip's normal entry W_nn - mu s W_nt = -1/2 < 0 and the free normal acceleration -g: no
// nonnegative normal force (InitialMode.PainleveSlipWithNegativeNormalForceIsRefused).

// The rod's state of the case 4 and the closed form of its impact without collision,
// computed here from the rod's inertia alone (mass 1 kg, length 1 m, I = 1/12 kg m^2).
struct PainleveCase {
  double c = std::sqrt(0.5);
  Vec<6> x0;
  Eigen::Matrix<double, 2, 3> J;  // rows w_n^T, w_t^T of the rod's end at 45 degrees
  Eigen::Matrix3d Minv = Eigen::Vector3d(1.0, 1.0, 12.0).asDiagonal();
  Eigen::Matrix2d W;
  PainleveCase() {
    x0 << 0.5 * c, 0.5 * c, M_PI / 4, -1.0, 0.0, 0.0;
    J = end_jacobian(M_PI / 4);
    W = J * Minv * J.transpose();
  }
  // End: (x - cos(theta)/2, y - sin(theta)/2): w_n = (0, 1, -cos(theta)/2), w_t = (1, 0, sin(theta)/2).
  static Eigen::Matrix<double, 2, 3> end_jacobian(double theta) {
    Eigen::Matrix<double, 2, 3> Jt;
    Jt << 0.0, 1.0, -0.5 * std::cos(theta), 1.0, 0.0, 0.5 * std::sin(theta);
    return Jt;
  }
  // The Darboux-Keller phases, written out: slip (s = sign v_t) until v_t = 0, then stick until
  // v_n = 0.
  static Eigen::Vector2d impulse(const Eigen::Matrix2d& W, double mu, double v_n, double v_t) {
    const double s = v_t > 0 ? 1.0 : -1.0;
    const double P_n1 = -v_t / (W(1, 0) - mu * s * W(1, 1));
    const double v_n1 = v_n + (W(0, 0) - mu * s * W(0, 1)) * P_n1;
    const double P_n2 = -v_n1 / (W(0, 0) - W(0, 1) * W(1, 0) / W(1, 1));
    return {P_n1 + P_n2, -mu * s * P_n1 - W(1, 0) / W(1, 1) * P_n2};
  }
  Eigen::Vector2d impulse(double mu) const { return impulse(W, mu, 0.0, -1.0); }
  double kinetic_energy(const Vec<6>& x) const {
    const Eigen::Vector3d v = x.tail<3>();
    return 0.5 * v.dot(Minv.inverse() * v);
  }
};

SimulationOptions resolving_painleve() {
  SimulationOptions o;
  o.painleve.resolution = InconsistentContactResolution::ImpactWithoutCollision;
  return o;
}

// The scene-free integration: both phases and the total against the fractions of the rod.
TEST(ImpactWithoutCollision, TheRodsPhasesAreTheClosedForm) {
  const PainleveCase rod;
  const ImpactWithoutCollision r = impact_without_collision(rod.W, 2.0, 0.0, -1.0);
  EXPECT_EQ(r.slip_sign, -1.0);
  EXPECT_NEAR(r.normal_slip, 2.0 / 7, 1e-14);
  EXPECT_NEAR(r.tangent_slip, 4.0 / 7, 1e-14);
  EXPECT_NEAR(r.normal_velocity_after_slip, -1.0 / 7, 1e-14);
  EXPECT_NEAR(r.normal_stick, 5.0 / 56, 1e-14);
  EXPECT_NEAR(r.tangent_stick, 3.0 / 56, 1e-14);
  EXPECT_NEAR(r.normal, 3.0 / 8, 1e-14);
  EXPECT_NEAR(r.tangent, 5.0 / 8, 1e-14);
  // The total is the contact's stick impulse -W^-1 (v_n, v_t), inside the cone.
  const Eigen::Vector2d stick = -rod.W.inverse() * Eigen::Vector2d(0.0, -1.0);
  EXPECT_NEAR(r.normal, stick[0], 1e-14);
  EXPECT_NEAR(r.tangent, stick[1], 1e-14);
  EXPECT_LE(std::abs(r.tangent), 2.0 * r.normal);
  // A consistent slip (towards +x, s = +1: W_nn - mu s W_nt = 5.5 > 0) calls for no impulse.
  EXPECT_THROW((void)impact_without_collision(rod.W, 2.0, 0.0, 1.0), InvalidArgument);
  EXPECT_THROW((void)impact_without_collision(rod.W, 2.0, 0.0, 0.0), InvalidArgument);
}

// The phases the derivation guarantees for a symmetric positive semidefinite W fail only for
// another W: a slip that the impulse does not stop, and a stick outside the cone after it (a
// reverse slip would follow). Both refused, naming the case.
TEST(ImpactWithoutCollision, PhasesThatCannotHappenAreRefusedNamingTheCase) {
  Eigen::Matrix2d indefinite;
  indefinite << 1.0, 2.0, 2.0, 1.0;  // d = 1 - 2 = -1, dv_t/dP_n = 2 - 1 > 0: the slip grows
  try {
    (void)impact_without_collision(indefinite, 1.0, 0.0, 1.0);
    FAIL() << "a slip that does not stop was accepted";
  } catch (const ContactProblemFailure& e) {
    EXPECT_NE(std::string(e.what()).find("does not stop the slip"), std::string::npos) << e.what();
  }
  Eigen::Matrix2d skew;
  skew << 1.0, 1.0, -5.0, 1.0;  // d = -1, dv_t/dP_n = -7: stops; |W_tn / W_tt| = 5 > mu = 2
  try {
    (void)impact_without_collision(skew, 2.0, 0.0, 1.0);
    FAIL() << "a stick outside the friction cone was accepted";
  } catch (const ContactProblemFailure& e) {
    EXPECT_NE(std::string(e.what()).find("reverse slip"), std::string::npos) << e.what();
  }
}

// The default is unchanged: the run from the inconsistent state throws the selection's failure,
// the given inconsistent slip the initial-mode check's refusal.
TEST(ImpactWithoutCollision, TheDefaultStillRefusesThePainleveState) {
  const PainleveRod rod(2.0);
  const PainleveCase pc;
  Simulator<PainleveRod> sim(rod, SimulationOptions{});
  EXPECT_EQ(sim.options().painleve.resolution, InconsistentContactResolution::Refuse);
  try {
    (void)sim.run(pc.x0, 0.0, 0.1);
    FAIL() << "the inconsistent state was accepted";
  } catch (const ContactProblemFailure& e) {
    EXPECT_NE(std::string(e.what()).find("no consistent contact mode at the acceleration level (Painleve's paradox"),
              std::string::npos)
        << e.what();
  }
  auto no_u = [](double, const Vec<6>&, const Mode<1>&) { return Vec<0>(); };
  try {
    (void)sim.run(pc.x0, Mode<1>{ContactState::slip_planar(-1)}, 0.0, 0.1, no_u);
    FAIL() << "the inconsistent initial mode was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("a Painleve configuration"), std::string::npos) << e.what();
  }
}

// With the option, the run from the inconsistent state starts with the impact without collision:
// its impulse and the velocity after it are the closed form (to 1e-12), the end leaves it at rest
// (v_n+ = v_t+ = 0), the kinetic energy falls from 0.5 J to 0.1875 J, and the rod then pivots on
// its sticking end. The same from the inconsistent slip given as the initial mode.
TEST(ImpactWithoutCollision, ThePainleveRodContinuesAfterTheClosedFormImpulse) {
  const PainleveRod rod(2.0);
  const PainleveCase pc;
  const Eigen::Vector2d P = pc.impulse(2.0);
  EXPECT_NEAR(P[0], 3.0 / 8, 1e-14);
  EXPECT_NEAR(P[1], 5.0 / 8, 1e-14);
  Vec<6> x_plus = pc.x0;
  x_plus.tail<3>() += pc.Minv * pc.J.transpose() * P;
  Simulator<PainleveRod> sim(rod, resolving_painleve());
  auto no_u = [](double, const Vec<6>&, const Mode<1>&) { return Vec<0>(); };
  for (const bool given_mode : {false, true}) {
    SCOPED_TRACE(given_mode ? "from the given slip" : "from the state");
    const auto traj = given_mode ? sim.run(pc.x0, Mode<1>{ContactState::slip_planar(-1)}, 0.0, 0.2, no_u)
                                 : sim.run(pc.x0, 0.0, 0.2);
    ASSERT_GE(traj.events.size(), 1u);
    const auto& ev = traj.events.front();
    ASSERT_EQ(ev.transitions.size(), 1u);
    const auto& tr = ev.transitions.front();
    EXPECT_EQ(ev.t, 0.0);
    EXPECT_TRUE(tr.impact_without_collision);
    EXPECT_TRUE(tr.impact);
    EXPECT_TRUE(tr.guards.empty());
    EXPECT_EQ(tr.impulse_mode[0].role, ImpulseRole::Stick);
    EXPECT_EQ(ev.mode_before, Mode<1>{ContactState::slip_planar(-1)});
    EXPECT_EQ(ev.mode_after, Mode<1>{ContactState::stick()});
    EXPECT_NEAR(tr.impulse[0].normal, P[0], 1e-12);
    EXPECT_NEAR(tr.impulse[0].tangent[0], P[1], 1e-12);
    EXPECT_LT((ev.x_plus - x_plus).cwiseAbs().maxCoeff(), 1e-12) << ev.x_plus.transpose() << "\n" << x_plus.transpose();
    const Eigen::Vector2d v_end = pc.J * Eigen::Vector3d(ev.x_plus.tail<3>());
    EXPECT_NEAR(v_end[0], 0.0, 1e-12);
    EXPECT_NEAR(v_end[1], 0.0, 1e-12);
    EXPECT_NEAR(pc.kinetic_energy(pc.x0), 0.5, 1e-15);
    EXPECT_NEAR(pc.kinetic_energy(ev.x_plus), 0.1875, 1e-12);
    EXPECT_EQ(traj.statistics.impacts_without_collision, 1);
    // The run goes on: the end sticks while the rod turns up at 3 sqrt(2)/4 rad/s.
    EXPECT_EQ(traj.status, SimulationStatus::Completed);
    ASSERT_GE(traj.segments.size(), 2u);
    EXPECT_EQ(traj.segments[1].mode, Mode<1>{ContactState::stick()});
    EXPECT_NEAR(ev.x_plus[5], 3 * std::sqrt(2.0) / 4, 1e-12);
    EXPECT_GT(traj.t_end(), 0.2 - 1e-12);
    // The jump map of the recorded impulse mode (stick) gives the same velocity jump.
    TransitionResolver<PainleveRod> resolver(rod, resolving_painleve());
    EXPECT_LT((resolver.replay(tr, ev.x_minus) - ev.x_plus).cwiseAbs().maxCoeff(), 1e-12);
    // The flag and the count survive the complete JSON.
    std::stringstream text;
    write_json(text, traj, rod, TrajectoryJsonOptions{true});
    const auto back = read_json(text, rod);
    EXPECT_TRUE(back.events.front().transitions.front().impact_without_collision);
    EXPECT_EQ(back.statistics.impacts_without_collision, 1);
    std::printf("start: P = (%.17g, %.17g) N s, closed form (3/8, 5/8); |x+ - closed form| = %.3g; kinetic energy "
                "%.17g -> %.17g J; then %s\n",
                tr.impulse[0].normal, tr.impulse[0].tangent[0], (ev.x_plus - x_plus).cwiseAbs().maxCoeff(),
                pc.kinetic_energy(ev.x_minus), pc.kinetic_energy(ev.x_plus), describe(rod, traj.segments[1].mode).c_str());
  }
}

// Several closed contacts: a flat unit block sliding at 1 m/s on both corners, mu = 2. Per unit
// mass and with I = 1/6, the slip's acceleration-level matrix is [5.5, 2.5; -3.5, -0.5] against
// b = (-g, -g): no combination of the corners' states solves it. The impact without collision is
// for one contact: refused, naming the contacts and the reason.
TEST(ImpactWithoutCollision, SeveralClosedContactsAreRefusedNamingThem) {
  const RockingBlock block(1.0, 1.0, 2.0);
  Vec<6> x0;
  x0 << 0.0, 0.5, 0.0, 1.0, 0.0, 0.0;
  {
    Simulator<RockingBlock> sim(block, SimulationOptions{});
    EXPECT_THROW((void)sim.run(x0, 0.0, 0.1, no_input()), ContactProblemFailure);
  }
  Simulator<RockingBlock> sim(block, resolving_painleve());
  try {
    (void)sim.run(x0, 0.0, 0.1, no_input());
    FAIL() << "an inconsistent configuration of two contacts was accepted";
  } catch (const ContactProblemFailure& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("2 closed contacts ('left', 'right')"), std::string::npos) << what;
    EXPECT_NE(what.find("implemented for one closed contact"), std::string::npos) << what;
  }
}

// The rod's end as a spatial-friction contact (its second tangent does not move in the plane): the
// same inconsistent slip, refused with the option, naming the contact and its spatial friction.
class SpatialEndRod : public PainleveRod {
 public:
  explicit SpatialEndRod(double mu) : PainleveRod(mu), end_{"end", Friction::Spatial, mu, 0.0} {}
  const ContactSpec& contact(int) const { return end_; }

 private:
  ContactSpec end_;
};

TEST(ImpactWithoutCollision, ASpatialContactIsRefusedNamingIt) {
  const SpatialEndRod rod(2.0);
  const PainleveCase pc;
  Simulator<SpatialEndRod> sim(rod, resolving_painleve());
  try {
    (void)sim.run(pc.x0, 0.0, 0.1);
    FAIL() << "an inconsistent spatial contact was accepted";
  } catch (const ContactProblemFailure& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("contact 'end'"), std::string::npos) << what;
    EXPECT_NE(what.find("spatial friction"), std::string::npos) << what;
  }
}

// Reached during a run: the rod pushed at its centre by u = (0, g + 2 - 100 t) N, from the state
// above given in slip-. With d = -1/2 the slip is Painleve's indeterminacy while the free normal
// acceleration b > 0 (lift-off, or the normal force -b/d the persistent choice keeps); b falls with
// the push, and the release guard fires where the force reaches zero (t = 0.0201 s). Past it no
// mode is consistent. By default the contact opens and touches down 0.25 ms later, an ordinary
// impact of the flight's small approach velocity; with the option the release is the impact
// without collision: the closed form at the release state (computed here from the rod's inertia
// at its angle then), the end at rest after it, less kinetic energy, and the run goes on (the rod,
// turning up at 1.08 rad/s and pushed up by nearly its weight, lifts off and lands again).
TEST(ImpactWithoutCollision, TheReleaseOfAPainleveSlipIsAnImpactWithoutCollision) {
  const PushedRod rod(2.0);
  const PainleveCase pc;
  const InputLaw<PushedRod> push = [](double t, const Vec<6>&, const Mode<1>&) {
    return Vec<2>(0.0, g + 2.0 - 100.0 * t);
  };
  const Mode<1> slip_back{ContactState::slip_planar(-1)};
  {
    Simulator<PushedRod> sim(rod, SimulationOptions{});
    const auto traj = sim.run(pc.x0, slip_back, 0.0, 0.1, push);
    ASSERT_GE(traj.events.size(), 2u);
    EXPECT_EQ(traj.events[0].guards().front().kind, GuardKind::Release);
    EXPECT_EQ(traj.events[0].mode_after, Mode<1>{ContactState::open()});
    EXPECT_EQ(traj.events[1].guards().front().kind, GuardKind::Touchdown);
    EXPECT_EQ(traj.statistics.impacts_without_collision, 0);
  }
  Simulator<PushedRod> sim(rod, resolving_painleve());
  const auto traj = sim.run(pc.x0, slip_back, 0.0, 0.1, push);
  ASSERT_GE(traj.events.size(), 1u);
  const auto& ev = traj.events.front();
  ASSERT_EQ(ev.transitions.size(), 1u);
  const auto& tr = ev.transitions.front();
  EXPECT_NEAR(ev.t, 0.0201029, 1e-6);
  ASSERT_EQ(tr.guards.size(), 1u);
  EXPECT_EQ(tr.guards.front().kind, GuardKind::Release);
  EXPECT_TRUE(tr.impact_without_collision);
  EXPECT_EQ(ev.mode_before, slip_back);
  const auto J = PainleveCase::end_jacobian(ev.x_minus[2]);
  const Eigen::Matrix2d W = J * pc.Minv * J.transpose();
  const Eigen::Vector2d v_minus = J * Eigen::Vector3d(ev.x_minus.tail<3>());
  EXPECT_NEAR(v_minus[0], 0.0, 1e-9);
  EXPECT_LT(W(0, 0) - 2.0 * (v_minus[1] > 0 ? 1.0 : -1.0) * W(0, 1), 0.0) << "not a Painleve slip";
  const Eigen::Vector2d P = PainleveCase::impulse(W, 2.0, v_minus[0], v_minus[1]);
  EXPECT_NEAR(tr.impulse[0].normal, P[0], 1e-12);
  EXPECT_NEAR(tr.impulse[0].tangent[0], P[1], 1e-12);
  Vec<6> x_plus = ev.x_minus;
  x_plus.tail<3>() += pc.Minv * J.transpose() * P;
  EXPECT_LT((ev.x_plus - x_plus).cwiseAbs().maxCoeff(), 1e-12) << ev.x_plus.transpose() << "\n" << x_plus.transpose();
  const Eigen::Vector2d v_plus = J * Eigen::Vector3d(ev.x_plus.tail<3>());
  EXPECT_NEAR(v_plus[0], 0.0, 1e-12);
  EXPECT_NEAR(v_plus[1], 0.0, 1e-12);
  EXPECT_LT(pc.kinetic_energy(ev.x_plus), pc.kinetic_energy(ev.x_minus));
  EXPECT_EQ(traj.statistics.impacts_without_collision, 1);
  EXPECT_EQ(traj.status, SimulationStatus::Completed);
  EXPECT_GT(traj.t_end(), 0.1 - 1e-12);
  EXPECT_GE(traj.events.size(), 2u);  // it lands again
  // The event report names it.
  std::FILE* report = std::tmpfile();
  ASSERT_NE(report, nullptr);
  print_events(rod, traj, report);
  std::rewind(report);
  std::string printed;
  for (int ch = std::fgetc(report); ch != EOF; ch = std::fgetc(report)) printed += static_cast<char>(ch);
  std::fclose(report);
  EXPECT_NE(printed.find("end release, end impact without collision"), std::string::npos) << printed;
  std::printf("release at t = %.12f: P = (%.15f, %.15f) N s, closed form (%.15f, %.15f); |x+ - closed form| = %.3g; "
              "kinetic energy %.6f -> %.6f J\n",
              ev.t, tr.impulse[0].normal, tr.impulse[0].tangent[0], P[0], P[1], (ev.x_plus - x_plus).cwiseAbs().maxCoeff(),
              pc.kinetic_energy(ev.x_minus), pc.kinetic_energy(ev.x_plus));
}

}  // namespace
}  // namespace saltus::testing
