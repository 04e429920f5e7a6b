// The impact problem: closed forms (a frictionless multi-contact impact is the kinetic-metric
// projection of the velocity; a point mass hitting a table with friction), the Signorini and
// Coulomb conditions and energy over 10,000 random pre-impact states per scene (redundant
// contacts included), and bad input.
#include "scenes/sampling.hpp"
#include "support.hpp"

#include <saltus/hybrid/dynamics/impact.hpp>

namespace saltus::testing {
namespace {

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
