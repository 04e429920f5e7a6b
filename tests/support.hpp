// Shared test helpers: central differences, random states and modes, and matrix comparison
// that prints both matrices and the tolerance on failure.
#pragma once

#include "scenes/all_scenes.hpp"

#include <saltus/hybrid/dynamics/constraints.hpp>
#include <saltus/hybrid/dynamics/kinematics.hpp>
#include <saltus/hybrid/vocabulary/mode.hpp>
#include <saltus/hybrid/vocabulary/scene.hpp>
#include <saltus/hybrid/vocabulary/trajectory.hpp>

#include <Eigen/QR>

#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace saltus::testing {

/// Expects InvalidArgument whose message contains every one of `parts`.
template <class F>
void expect_invalid(F&& f, std::initializer_list<std::string> parts) {
  try {
    f();
    ADD_FAILURE() << "no InvalidArgument thrown";
  } catch (const InvalidArgument& e) {
    for (const std::string& p : parts) EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
  }
}

/// The eps values of a remainder-slope check (the validation protocol's eps^2 test): all of them
/// in the release stage. Under the sanitizers (tests/CMakeLists.txt defines
/// SALTUS_TESTS_UNDER_SANITIZERS; the nonlinear runs there are 5-20 times slower) only the first
/// and the last: every run takes the same code paths, and the slope between the two ends of the
/// range is still checked. The release stage keeps the fit over every value.
inline std::vector<double> slope_eps(const std::vector<double>& eps) {
#if defined(SALTUS_TESTS_UNDER_SANITIZERS)
  if (eps.size() > 2) return {eps.front(), eps.back()};
#endif
  return eps;
}

/// Monte Carlo run counts: a quarter under the sanitizers (see slope_eps), at least 2.
inline int monte_carlo_runs(int runs) {
#if defined(SALTUS_TESTS_UNDER_SANITIZERS)
  return runs / 4 > 2 ? runs / 4 : 2;
#else
  return runs;
#endif
}

/// ||a - b||_inf <= abs_tol + rel_tol * ||b||_inf, reporting both matrices otherwise.
template <class A, class B>
::testing::AssertionResult matrices_near(const A& a, const B& b, double rel_tol, double abs_tol = 0.0) {
  if (a.size() == 0 && b.size() == 0) return ::testing::AssertionSuccess();  // maxCoeff of an empty matrix asserts
  const double err = (a - b).cwiseAbs().maxCoeff();
  const double scale = b.cwiseAbs().maxCoeff();
  if (err <= abs_tol + rel_tol * scale) return ::testing::AssertionSuccess();
  std::ostringstream os;
  os.precision(12);
  os << "max |a - b| = " << err << " > " << abs_tol << " + " << rel_tol << " * " << scale << "\n a =\n"
     << a << "\n b =\n"
     << b << "\n a - b =\n"
     << (a - b);
  return ::testing::AssertionFailure() << os.str();
}

/// Central-difference Jacobian of f: R^n -> R^m at x, with step h * max(1, |x_k|).
template <int M, int N, class F>
Mat<M, N> central_jacobian(F&& f, const Vec<N>& x, double h = 1e-6) {
  Mat<M, N> J;
  for (int k = 0; k < N; ++k) {
    const double step = h * std::max(1.0, std::abs(x[k]));
    Vec<N> xp = x, xm = x;
    xp[k] += step;
    xm[k] -= step;
    const Vec<M> fp = f(xp);
    const Vec<M> fm = f(xm);
    J.col(k) = (fp - fm) / (2 * step);
  }
  return J;
}

template <class Rng>
double uniform(Rng& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

template <int N, class Rng>
Vec<N> random_vector(Rng& rng, double amplitude) {
  Vec<N> v;
  for (int k = 0; k < N; ++k) v[k] = uniform(rng, -amplitude, amplitude);
  return v;
}

/// (a, b) stacked, e.g. x = (q, v).
template <int N>
Vec<2 * N> stack(const Vec<N>& a, const Vec<N>& b) {
  Vec<2 * N> x;
  for (int k = 0; k < N; ++k) {
    x[k] = a[k];
    x[N + k] = b[k];
  }
  return x;
}

/// A random mode: contacts open, sticking or slipping along a random direction, with at most
/// nq - 1 constrained directions so that the mode leaves the scene some motion (seven closed
/// corners of a box at a generic configuration would force it to rest, with no slip direction).
template <Scene S, class Rng>
Mode<S::nc> random_mode(const S& scene, Rng& rng) {
  Mode<S::nc> mode;
  int budget = std::max(S::nq - 1, 1);
  for (int i = 0; i < S::nc; ++i) {
    const int pick = std::uniform_int_distribution<int>(0, 2)(rng);
    const int nt = scene.contact(i).tangents();
    const int rows = pick == 0 ? 0 : (pick == 1 ? 1 + nt : 1);
    if (rows > budget) continue;
    budget -= rows;
    if (pick == 1) mode[i] = ContactState::stick();
    if (pick == 2) {
      if (nt == 1)
        mode[i] = ContactState::slip_planar(uniform(rng, -1, 1) > 0 ? 1 : -1);
      else {
        const double a = uniform(rng, -M_PI, M_PI);
        mode[i] = ContactState::slip(Eigen::Vector2d(std::cos(a), std::sin(a)));
      }
    }
  }
  return mode;
}

/// x with its velocity projected (in the kinetic metric) onto the velocities a mode allows:
/// zero normal velocity at closed contacts, zero tangential velocity at sticking ones, the
/// configuration kept (ConstraintProjection with the current gaps as targets). Flows are only
/// consistent there: for a rigid pair of sticking contacts (a box stuck on the plank at both
/// corners) the Delassus system has a solution only if the velocities respect the contacts.
template <Scene S>
Vec<2 * S::nq> consistent_with_mode(const S& scene, const Mode<S::nc>& mode, const Vec<2 * S::nq>& x) {
  ConstraintProjection<S> projection;
  typename ConstraintProjection<S>::Values gaps, velocities;
  projection.values(scene, mode, x, gaps, velocities);
  Vec<2 * S::nq> out = x;
  projection.project(scene, mode, out, &gaps);
  return out;
}

/// A generic configuration: touching_configuration moved a little in every coordinate, so no
/// contact rows are redundant.
template <Scene S, class Rng>
Vec<S::nq> generic_configuration(const S& scene, Rng& rng) {
  return scene.touching_configuration(rng) + random_vector<S::nq>(rng, 0.05);
}

/// The lowest gap of any contact (of the open ones only, with open_contacts_only) at 5 points
/// of every dense-output piece of every segment of a trajectory.
template <Scene S>
double lowest_gap(const S& scene, const HybridTrajectory<S>& traj, bool open_contacts_only) {
  double lowest = std::numeric_limits<double>::infinity();
  for (const auto& seg : traj.segments)
    for (const auto& piece : seg.x.pieces())
      for (int k = 0; k <= 4; ++k) {
        const auto x = piece.value(piece.t0 + (piece.t1 - piece.t0) * k / 4.0);
        for (int i = 0; i < S::nc; ++i)
          if (!(open_contacts_only && seg.mode[i].closed()))
            lowest = std::min(lowest, scene.template gap<double>(i, VecT<double, S::nq>(x.template head<S::nq>())));
      }
  return lowest;
}

}  // namespace saltus::testing
