// A planar block with redundant contacts, used by tests/test_impact.cpp and the impact-solver fuzz
// target (bench/fuzz/fuzz_impact_solver.cpp): header-only, instantiated where it is used (not one of
// the five scenes of all_scenes.hpp, and not compiled into saltus_scenes).
#pragma once

#include <saltus/hybrid/vocabulary/scene.hpp>

#include <array>
#include <cmath>
#include <optional>

namespace saltus::scenes {

// A planar block (1 kg, 0.4 m x 0.2 m, q = (x, y, theta)) with three planar-friction contacts
// along its bottom edge, at x = -0.2, 0 and 0.2 m in the body frame: redundant collinear
// contacts.
class ThreePointBlock {
 public:
  static constexpr int nq = 3, nu = 0, nc = 3;
  static constexpr const char* name = "three_point_block";
  /// Coulomb mu, restitution e_n, tangential restitution e_t (unset: the energy-consistent law)
  /// of all three contacts.
  ThreePointBlock(double mu, double e_n, std::optional<double> e_t = std::nullopt)
      : points_{ContactSpec{"left", Friction::Planar, mu, e_n, e_t}, ContactSpec{"middle", Friction::Planar, mu, e_n, e_t},
                ContactSpec{"right", Friction::Planar, mu, e_n, e_t}} {}
  const ContactSpec& contact(int i) const { return points_[i]; }
  template <class T>
  MatT<T, nq, nq> mass_matrix(const VecT<T, nq>&) const {
    MatT<T, nq, nq> M = MatT<T, nq, nq>::Zero();
    M(0, 0) = M(1, 1) = T(1.0);
    M(2, 2) = T((0.4 * 0.4 + 0.2 * 0.2) / 12.0);
    return M;
  }
  template <class T>
  VecT<T, nq> bias(const VecT<T, nq>&, const VecT<T, nq>&) const {
    return VecT<T, nq>(T(0), T(9.81), T(0));
  }
  template <class T>
  MatT<T, nq, nu> input_matrix(const VecT<T, nq>&) const {
    return MatT<T, nq, nu>::Zero();
  }
  template <class T>
  VecT<T, 2> point(int i, const VecT<T, nq>& q) const {
    using std::cos;
    using std::sin;
    const double bx = 0.2 * (i - 1), by = -0.1;
    return VecT<T, 2>(q[0] + cos(q[2]) * bx - sin(q[2]) * by, q[1] + sin(q[2]) * bx + cos(q[2]) * by);
  }
  template <class T>
  T gap(int i, const VecT<T, nq>& q) const {
    return point(i, q)[1];
  }
  template <class T>
  VecT<T, 2> tangent_position(int i, const VecT<T, nq>& q) const {
    return VecT<T, 2>(point(i, q)[0], T(0));
  }

 private:
  std::array<ContactSpec, 3> points_;
};

}  // namespace saltus::scenes
