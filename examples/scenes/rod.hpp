// A uniform rod in the vertical plane whose two ends touch a horizontal table, the two-contact
// case of the time-freezing battery (bench/time_freezing_battery.cpp) and of the rod-landing test
// (tests/test_time_freezing.cpp), after NOSNOC's `falling_rod` example:
//   q = (x, y, theta): the centre's position [m] and the rod's angle to the table [rad];
//   the ends at (x -+ l/2 cos theta, y -+ l/2 sin theta), gaps their heights; planar Coulomb
//   friction mu at both ends, no inputs; m = 1 kg, l = 1 m, inertia m l^2 / 12 about the centre.
// Dropped flat (theta = 0) while sliding, both ends land at once; by symmetry the impact and the
// slide that follows keep theta = 0 and are those of a point mass: v_x+ = v_x- - mu v_y- (while
// positive), then a deceleration mu g to rest.
// Not in AllScenes (all_scenes.hpp): the scene batteries there need the canonical reference
// motions of references.hpp; this scene serves the time-freezing engine's cases only.
#pragma once

#include <saltus/hybrid/instantiate.hpp>
#include <saltus/hybrid/vocabulary/scene.hpp>
#include <saltus/timefreezing/formulation/time_freezing_system.hpp>
#include <saltus/timefreezing/instantiate.hpp>

#include <array>
#include <cmath>

namespace saltus::scenes {

struct RodParameters {
  double mass = 1.0;     ///< kg
  double length = 1.0;   ///< m
  double gravity = 9.81; ///< m/s^2
  double mu = 0.2;       ///< Coulomb coefficient at both ends
  double restitution = 0.0;
};

class Rod {
 public:
  static constexpr int nq = 3, nu = 0, nc = 2;
  using Parameters = RodParameters;
  static constexpr const char* name = "rod";

  explicit Rod(Parameters p = {})
      : p_(p), ends_{ContactSpec{"left end", Friction::Planar, p.mu, p.restitution},
                     ContactSpec{"right end", Friction::Planar, p.mu, p.restitution}} {}

  const Parameters& parameters() const { return p_; }
  const ContactSpec& contact(int i) const { return ends_[i]; }

  template <class T>
  MatT<T, nq, nq> mass_matrix(const VecT<T, nq>&) const {
    MatT<T, nq, nq> M = MatT<T, nq, nq>::Identity() * T(p_.mass);
    M(2, 2) = T(p_.mass * p_.length * p_.length / 12.0);
    return M;
  }
  template <class T>
  VecT<T, nq> bias(const VecT<T, nq>&, const VecT<T, nq>&) const {
    return VecT<T, nq>(T(0), T(p_.mass * p_.gravity), T(0));
  }
  template <class T>
  MatT<T, nq, nu> input_matrix(const VecT<T, nq>&) const {
    return {};
  }
  /// End i (0: left, 1: right) in the plane.
  template <class T>
  VecT<T, 2> end(int i, const VecT<T, nq>& q) const {
    using std::cos;
    using std::sin;
    const double s = i == 0 ? -0.5 * p_.length : 0.5 * p_.length;
    return VecT<T, 2>(q[0] + s * cos(q[2]), q[1] + s * sin(q[2]));
  }
  template <class T>
  T gap(int i, const VecT<T, nq>& q) const {
    return end(i, q)[1];
  }
  template <class T>
  VecT<T, 2> tangent_position(int i, const VecT<T, nq>& q) const {
    return VecT<T, 2>(end(i, q)[0], T(0));
  }
  template <class T>
  T potential_energy(const VecT<T, nq>& q) const {
    return T(p_.mass * p_.gravity) * q[1];
  }

 private:
  Parameters p_;
  std::array<ContactSpec, 2> ends_;
};

}  // namespace saltus::scenes

// Compiled once, in rod.cpp (saltus_scenes): its hybrid machinery, its time-freezing machinery and
// its simulation without input.
SALTUS_DECLARE_SCENE(saltus::scenes::Rod)
SALTUS_DECLARE_TIME_FREEZING_SCENE(saltus::scenes::Rod)
SALTUS_DECLARE_TIME_FREEZING_SIMULATION(saltus::scenes::Rod, saltus::timefreezing::NoObjective)
