// Accumulations of impacts whose interval ratio is not constant, against closed forms: the
// predicted accumulation time (HybridTrajectory::zeno_time) and its stated uncertainty.
//
// The scene: balls on springs. Ball i (unit mass, height x_i >= 0 above the ground) is pulled down
// by gravity and by a spring of stiffness k = omega^2 anchored at the ground: x'' = -g - omega^2 x
// in flight. Launched from the ground with speed v, it flies on x(s) = (g / omega^2)(cos(omega s)
// - 1) + (v / omega) sin(omega s), which returns to the ground after
//     T(v) = (2 / omega) atan(v omega / g)                                   (tan(omega s / 2) = v omega / g)
// with speed v (energy is conserved in flight), and bounces with e v. So its flights last
// T(e^k v) (k = 0, 1, ...): the interval ratio T(e^{k+1} v) / T(e^k v) tends to e as v -> 0 but is
// not constant (1 - (e^2 - 1)(v omega / g)^2 / 3 + ... relative to e), and the accumulation
// time of a ball launched at t_0 with speed v is the convergent series
//     t_inf = t_0 + sum_k T(e^k v),
// summed here to round-off. The balls are decoupled, so two of them bounce each on its own contact;
// started so that both accumulate at the same instant, their touchdowns alternate between the two
// contacts, with no constant ratio between consecutive intervals nor between intervals two apart.
// Bodies rocking between two supports (Housner's rocking block, a spoked wheel settling on two
// spokes): their scene and closed form, with its derivation, in accumulation_scenes.hpp.
// AccumulationTable runs every closed form at three tolerance settings and prints the table of
// docs/simulation.md: the error of the accumulation time against its stated uncertainty.
#include "accumulation_scenes.hpp"
#include "scenes/bouncing_ball.hpp"
#include "support.hpp"

#include <saltus/hybrid/instantiate.hxx>
#include <saltus/hybrid/vocabulary/trajectory_io.hpp>

#include <cmath>
#include <cstdio>
#include <string>

namespace saltus::testing {

struct SpringBalls {
  static constexpr int nq = 2, nu = 0, nc = 2;
  static constexpr double g = 9.81, omega = 10.0, e = 0.8;
  std::array<ContactSpec, 2> grounds{ContactSpec{"ball 1", Friction::None, 0.0, e},
                                     ContactSpec{"ball 2", Friction::None, 0.0, e}};
  const ContactSpec& contact(int i) const { return grounds[i]; }
  template <class T>
  MatT<T, 2, 2> mass_matrix(const VecT<T, 2>&) const {
    return MatT<T, 2, 2>::Identity();
  }
  template <class T>
  VecT<T, 2> bias(const VecT<T, 2>& q, const VecT<T, 2>&) const {
    return VecT<T, 2>(T(g) + omega * omega * q[0], T(g) + omega * omega * q[1]);
  }
  template <class T>
  MatT<T, 2, 0> input_matrix(const VecT<T, 2>&) const {
    return {};
  }
  template <class T>
  T gap(int i, const VecT<T, 2>& q) const {
    return q[i];
  }
  template <class T>
  VecT<T, 2> tangent_position(int, const VecT<T, 2>&) const {
    return VecT<T, 2>::Zero();
  }

  static double flight(double v) { return 2.0 / omega * std::atan(v * omega / g); }
  /// sum_{k >= first} T(e^k v): the time from the launch with speed e^first v to the accumulation.
  static double remaining(double v, int first = 0) {
    double sum = 0.0, speed = v * std::pow(e, first);
    for (int k = 0; k < 400 && speed > 1e-300; ++k, speed *= e) sum += flight(speed);
    return sum;
  }
  /// Height and velocity s seconds after a launch from the ground with speed v.
  static Vec<2> in_flight(double v, double s) {
    const double c = g / (omega * omega);
    return Vec<2>(c * (std::cos(omega * s) - 1) + v / omega * std::sin(omega * s),
                  -c * omega * std::sin(omega * s) + v * std::cos(omega * s));
  }
};

/// A uniform block (w x h, 1 kg) in the vertical plane, q = (x, y, theta), its bottom corners as
/// planar Coulomb contacts with friction mu and restitution e; no inputs.
struct Block {
  static constexpr int nq = 3, nu = 0, nc = 2;
  double w, h;
  std::array<ContactSpec, 2> corners;
  Block(double width, double height, double mu, double e)
      : w(width), h(height), corners{ContactSpec{"left", Friction::Planar, mu, e}, ContactSpec{"right", Friction::Planar, mu, e}} {}
  const ContactSpec& contact(int i) const { return corners[i]; }
  template <class T>
  MatT<T, 3, 3> mass_matrix(const VecT<T, 3>&) const {
    MatT<T, 3, 3> M = MatT<T, 3, 3>::Identity();
    M(2, 2) = T((w * w + h * h) / 12);
    return M;
  }
  template <class T>
  VecT<T, 3> bias(const VecT<T, 3>&, const VecT<T, 3>&) const {
    return VecT<T, 3>(T(0), T(9.81), T(0));
  }
  template <class T>
  MatT<T, 3, 0> input_matrix(const VecT<T, 3>&) const {
    return {};
  }
  template <class T>
  VecT<T, 2> corner(int i, const VecT<T, 3>& q) const {
    using std::cos;
    using std::sin;
    const double bx = i == 0 ? -w / 2 : w / 2, by = -h / 2;
    return VecT<T, 2>(q[0] + cos(q[2]) * bx - sin(q[2]) * by, q[1] + sin(q[2]) * bx + cos(q[2]) * by);
  }
  template <class T>
  T gap(int i, const VecT<T, 3>& q) const {
    return corner(i, q)[1];
  }
  template <class T>
  VecT<T, 2> tangent_position(int i, const VecT<T, 3>& q) const {
    return VecT<T, 2>(corner(i, q)[0], T(0));
  }
  /// At rest on the left corner, tilted by `tilt` (rad) so that the right corner is lifted.
  Vec<6> resting_on_left_corner(double tilt) const {
    Vec<6> x = Vec<6>::Zero();
    x << std::cos(tilt) * w / 2 - std::sin(tilt) * h / 2, std::sin(tilt) * w / 2 + std::cos(tilt) * h / 2, tilt, 0, 0, 0;
    return x;
  }
};

/// A box (0.3 m x 0.1 m, 1 kg) in the vertical plane: the Block with mu = 0.5 and restitution 0.3.
struct BouncingBox : Block {
  BouncingBox() : Block(0.3, 0.1, 0.5, 0.3) {}
};

}  // namespace saltus::testing

SALTUS_INSTANTIATE_SCENE(saltus::testing::SpringBalls)
SALTUS_INSTANTIATE_SCENE(saltus::testing::BouncingBox)
SALTUS_INSTANTIATE_SCENE(saltus::testing::Block)
SALTUS_INSTANTIATE_SCENE(saltus::testing::SpokedWheel)

namespace saltus::testing {
namespace {

SimulationOptions tight() {
  SimulationOptions o;
  o.integrator.relative_tolerance = 1e-12;
  o.integrator.absolute_tolerance = 1e-14;
  return o;
}

/// The accumulation time predicted by `traj` is t_inf to within its stated (finite) uncertainty.
template <Scene S>
void expect_within_its_uncertainty(const HybridTrajectory<S>& traj, double t_inf) {
  EXPECT_TRUE(std::isfinite(traj.zeno_time_uncertainty));
  EXPECT_LE(std::abs(traj.zeno_time - t_inf), traj.zeno_time_uncertainty)
      << "zeno_time " << traj.zeno_time << " closed form " << t_inf << " uncertainty " << traj.zeno_time_uncertainty;
}

// One ball bouncing (ball 2 resting on its spring's anchor at the ground, never touching down again):
// launched at t = 0 from the ground with v = 2 m/s (v omega / g = 2: far from the geometric regime).
TEST(Accumulation, OneBallOnASpringAccumulatesAtTheSumOfItsFlights) {
  const SpringBalls scene;
  const double v = 2.0, t_inf = SpringBalls::remaining(v);
  Simulator<SpringBalls> sim(scene, tight());
  const auto traj = sim.run(Vec<4>(0.0, 0.0, v, 0.0), 0.0, 10.0);
  ASSERT_EQ(traj.status, SimulationStatus::Zeno);
  ASSERT_GE(traj.events.size(), 6u);
  for (std::size_t k = 0; k < 6; ++k)  // the touchdowns of the closed form
    EXPECT_NEAR(traj.events[k].t, SpringBalls::remaining(v) - SpringBalls::remaining(v, static_cast<int>(k) + 1), 1e-9)
        << "touchdown " << k;
  expect_within_its_uncertainty(traj, t_inf);
  // Detected after 12 ratios within 5 %: the geometric sum of the remaining intervals was off by
  // 7.6e-3 s there; the extrapolation is right to 2.5e-7 s.
  EXPECT_LT(traj.zeno_time_uncertainty, 2e-6);
  EXPECT_LT(std::abs(traj.zeno_time - t_inf), 1e-6);
}

// With a CVODE backend no bound from the tolerances is stated (accumulation_time.hpp: its
// touchdown times were measured up to 3200 rho T off): the integration part and the uncertainty
// are infinite, the extrapolation's part is still given.
TEST(Accumulation, CvodeStatesNoBoundOnTheAccumulationTime) {
  const SpringBalls scene;
  SimulationOptions options = tight();
  options.integrator.kind = IntegratorKind::CvodeBdf;
  Simulator<SpringBalls> sim(scene, options);
  const auto traj = sim.run(Vec<4>(0.0, 0.0, 2.0, 0.0), 0.0, 10.0);
  ASSERT_EQ(traj.status, SimulationStatus::Zeno);
  EXPECT_TRUE(std::isinf(traj.zeno_time_integration_uncertainty));
  EXPECT_TRUE(std::isinf(traj.zeno_time_uncertainty));
  EXPECT_TRUE(std::isfinite(traj.zeno_time_extrapolation_uncertainty));
  EXPECT_NEAR(traj.zeno_time, SpringBalls::remaining(2.0), 1e-5);
}

// Two balls whose touchdowns alternate and accumulate at one instant: ball 1 launched at t = 0 with
// v1 = 1.5 m/s; ball 2 lands first, at tau = T(v1) / 2 with speed w, chosen so that
// tau + sum_{k >= 1} T(e^k w) = t_inf of ball 1; it started its flight at tau - T(w) < 0. The
// accumulation is detected with period 2 (the ratio of intervals two apart); the geometric sum was
// off by 3.8e-2 s there, the extrapolation by 2.4e-4 s.
TEST(Accumulation, TwoBallsAlternatingAccumulateAtTheirCommonLimit) {
  const SpringBalls scene;
  const double v1 = 1.5, t_inf = SpringBalls::remaining(v1);
  const double first = SpringBalls::flight(v1);  // ball 1's first touchdown
  // w with tau(w) = t_inf - remaining(w, 1) = first + 0.5 T(e v1) (bisection: tau decreases in w).
  const double target = 0.5 * first;
  double lo = 1e-3, hi = 10.0;
  for (int k = 0; k < 200; ++k) {
    const double w = 0.5 * (lo + hi);
    (t_inf - SpringBalls::remaining(w, 1) > target ? lo : hi) = w;
  }
  const double w = 0.5 * (lo + hi), tau = t_inf - SpringBalls::remaining(w, 1);
  ASSERT_GT(SpringBalls::flight(w), tau) << "ball 2 must be in flight at t = 0";
  const Vec<2> ball2 = SpringBalls::in_flight(w, SpringBalls::flight(w) - tau);
  Simulator<SpringBalls> sim(scene, tight());
  const auto traj = sim.run(Vec<4>(0.0, ball2[0], v1, ball2[1]), 0.0, 10.0);
  ASSERT_EQ(traj.status, SimulationStatus::Zeno);
  int alternations = 0;
  for (std::size_t k = 1; k < traj.events.size(); ++k)
    alternations += traj.events[k].guards().at(0).contact != traj.events[k - 1].guards().at(0).contact;
  EXPECT_EQ(alternations + 1, static_cast<int>(traj.events.size())) << "the touchdowns alternate";
  expect_within_its_uncertainty(traj, t_inf);
  EXPECT_LT(traj.zeno_time_uncertainty, 2e-3);
  EXPECT_LT(std::abs(traj.zeno_time - t_inf), 1e-3);
}

// A box dropped tilted by 0.02 rad (lowest corner 5 cm above the ground) bounces on its corners with
// e_n = 0.3: the intervals between touchdowns shrink by about 0.3 per bounce, so 12 ratios would need
// intervals down to 5e-7 of the first, below the time resolution of the event location. The run
// ends with status Zeno before that (4 ratios suffice once the intervals are below 1e3 simultaneity
// windows), whatever zeno_bounces, instead of "events stall" at one instant; never below the ground.
TEST(Accumulation, BoxBouncingOnItsCornersWithLowRestitutionEndsInAnAccumulation) {
  const BouncingBox box;
  Vec<6> x0 = Vec<6>::Zero();
  x0[1] = 0.05 + 0.5 * box.h + 0.5 * box.w * std::sin(0.02);
  x0[2] = 0.02;
  std::vector<double> predicted;
  for (int bounces : {12, 40}) {
    SimulationOptions o;
    o.zeno_bounces = bounces;
    Simulator<BouncingBox> sim(box, o);
    const auto traj = sim.run(x0, 0.0, 2.0);
    ASSERT_EQ(traj.status, SimulationStatus::Zeno) << "zeno_bounces " << bounces;
    ASSERT_GE(traj.events.size(), 6u);
    const double last = traj.events.back().t;
    EXPECT_GT(traj.zeno_time, last);
    EXPECT_LT(traj.zeno_time - last, 1e-5);
    EXPECT_LT(traj.zeno_time_uncertainty, 1e-9);
    for (const auto& seg : traj.segments)
      for (const auto& piece : seg.x.pieces())
        for (int i = 0; i < 2; ++i) EXPECT_GE(box.gap(i, Vec<3>(piece.value(piece.t1).head<3>())), -1e-9);
    predicted.push_back(traj.zeno_time);
  }
  EXPECT_EQ(predicted[0], predicted[1]);
}

/// The times of the touchdown events of `traj` and, for each, the contacts that touched down.
template <Scene S>
std::vector<std::pair<double, std::vector<int>>> touchdowns(const HybridTrajectory<S>& traj) {
  std::vector<std::pair<double, std::vector<int>>> out;
  for (const auto& ev : traj.events) {
    std::vector<int> contacts;
    for (const Guard& g : ev.guards())
      if (g.kind == GuardKind::Touchdown) contacts.push_back(g.contact);
    if (!contacts.empty()) out.emplace_back(ev.t, contacts);
  }
  return out;
}

/// The closed form of the Block rocking on its bottom corners (accumulation_scenes.hpp): R the
/// half-diagonal, alpha = atan(w / h), I_c = m (w^2 + h^2) / 12.
PivotRocking block_rocking(const Block& block) {
  return PivotRocking::of(1.0, (block.w * block.w + block.h * block.h) / 12, 0.5 * std::hypot(block.w, block.h),
                          std::atan(block.w / block.h));
}

/// The closed form of the SpokedWheel rocking on two neighbouring spokes: R = L, alpha = pi / N.
PivotRocking wheel_rocking(const SpokedWheel& wheel) {
  return PivotRocking::of(wheel.m, wheel.I_c, wheel.L, SpokedWheel::alpha());
}

// The rocking block against Housner's closed form (PivotRocking, accumulation_scenes.hpp, which
// derives it): the tall block (0.2 m x 0.6 m, mu = 2, e_n = 0) released at rest on its left corner
// tilted by A = 0.05 rad lands on its right corner after the fall T(A) = 0.1247 s, then rocks with
// impact speeds shrinking by Housner's r = 1 - (3/2) sin^2(alpha) = 0.85 (alpha = atan(1/3)); the
// accumulation time t_1 + sum_k 2 T(A(r^k w_1)) = 1.4314569879362525 s (the nonlinear rocking
// equation; the linearised one is off by 8e-4 s in the first fall alone). The touchdowns are
// resolved to 2.2e-12 s with tight tolerances. Measured: zeno_bounces 12: error 9.1e-7 s, stated
// uncertainty 2.3e-6 s; zeno_bounces 40: error 8e-13 s, uncertainty 7.5e-11 s.
TEST(Accumulation, RockingBlockAccumulatesAtHousnersClosedForm) {
  const Block block(0.2, 0.6, 2.0, 0.0);
  const double A = 0.05;
  const PivotRocking ref = block_rocking(block);
  EXPECT_NEAR(ref.r, 1 - 1.5 * std::pow(std::sin(ref.alpha), 2), 1e-15);
  const auto impacts = ref.rocking(ref.fall(A), ref.impact_speed(A));
  {  // the quadrature has converged: 48 nodes agree with 64, and with mpmath's quad at 40 digits
    PivotRocking coarse = ref;
    coarse.set_nodes(48);
    EXPECT_NEAR(coarse.rocking(coarse.fall(A), coarse.impact_speed(A)).t_inf, impacts.t_inf, 1e-15);
    EXPECT_NEAR(impacts.t[1], 0.329895237759881, 1e-15);
    EXPECT_NEAR(impacts.t_inf, 1.4314569879362525, 2e-15);
  }
  for (int bounces : {12, 40}) {
    SimulationOptions o = tight();
    o.zeno_bounces = bounces;
    Simulator<Block> sim(block, o);
    const auto traj = sim.run(block.resting_on_left_corner(A), 0.0, 2.0);
    ASSERT_EQ(traj.status, SimulationStatus::Zeno) << "zeno_bounces " << bounces;
    const auto td = touchdowns(traj);
    ASSERT_GE(td.size(), 14u);
    for (std::size_t k = 0; k < 14; ++k) {  // right, left, right, ...: the closed form's impacts
      EXPECT_EQ(td[k].second, std::vector<int>{k % 2 == 0 ? 1 : 0}) << "touchdown " << k;
      EXPECT_NEAR(td[k].first, impacts.t[k], 1e-11) << "touchdown " << k;
    }
    expect_within_its_uncertainty(traj, impacts.t_inf);
    EXPECT_LT(traj.zeno_time_uncertainty, bounces == 12 ? 5e-6 : 1e-10);
  }
}

// The spoked wheel (SpokedWheel: 6 spokes of 0.5 m, hub 1 kg, I_c = 0.05 kg m^2, mu = 2, e_n = 0)
// standing on spoke 0 with its hub 0.1 rad behind the tip and turning forward at 1 rad/s vaults
// over the tip and lands on spoke 1 after T_v = 0.4966 s (PivotRocking::vault) at w_1 = 2.284 rad/s;
// its speed after the impact, r w_1 = 1.332 rad/s with r = (I_c + m L^2 cos(pi / 3)) / (I_c + m L^2)
// = 7/12 (angular momentum about the new tip, accumulation_scenes.hpp), is below the vault speed
// 2.093 rad/s, so it rocks between spokes 1 and 0, each impact sending it back with 7/12 of its
// angular velocity, and settles on both: t_inf = 1.3454336785526817 s. Measured (tight tolerances):
// touchdowns to 3.8e-13 s, the accumulation time to 3e-14 s against a stated uncertainty of 7.3e-12 s
// (detected after 14 touchdowns for zeno_bounces 12 and 40 alike: near the gap tolerance 4 ratios
// suffice).
TEST(Accumulation, SpokedWheelSettlingOnTwoSpokesAccumulatesAtTheClosedForm) {
  const SpokedWheel wheel(2.0, 0.0);
  const double psi0 = -0.1, w0 = 1.0;
  const PivotRocking ref = wheel_rocking(wheel);
  EXPECT_NEAR(ref.r, 7.0 / 12.0, 1e-15);
  const double w1 = ref.vault_impact_speed(psi0, w0);
  ASSERT_LT(ref.r * w1, ref.vault_speed()) << "the wheel must rock after its first impact, not vault again";
  const auto impacts = ref.rocking(ref.vault(psi0, w0), w1);
  {  // the quadrature has converged: 48 nodes agree with 64, and with mpmath's quad at 40 digits
    PivotRocking coarse = ref;
    coarse.set_nodes(48);
    EXPECT_NEAR(coarse.rocking(coarse.vault(psi0, w0), w1).t_inf, impacts.t_inf, 1e-15);
    EXPECT_NEAR(impacts.t[0], 0.49661553652145112, 1e-15);
    EXPECT_NEAR(impacts.t_inf, 1.3454336785526818, 2e-15);
  }
  for (int bounces : {12, 40}) {
    SimulationOptions o = tight();
    o.zeno_bounces = bounces;
    Simulator<SpokedWheel> sim(wheel, o);
    const auto traj = sim.run(wheel.standing_on_spoke_0(psi0, w0), 0.0, 3.0);
    ASSERT_EQ(traj.status, SimulationStatus::Zeno) << "zeno_bounces " << bounces;
    const auto td = touchdowns(traj);
    ASSERT_GE(td.size(), 14u);
    ASSERT_EQ(td.size(), traj.events.size()) << "every event is an impact";
    for (std::size_t k = 0; k < 14; ++k) {  // spoke 1, spoke 0, spoke 1, ...: the closed form's impacts
      EXPECT_EQ(td[k].second, std::vector<int>{k % 2 == 0 ? 1 : 0}) << "touchdown " << k;
      EXPECT_NEAR(td[k].first, impacts.t[k], 1e-11) << "touchdown " << k;
    }
    for (const auto& ev : traj.events) {  // every impact: the angular velocity times r, the new tip sticking
      EXPECT_NEAR(ev.x_plus[5] / ev.x_minus[5], ref.r, 1e-9) << "t = " << ev.t;
      for (int i = 0; i < SpokedWheel::N; ++i)
        EXPECT_EQ(ev.mode_after[i].mode, i == ev.guards().at(0).contact ? ContactMode::Stick : ContactMode::Open)
            << "t = " << ev.t << ", spoke " << i;
    }
    expect_within_its_uncertainty(traj, impacts.t_inf);
    EXPECT_LT(traj.zeno_time_uncertainty, 1e-10);
  }
}

// Zeno completion of the spoked wheel above (the wheel in double support): carried past
// its accumulation at the closed-form time (within the stated uncertainty), it stands at rest on
// spokes 0 and 1, both sticking: the hub at (L sin(pi/6), L cos(pi/6)) above the middle of the tips
// (spoke 0's tip at the origin, spoke 1's at 2 L sin(pi/6)), theta = -pi/6, v = 0.
TEST(ZenoCompletion, SpokedWheelIsCarriedToRestInDoubleSupport) {
  const SpokedWheel wheel(2.0, 0.0);
  const double alpha = SpokedWheel::alpha(), psi0 = -0.1, w0 = 1.0;
  const PivotRocking ref = wheel_rocking(wheel);
  const auto impacts = ref.rocking(ref.vault(psi0, w0), ref.vault_impact_speed(psi0, w0));
  for (int bounces : {12, 40}) {
    SimulationOptions o = tight();
    o.zeno_bounces = bounces;
    o.zeno_completion = true;
    Simulator<SpokedWheel> sim(wheel, o);
    const auto traj = sim.run(wheel.standing_on_spoke_0(psi0, w0), 0.0, 3.0);
    ASSERT_EQ(traj.status, SimulationStatus::Completed) << "zeno_bounces " << bounces;
    ASSERT_EQ(traj.zeno_completions.size(), 1u);
    const ZenoCompletion& z = traj.zeno_completions[0];
    EXPECT_EQ(z.contacts, (std::vector<int>{0, 1}));
    EXPECT_LE(std::abs(z.t - impacts.t_inf), z.uncertainty) << z.t << " vs " << impacts.t_inf;
    EXPECT_LT(z.uncertainty, 1e-10);
    EXPECT_TRUE(traj.events.at(z.event).transitions.front().zeno_completion);
    EXPECT_EQ(describe(wheel, traj.segments.back().mode),
              "spoke 0:stick spoke 1:stick spoke 2:open spoke 3:open spoke 4:open spoke 5:open");
    const Vec<6> rest = traj.final_state();
    EXPECT_NEAR(rest[0], wheel.L * std::sin(alpha), 1e-12);
    EXPECT_NEAR(rest[1], wheel.L * std::cos(alpha), 1e-12);
    EXPECT_NEAR(rest[2], -alpha, 1e-12);
    EXPECT_LT(rest.tail<3>().cwiseAbs().maxCoeff(), 1e-12);
    for (int i = 0; i < 2; ++i) EXPECT_NEAR(wheel.gap(i, Vec<3>(rest.head<3>())), 0.0, 1e-12) << "spoke " << i;
    for (int i = 2; i < SpokedWheel::N; ++i) EXPECT_GT(wheel.gap(i, Vec<3>(rest.head<3>())), 0.4) << "spoke " << i;
    EXPECT_EQ(traj.t_end(), 3.0);
    for (const auto& seg : traj.segments)
      for (const auto& piece : seg.x.pieces())
        for (int i = 0; i < SpokedWheel::N; ++i)
          EXPECT_GE(wheel.gap(i, Vec<3>(piece.value(piece.t1).head<3>())), -1e-9);
  }
}

// Zeno completion of a simultaneous accumulation. The box dropped flat from H = 5 cm above its
// base hits with both corners at once at t_1 = sqrt(2 H / g) with speed v_1 = sqrt(2 g H), and the
// k-th impact sends it up at e^k v_1 for a flight of 2 e^k v_1 / g, so that
//     t_inf = t_1 + sum_{k >= 1} 2 e^k v_1 / g = t_1 + 2 e v_1 / (g (1 - e))      (e = 0.3)
// = 0.1875041173 s. With zeno_completion the run is continued past it on both corners and ends at
// rest on its base (y = h / 2, theta = 0, v = 0, both corners sticking); measured: t_inf to
// 2.4e-15 s against an uncertainty of 7.6e-11 s (the flights are parabolas, which the integrator
// follows exactly; the uncertainty is that of the tolerances), after 7 touchdowns.
TEST(ZenoCompletion, FlatBoxComesToRestOnItsBaseAtTheClosedFormAccumulationTime) {
  const BouncingBox box;
  const double g = 9.81, e = 0.3, H = 0.05, t1 = std::sqrt(2 * H / g), v1 = std::sqrt(2 * g * H);
  const double t_inf = t1 + 2 * e * v1 / (g * (1 - e));
  Vec<6> x0 = Vec<6>::Zero();
  x0[1] = H + 0.5 * box.h;
  for (int bounces : {12, 40}) {
    SimulationOptions o;
    o.zeno_bounces = bounces;
    o.zeno_completion = true;
    Simulator<BouncingBox> sim(box, o);
    const auto traj = sim.run(x0, 0.0, 0.5);
    ASSERT_EQ(traj.status, SimulationStatus::Completed) << "zeno_bounces " << bounces;
    ASSERT_EQ(traj.zeno_completions.size(), 1u);
    const ZenoCompletion& z = traj.zeno_completions[0];
    EXPECT_EQ(z.contacts, (std::vector<int>{0, 1}));
    EXPECT_LE(std::abs(z.t - t_inf), z.uncertainty) << z.t << " vs " << t_inf;
    EXPECT_LT(z.uncertainty, 1e-10);
    EXPECT_TRUE(traj.events.at(z.event).transitions.front().zeno_completion);
    EXPECT_EQ(traj.events.at(z.event).t, z.t);
    EXPECT_EQ(describe(box, traj.segments.back().mode), "left:stick right:stick");
    const Vec<6> rest = traj.final_state();
    EXPECT_NEAR(rest[1], 0.5 * box.h, 1e-12);
    EXPECT_NEAR(rest[2], 0.0, 1e-12);
    EXPECT_LT(rest.tail<3>().cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_EQ(traj.t_end(), 0.5);
  }
}

// Zeno completion of an alternating accumulation: the tall block (0.2 m x 0.6 m, mu = 2, e_n = 0)
// released on its left corner tilted by 0.05 rad rocks with impacts alternating between its
// corners (Housner's ratio 0.85). Raising zeno_bounces to 100 ended in "events stall" after the
// accumulation (the bounces reach the gap tolerance before 100 ratios are recorded); with the
// gap-scale criterion it is detected after 40 ratios at most. Completed, the block stands at rest
// on its base (x = w / 2, y = h / 2, theta = 0, v = 0, both corners sticking) past the accumulation;
// the accumulation times of zeno_bounces 12 and 40/100 agree within their uncertainties
// (measured: 1.431456083 +- 2.3e-6 s, 1.4314569877 +- 6.5e-10 s).
TEST(ZenoCompletion, RockingBlockIsCarriedToRestInDoubleSupport) {
  const Block block(0.2, 0.6, 2.0, 0.0);
  std::vector<ZenoCompletion> found;
  for (int bounces : {12, 40, 100}) {
    SimulationOptions o;
    o.zeno_bounces = bounces;
    o.zeno_completion = true;
    Simulator<Block> sim(block, o);
    const auto traj = sim.run(block.resting_on_left_corner(0.05), 0.0, 2.0);
    ASSERT_EQ(traj.status, SimulationStatus::Completed) << "zeno_bounces " << bounces;
    ASSERT_EQ(traj.zeno_completions.size(), 1u);
    EXPECT_EQ(traj.zeno_completions[0].contacts, (std::vector<int>{0, 1}));
    EXPECT_EQ(describe(block, traj.segments.back().mode), "left:stick right:stick");
    const Vec<6> rest = traj.final_state();
    EXPECT_NEAR(rest[0], 0.1, 1e-12);
    EXPECT_NEAR(rest[1], 0.3, 1e-12);
    EXPECT_NEAR(rest[2], 0.0, 1e-12);
    EXPECT_LT(rest.tail<3>().cwiseAbs().maxCoeff(), 1e-12);
    found.push_back(traj.zeno_completions[0]);
  }
  EXPECT_LE(std::abs(found[0].t - found[2].t), found[0].uncertainty + found[2].uncertainty);
  EXPECT_LT(found[2].uncertainty, 1e-9);
  // Without completion, zeno_bounces = 100 ends in a detected accumulation, not in "events stall".
  SimulationOptions o;
  o.zeno_bounces = 100;
  Simulator<Block> sim(block, o);
  const auto traj = sim.run(block.resting_on_left_corner(0.05), 0.0, 2.0);
  EXPECT_EQ(traj.status, SimulationStatus::Zeno);
  EXPECT_NEAR(traj.zeno_time, found[2].t, found[2].uncertainty);
}

// A box dropped flat but for a 1e-6 rad tilt: one corner lands first and its bounces accumulate
// alone (the box then pivots on it), then the other's: two completions, each over one corner,
// and the box ends at rest on its base.
TEST(ZenoCompletion, NearlyFlatBoxIsCarriedThroughTwoSingleCornerAccumulations) {
  const BouncingBox box;
  Vec<6> x0 = Vec<6>::Zero();
  x0[1] = 0.05 + 0.5 * box.h + 0.5 * box.w * std::sin(1e-6);
  x0[2] = 1e-6;
  SimulationOptions o;
  o.zeno_completion = true;
  Simulator<BouncingBox> sim(box, o);
  const auto traj = sim.run(x0, 0.0, 0.5);
  ASSERT_EQ(traj.status, SimulationStatus::Completed);
  ASSERT_EQ(traj.zeno_completions.size(), 2u);
  EXPECT_EQ(traj.zeno_completions[0].contacts, (std::vector<int>{0}));
  EXPECT_EQ(traj.zeno_completions[1].contacts, (std::vector<int>{1}));
  EXPECT_EQ(describe(box, traj.segments.back().mode), "left:stick right:stick");
  EXPECT_NEAR(traj.final_state()[1], 0.5 * box.h, 1e-12);
  EXPECT_LT(traj.final_state().tail<3>().cwiseAbs().maxCoeff(), 1e-12);
  for (const auto& seg : traj.segments)
    for (const auto& piece : seg.x.pieces())
      for (int i = 0; i < 2; ++i) EXPECT_GE(box.gap(i, Vec<3>(piece.value(piece.t1).head<3>())), -1e-9);
}

// Zeno completion of one contact: the ball on its spring (first test) is continued past its
// accumulation at the closed-form t_inf (within the stated uncertainty) and rests on the ground;
// the JSON says so.
TEST(ZenoCompletion, OneBallOnASpringRestsPastItsAccumulation) {
  const SpringBalls scene;
  const double v = 2.0, t_inf = SpringBalls::remaining(v);
  SimulationOptions o = tight();
  o.zeno_completion = true;
  Simulator<SpringBalls> sim(scene, o);
  const auto traj = sim.run(Vec<4>(0.0, 0.0, v, 0.0), 0.0, 10.0);
  ASSERT_EQ(traj.status, SimulationStatus::Completed);
  ASSERT_EQ(traj.zeno_completions.size(), 1u);
  const ZenoCompletion& z = traj.zeno_completions[0];
  EXPECT_EQ(z.contacts, (std::vector<int>{0}));
  EXPECT_LE(std::abs(z.t - t_inf), z.uncertainty);
  EXPECT_LT(traj.final_state().cwiseAbs().maxCoeff(), 1e-12);
  const auto j = to_json(traj, scene);
  ASSERT_EQ(j.at("zeno_completions").size(), 1u);
  EXPECT_EQ(j.at("zeno_completions")[0].at("contacts")[0], "ball 1");
  EXPECT_EQ(j.at("zeno_completions")[0].at("t").get<double>(), z.t);
}

// The predicted accumulation time against its closed form on every closed-form case, at three
// settings of the integrator's tolerances: the table of docs/simulation.md.
struct ToleranceSetting {
  const char* name;
  double relative, absolute;
};
constexpr std::array<ToleranceSetting, 3> tolerance_settings{ToleranceSetting{"loose", 1e-8, 1e-10},
                                                             ToleranceSetting{"default", 1e-10, 1e-12},
                                                             ToleranceSetting{"tight", 1e-12, 1e-14}};

struct AccumulationRow {
  std::string name;
  ToleranceSetting tol;
  double t_inf = 0, error = 0, stated = 0, extrapolation = 0, integration = 0;
  double worst_touchdown = 0, last_touchdown = 0, oracle = 0, lebesgue = 0, localisation = 0, position = 0, drift = 0;
  int used = 0;
};

/// Runs `scene` from x0 with the tolerances `tol` and measures the accumulation time against
/// t_inf and the touchdown times against `closed_touchdowns` (the first ones; may be empty).
template <Scene S>
AccumulationRow measure(const std::string& name, const S& scene, const VecT<double, 2 * S::nq>& x0, double t_final,
                        SimulationOptions o, const ToleranceSetting& tol, double t_inf,
                        const std::vector<double>& closed_touchdowns) {
  o.integrator.relative_tolerance = tol.relative;
  o.integrator.absolute_tolerance = tol.absolute;
  Simulator<S> sim(scene, o);
  const auto traj = sim.run(x0, 0.0, t_final);
  AccumulationRow row{name, tol};
  EXPECT_EQ(traj.status, SimulationStatus::Zeno) << name << " " << tol.name;
  row.t_inf = t_inf;
  row.error = std::abs(traj.zeno_time - t_inf);
  row.stated = traj.zeno_time_uncertainty;
  row.integration = traj.zeno_time_integration_uncertainty;
  EXPECT_EQ(row.stated, traj.zeno_time_extrapolation_uncertainty + traj.zeno_time_integration_uncertainty);
  std::vector<double> times, speeds, errors, qnorm;
  for (const auto& ev : traj.events) {
    double speed = 0.0;
    bool touchdown = false;
    const VecT<double, S::nq> q = ev.x_minus.template head<S::nq>(), v = ev.x_minus.template tail<S::nq>();
    for (const Guard& g : ev.guards()) {
      if (g.kind != GuardKind::Touchdown) continue;
      touchdown = true;
      const double h = 1e-7;
      const VecT<double, S::nq> qp = q + h * v, qm = q - h * v;
      speed = std::max(speed, -(scene.gap(g.contact, qp) - scene.gap(g.contact, qm)) / (2 * h));
    }
    if (!touchdown) continue;
    times.push_back(ev.t);
    speeds.push_back(speed);
    qnorm.push_back(q.cwiseAbs().maxCoeff());
    const std::size_t k = times.size() - 1;
    errors.push_back(k < closed_touchdowns.size() ? ev.t - closed_touchdowns[k]
                                                  : std::numeric_limits<double>::quiet_NaN());
  }
  AccumulationTime a;
  for (int period = 1; period <= 2; ++period) {
    a = extrapolate_accumulation_time(times, period, 0.5);
    if (a.t == traj.zeno_time) break;
  }
  EXPECT_EQ(a.t, traj.zeno_time) << name;
  EXPECT_EQ(a.extrapolation_uncertainty, traj.zeno_time_extrapolation_uncertainty) << name;
  row.extrapolation = a.extrapolation_uncertainty;
  row.used = a.used;
  const std::size_t m = times.size();
  row.last_touchdown = std::abs(errors[m - 1]);
  for (int k = 0; k < a.used; ++k) {
    const std::size_t i = m - 1 - k;
    const double w = std::abs(a.sensitivity[k]);
    row.worst_touchdown = std::max(row.worst_touchdown, std::abs(errors[i]));
    row.oracle += w * std::abs(errors[i]);
    row.lebesgue += w;
    row.localisation += w * o.integrator.root_tolerance * std::max(1.0, std::abs(times[i]));
    row.position += w * (tol.relative * qnorm[i] + tol.absolute) / speeds[i];
  }
  row.drift = tol.relative * (times.back() - traj.t_begin());
  return row;
}

TEST(AccumulationTable, EveryClosedFormAtThreeTolerances) {
  std::vector<AccumulationRow> rows;
  for (const ToleranceSetting& tol : tolerance_settings) {
    {  // the bouncing ball (e_n = 0.5) dropped from 1 m
      const scenes::BouncingBall ball;
      const double g = 9.81, e = 0.5, t1 = std::sqrt(2.0 / g), v1 = std::sqrt(2 * g);
      std::vector<double> closed{t1};
      for (int k = 1; k < 80; ++k) closed.push_back(closed.back() + 2 * v1 * std::pow(e, k) / g);
      rows.push_back(measure("bouncing ball", ball, Vec<2>(1.0, 0.0), 10.0, SimulationOptions{}, tol,
                             t1 + 2 * v1 * e / (g * (1 - e)), closed));
    }
    {  // one ball on a spring
      const SpringBalls scene;
      const double v = 2.0;
      std::vector<double> closed;
      for (int k = 0; k < 80; ++k) closed.push_back(SpringBalls::remaining(v) - SpringBalls::remaining(v, k + 1));
      rows.push_back(measure("ball on a spring", scene, Vec<4>(0.0, 0.0, v, 0.0), 10.0, SimulationOptions{}, tol,
                             SpringBalls::remaining(v), closed));
    }
    {  // the flat box on its two corners
      const BouncingBox box;
      const double g = 9.81, e = 0.3, H = 0.05, t1 = std::sqrt(2 * H / g), v1 = std::sqrt(2 * g * H);
      std::vector<double> closed{t1};
      for (int k = 1; k < 40; ++k) closed.push_back(closed.back() + 2 * v1 * std::pow(e, k) / g);
      Vec<6> x0 = Vec<6>::Zero();
      x0[1] = H + 0.5 * box.h;
      rows.push_back(
          measure("flat box", box, x0, 0.5, SimulationOptions{}, tol, t1 + 2 * e * v1 / (g * (1 - e)), closed));
    }
    for (int bounces : {12, 40}) {  // Housner's rocking block
      const Block block(0.2, 0.6, 2.0, 0.0);
      const PivotRocking ref = block_rocking(block);
      const auto impacts = ref.rocking(ref.fall(0.05), ref.impact_speed(0.05));
      SimulationOptions o;
      o.zeno_bounces = bounces;
      rows.push_back(measure("rocking block " + std::to_string(bounces), block, block.resting_on_left_corner(0.05), 2.0,
                             o, tol, impacts.t_inf, impacts.t));
    }
    {  // the spoked wheel
      const SpokedWheel wheel(2.0, 0.0);
      const PivotRocking ref = wheel_rocking(wheel);
      const double w1 = ref.vault_impact_speed(-0.1, 1.0);
      const auto impacts = ref.rocking(ref.vault(-0.1, 1.0), w1);
      rows.push_back(measure("spoked wheel", wheel, wheel.standing_on_spoke_0(-0.1, 1.0), 3.0, SimulationOptions{}, tol,
                             impacts.t_inf, impacts.t));
    }
  }
  // The columns: the error of zeno_time, its stated uncertainty and the two parts of it; the
  // touchdown times' errors (the worst in the window the extrapolation used, the last), the
  // propagation sum_k |dZ/ds_k| |e_k| of the actual errors and L = sum_k |dZ/ds_k| (both as if
  // the errors were independent), the candidates: event location carried through the
  // sensitivities, the position tolerance over the approach speed carried through them, the
  // phase drift rho T (accumulation_time.hpp); n the touchdowns used.
  std::printf("%-17s %-7s %8s %8s %8s %8s %6s | %8s %8s %8s %6s %8s %8s %8s %2s\n", "case", "tol", "error", "stated",
              "extrap", "integr", "st/err", "worst td", "last td", "sum|w e|", "L", "location", "position", "rho T",
              "n");
  for (const auto& r : rows)
    std::printf("%-17s %-7s %8.2e %8.2e %8.2e %8.2e %6.3g | %8.2e %8.2e %8.2e %6.0f %8.2e %8.2e %8.2e %2d\n",
                r.name.c_str(), r.tol.name, r.error, r.stated, r.extrapolation, r.integration, r.stated / r.error,
                r.worst_touchdown, r.last_touchdown, r.oracle, r.lebesgue, r.localisation, r.position, r.drift, r.used);
  // The user's rule: the accumulation time is right to its stated uncertainty, on every case and at
  // every setting; and the statement is not loose by more than a factor 30 where the error is
  // above the event location's resolution (100 root tolerances of t_inf; below it the error is
  // round-off and the bound from the tolerances is all the simulator knows).
  for (const auto& r : rows) {
    EXPECT_LE(r.error, r.stated) << r.name << " at the " << r.tol.name << " tolerances";
    if (r.error > 100 * IntegratorOptions{}.root_tolerance * std::max(1.0, r.t_inf))
      EXPECT_LE(r.stated, 30 * r.error) << r.name << " at the " << r.tol.name << " tolerances";
  }
}

}  // namespace
}  // namespace saltus::testing
