// The plank-box (thesis appendix F): a fully actuated box above a plank that is hinged to the
// world at its left end, held by a torsional spring k_P and damper b_P. The box's bottom edge
// touches the plank at two contact points C_L and C_R (planar Coulomb friction); landing flat,
// both touch at once: the planned simultaneous impact.
//
// Saltus writes the model in world coordinates (the thesis' "global" coordinates, F.1-F.6),
// where the mass matrix is constant, and lets automatic differentiation produce the contact
// Jacobians in the plank's frame; the thesis' local-coordinate form (F.7-F.11, F.34-F.35) carries
// typos (the sign of k_P in F.5, W_T in F.35) and is not needed.
//
//   q = (x, y, theta, phi)   box centre [m], box angle [rad], plank angle from horizontal [rad]
//   u = (F_x, F_y, tau)      world-frame force [N] and torque [N m] on the box
//   M = diag(m_B, m_B, J_B, m_P L_P^2 / 3)     (F.4; J about the hinge = m_P L^2/4 + m_P L^2/12)
//   h = (0, m_B g, 0, k_P (phi - phi_0) + b_P phi' + m_P g (L_P/2) cos phi)
// with the spring's rest angle phi_0 = m_P g L_P / (2 k_P) chosen so that the empty plank rests
// horizontally. A corner at r_c in the box frame is at p = (x, y) + R(theta) r_c; in the plank frame
// (origin at the hinge, axis along the plank) its coordinates are R(phi)^T p, so the gap is its
// height above the plank's top face and its tangent position the coordinate along the plank.
//
// Parameter values (the thesis gives none; chosen as a table-top experiment): box 0.3 m x 0.1 m,
// 1 kg; plank 1.0 m long, 0.02 m thick, 2 kg; k_P = 200 N m/rad, b_P = 2 N m s/rad
// (a 1 kg box at 0.6 m tilts it by about 0.03 rad); mu = 0.4 on both corners; e_n = 0.
#pragma once

#include <saltus/hybrid/instantiate.hpp>
#include <saltus/hybrid/vocabulary/scene.hpp>
#include <saltus/sensitivity/instantiate.hpp>

#include <array>
#include <cmath>
#include <random>

namespace saltus::scenes {

struct PlankBoxParameters {
  double box_mass = 1.0;        ///< kg
  double box_length = 0.3;      ///< m, along the bottom edge (L_B)
  double box_height = 0.1;      ///< m (l_B)
  double plank_mass = 2.0;      ///< kg
  double plank_length = 1.0;    ///< m (L_P), hinge at its left end
  double plank_thickness = 0.02;  ///< m, the hinge is on the plank's mid-plane
  double spring = 200.0;        ///< k_P, N m/rad
  double damper = 2.0;          ///< b_P, N m s/rad
  double gravity = 9.81;        ///< m/s^2
  double mu = 0.4;              ///< box-plank Coulomb coefficient, both corners
  double restitution = 0.0;
};

class PlankBox {
 public:
  static constexpr int nq = 4, nu = 3, nc = 2;
  using Parameters = PlankBoxParameters;
  static constexpr const char* name = "plank_box";
  enum Corner { left = 0, right = 1 };

  explicit PlankBox(Parameters p = {})
      : p_(p),
        corners_{ContactSpec{"C_L", Friction::Planar, p.mu, p.restitution},
                 ContactSpec{"C_R", Friction::Planar, p.mu, p.restitution}} {}

  const Parameters& parameters() const { return p_; }
  const ContactSpec& contact(int i) const { return corners_[i]; }

  double box_inertia() const {
    return p_.box_mass * (p_.box_length * p_.box_length + p_.box_height * p_.box_height) / 12.0;
  }
  double plank_inertia_about_hinge() const { return p_.plank_mass * p_.plank_length * p_.plank_length / 3.0; }
  double spring_rest_angle() const { return p_.plank_mass * p_.gravity * p_.plank_length / (2.0 * p_.spring); }

  template <class T>
  MatT<T, nq, nq> mass_matrix(const VecT<T, nq>&) const {
    MatT<T, nq, nq> M = MatT<T, nq, nq>::Zero();
    M(0, 0) = T(p_.box_mass);
    M(1, 1) = T(p_.box_mass);
    M(2, 2) = T(box_inertia());
    M(3, 3) = T(plank_inertia_about_hinge());
    return M;
  }
  template <class T>
  VecT<T, nq> bias(const VecT<T, nq>& q, const VecT<T, nq>& v) const {
    using std::cos;
    return VecT<T, nq>(T(0), T(p_.box_mass * p_.gravity), T(0),
                       p_.spring * (q[3] - spring_rest_angle()) + p_.damper * v[3] +
                           p_.plank_mass * p_.gravity * 0.5 * p_.plank_length * cos(q[3]));
  }
  template <class T>
  MatT<T, nq, nu> input_matrix(const VecT<T, nq>&) const {
    MatT<T, nq, nu> S = MatT<T, nq, nu>::Zero();
    S(0, 0) = S(1, 1) = S(2, 2) = T(1);
    return S;
  }

  /// The box flat over the level plank, everything at rest: its centre at x = `along` (m, world
  /// frame; the hinge is at the origin) and its bottom edge `clearance` (m) above the plank's top
  /// face, so both corners have gap `clearance`. The start of "the box lowered flat".
  Vec<2 * nq> flat_state(double along = 0.6, double clearance = 0.05) const {
    Vec<2 * nq> x = Vec<2 * nq>::Zero();
    x[0] = along;
    x[1] = 0.5 * (p_.box_height + p_.plank_thickness) + clearance;
    return x;
  }
  /// The input that lowers the box flat: the actuated box holds its weight but `push` (N),
  /// u = (0, m g - push, 0); from flat_state(x, c) both corners land at once at sqrt(2 c m / push).
  Vec<nu> lowering_input(double push = 2.0) const { return Vec<nu>(0.0, p_.box_mass * p_.gravity - push, 0.0); }

  /// Corner i in world coordinates.
  template <class T>
  VecT<T, 2> corner(int i, const VecT<T, nq>& q) const {
    using std::cos;
    using std::sin;
    const double rx = (i == left ? -0.5 : 0.5) * p_.box_length, ry = -0.5 * p_.box_height;
    const T c = cos(q[2]), s = sin(q[2]);
    return VecT<T, 2>(q[0] + c * rx - s * ry, q[1] + s * rx + c * ry);
  }
  /// Corner i in the plank frame (x along the plank from the hinge, y normal to it).
  template <class T>
  VecT<T, 2> corner_in_plank_frame(int i, const VecT<T, nq>& q) const {
    using std::cos;
    using std::sin;
    const VecT<T, 2> p = corner(i, q);
    const T c = cos(q[3]), s = sin(q[3]);
    return VecT<T, 2>(c * p[0] + s * p[1], -s * p[0] + c * p[1]);
  }

  template <class T>
  T gap(int i, const VecT<T, nq>& q) const {
    return corner_in_plank_frame(i, q)[1] - 0.5 * p_.plank_thickness;
  }
  template <class T>
  VecT<T, 2> tangent_position(int i, const VecT<T, nq>& q) const {
    return VecT<T, 2>(corner_in_plank_frame(i, q)[0], T(0));
  }

  template <class T>
  T potential_energy(const VecT<T, nq>& q) const {
    using std::sin;
    const T dphi = q[3] - spring_rest_angle();
    return p_.box_mass * p_.gravity * q[1] + p_.plank_mass * p_.gravity * 0.5 * p_.plank_length * sin(q[3]) +
           0.5 * p_.spring * dphi * dphi;
  }

  /// The box resting on the plank: flat on both corners (half of the draws, a singular
  /// Delassus matrix in stick) or tilted on one corner.
  template <class Rng>
  Vec<nq> touching_configuration(Rng& rng) const {
    std::uniform_real_distribution<double> phi(-0.05, 0.05), along(0.2, 0.8), tilt(-0.3, 0.3), coin(0.0, 1.0);
    Vec<nq> q;
    q[3] = phi(rng);
    const bool flat = coin(rng) < 0.5;
    q[2] = q[3] + (flat ? 0.0 : tilt(rng));
    // Centre placed along the plank, then lifted until the lowest corner touches.
    const double s = along(rng);
    q[0] = s * std::cos(q[3]);
    q[1] = s * std::sin(q[3]) + 0.5;
    const double lowest = std::min(gap(0, q), gap(1, q));
    // Move along the plank normal so the lowest corner's gap is zero.
    q[0] += lowest * std::sin(q[3]);
    q[1] -= lowest * std::cos(q[3]);
    return q;
  }

 private:
  Parameters p_;
  std::array<ContactSpec, nc> corners_;
};

}  // namespace saltus::scenes

// Compiled once, in plank_box.cpp (saltus_scenes): a program that includes this header links it.
SALTUS_DECLARE_SCENE(saltus::scenes::PlankBox)
SALTUS_DECLARE_SCENE_SENSITIVITY(saltus::scenes::PlankBox)
