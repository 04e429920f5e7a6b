// A user's program: simulates the user's scene (falling_mass.hpp) and checks the impact time,
// which must be sqrt(2 h / g). Includes no definition of the simulator: it links falling_mass.cpp.
//
// Then a derivative check of the contact kinematics built with the consumer's own flags (CMake's
// default Release flags, -O3; CMakeLists.txt keeps this file at -O3 when the test builds the rest
// lower, check.cmake): those templates are compiled in the user's translation units, not in
// Saltus' library, so only their code and the options saltus::hybrid exports (-fno-ipa-modref
// for GCC >= 12: hybrid/CMakeLists.txt) protect them. GCC 12.2 -O3 once miscompiled
// evaluate_contact (the tangential terms read back as zero: kinematics.hxx, tests/test_dual.cpp
// GccModrefNullBaseLoop). Checked: the contact of FallingMass (compiled in falling_mass.cpp, at
// the project's Release flags) and a curved frictional contact, a box corner over a tilted plank,
// whose kinematics this file compiles (one kernel, a few seconds): the normal and tangent
// Jacobians, velocities and curvature terms against central differences. With the old
// evaluate_contact and without -fno-ipa-modref this check failed at -O3 (W_t of the corner read
// back as 0).
#include "falling_mass.hpp"

#include <saltus/hybrid/dynamics/kinematics.hxx>  // evaluate_contact for the corner, here
#include <saltus/hybrid/simulation/simulator.hpp>

#include <cmath>
#include <cstdio>
#include <string>

/// A box corner over a plank tilted by q[3] (q = box x, y, angle; plank angle), planar friction:
/// only its contact is used.
struct TiltedCorner {
  static constexpr int nq = 4, nu = 0, nc = 1;
  saltus::ContactSpec spec{"corner", saltus::Friction::Planar, 0.4, 0.0};
  double length = 0.3, height = 0.1, thickness = 0.02;
  const saltus::ContactSpec& contact(int) const { return spec; }
  template <class T> saltus::MatT<T, 4, 4> mass_matrix(const saltus::VecT<T, 4>&) const {
    return saltus::MatT<T, 4, 4>::Identity();
  }
  template <class T> saltus::VecT<T, 4> bias(const saltus::VecT<T, 4>&, const saltus::VecT<T, 4>&) const {
    return saltus::VecT<T, 4>::Zero();
  }
  template <class T> saltus::MatT<T, 4, 0> input_matrix(const saltus::VecT<T, 4>&) const { return {}; }
  template <class T> saltus::VecT<T, 2> in_plank(int i, const saltus::VecT<T, 4>& q) const {
    using std::cos;
    using std::sin;
    const double rx = (i == 0 ? -0.5 : 0.5) * length, ry = -0.5 * height;
    const T c = cos(q[2]), s = sin(q[2]);
    const saltus::VecT<T, 2> p(q[0] + c * rx - s * ry, q[1] + s * rx + c * ry);
    const T cp = cos(q[3]), sp = sin(q[3]);
    return saltus::VecT<T, 2>(cp * p[0] + sp * p[1], -sp * p[0] + cp * p[1]);
  }
  template <class T> T gap(int i, const saltus::VecT<T, 4>& q) const { return in_plank(i, q)[1] - 0.5 * thickness; }
  template <class T> saltus::VecT<T, 2> tangent_position(int i, const saltus::VecT<T, 4>& q) const {
    return saltus::VecT<T, 2>(in_plank(i, q)[0], T(0));
  }
};

/// evaluate_contact of contact 0 against central differences of the scene's gap and tangent
/// position (w_n, W_t) and of the AD Jacobians along v (kappa_n, kappa_t). Returns the failures.
template <class S>
int check_contact(const char* name, const S& scene, const saltus::Vec<S::nq>& q, const saltus::Vec<S::nq>& v) {
  constexpr int nq = S::nq;
  const double h = 1e-6;
  int failures = 0;
  auto expect = [&](const char* what, double got, double want, double tol) {
    if (std::abs(got - want) <= tol * (1 + std::abs(want))) return;
    std::printf("%s: %s = %.12g, central difference %.12g\n", name, what, got, want);
    ++failures;
  };
  saltus::ContactKinematics<S> c;
  saltus::evaluate_contact(scene, 0, q, v, c);
  expect("gap", c.gap, scene.template gap<double>(0, q), 1e-15);
  expect("zeta_n", c.zeta_n, c.wn.dot(v), 1e-13);
  for (int k = 0; k < nq; ++k) {
    const saltus::Vec<nq> e = h * saltus::Vec<nq>::Unit(k);
    expect("w_n", c.wn[k], (scene.template gap<double>(0, q + e) - scene.template gap<double>(0, q - e)) / (2 * h), 1e-8);
  }
  // Tangent j by a call with a constant j (the miscompiled values were visible through constant
  // indices only).
  auto check_tangent = [&](int j) {
    for (int k = 0; k < nq; ++k) {
      const saltus::Vec<nq> e = h * saltus::Vec<nq>::Unit(k);
      expect("W_t", c.Wt(k, j), (scene.template tangent_position<double>(0, q + e)[j] -
                                 scene.template tangent_position<double>(0, q - e)[j]) / (2 * h), 1e-8);
    }
    expect("zeta_t", c.zeta_t[j], c.Wt.col(j).dot(v), 1e-13);
  };
  if (c.tangents > 0) check_tangent(0);
  if (c.tangents > 1) check_tangent(1);
  saltus::ContactKinematics<S> cp, cm;
  saltus::evaluate_contact(scene, 0, saltus::Vec<nq>(q + h * v), v, cp);
  saltus::evaluate_contact(scene, 0, saltus::Vec<nq>(q - h * v), v, cm);
  expect("kappa_n", c.kappa_n, (cp.wn.dot(v) - cm.wn.dot(v)) / (2 * h), 1e-7);
  auto check_curvature = [&](int j) {
    expect("kappa_t", c.kappa_t[j], (cp.Wt.col(j).dot(v) - cm.Wt.col(j).dot(v)) / (2 * h), 1e-7);
  };
  if (c.tangents > 0) check_curvature(0);
  if (c.tangents > 1) check_curvature(1);
  return failures;
}

int main() {
  FallingMass scene;
  saltus::Simulator<FallingMass> sim(scene);
  const auto traj = sim.run(saltus::Vec<2>(2.0, 0.0), 0.0, 1.0, saltus::zero_input<FallingMass>());
  const double expected = std::sqrt(2 * 2.0 / 9.81);
  std::printf("impact at %.12f (expected %.12f)\n", traj.events.at(0).t, expected);
  int failures = std::abs(traj.events.at(0).t - expected) < 1e-9 ? 0 : 1;

  // This project links saltus::hybrid only (no component cvode, no SUNDIALS): asking for CVODE is
  // refused with InvalidArgument naming the component.
  try {
    saltus::SimulationOptions options;
    options.integrator.kind = saltus::IntegratorKind::CvodeBdf;
    saltus::Simulator<FallingMass> cvode(scene, options);
    std::printf("CVODE was accepted without the component saltus::cvode\n");
    ++failures;
  } catch (const saltus::InvalidArgument& e) {
    const bool names_component = std::string(e.what()).find("saltus::cvode") != std::string::npos;
    std::printf("CVODE without the component: %s\n", e.what());
    failures += names_component ? 0 : 1;
  }

  failures += check_contact("falling mass", scene, saltus::Vec<1>(0.7), saltus::Vec<1>(-1.3));
  const TiltedCorner corner;
  failures += check_contact("tilted corner", corner, saltus::Vec<4>(0.1, 0.2, 0.3, 0.4), saltus::Vec<4>(0.5, -0.7, 1.1, 0.9));
  std::printf("contact kinematics against central differences: %d failure(s)\n", failures);
  return failures == 0 ? 0 : 1;
}
