// The two impact laws on the classic single-contact examples, against their closed forms: the
// default energy-consistent law (one coefficient e for the normal and the tangential rows:
// a sticking contact leaves with zeta_t+ = -e zeta_t-) and Newton's kinematic law with Coulomb
// friction (ContactSpec::tangential_restitution = 0: zeta_t+ = 0 when sticking). The numbers
// printed here are the table of the README's paragraph on impacts with restitution.
//
// Closed forms. One planar contact whose Delassus matrix has no normal-tangential coupling,
// G = diag(G_nn, G_tt) (both examples below). Impulses Lambda_n >= 0, Lambda_t; velocities at
// the contact zeta_n- < 0 (approaching), zeta_t-. Both laws give the normal row
//     Lambda_n = (1 + e) |zeta_n-| / G_nn,   zeta_n+ = e |zeta_n-|.
// Tangential row with coefficient e_t (e_t = e: the default law; e_t = 0: Newton's):
//   stick, zeta_t+ = -e_t zeta_t-, needs Lambda_t = -(1 + e_t) zeta_t- / G_tt inside the cone
//     |Lambda_t| <= mu Lambda_n  <=>  (1 + e_t) |zeta_t-| / G_tt <= mu (1 + e) |zeta_n-| / G_nn;
//   otherwise slip, Lambda_t = -mu Lambda_n sign(zeta_t-), zeta_t+ = zeta_t- + G_tt Lambda_t.
// So for zeta_t- > 0: zeta_t+ = max(-e_t zeta_t-, zeta_t- - mu (1 + e) |zeta_n-| G_tt / G_nn).
// The default law's stick test, (1 + e) |zeta_t-| / G_tt <= mu (1 + e) |zeta_n-| / G_nn, is the
// kinematic law's with (1 + e) on the left too: it sticks for fewer approach angles, and where
// both stick it reverses the contact point's tangential velocity by the factor e.
//
// Disk on a slope: a uniform disk (mass m, radius r, I = m r^2 / 2), q = (s, h, theta): s along
// the slope, h the centre's height above the slope plane, theta anticlockwise; the material
// contact point moves at zeta_t = s' + r theta', zeta_n = h'. Hence G_nn = 1/m and
// G_tt = 1/m + r^2/I = 3/m. Dropped with speed V straight down onto a slope of angle alpha
// (no spin): zeta_n- = -V cos(alpha), zeta_t- = -V sin(alpha) (downhill). Both laws stick when
// tan(alpha) <= mu (1 + e) 3 / (1 + e_t), i.e. tan(alpha) <= 3 mu for the default law. Then
//     Lambda_t = -(1 + e_t) m zeta_t- / 3,  s'+ = s'- + Lambda_t / m,  theta'+ = r Lambda_t / I,
// Newton's law (e_t = 0): s'+ = (2/3) s'-, r theta'+ = -(2/3) s'-: rolling (zeta_t+ = 0);
// the default law (e_t = e): s'+ = (2 - e)/3 s'-, r theta'+ = -2 (1 + e)/3 s'-, zeta_t+ = -e zeta_t-:
// the disk leaves over-spun, its contact point moving uphill.
// With V = 2 m/s, alpha = 30 deg, e = 0.5, mu = 0.5, m = 1 kg, r = 0.1 m (zeta_t- = -1 m/s,
// zeta_n- = -sqrt(3) m/s): Newton s'+ = -2/3, theta'+ = 20/3 rad/s, KE+ = 17/24 J; default
// s'+ = -1/2, theta'+ = 10 rad/s, KE+ = 3/4 J (KE- = 2 J).
//
// Box landing while sliding: a box that does not rotate (a point mass on a table: the box landing
// flat on its bottom face, whose contact rows act as one), G_nn = G_tt = 1/m. Landing with
// x' = u > 0, y' = -w: Newton x'+ = max(0, u - mu (1 + e) w); default x'+ = max(-e u,
// u - mu (1 + e) w). With e = 0.5, mu = 0.5, w = 3 m/s: u = 1 m/s: Newton stops (0), the
// default law sends it back at -0.5 m/s (stick); u = 2 m/s: Newton stops, the default law slips
// to -0.25 m/s; u = 3 m/s: both slip to 0.75 m/s.
//
// Stronge's energetic restitution (the normal impulse's work in restitution is -e^2 times its work
// in compression) is not a law of the library; stronge_planar below integrates it in impulse
// space as a reference. For these two examples it coincides with Newton's law (checked below):
// without normal-tangential coupling (G_nt = 0) the normal velocity grows as Lambda_n / G_nn
// whatever the friction does, so the energetic, kinetic (Poisson) and kinematic (Newton)
// coefficients agree, and a contact that stops slipping sticks (its sticking impulse ratio,
// G_tn / G_tt = 0, is inside any cone): zero tangential restitution, as the kinematic law. The
// laws differ only with coupling (a rod or a box landing on one corner).
#include "support.hpp"

#include <saltus/hybrid/dynamics/impact.hpp>
#include <saltus/hybrid/header_only.hpp>  // the two test-local scenes below

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>

namespace saltus::testing {
namespace {

constexpr double kG = 9.81;

/// A uniform disk on a slope of angle `alpha` (rad), in the slope's frame: q = (s, h, theta).
struct DiskOnSlope {
  static constexpr int nq = 3, nu = 0, nc = 1;
  [[maybe_unused]] static constexpr const char* name = "disk_on_slope";
  double m = 1.0, r = 0.1, alpha = std::numbers::pi / 6;
  ContactSpec slope;
  DiskOnSlope(double mu, double e, std::optional<double> e_t) : slope{"slope", Friction::Planar, mu, e, e_t} {}
  double inertia() const { return 0.5 * m * r * r; }
  const ContactSpec& contact(int) const { return slope; }
  template <class T>
  MatT<T, nq, nq> mass_matrix(const VecT<T, nq>&) const {
    return Vec<3>(m, m, inertia()).asDiagonal().toDenseMatrix().cast<T>();
  }
  template <class T>
  VecT<T, nq> bias(const VecT<T, nq>&, const VecT<T, nq>&) const {  // gravity: downhill is -s
    return VecT<T, nq>(T(m * kG * std::sin(alpha)), T(m * kG * std::cos(alpha)), T(0));
  }
  template <class T>
  MatT<T, nq, nu> input_matrix(const VecT<T, nq>&) const {
    return {};
  }
  template <class T>
  T gap(int, const VecT<T, nq>& q) const {
    return q[1] - T(r);
  }
  template <class T>
  VecT<T, 2> tangent_position(int, const VecT<T, nq>& q) const {  // its rate: the contact point's slip
    return VecT<T, 2>(q[0] + T(r) * q[2], T(0));
  }
};

/// A box that slides without rotating on a table: q = (x, y) of its bottom face.
struct SlidingBox {
  static constexpr int nq = 2, nu = 0, nc = 1;
  [[maybe_unused]] static constexpr const char* name = "sliding_box";
  double m = 1.0;
  ContactSpec table;
  SlidingBox(double mu, double e, std::optional<double> e_t) : table{"table", Friction::Planar, mu, e, e_t} {}
  const ContactSpec& contact(int) const { return table; }
  template <class T>
  MatT<T, nq, nq> mass_matrix(const VecT<T, nq>&) const {
    return MatT<T, nq, nq>::Identity() * T(m);
  }
  template <class T>
  VecT<T, nq> bias(const VecT<T, nq>&, const VecT<T, nq>&) const {
    return VecT<T, nq>(T(0), T(m * kG));
  }
  template <class T>
  MatT<T, nq, nu> input_matrix(const VecT<T, nq>&) const {
    return {};
  }
  template <class T>
  T gap(int, const VecT<T, nq>& q) const {
    return q[1];
  }
  template <class T>
  VecT<T, 2> tangent_position(int, const VecT<T, nq>& q) const {
    return VecT<T, 2>(q[0], T(0));
  }
};

/// The exit of one planar contact's impact under Stronge's energetic restitution.
struct StrongeExit {
  double zeta_n = 0.0, zeta_t = 0.0;  ///< contact velocities after (m/s)
  double normal = 0.0, tangent = 0.0;  ///< impulses Lambda_n, Lambda_t (N s)
};

/// Stronge's energetic restitution with Coulomb friction for one planar contact, integrated
/// exactly in impulse space: with the normal impulse P as the time-like variable, the contact
/// velocities (zeta_n, zeta_t) are piecewise linear in P (d zeta / dP = G (1, r), r = dLambda_t / dP:
/// -mu sign(zeta_t) while slipping, -G_tn / G_tt while sticking, which needs |G_tn| <= mu G_tt, else
/// slip resumes along sign(G_tn)). Compression ends at zeta_n = 0 with the normal impulse's work
/// W_c = int zeta_n dP < 0; restitution ends when the total work is (1 - e^2) W_c. G: Delassus
/// matrix over the rows (normal, tangent), positive definite, G_nn + G_nt r > 0 on every segment
/// (no jam); zeta_n- < 0. A test-side reference (Stronge, Impact Mechanics, 2000, ch. 5), not a
/// law of the library.
StrongeExit stronge_planar(const Eigen::Matrix2d& G, double zeta_n, double zeta_t, double mu, double e) {
  StrongeExit out;
  double work = 0.0, target = 0.0;
  bool compressing = true;
  for (int segment = 0; segment < 16; ++segment) {
    double r;  // dLambda_t / dP on this segment
    if (zeta_t != 0.0)
      r = -mu * (zeta_t > 0 ? 1.0 : -1.0);
    else if (std::abs(G(1, 0)) <= mu * G(1, 1))
      r = -G(1, 0) / G(1, 1);
    else
      r = -mu * (G(1, 0) > 0 ? 1.0 : -1.0);
    const double a_n = G(0, 0) + G(0, 1) * r, a_t = G(1, 0) + G(1, 1) * r;
    EXPECT_GT(a_n, 0.0) << "the normal velocity must grow with the normal impulse (no jam)";
    enum class End { Slip, Compression, Restitution } end;
    double dp;
    if (compressing) {
      dp = -zeta_n / a_n;
      end = End::Compression;
    } else {  // work + zeta_n x + a_n x^2 / 2 = target, zeta_n >= 0
      dp = (-zeta_n + std::sqrt(zeta_n * zeta_n + 2.0 * a_n * (target - work))) / a_n;
      end = End::Restitution;
    }
    if (zeta_t != 0.0 && a_t * zeta_t < 0.0 && -zeta_t / a_t < dp) {
      dp = -zeta_t / a_t;
      end = End::Slip;
    }
    work += zeta_n * dp + 0.5 * a_n * dp * dp;
    zeta_n += a_n * dp;
    zeta_t = end == End::Slip ? 0.0 : zeta_t + a_t * dp;
    out.normal += dp;
    out.tangent += r * dp;
    if (end == End::Compression) {
      zeta_n = 0.0;
      compressing = false;
      target = (1.0 - e * e) * work;
      if (e == 0.0) break;
    } else if (end == End::Restitution) {
      break;
    }
  }
  out.zeta_n = zeta_n;
  out.zeta_t = zeta_t;
  return out;
}

/// Kinetic energy change of impulses Lambda = (Lambda_n, Lambda_t) at contact velocities zeta-:
/// Lambda^T zeta- + Lambda^T G Lambda / 2 (J per unit of the scene's mass units).
double energy_change(const Eigen::Matrix2d& G, double zeta_n, double zeta_t, const StrongeExit& s) {
  const Eigen::Vector2d lambda(s.normal, s.tangent);
  return lambda.dot(Eigen::Vector2d(zeta_n, zeta_t)) + 0.5 * lambda.dot(G * lambda);
}

constexpr double kE = 0.5, kMu = 0.5;
constexpr double kTol = 1e-12;

TEST(ImpactLaw, DiskDroppedOnASlopeRollsUnderNewtonAndLeavesOverSpunUnderTheDefault) {
  const double V = 2.0;
  DiskOnSlope newton(kMu, kE, 0.0), common(kMu, kE, std::nullopt);
  const double a = newton.alpha, r = newton.r;
  const Vec<6> x_minus(0.0, r, 0.0, -V * std::sin(a), -V * std::cos(a), 0.0);
  const double zt = x_minus[3], zn = x_minus[4];  // zeta_t-, zeta_n- (no spin)

  ImpactSolver<DiskOnSlope> newton_solver(newton), common_solver(common);
  const ImpactResult<DiskOnSlope> n = newton_solver.solve(x_minus);
  const ImpactResult<DiskOnSlope> c = common_solver.solve(x_minus);
  for (const auto* res : {&n, &c}) {
    EXPECT_EQ(res->impulse_mode[0].role, ImpulseRole::Stick);
    EXPECT_NEAR(res->x_plus[4], -kE * zn, kTol);  // h'+ = e |zeta_n-|
    EXPECT_NEAR(res->impulse[0].normal, (1 + kE) * newton.m * -zn, kTol);
    EXPECT_LE(res->kinetic_energy_plus, res->kinetic_energy_minus);
  }
  // Newton: s'+ = (2/3) s'-, r theta'+ = -(2/3) s'-, zeta_t+ = 0 (rolling).
  EXPECT_NEAR(n.x_plus[3], 2.0 / 3.0 * zt, kTol);
  EXPECT_NEAR(r * n.x_plus[5], -2.0 / 3.0 * zt, kTol);
  EXPECT_NEAR(n.tangent_velocity_plus[0][0], 0.0, kTol);
  EXPECT_NEAR(n.kinetic_energy_plus, 17.0 / 24.0, kTol);
  // Default: s'+ = (2 - e)/3 s'-, r theta'+ = -2 (1 + e)/3 s'-, zeta_t+ = -e zeta_t- (over-spun).
  EXPECT_NEAR(c.x_plus[3], (2 - kE) / 3 * zt, kTol);
  EXPECT_NEAR(r * c.x_plus[5], -2 * (1 + kE) / 3 * zt, kTol);
  EXPECT_NEAR(c.tangent_velocity_plus[0][0], -kE * zt, kTol);
  EXPECT_NEAR(c.kinetic_energy_plus, 0.75, kTol);
  EXPECT_TRUE(c.coefficients.energy_consistent);
  EXPECT_FALSE(n.coefficients.energy_consistent);
  // Stronge's energetic law (G = diag(1/m, 3/m)): Newton's exit, zeta_t+ = 0.
  const Eigen::Matrix2d G = Eigen::Vector2d(1.0 / newton.m, 3.0 / newton.m).asDiagonal();
  const StrongeExit s = stronge_planar(G, zn, zt, kMu, kE);
  EXPECT_NEAR(s.zeta_n, n.x_plus[4], kTol);
  EXPECT_NEAR(s.zeta_t, 0.0, kTol);
  EXPECT_NEAR(s.normal, n.impulse[0].normal, kTol);
  EXPECT_NEAR(s.tangent, n.impulse[0].tangent[0], kTol);
  EXPECT_NEAR(energy_change(G, zn, zt, s), n.kinetic_energy_plus - n.kinetic_energy_minus, kTol);
  std::printf("disk on a 30 deg slope, V = 2 m/s, e = %.1f, mu = %.1f:\n", kE, kMu);
  std::printf("  %-8s s'+ = %+.6f m/s  theta'+ = %+.6f rad/s  zeta_t+ = %+.6f m/s  h'+ = %.6f m/s  KE+ = %.6f J (KE- = %.1f J)\n",
              "newton", n.x_plus[3], n.x_plus[5], n.tangent_velocity_plus[0][0], n.x_plus[4], n.kinetic_energy_plus,
              n.kinetic_energy_minus);
  std::printf("  %-8s s'+ = %+.6f m/s  theta'+ = %+.6f rad/s  zeta_t+ = %+.6f m/s  h'+ = %.6f m/s  KE+ = %.6f J\n",
              "default", c.x_plus[3], c.x_plus[5], c.tangent_velocity_plus[0][0], c.x_plus[4], c.kinetic_energy_plus);
  std::printf("  %-8s zeta_t+ = %+.6f m/s  h'+ = %.6f m/s  KE+ = %.6f J\n", "stronge", s.zeta_t, s.zeta_n,
              n.kinetic_energy_minus + energy_change(G, zn, zt, s));
}

TEST(ImpactLaw, DiskOnASteepSlopeSlipsUnderTheDefaultWhereNewtonSticks) {
  // tan(alpha) between 3 mu and 3 mu (1 + e): Newton's law sticks, the default law slips,
  // zeta_t+ = zeta_t- + 3 mu (1 + e) |zeta_n-| (G_tt / G_nn = 3), still reversed.
  DiskOnSlope newton(kMu, kE, 0.0), common(kMu, kE, std::nullopt);
  const double a = std::atan(3 * kMu * (1 + 0.5 * kE));  // tan(alpha) = 1.875 in (1.5, 2.25)
  newton.alpha = common.alpha = a;
  const Vec<6> x_minus(0.0, newton.r, 0.0, -2.0 * std::sin(a), -2.0 * std::cos(a), 0.0);
  const double zt = x_minus[3], zn = x_minus[4];
  ImpactSolver<DiskOnSlope> newton_solver(newton), common_solver(common);
  const ImpactResult<DiskOnSlope> n = newton_solver.solve(x_minus);
  const ImpactResult<DiskOnSlope> c = common_solver.solve(x_minus);
  EXPECT_EQ(n.impulse_mode[0].role, ImpulseRole::Stick);
  EXPECT_NEAR(n.tangent_velocity_plus[0][0], 0.0, kTol);
  const StrongeExit s = stronge_planar(Eigen::Vector2d(1.0, 3.0).asDiagonal(), zn, zt, kMu, kE);  // m = 1
  EXPECT_NEAR(s.zeta_t, 0.0, kTol);  // Stronge's exit is Newton's: rolling
  EXPECT_NEAR(s.zeta_n, n.x_plus[4], kTol);
  EXPECT_EQ(c.impulse_mode[0].role, ImpulseRole::Slip);
  EXPECT_NEAR(c.tangent_velocity_plus[0][0], zt + 3 * kMu * (1 + kE) * -zn, kTol);
  EXPECT_GT(c.tangent_velocity_plus[0][0], 0.0);
}

TEST(ImpactLaw, BoxLandingWhileSlidingBouncesBackwardUnderTheDefault) {
  SlidingBox newton(kMu, kE, 0.0), common(kMu, kE, std::nullopt);
  ImpactSolver<SlidingBox> newton_solver(newton), common_solver(common);
  const double w = 3.0;
  std::printf("box landing at y' = -%.1f m/s, e = %.1f, mu = %.1f:\n", w, kE, kMu);
  for (double u : {1.0, 2.0, 3.0}) {
    const Vec<4> x_minus(0.0, 0.0, u, -w);
    const ImpactResult<SlidingBox> n = newton_solver.solve(x_minus);
    const ImpactResult<SlidingBox> c = common_solver.solve(x_minus);
    const double slip = u - kMu * (1 + kE) * w;
    EXPECT_NEAR(n.x_plus[2], std::max(0.0, slip), kTol) << "u = " << u;
    EXPECT_NEAR(c.x_plus[2], std::max(-kE * u, slip), kTol) << "u = " << u;
    EXPECT_NEAR(n.x_plus[3], kE * w, kTol);
    EXPECT_NEAR(c.x_plus[3], kE * w, kTol);
    EXPECT_EQ(c.impulse_mode[0].role, -kE * u >= slip ? ImpulseRole::Stick : ImpulseRole::Slip) << "u = " << u;
    EXPECT_LE(c.kinetic_energy_plus, c.kinetic_energy_minus);
    const StrongeExit s = stronge_planar(Eigen::Matrix2d::Identity(), -w, u, kMu, kE);  // m = 1
    EXPECT_NEAR(s.zeta_t, n.x_plus[2], kTol) << "u = " << u;  // Stronge's exit is Newton's
    EXPECT_NEAR(s.zeta_n, n.x_plus[3], kTol) << "u = " << u;
    EXPECT_LE(energy_change(Eigen::Matrix2d::Identity(), -w, u, s), 0.0);
    std::printf("  x'- = %.1f m/s: newton x'+ = %+.4f m/s (KE+ %.4f J), default x'+ = %+.4f m/s (KE+ %.4f J), KE- %.1f J\n",
                u, n.x_plus[2], n.kinetic_energy_plus, c.x_plus[2], c.kinetic_energy_plus, c.kinetic_energy_minus);
  }
}

}  // namespace
}  // namespace saltus::testing
