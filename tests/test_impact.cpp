// The impact problem: closed forms (a frictionless multi-contact impact is the kinetic-metric
// projection of the velocity; a point mass hitting a table with friction), the Signorini and
// Coulomb conditions and energy over 10,000 random pre-impact states per scene (redundant
// contacts included), and bad input.
#include "scenes/sampling.hpp"
#include "scenes/three_point_block.hpp"

#include "support.hpp"

#include <saltus/hybrid/dynamics/impact.hpp>
#include <saltus/hybrid/header_only.hpp>  // the test-local Kane pendulum below

#include <numbers>
#include <optional>
#include <random>

namespace saltus::testing {
namespace {

using scenes::ThreePointBlock;

TEST(Impact, BouncingBallReboundsWithItsRestitution) {
  scenes::BouncingBall ball;
  ImpactSolver<scenes::BouncingBall> solver(ball);
  const auto& r = solver.solve(Vec<2>(0.0, -3.0));
  EXPECT_NEAR(r.x_plus[1], 1.5, 1e-15);
  EXPECT_EQ(r.post_mode[0].mode, ContactMode::Open);
  EXPECT_NEAR(r.impulse[0].normal, 0.1 * 4.5, 1e-15);
}

// Point mass hitting the table with (vt, vn < 0): Lambda_n = -m vn; stick if |vt| <= mu |vn|,
// else slip with vt+ = vt - mu |vn| sign(vt).
TEST(Impact, PointMassWithFrictionMatchesClosedForm) {
  scenes::PointMassParameters p;
  p.friction = Friction::Planar;
  p.mu = 0.3;
  p.mass = 2.0;
  scenes::PointMass mass(p);
  ImpactSolver<scenes::PointMass> solver(mass);
  for (double vt : {-2.0, -0.5, 0.0, 0.2, 0.6, 3.0}) {
    const double vn = -1.5;
    const auto& r = solver.solve(Vec<4>(0.3, 0.0, vt, vn));
    const double expected_vt = std::abs(vt) <= p.mu * std::abs(vn) ? 0.0 : vt - p.mu * std::abs(vn) * (vt > 0 ? 1 : -1);
    EXPECT_NEAR(r.x_plus[2], expected_vt, 1e-14) << "vt = " << vt;
    EXPECT_NEAR(r.x_plus[3], 0.0, 1e-14);
    EXPECT_NEAR(r.impulse[0].normal, -p.mass * vn, 1e-13);
    EXPECT_EQ(r.impulse_mode[0].role, std::abs(vt) <= p.mu * std::abs(vn) ? ImpulseRole::Stick : ImpulseRole::Slip);
  }
}

// min 1/2 (v - v-)^T M (v - v-) subject to W_n v >= 0, by enumerating the active sets.
template <int N>
Vec<N> kinetic_metric_projection(const Mat<N, N>& M, const Eigen::MatrixXd& Wn, const Vec<N>& v_minus) {
  const int c = static_cast<int>(Wn.rows());
  for (int set = 0; set < (1 << c); ++set) {
    Eigen::MatrixXd Wa(0, N);
    for (int i = 0; i < c; ++i)
      if (set & (1 << i)) {
        Wa.conservativeResize(Wa.rows() + 1, N);
        Wa.row(Wa.rows() - 1) = Wn.row(i);
      }
    Vec<N> v = v_minus;
    Eigen::VectorXd lambda;
    if (Wa.rows() > 0) {
      const Eigen::MatrixXd MinvWt = M.llt().solve(Wa.transpose());
      lambda = (Wa * MinvWt).completeOrthogonalDecomposition().solve(-Wa * v_minus);
      v += MinvWt * lambda;
    }
    if ((Wn * v).minCoeff() >= -1e-12 && (lambda.size() == 0 || lambda.minCoeff() >= -1e-12)) return v;
  }
  ADD_FAILURE() << "no active set satisfies the KKT conditions";
  return v_minus;
}

TEST(Impact, FrictionlessMultiContactImpactIsTheKineticMetricProjection) {
  scenes::PlankBoxParameters pp;
  pp.mu = 0.0;
  scenes::PlankBox plank_box(pp);
  scenes::SpatialBoxParameters sp;
  sp.mu = 0.0;
  scenes::SpatialBox box(sp);
  std::mt19937 rng(7);
  auto check = [&](const auto& scene, int trials) {
    using S = std::decay_t<decltype(scene)>;
    constexpr int nq = S::nq;
    ImpactSolver<S> solver(scene);
    for (int t = 0; t < trials; ++t) {
      const Vec<2 * nq> x = scenes::random_pre_impact_state(scene, rng);
      const auto& r = solver.solve(x);
      Kinematics<S> kin;
      evaluate_kinematics(scene, Vec<nq>(x.template head<nq>()), Vec<nq>(x.template tail<nq>()), kin);
      Eigen::MatrixXd Wn(0, nq);
      for (int i = 0; i < S::nc; ++i)
        if (r.in_problem[i]) {
          Wn.conservativeResize(Wn.rows() + 1, nq);
          Wn.row(Wn.rows() - 1) = kin.contacts[i].wn.transpose();
        }
      const Vec<nq> expected = kinetic_metric_projection<nq>(kin.M, Wn, Vec<nq>(x.template tail<nq>()));
      EXPECT_TRUE(matrices_near(Vec<nq>(r.x_plus.template tail<nq>()), expected, 1e-12, 1e-13)) << S::name << " trial " << t;
    }
  };
  check(plank_box, 300);
  check(box, 300);
}

// A flat box landing straight down on a plank: both corners hit at once (singular Delassus
// matrix in stick); the minimum-norm impulse is split equally.
TEST(Impact, FlatLandingSplitsTheImpulseEqually) {
  scenes::PlankBox plank_box;
  Vec<8> x = plank_box.flat_state(0.6, 0.0);  // touching, flat
  x.tail<4>() << 0.1, -1.0, 0, 0;
  ImpactSolver<scenes::PlankBox> solver(plank_box);
  const auto& r = solver.solve(x);
  EXPECT_TRUE(r.singular_delassus);
  EXPECT_TRUE(r.minimum_norm_impulse);
  EXPECT_NEAR(r.impulse[0].tangent[0], r.impulse[1].tangent[0], 1e-12);
  EXPECT_LE(r.signorini_residual, 1e-12);
  EXPECT_LE(r.coulomb_residual, 1e-12);
  EXPECT_EQ(r.post_mode[0].mode, ContactMode::Stick);
  EXPECT_EQ(r.post_mode[1].mode, ContactMode::Stick);
}

// Kane and Levinson's example: a planar double pendulum (two 1 kg point masses on 1 m massless
// links, absolute angles q = (theta1, theta2) from the downward vertical [rad]) whose tip hits
// the floor with planar friction. Newton's kinematic law (e_t = 0) with e_n > 0 gains energy on
// part of the random impacts; the default, energy-consistent law (impact_law.hpp) never does.
class KaneDoublePendulum {
 public:
  static constexpr int nq = 2, nu = 0, nc = 1;
  [[maybe_unused]] static constexpr const char* name = "kane_double_pendulum";  // read by templates (S::name)
  KaneDoublePendulum(double mu, double e_n, std::optional<double> e_t)
      : tip_{"tip", Friction::Planar, mu, e_n, e_t} {}
  const ContactSpec& contact(int) const { return tip_; }
  template <class T>
  MatT<T, nq, nq> mass_matrix(const VecT<T, nq>& q) const {
    using std::cos;
    MatT<T, nq, nq> M;
    M(0, 0) = T(2.0);
    M(0, 1) = M(1, 0) = cos(q[0] - q[1]);
    M(1, 1) = T(1.0);
    return M;
  }
  template <class T>
  VecT<T, nq> bias(const VecT<T, nq>& q, const VecT<T, nq>& v) const {
    using std::sin;
    const T s = sin(q[0] - q[1]);
    return VecT<T, nq>(s * v[1] * v[1] + T(2 * 9.81) * sin(q[0]), -s * v[0] * v[0] + T(9.81) * sin(q[1]));
  }
  template <class T>
  MatT<T, nq, nu> input_matrix(const VecT<T, nq>&) const {
    return MatT<T, nq, nu>::Zero();
  }
  template <class T>
  T gap(int, const VecT<T, nq>& q) const {  // floor 1.5 m below the pivot
    using std::cos;
    return T(1.5) - cos(q[0]) - cos(q[1]);
  }
  template <class T>
  VecT<T, 2> tangent_position(int, const VecT<T, nq>& q) const {
    using std::sin;
    return VecT<T, 2>(sin(q[0]) + sin(q[1]), T(0));
  }

 private:
  ContactSpec tip_;
};

struct EnergyCount {
  int impacts = 0, gains = 0;
  double worst_ratio = 0.0;
};

EnergyCount random_frictional_impacts(const KaneDoublePendulum& pendulum, int impacts) {
  ImpactSolver<KaneDoublePendulum> solver(pendulum);
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi);
  std::normal_distribution<double> speed(0.0, 2.0);
  EnergyCount count;
  while (count.impacts < impacts) {
    Vec<4> x(angle(rng), angle(rng), speed(rng), speed(rng));
    Kinematics<KaneDoublePendulum> kin;
    evaluate_kinematics(pendulum, Vec<2>(x.head<2>()), Vec<2>(x.tail<2>()), kin);
    if (!(kin.contacts[0].zeta_n < -1e-3)) continue;  // approaching the floor
    // Away from the singular configurations (links aligned or folded, theta1 = theta2 mod pi):
    // there the tip moves along one line only, w_n and W_t are parallel, the Delassus matrix has
    // rank 1, and Newton's kinematic law jams with unbounded impulses (KE+/KE- up to 1e9 at
    // |sin(theta1 - theta2)| < 0.01 in this sample, with Signorini residuals of 1e-7).
    if (std::abs(std::sin(x[0] - x[1])) < 0.1) continue;
    const auto& r = solver.solve(x, {true});
    const double ratio = r.kinetic_energy_plus / r.kinetic_energy_minus;
    EXPECT_LE(r.signorini_residual, 1e-12) << "x- = " << x.transpose();
    EXPECT_LE(r.coulomb_residual, 1e-12) << "x- = " << x.transpose();
    EXPECT_GE(r.normal_velocity_plus[0], -1e-12 * r.velocity_scale);
    ++count.impacts;
    if (ratio > 1.0 + 1e-12) ++count.gains;
    count.worst_ratio = std::max(count.worst_ratio, ratio);
  }
  return count;
}

TEST(Impact, KaneDoublePendulumGainsEnergyOnlyUnderTheKinematicLaw) {
  struct Case {
    double mu, e_n;
  };
  for (const Case c : {Case{0.5, 0.5}, Case{0.3, 1.0}}) {
    const EnergyCount kinematic = random_frictional_impacts(KaneDoublePendulum(c.mu, c.e_n, 0.0), 40000);
    const EnergyCount consistent = random_frictional_impacts(KaneDoublePendulum(c.mu, c.e_n, std::nullopt), 40000);
    std::printf("mu %.1f e_n %.1f: kinematic law (e_t = 0) %d / %d impacts gain energy, worst KE+/KE- %.3f; "
                "energy-consistent law %d gains, worst KE+/KE- %.6f\n",
                c.mu, c.e_n, kinematic.gains, kinematic.impacts, kinematic.worst_ratio, consistent.gains,
                consistent.worst_ratio);
    EXPECT_GT(kinematic.gains, 100) << "the kinematic law's known defect must show on this example";
    EXPECT_GT(kinematic.worst_ratio, 1.5);
    EXPECT_EQ(consistent.gains, 0);
    EXPECT_LE(consistent.worst_ratio, 1.0 + 1e-12);
  }
  // Frictionless, e_n = 1: the energy is conserved exactly, and the default law is the same.
  const EnergyCount elastic = random_frictional_impacts(KaneDoublePendulum(0.0, 1.0, std::nullopt), 2000);
  EXPECT_EQ(elastic.gains, 0);
  EXPECT_NEAR(elastic.worst_ratio, 1.0, 1e-12);
}

// The jump map of the energy-consistent law (tangential restitution on sticking rows, the slip
// direction of xi_t) is differentiated like the rest: its Jacobian against central differences,
// on sticking and slipping impacts.
TEST(Impact, EnergyConsistentJumpMapJacobianMatchesCentralDifferences) {
  const KaneDoublePendulum pendulum(0.5, 0.5, std::nullopt);
  ImpactSolver<KaneDoublePendulum> solver(pendulum);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi);
  std::normal_distribution<double> speed(0.0, 2.0);
  int stick = 0, slip = 0;
  auto derivative_ws = std::make_unique<DerivativeWorkspace<KaneDoublePendulum>>();
  JumpWorkspace<KaneDoublePendulum> ws;
  while (stick < 20 || slip < 20) {
    Vec<4> x(angle(rng), angle(rng), speed(rng), speed(rng));
    Kinematics<KaneDoublePendulum> kin;
    evaluate_kinematics(pendulum, Vec<2>(x.head<2>()), Vec<2>(x.tail<2>()), kin);
    if (!(kin.contacts[0].zeta_n < -1e-2)) continue;
    const auto r = solver.solve(x, {true});
    const bool is_stick = r.impulse_mode[0].role == ImpulseRole::Stick;
    if ((is_stick && stick >= 20) || (!is_stick && slip >= 20)) continue;
    (is_stick ? stick : slip) += 1;
    Vec<4> xp;
    Mat<4, 4> G;
    jump_map_jacobian(pendulum, r.impulse_mode, x, *derivative_ws, xp, G);
    EXPECT_TRUE(matrices_near(xp, r.x_plus, 1e-12, 1e-12)) << "the map reproduces the solver's v+";
    auto g = [&](const Vec<4>& y) {
      Vec<4> out;
      apply_jump_map(pendulum, r.impulse_mode, y, ws, out);
      return out;
    };
    EXPECT_TRUE(matrices_near(G, central_jacobian<4, 4>(g, x), 2e-6, 1e-7)) << to_string(r.impulse_mode[0].role);
  }
}

// Landing flat while sliding (vx = 1, vy = -1 m/s, mu = 0.3): the velocity is unique, vx+ = 0.7,
// vy+ = omega+ = 0, while the normal impulses only have to add up to 1 N s with their moment
// balancing that of friction. The result says that the split is not unique (singular_delassus)
// and what the returned split is (minimum_norm_impulse: the minimum norm within the mode found).
TEST(Impact, CollinearContactsReportANonUniqueSplit) {
  const ThreePointBlock block(0.3, 0.0);
  ImpactSolver<ThreePointBlock> solver(block);
  Vec<6> x;
  x << 0.0, 0.1, 0.0, 1.0, -1.0, 0.0;  // flat, all three points on the ground
  const auto& r = solver.solve(x);
  EXPECT_TRUE(r.singular_delassus) << "three collinear contacts are redundant";
  EXPECT_NEAR(r.x_plus[3], 0.7, 1e-12);
  EXPECT_NEAR(r.x_plus[4], 0.0, 1e-12);
  EXPECT_NEAR(r.x_plus[5], 0.0, 1e-12);
  double total = 0.0, moment = 0.0;
  int with_impulse = 0;
  for (int i = 0; i < 3; ++i) {
    EXPECT_GE(r.impulse[i].normal, 0.0);
    total += r.impulse[i].normal;
    moment += 0.2 * (i - 1) * r.impulse[i].normal;
    with_impulse += r.impulse_mode[i].role != ImpulseRole::None;
  }
  EXPECT_NEAR(total, 1.0, 1e-12);
  EXPECT_NEAR(moment, 0.1 * 0.3 * total, 1e-12) << "the normal impulses' moment balances friction's";
  EXPECT_LE(r.signorini_residual, 1e-12);
  EXPECT_LE(r.coulomb_residual, 1e-12);
  // minimum_norm_impulse means "within the identified mode": with every point in the mode the
  // returned split is the minimum-norm solution of the two balances above.
  if (r.minimum_norm_impulse && with_impulse == 3) {
    // min ||P|| s.t. sum P = 1, sum x_i P_i = 0.03: P = 1/3 + x_i * 0.03 / sum x_i^2.
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(r.impulse[i].normal, 1.0 / 3 + 0.2 * (i - 1) * 0.03 / 0.08, 1e-12);
  }
  std::printf("collinear split %.4f / %.4f / %.4f, contacts in the mode %d, minimum_norm_impulse %d\n",
              r.impulse[0].normal, r.impulse[1].normal, r.impulse[2].normal, with_impulse, r.minimum_norm_impulse);
}

// The impact problem is positively homogeneous of degree one in v- (impact.hxx): the same
// impact at 1e-156 m/s or 1e140 m/s as at 1 m/s gives the same mode, and impulses and v+ scaled
// by the same factor, with the law residuals at round-off (fuzz finding: velocities of 1e-156
// squared to subnormals and left a Coulomb residual of 1.2e-9).
TEST(Impact, ImpactScalesWithThePreImpactVelocity) {
  std::mt19937 rng(20261130);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const ThreePointBlock block(0.7, 0.4);
  ImpactSolver<ThreePointBlock> solver(block);
  int compared = 0;
  for (int trial = 0; trial < 200; ++trial) {
    Vec<6> x;
    x << u(rng), 0.1, 0.0, u(rng), -0.2 - std::abs(u(rng)), 0.3 * u(rng);  // flat: redundant contacts
    if (trial % 2) {  // tilted, the lower corner on the ground
      x[2] = 0.05 * u(rng);
      x[1] = -std::min(block.point(0, Vec<3>(0, 0, x[2]))[1], block.point(2, Vec<3>(0, 0, x[2]))[1]);
    }
    const ImpactResult<ThreePointBlock> unit = solver.solve(x);
    for (const double scale : {0x1p-520, 0x1p-90, 0x1p70, 0x1p460}) {
      Vec<6> xs = x;
      xs.tail<3>() *= scale;  // a power of two: exact
      const auto& r = solver.solve(xs);
      ASSERT_LE(r.signorini_residual, 1e-12) << "scale " << scale;
      ASSERT_LE(r.coulomb_residual, 1e-12) << "scale " << scale;
      for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(r.impulse_mode[i].role, unit.impulse_mode[i].role);
        EXPECT_TRUE(r.post_mode[i] == unit.post_mode[i]) << "contact " << i << ", scale " << scale;
        EXPECT_NEAR(r.impulse[i].normal / scale, unit.impulse[i].normal, 1e-12);
      }
      for (int k = 3; k < 6; ++k) EXPECT_NEAR(r.x_plus[k] / scale, unit.x_plus[k], 1e-12);
      EXPECT_EQ(r.x_plus.head<3>(), x.head<3>());
      // Kinetic energies scale with scale^2: at 2^-520 that is below the normal range (subnormal,
      // digits lost), so they are compared where scale^2 is a normal number.
      if (std::isnormal(scale * scale) && std::isnormal(unit.kinetic_energy_plus * scale * scale)) {
        EXPECT_NEAR(r.kinetic_energy_plus / (scale * scale), unit.kinetic_energy_plus, 1e-12);
      }
      ++compared;
    }
  }
  EXPECT_EQ(compared, 800);
}

TEST(Impact, BadInputIsRejectedWithANamedProblem) {
  scenes::PlankBox plank_box;
  ImpactSolver<scenes::PlankBox> solver(plank_box);
  Vec<8> x = Vec<8>::Zero();
  x[5] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(solver.solve(x), InvalidArgument);

  scenes::PlankBoxParameters negative_mu;
  negative_mu.mu = -0.1;
  const scenes::PlankBox bad_mu(negative_mu);
  EXPECT_THROW(ImpactSolver<scenes::PlankBox>{bad_mu}, InvalidArgument);
  scenes::BouncingBallParameters superelastic;
  superelastic.restitution = 1.5;
  const scenes::BouncingBall bad_restitution(superelastic);
  EXPECT_THROW(ImpactSolver<scenes::BouncingBall>{bad_restitution}, InvalidArgument);

  // A state whose square overflows (found by fuzzing: |v| = 4.5e279 gave an infinite ||zeta_t||
  // and a zero slip direction): refused up front.
  {
    const ThreePointBlock block(0.2, 0.1);
    ImpactSolver<ThreePointBlock> solver(block);
    try {
      (void)solver.solve(Vec<6>(0, 0, 0, -4.5e279, -2.0, 0));
      ADD_FAILURE() << "an overflowing state was accepted";
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find("larger than 1e150"), std::string::npos) << e.what();
    }
  }

  // Tangential restitution outside [0, 1], or NaN: refused, naming the contact and e_t.
  for (const double e_t : {-0.1, 1.5, std::numeric_limits<double>::quiet_NaN()}) {
    try {
      const KaneDoublePendulum pendulum(0.5, 0.5, e_t);
      ImpactSolver<KaneDoublePendulum> solver(pendulum);
      ADD_FAILURE() << "e_t = " << e_t << " accepted";
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find("tangential restitution e_t"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("'tip'"), std::string::npos) << e.what();
    }
  }

  scenes::PointMassParameters negative_mass;
  negative_mass.mass = -1.0;
  scenes::PointMass bad(negative_mass);
  ImpactSolver<scenes::PointMass> bad_solver(bad);
  EXPECT_THROW(bad_solver.solve(Vec<4>(0, 0, 0, -1)), NonSpdMassMatrix);
  FlowWorkspace<scenes::PointMass> ws;
  EXPECT_THROW(flow(bad, Mode<1>{}, Vec<4>(0, 1, 0, 0), Vec<2>(Vec<2>::Zero()), ws), NonSpdMassMatrix);
  try {
    flow(bad, Mode<1>{}, Vec<4>(0, 1, 0, 0), Vec<2>(Vec<2>::Zero()), ws);
  } catch (const NonSpdMassMatrix& e) {
    EXPECT_NE(std::string(e.what()).find("not symmetric positive definite"), std::string::npos) << e.what();
  }
}

// A spatial impact on four corners that the Newton solver may not finish in one iteration: the
// failure is an exception that names the residual, never a silent answer.
TEST(Impact, UnsolvedImpactProblemRaisesContactProblemFailure) {
  scenes::SpatialBox box;
  ImpactOptions options;
  options.coulomb.max_iterations = 1;
  options.coulomb.polyhedral_restarts = false;
  options.residual_tolerance = 1e-15;
  ImpactSolver<scenes::SpatialBox> solver(box, options);
  Vec<12> x = Vec<12>::Zero();
  x[2] = 0.5 * box.parameters().size[2];
  x.tail<6>() << 1.3, -0.4, -2.0, 0.7, -0.2, 0.9;
  try {
    solver.solve(x);
    FAIL() << "expected ContactProblemFailure";
  } catch (const ContactProblemFailure& e) {
    EXPECT_NE(std::string(e.what()).find("residual"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace saltus::testing
