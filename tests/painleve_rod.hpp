// Test-local scenes of Painleve's paradox (tests/test_event_detection.cpp,
// tests/test_impact_without_collision_gain.cpp): a uniform rod whose lower end slides on the ground,
// and the same rod pushed at its centre.
#pragma once

#include "support.hpp"

namespace saltus::testing {

// A uniform rod of length 1 m and mass 1 kg, q = (x, y, theta) of its centre, its lower end
// (centre - (L/2)(cos theta, sin theta)) as a planar-friction contact.
class PainleveRod {
 public:
  static constexpr int nq = 3, nu = 0, nc = 1;
  static constexpr double g = 9.81;  ///< m/s^2
  explicit PainleveRod(double mu) : end_{"end", Friction::Planar, mu, 0.0} {}
  const ContactSpec& contact(int) const { return end_; }
  template <class T>
  MatT<T, nq, nq> mass_matrix(const VecT<T, nq>&) const {
    MatT<T, nq, nq> M = MatT<T, nq, nq>::Identity();
    M(2, 2) = T(1.0 / 12.0);
    return M;
  }
  template <class T>
  VecT<T, nq> bias(const VecT<T, nq>&, const VecT<T, nq>&) const {
    return VecT<T, nq>(T(0), T(g), T(0));
  }
  // No input_matrix: optional for a scene without inputs.
  template <class T>
  T gap(int, const VecT<T, nq>& q) const {
    using std::sin;
    return q[1] - T(0.5) * sin(q[2]);
  }
  template <class T>
  VecT<T, 2> tangent_position(int, const VecT<T, nq>& q) const {
    using std::cos;
    return VecT<T, 2>(q[0] - T(0.5) * cos(q[2]), T(0));
  }

 private:
  ContactSpec end_;
};

// The rod of PainleveRod pushed at its centre by a force u = (horizontal, vertical) [N].
class PushedRod : public PainleveRod {
 public:
  static constexpr int nu = 2;
  using PainleveRod::PainleveRod;
  template <class T>
  MatT<T, nq, nu> input_matrix(const VecT<T, nq>&) const {
    MatT<T, nq, nu> B = MatT<T, nq, nu>::Zero();
    B(0, 0) = T(1);
    B(1, 1) = T(1);
    return B;
  }
};

}  // namespace saltus::testing
