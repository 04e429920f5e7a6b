#define EIGEN_RUNTIME_NO_MALLOC
// The contact solvers: Lemke on the planar LCP and the semismooth Newton Coulomb solver, on
// closed-form cases, on thousands of random mechanical problems (A = J M^{-1} J^T, singular
// when contacts are redundant), for heap allocations and for bad input.
//
// Eigen reports a forbidden heap allocation through eigen_assert, which NDEBUG (Release)
// silences; it is routed here to an exception that every build reports.
#include <stdexcept>
#include <string>

namespace saltus_test {
[[noreturn]] inline void eigen_assert_failed(const char* cond, const char* file, int line) {
  throw std::logic_error(std::string("eigen_assert(") + cond + ") failed at " + file + ":" +
                         std::to_string(line));
}
}  // namespace saltus_test
#define eigen_assert(x) \
  ((x) ? static_cast<void>(0) : ::saltus_test::eigen_assert_failed(#x, __FILE__, __LINE__))

// The solvers are instantiated here from their definitions (.hxx), not taken from the library,
// so that they are compiled with EIGEN_RUNTIME_NO_MALLOC and the eigen_assert above: that is
// what makes SolveDoesNotAllocate see their allocations.
#define SALTUS_CONTACT_NO_EXTERN_TEMPLATES
#include <saltus/hybrid/contact/coulomb_solver.hxx>
#include <saltus/hybrid/contact/lemke.hxx>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <sstream>
#include <vector>

namespace {

constexpr int MC = 4;
using Problem = saltus::ContactProblem<MC>;
using Solution = saltus::ContactSolution<MC>;
using Lemke = saltus::LemkeSolver<MC>;
using Coulomb = saltus::CoulombSolver<MC>;
using saltus::ContactSolveStatus;
using Eigen::MatrixXd;
using Eigen::VectorXd;

const Eigen::IOFormat full(17, 0, ", ", "\n", "  [", "]");

std::string describe(const Problem& p) {
  std::ostringstream os;
  os.precision(17);
  os << p.contacts << " contacts:";
  for (int k = 0; k < p.contacts; ++k)
    os << " (row " << p.row[k] << ", " << p.tangents[k] << " tangents, mu " << p.mu[k] << ")";
  os << "\nA =\n" << p.A.format(full) << "\nb = " << p.b.transpose().format(full) << "\n";
  return os.str();
}

std::string describe(const Problem& p, const Solution& s) {
  std::ostringstream os;
  os.precision(17);
  os << describe(p) << "lambda = " << s.lambda.transpose().format(full)
     << "\ny = " << s.y.transpose().format(full) << "\nresidual = " << s.residual
     << ", iterations = " << s.iterations << ", status = " << saltus::to_string(s.status) << "\n";
  return os.str();
}

// Scales of lambda and y used by natural_map_residual: ||lambda|| + rho ||b|| and that / rho.
struct Scales {
  double lambda, y;
};
Scales scales(const Problem& p, const Solution& s) {
  const double rho = saltus::contact_problem_scale(p);
  const int m = p.rows();
  const double l = (m > 0 ? s.lambda.cwiseAbs().maxCoeff() : 0.0) +
                   rho * (m > 0 ? p.b.cwiseAbs().maxCoeff() : 0.0);
  return {l, l / rho};
}

// Signorini, the friction cone and the slip direction, checked law by law (the natural-map
// residual bounds all of them, this says which one fails).
::testing::AssertionResult satisfies_laws(const Problem& p, const Solution& s, double tol) {
  const Scales sc = scales(p, s);
  for (int k = 0; k < p.contacts; ++k) {
    const int r = p.row[k], nt = p.tangents[k];
    const double ln = s.lambda[r], yn = s.y[r];
    if (ln < -tol * sc.lambda)
      return ::testing::AssertionFailure() << "contact " << k << ": lambda_n = " << ln;
    if (yn < -tol * sc.y)
      return ::testing::AssertionFailure() << "contact " << k << ": y_n = " << yn;
    if (std::min(ln / sc.lambda, yn / sc.y) > 10 * tol)
      return ::testing::AssertionFailure()
             << "contact " << k << ": complementarity lambda_n = " << ln << ", y_n = " << yn;
    if (nt == 0) continue;
    const VectorXd lt = s.lambda.segment(r + 1, nt), yt = s.y.segment(r + 1, nt);
    const double radius = p.mu[k] * std::max(ln, 0.0);
    if (lt.norm() > radius + tol * sc.lambda)
      return ::testing::AssertionFailure()
             << "contact " << k << ": |lambda_t| = " << lt.norm() << " > mu lambda_n = " << radius;
    // Sliding: lambda_t = -mu lambda_n y_t / |y_t|. A residual r bounds the angle between
    // lambda_t and -y_t by about r |lambda| / (rho |y_t|): the tolerance grows as y_t -> 0.
    if (yt.norm() > 1e-6 * sc.y) {
      const VectorXd expect = -radius * yt / yt.norm();
      if ((lt - expect).norm() > 10 * tol * sc.lambda * std::max(1.0, sc.y / yt.norm()))
        return ::testing::AssertionFailure()
               << "contact " << k << ": slipping with y_t = " << yt.transpose()
               << " but lambda_t = " << lt.transpose() << ", expected " << expect.transpose();
    }
  }
  return ::testing::AssertionSuccess();
}

// ---- closed-form cases -----------------------------------------------------------------------

TEST(ContactSolvers, SeparatingContactsGiveZeroForce) {
  Problem p;
  p.add_contact(1, 0.5);
  p.add_contact(0, 0.0);
  p.add_contact(1, 0.2);
  p.resize();
  p.A << 2, 0.3, 0.1, 0, 0.2, //
      0.3, 1, 0, 0.1, 0,      //
      0.1, 0, 1.5, 0.2, 0.1,  //
      0, 0.1, 0.2, 3, 0,      //
      0.2, 0, 0.1, 0, 1;
  p.b << 0.5, -1.0, 0.0, 2.0, 3.0;  // normals 0.5, 0, 2 are >= 0; tangential velocities vary
  Solution s;
  Lemke lemke;
  Coulomb coulomb;
  for (int which = 0; which < 2; ++which) {
    const auto status = which == 0 ? lemke.solve(p, s) : coulomb.solve(p, s);
    EXPECT_EQ(status, ContactSolveStatus::Solved) << describe(p, s);
    EXPECT_EQ(s.lambda.cwiseAbs().maxCoeff(), 0.0) << describe(p, s);
    EXPECT_EQ(s.residual, 0.0) << describe(p, s);
  }
}

TEST(ContactSolvers, SingleFrictionlessContact) {
  Lemke lemke;
  Coulomb coulomb;
  Solution s;
  for (double a : {1e-6, 0.37, 1.0, 42.0, 3e5}) {
    for (double b : {-2.5, -1e-3, 0.0, 0.8}) {
      Problem p;
      p.add_contact(0, 0.0);
      p.resize();
      p.A << a;
      p.b << b;
      const double expected = std::max(0.0, -b / a);
      for (int which = 0; which < 2; ++which) {
        const auto status = which == 0 ? lemke.solve(p, s) : coulomb.solve(p, s);
        EXPECT_EQ(status, ContactSolveStatus::Solved) << describe(p, s);
        EXPECT_NEAR(s.lambda[0], expected, 1e-14 * expected) << describe(p, s);
        EXPECT_LE(s.residual, 1e-15) << describe(p, s);
      }
    }
  }
}

// A point mass m hits a table with velocity (vt, vn < 0), no restitution: the normal impulse
// stops it, Lambda_n = -m vn; it slides on if |vt| > mu |vn| with Lambda_t = -mu Lambda_n
// sign(vt), else sticks with Lambda_t = -m vt.
TEST(ContactSolvers, PointMassHittingATable) {
  Lemke lemke;
  Coulomb coulomb;
  Solution s;
  for (double mass : {1.0, 2.5}) {
    for (double mu : {0.0, 0.3, 1.0}) {
      for (double vt : {-2.0, -0.2, 0.0, 0.29, 0.31, 3.0}) {
        const double vn = -1.0;
        Problem p;
        p.add_contact(1, mu);
        p.resize();
        p.A << 1 / mass, 0, 0, 1 / mass;
        p.b << vn, vt;
        const double Ln = -mass * vn;
        const double Lt = std::abs(vt) > mu * std::abs(vn)
                              ? -mu * Ln * (vt > 0 ? 1.0 : vt < 0 ? -1.0 : 0.0)
                              : -mass * vt;
        for (int which = 0; which < 2; ++which) {
          const auto status = which == 0 ? lemke.solve(p, s) : coulomb.solve(p, s);
          SCOPED_TRACE(which == 0 ? "Lemke" : "CoulombSolver");
          EXPECT_EQ(status, ContactSolveStatus::Solved) << describe(p, s);
          EXPECT_NEAR(s.lambda[0], Ln, 1e-14 * Ln) << describe(p, s);
          EXPECT_NEAR(s.lambda[1], Lt, 1e-14 * Ln) << describe(p, s);
          EXPECT_LE(s.residual, 1e-14) << describe(p, s);
        }
      }
    }
  }
}

// The same, spatial: the tangential velocity is a vector, the impulse opposes it on the disk.
TEST(ContactSolvers, PointMassHittingATableSpatial) {
  Coulomb coulomb;
  Solution s;
  const double mu = 0.5, vn = -2.0;
  for (double angle : {0.0, 0.7, 2.0, -2.9}) {
    for (double speed : {0.0, 0.5, 0.99, 1.01, 4.0}) {
      Problem p;
      p.add_contact(2, mu);
      p.resize();
      p.A.setIdentity();
      p.b << vn, speed * std::cos(angle), speed * std::sin(angle);
      const double Ln = -vn;
      const Eigen::Vector2d vt = p.b.tail<2>();
      const Eigen::Vector2d Lt = vt.norm() > mu * Ln ? Eigen::Vector2d(-mu * Ln * vt / vt.norm())
                                                     : Eigen::Vector2d(-vt);
      EXPECT_EQ(coulomb.solve(p, s), ContactSolveStatus::Solved) << describe(p, s);
      EXPECT_NEAR(s.lambda[0], Ln, 1e-14 * Ln) << describe(p, s);
      EXPECT_NEAR((s.lambda.tail<2>() - Lt).norm(), 0.0, 1e-14 * Ln) << describe(p, s);
    }
  }
}

// ---- random mechanical problems ---------------------------------------------------------------

struct Rng {
  std::mt19937_64 gen;
  explicit Rng(std::uint64_t seed) : gen(seed) {}
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(gen); }
  double normal() { return std::normal_distribution<double>(0.0, 1.0)(gen); }
  int integer(int a, int b) { return std::uniform_int_distribution<int>(a, b)(gen); }
  MatrixXd normal(int r, int c) {
    MatrixXd x(r, c);
    for (int i = 0; i < r; ++i)
      for (int j = 0; j < c; ++j) x(i, j) = normal();
    return x;
  }
  // Symmetric positive definite, condition number up to ~1e3, overall scale 1e-2..1e2.
  MatrixXd spd(int n) {
    const MatrixXd B = normal(n, n);
    const double scale = std::pow(10.0, uniform(-2, 2));
    return scale * (B * B.transpose() + 0.05 * n * MatrixXd::Identity(n, n));
  }
};

// Fills A = J M^{-1} J^T and b = J v (b in the range of J, as for an impact: the problem then
// has a solution even when A is singular), or a fully random b when J has full row rank.
void fill(Problem& p, const MatrixXd& J, const MatrixXd& M, Rng& rng, bool random_b) {
  p.resize();
  const MatrixXd A = J * M.ldlt().solve(J.transpose());
  p.A = 0.5 * (A + A.transpose());
  const double speed = std::pow(10.0, rng.uniform(-2, 2));
  VectorXd b;
  if (random_b) {
    b = speed * rng.normal(static_cast<int>(J.rows()), 1);
  } else {
    b = J * (speed * rng.normal(static_cast<int>(J.cols()), 1));
  }
  // The first contact approaches, so that most problems are not the trivial one.
  if (b[0] > 0) b = -b;
  p.b = b;
}

struct Generated {
  Problem p;
  std::string kind;
};

// Planar problems with 1..4 contacts (0 or 1 tangent) on n = 3..6 generalised velocities,
// including rank-deficient ones: duplicated contacts, identical tangent rows, more rows than
// velocities, a rigid body landing flat on two corners.
Generated random_planar(Rng& rng) {
  Generated out;
  Problem& p = out.p;
  p.reset();
  const int kind = rng.integer(0, 4);
  const int n = kind == 4 ? 3 : rng.integer(3, 6);
  const int nc = kind == 4 ? 2 : kind == 1 || kind == 3 ? rng.integer(2, 4) : rng.integer(1, 4);
  for (int k = 0; k < nc; ++k) {
    const bool friction = kind == 3 || kind == 4 || rng.uniform(0, 1) < 0.8;
    const double mu = friction ? (rng.uniform(0, 1) < 0.1 ? 0.0 : rng.uniform(0.05, 1.5)) : 0.0;
    p.add_contact(friction ? 1 : 0, mu);
  }
  const int m = p.rows();
  MatrixXd J = rng.normal(m, n);
  MatrixXd M = rng.spd(n);
  bool random_b = false;
  switch (kind) {
    case 0:
      out.kind = "generic";
      random_b = m <= n;
      break;
    case 1: {  // the last contact duplicates the first (same rows where both have them)
      out.kind = "duplicate contact";
      const int last = p.contacts - 1;
      J.row(p.row[last]) = J.row(0);
      if (p.tangents[last] == 1 && p.tangents[0] == 1) J.row(p.row[last] + 1) = J.row(1);
      break;
    }
    case 2:
      out.kind = "more rows than velocities";
      if (m <= n) {  // make it so: drop velocities
        J = J.leftCols(std::max(1, m - 1)).eval();
        M = rng.spd(static_cast<int>(J.cols()));
      }
      break;
    case 3: {  // all contacts share the tangent row (one sliding direction)
      out.kind = "identical tangent rows";
      for (int k = 1; k < p.contacts; ++k) J.row(p.row[k] + 1) = J.row(1);
      break;
    }
    case 4: {  // planar box (x, z, theta) on its two bottom corners: 4 rows, rank 3
      out.kind = "box on two corners";
      const double w = rng.uniform(0.1, 2), h = rng.uniform(0.1, 2), mass = rng.uniform(0.1, 10);
      M = MatrixXd::Zero(3, 3);
      M.diagonal() << mass, mass, mass * (w * w + h * h) / 3;
      J = MatrixXd::Zero(4, 3);
      for (int k = 0; k < 2; ++k) {
        const double rx = k == 0 ? -w : w, rz = -h;
        J.row(2 * k) << 0, 1, rx;      // normal velocity of the corner
        J.row(2 * k + 1) << 1, 0, -rz;  // tangential velocity
      }
      break;
    }
  }
  fill(p, J, M, rng, random_b);
  return out;
}

TEST(ContactSolvers, RandomPlanarProblems) {
  Rng rng(20240611);
  Lemke lemke;
  Coulomb coulomb;
  Solution sl, sc;
  const int count = 3000;
  double worst_lemke = 0, worst_coulomb = 0, worst_y = 0;
  int lemke_pivots = 0, coulomb_iterations = 0, frictionless = 0, failures = 0;
  for (int i = 0; i < count && failures < 10; ++i) {
    const Generated pr = random_planar(rng);
    const Problem& p = pr.p;
    const auto status = lemke.solve(p, sl);
    SCOPED_TRACE(::testing::Message() << "problem " << i << " (" << pr.kind << ")");
    const int before = ::testing::Test::HasFailure() ? 1 : 0;
    EXPECT_EQ(status, ContactSolveStatus::Solved) << describe(p, sl);
    EXPECT_LE(sl.residual, 1e-12) << "Lemke\n" << describe(p, sl);
    EXPECT_TRUE(satisfies_laws(p, sl, 1e-12)) << "Lemke\n" << describe(p, sl);
    worst_lemke = std::max(worst_lemke, sl.residual);
    lemke_pivots = std::max(lemke_pivots, sl.iterations);

    coulomb.solve(p, sc);
    EXPECT_LE(sc.residual, 1e-12) << "CoulombSolver\n" << describe(p, sc);
    EXPECT_TRUE(satisfies_laws(p, sc, 1e-12)) << "CoulombSolver\n" << describe(p, sc);
    worst_coulomb = std::max(worst_coulomb, sc.residual);
    coulomb_iterations = std::max(coulomb_iterations, sc.iterations);

    // Without friction the post-impact velocities are unique (they minimise the kinetic
    // energy over a convex set), hence y = J v+ must agree; with friction only the residuals.
    bool has_friction = false;
    for (int k = 0; k < p.contacts; ++k) has_friction |= p.tangents[k] > 0 && p.mu[k] > 0;
    if (!has_friction) {
      ++frictionless;
      const double ys = scales(p, sl).y;
      const double dy = (sl.y - sc.y).cwiseAbs().maxCoeff() / ys;
      worst_y = std::max(worst_y, dy);
      EXPECT_LE(dy, 1e-9) << "Lemke\n" << describe(p, sl) << "CoulombSolver\n" << describe(p, sc);
    }
    if (::testing::Test::HasFailure() && !before) ++failures;
  }
  std::printf("  %d planar problems (%d frictionless): worst residual Lemke %.3g, Coulomb %.3g;\n"
              "  worst relative y difference (frictionless) %.3g; max pivots %d, max Coulomb "
              "iterations %d\n",
              count, frictionless, worst_lemke, worst_coulomb, worst_y, lemke_pivots,
              coulomb_iterations);
}

// A contact already slipping in a known direction s (acceleration level) is passed without
// tangent, its friction -mu s lambda_n folded into the column of its normal: A is then not
// symmetric, and the problem may have no solution (Painleve). Lemke must be exact whenever it
// reports a solution, and CoulombSolver must find one whenever Lemke does.
TEST(ContactSolvers, NonSymmetricProblemsFromPrescribedSlip) {
  Rng rng(31);
  Lemke lemke;
  Coulomb coulomb;
  Solution sl, sc;
  const int count = 2000;
  int lemke_solved = 0, coulomb_solved = 0, nonsymmetric = 0;
  for (int i = 0; i < count; ++i) {
    Generated pr = random_planar(rng);
    const Problem& full = pr.p;
    Problem p;
    std::vector<int> rows;
    MatrixXd A = full.A;
    for (int k = 0; k < full.contacts; ++k) {
      const double mu = std::min(full.mu[k], 0.3);
      const bool slipping = full.tangents[k] == 1 && rng.uniform(0, 1) < 0.5;
      if (slipping) {
        const double s = rng.uniform(0, 1) < 0.5 ? 1.0 : -1.0;
        A.col(full.row[k]) -= mu * s * A.col(full.row[k] + 1);
      }
      p.add_contact(slipping ? 0 : full.tangents[k], mu);
      rows.push_back(full.row[k]);
      if (!slipping && full.tangents[k] == 1) rows.push_back(full.row[k] + 1);
    }
    p.resize();
    for (std::size_t a = 0; a < rows.size(); ++a) {
      p.b[a] = full.b[rows[a]];
      for (std::size_t c = 0; c < rows.size(); ++c) p.A(a, c) = A(rows[a], rows[c]);
    }
    nonsymmetric += !p.A.isApprox(p.A.transpose());
    SCOPED_TRACE(::testing::Message() << "problem " << i);
    if (lemke.solve(p, sl) == ContactSolveStatus::Solved) {
      ++lemke_solved;
      EXPECT_LE(sl.residual, 1e-12) << describe(p, sl);
      EXPECT_TRUE(satisfies_laws(p, sl, 1e-12)) << describe(p, sl);
      coulomb.solve(p, sc);
      coulomb_solved += sc.residual <= 1e-12;
      EXPECT_LE(sc.residual, 1e-12) << describe(p, sc);
    }
  }
  std::printf("  %d problems (%d non-symmetric): Lemke solved %d, CoulombSolver %d of those\n",
              count, nonsymmetric, lemke_solved, coulomb_solved);
  EXPECT_GE(lemke_solved, count * 95 / 100);
}

// Spatial contacts (2 tangents): random J, and a rigid box on 2, 3 or 4 coplanar corners, for
// which A is 6x6, 9x9 or 12x12 of rank at most 6.
Generated random_spatial(Rng& rng, bool mixed) {
  Generated out;
  Problem& p = out.p;
  p.reset();
  const int kind = rng.integer(0, 2);
  if (kind == 2) {
    out.kind = "box on corners";
    const int nc = rng.integer(2, 4);
    for (int k = 0; k < nc; ++k)
      p.add_contact(2, rng.uniform(0, 1) < 0.05 ? 0.0 : rng.uniform(0.05, 1.5));
    const double a = rng.uniform(0.1, 2), b = rng.uniform(0.1, 2), c = rng.uniform(0.1, 2);
    const double mass = std::pow(10.0, rng.uniform(-1, 1));
    MatrixXd M = MatrixXd::Zero(6, 6);
    M.topLeftCorner(3, 3) = mass * Eigen::Matrix3d::Identity();
    Eigen::Vector4d quaternion;
    for (int i = 0; i < 4; ++i) quaternion[i] = rng.normal();  // sequenced: reproducible
    const Eigen::Matrix3d R = Eigen::Quaterniond(quaternion.normalized()).toRotationMatrix();
    const Eigen::Vector3d I(mass * (b * b + c * c) / 3, mass * (a * a + c * c) / 3,
                            mass * (a * a + b * b) / 3);
    M.bottomRightCorner(3, 3) = R * I.asDiagonal() * R.transpose();
    const double corners[4][2] = {{-a, -b}, {a, -b}, {a, b}, {-a, b}};
    MatrixXd J = MatrixXd::Zero(3 * nc, 6);
    for (int k = 0; k < nc; ++k) {
      const Eigen::Vector3d r(corners[k][0], corners[k][1], -c);
      Eigen::Matrix3d rx;
      rx << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
      Eigen::Matrix<double, 3, 6> Jc;
      Jc << Eigen::Matrix3d::Identity(), -rx;  // corner velocity v + omega x r
      J.row(3 * k) = Jc.row(2);                // normal: z
      J.row(3 * k + 1) = Jc.row(0);
      J.row(3 * k + 2) = Jc.row(1);
    }
    fill(p, J, M, rng, false);
    return out;
  }
  const int n = rng.integer(3, 6);
  const int nc = rng.integer(1, 4);
  for (int k = 0; k < nc; ++k) {
    const int nt = mixed ? rng.integer(0, 2) : 2;
    p.add_contact(nt, nt == 0 || rng.uniform(0, 1) < 0.05 ? 0.0 : rng.uniform(0.05, 1.5));
  }
  const int m = p.rows();
  MatrixXd J = rng.normal(m, n);
  if (kind == 1 && nc > 1) {
    out.kind = "duplicate contact";
    const int last = p.contacts - 1;
    const int rows = std::min(1 + p.tangents[last], 1 + p.tangents[0]);
    J.middleRows(p.row[last], rows) = J.topRows(rows);
  } else {
    out.kind = "generic";
  }
  fill(p, J, rng.spd(n), rng, m <= n && out.kind == "generic");
  return out;
}

void run_spatial(bool mixed, std::uint64_t seed) {
  Rng rng(seed);
  Coulomb coulomb;
  Solution s;
  const int count = 2000;
  int bad = 0, nan = 0, solved = 0, max_iterations = 0;
  double worst = 0;
  Problem worst_problem;
  Solution worst_solution;
  for (int i = 0; i < count; ++i) {
    const Generated pr = random_spatial(rng, mixed);
    const Problem& p = pr.p;
    const auto status = coulomb.solve(p, s);
    solved += status == ContactSolveStatus::Solved;
    max_iterations = std::max(max_iterations, s.iterations);
    if (!s.lambda.allFinite() || !s.y.allFinite() || std::isnan(s.residual)) {
      ++nan;
      ADD_FAILURE() << "non-finite result, problem " << i << "\n" << describe(p, s);
    }
    if (!(s.residual <= 1e-12)) ++bad;
    if (!(s.residual <= worst)) {
      worst = s.residual;
      worst_problem = p;
      worst_solution = s;
    }
    if (s.residual <= 1e-12) {
      EXPECT_TRUE(satisfies_laws(p, s, 1e-12)) << i << "\n" << describe(p, s);
    }
  }
  std::printf("  %d %s problems: %d with residual > 1e-12, %d at the 1e-14 tolerance, max "
              "iterations %d, worst residual %.3g\n",
              count, mixed ? "mixed 0/1/2-tangent" : "spatial", bad, solved, max_iterations, worst);
  EXPECT_EQ(nan, 0);
  EXPECT_LE(bad, count / 1000) << "worst case:\n" << describe(worst_problem, worst_solution);
  if (worst > 1e-12)
    std::printf("  worst case:\n%s", describe(worst_problem, worst_solution).c_str());
}

TEST(ContactSolvers, RandomSpatialProblems) { run_spatial(false, 777); }
TEST(ContactSolvers, RandomMixedProblems) { run_spatial(true, 4242); }

TEST(ContactSolvers, WarmStartFromASolutionReturnsAtOnce) {
  Rng rng(99);
  Coulomb coulomb;
  Solution s, s2;
  for (int i = 0; i < 50; ++i) {
    const Generated pr = random_spatial(rng, false);
    coulomb.solve(pr.p, s);
    ASSERT_LE(s.residual, 1e-12) << describe(pr.p, s);
    const Problem::Vector guess = s.lambda;
    coulomb.solve(pr.p, s2, &guess);
    EXPECT_LE(s2.residual, s.residual) << describe(pr.p, s2);
    if (s.status == ContactSolveStatus::Solved) {
      EXPECT_EQ(s2.iterations, 0) << describe(pr.p, s2);
    }
  }
}

// ---- no heap allocation in solve() ------------------------------------------------------------

struct NoMalloc {
  NoMalloc() { Eigen::internal::set_is_malloc_allowed(false); }
  ~NoMalloc() { Eigen::internal::set_is_malloc_allowed(true); }
  NoMalloc(const NoMalloc&) = delete;
  NoMalloc& operator=(const NoMalloc&) = delete;
};

TEST(ContactSolvers, SolveDoesNotAllocate) {
  Rng rng(5);
  Lemke lemke;
  Coulomb coulomb;
  // Unreachable targets drive every fallback path: all of Lemke's retries, and Newton's
  // stalls, the polyhedral LCP restarts and the Gauss-Seidel sweeps of CoulombSolver.
  Lemke::Options lemke_options;
  lemke_options.retry_residual = 0.0;
  Lemke lemke_retrying(lemke_options);
  Coulomb::Options coulomb_options;
  coulomb_options.tolerance = 0.0;
  Coulomb coulomb_stalling(coulomb_options);
  Solution s;
  // Problems are built (with heap-allocating MatrixXd) first, then solved with the heap off.
  std::vector<Problem> planar, spatial;
  for (int i = 0; i < 40; ++i) planar.push_back(random_planar(rng).p);
  for (int i = 0; i < 40; ++i) spatial.push_back(random_spatial(rng, i % 2 == 1).p);
  {
    NoMalloc guard;
    for (const Problem& p : planar) {
      EXPECT_NO_THROW(lemke.solve(p, s)) << describe(p);
      EXPECT_NO_THROW(lemke_retrying.solve(p, s)) << describe(p);
      EXPECT_NO_THROW(coulomb.solve(p, s)) << describe(p);
      EXPECT_NO_THROW(coulomb_stalling.solve(p, s)) << describe(p);
    }
    for (const Problem& p : spatial) {
      EXPECT_NO_THROW(coulomb.solve(p, s)) << describe(p);
      const Problem::Vector guess = s.lambda;
      EXPECT_NO_THROW(coulomb.solve(p, s, &guess)) << describe(p);
      EXPECT_NO_THROW(coulomb_stalling.solve(p, s)) << describe(p);
    }
  }
  // The fallback paths return the best point met, as good as the direct one.
  for (const Problem& p : spatial) {
    coulomb_stalling.solve(p, s);
    EXPECT_LE(s.residual, 1e-12) << describe(p, s);
  }
  // And the check itself works: a dynamic-size Eigen temporary is caught.
  bool caught = false;
  {
    NoMalloc guard;
    try {
      const MatrixXd x = MatrixXd::Identity(7, 7);
      (void)x;
    } catch (const std::logic_error&) {
      caught = true;
    }
  }
  EXPECT_TRUE(caught) << "EIGEN_RUNTIME_NO_MALLOC does not report allocations";
}

// ---- bad input --------------------------------------------------------------------------------

TEST(ContactSolvers, LemkeRejectsSpatialContacts) {
  Problem p;
  p.add_contact(1, 0.3);
  p.add_contact(2, 0.3);
  p.resize();
  p.A.setIdentity();
  p.b.setConstant(-1.0);
  Lemke lemke;
  Solution s;
  try {
    lemke.solve(p, s);
    FAIL() << "no exception";
  } catch (const saltus::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("contact 1"), std::string::npos) << e.what();
  }
}

TEST(ContactSolvers, SolversRejectInconsistentInput) {
  Problem p;
  p.add_contact(1, -0.3);  // negative friction coefficient
  p.resize();
  p.A.setIdentity();
  p.b.setConstant(-1.0);
  Lemke lemke;
  Coulomb coulomb;
  Solution s;
  EXPECT_THROW(lemke.solve(p, s), saltus::InvalidArgument);
  EXPECT_THROW(coulomb.solve(p, s), saltus::InvalidArgument);
  p.mu[0] = 0.3;
  p.b[1] = std::nan("");
  EXPECT_THROW(lemke.solve(p, s), saltus::InvalidArgument);
  EXPECT_THROW(coulomb.solve(p, s), saltus::InvalidArgument);
  p.b[1] = 0.0;
  const Problem::Vector guess = Problem::Vector::Zero(3);
  EXPECT_THROW(coulomb.solve(p, s, &guess), saltus::InvalidArgument);
}

}  // namespace
