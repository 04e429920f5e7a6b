// What a scene is: the smooth dynamics M(q) v' = S(q) u - h(q, v) + sum_i W_i(q) lambda_i and
// its contacts (thesis eq. 2.3). A scene writes positions and energies only; every Jacobian and
// curvature term is obtained by automatic differentiation of its templated functions.
#pragma once

#include <saltus/hybrid/vocabulary/errors.hpp>

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <concepts>
#include <optional>
#include <string>

namespace saltus {

template <class T, int N>
using VecT = Eigen::Matrix<T, N, 1>;
template <class T, int R, int C>
using MatT = Eigen::Matrix<T, R, C>;
template <int N>
using Vec = Eigen::Matrix<double, N, 1>;

/// Storage order Eigen requires for an R x C matrix (row vectors are row-major).
inline constexpr int storage_order(int rows, int cols) {
  return (rows == 1 && cols != 1) ? Eigen::RowMajor : Eigen::ColMajor;
}
/// A matrix of at most MR x MC entries stored inline: resizing up to that never allocates.
template <class T, int R, int C, int MR, int MC>
using BoundedMatrix = Eigen::Matrix<T, R, C, storage_order(MR, MC), MR, MC>;
template <int R, int C>
using Mat = Eigen::Matrix<double, R, C>;

/// Friction a contact declares. The number of tangential unknowns follows the declaration:
/// frictionless 0, planar 1 (one tangent, the plane of motion), spatial 2 (the friction disk).
enum class Friction { None = 0, Planar = 1, Spatial = 2 };

inline constexpr int tangent_count(Friction f) { return static_cast<int>(f); }

inline const char* to_string(Friction f) {
  switch (f) {
    case Friction::None: return "frictionless";
    case Friction::Planar: return "planar";
    case Friction::Spatial: return "spatial";
  }
  return "?";
}

/// Constant description of one contact.
struct ContactSpec {
  std::string name;               ///< used in messages and reports
  Friction friction = Friction::None;
  double mu = 0.0;                ///< Coulomb coefficient, >= 0 (ignored when frictionless)
  double restitution = 0.0;       ///< Newton normal restitution e_n in [0, 1] (thesis 2.10)
  /// Tangential restitution e_t in [0, 1]. Unset (the default): the energy-consistent impact law,
  /// one coefficient for the normal and tangential rows of an impact (dynamics/impact_law.hpp);
  /// set it (0 gives the thesis' kinematic Newton law) for per-contact coefficients, which can
  /// create energy with friction and e_n > 0.
  std::optional<double> tangential_restitution{};

  int tangents() const { return tangent_count(friction); }
};

/// Throws InvalidArgument when a contact's coefficients are outside their domain.
inline void validate(const ContactSpec& c) {
  SALTUS_REQUIRE(std::isfinite(c.mu) && c.mu >= 0.0, "contact '", c.name,
                "': friction coefficient mu must be finite and >= 0, got ", c.mu);
  SALTUS_REQUIRE(std::isfinite(c.restitution) && c.restitution >= 0.0 && c.restitution <= 1.0, "contact '", c.name,
                "': restitution e_n must lie in [0, 1], got ", c.restitution);
  if (c.tangential_restitution)
    SALTUS_REQUIRE(std::isfinite(*c.tangential_restitution) && *c.tangential_restitution >= 0.0 &&
                       *c.tangential_restitution <= 1.0,
                   "contact '", c.name, "': tangential restitution e_t must lie in [0, 1], got ",
                   *c.tangential_restitution);
}

/// A scene: compile-time sizes and templated functions of the configuration q and velocity v.
///
///  - `mass_matrix<T>(q)`   M(q), nq x nq, symmetric positive definite;
///  - `bias<T>(q, v)`       h(q, v): Coriolis, centrifugal, gravity, springs and dampers, with
///                          M v' = S u - h + sum W lambda;
///  - `input_matrix<T>(q)`  S(q), nq x nu (optional when nu = 0: zero-size);
///  - `gap<T>(i, q)`        normal distance h_n of contact i (>= 0 when open);
///  - `tangent_position<T>(i, q)`  coordinates of contact i along its tangents, whose time
///                          derivative is the relative tangential velocity (only the first
///                          `tangents()` entries are used). For a material point of one body on a
///                          flat surface of another, these are the point's coordinates in the
///                          surface's frame; the Jacobian W_t is their gradient.
///  - `contact(i)`          its ContactSpec.
///
/// Generalised coordinates satisfy q' = v.
template <class S>
concept Scene = requires(const S& s, const VecT<double, S::nq>& q, const VecT<double, S::nq>& v) {
  { S::nq } -> std::convertible_to<int>;
  { S::nu } -> std::convertible_to<int>;
  { S::nc } -> std::convertible_to<int>;
  { s.contact(0) } -> std::convertible_to<const ContactSpec&>;
  { s.template mass_matrix<double>(q) } -> std::convertible_to<MatT<double, S::nq, S::nq>>;
  { s.template bias<double>(q, v) } -> std::convertible_to<VecT<double, S::nq>>;
  requires S::nu == 0 || requires {
    { s.template input_matrix<double>(q) } -> std::convertible_to<MatT<double, S::nq, S::nu>>;
  };
  { s.template gap<double>(0, q) } -> std::convertible_to<double>;
  { s.template tangent_position<double>(0, q) } -> std::convertible_to<VecT<double, 2>>;
};

/// S(q) of a scene (nq x nu): its input_matrix, or the zero-size matrix of a scene without
/// inputs that does not define one.
template <Scene S, class T>
MatT<T, S::nq, S::nu> scene_input_matrix(const S& scene, const VecT<T, S::nq>& q) {
  if constexpr (requires { scene.template input_matrix<T>(q); })
    return scene.template input_matrix<T>(q);
  else
    return MatT<T, S::nq, S::nu>();
}

/// Compile-time dimensions of a scene, named as in the math.
template <Scene S>
struct Dims {
  static constexpr int nq = S::nq;
  static constexpr int nv = S::nq;
  static constexpr int nx = 2 * S::nq;
  static constexpr int nu = S::nu;
  static constexpr int nc = S::nc;
  /// Most rows a contact problem can have: one normal and two tangents per contact.
  static constexpr int max_rows = 3 * S::nc;
};

/// Checks all contact specifications of a scene; call once when a scene is built.
template <Scene S>
void validate_scene(const S& scene) {
  static_assert(S::nq > 0, "a scene needs at least one generalised coordinate");
  static_assert(S::nu >= 0 && S::nc >= 0, "input and contact counts must be >= 0");
  for (int i = 0; i < S::nc; ++i) validate(scene.contact(i));
}

/// Largest magnitude accepted in a state (scene units): its square, and so a kinetic energy or a
/// norm, must not overflow a double (found by fuzzing the impact solver: a velocity of 4.5e279
/// made ||zeta_t|| infinite and the slip direction zero).
inline constexpr double max_state_magnitude = 1e150;

/// Throws InvalidArgument naming `what` if any entry is NaN, infinite, or larger in magnitude
/// than max_state_magnitude.
template <class Derived>
void require_finite(const Eigen::MatrixBase<Derived>& m, const char* what) {
  const bool finite = m.allFinite();
  if (!finite || (m.size() > 0 && m.cwiseAbs().maxCoeff() > max_state_magnitude)) {
    std::ostringstream os;
    os.precision(17);
    os << what << (finite ? " has an entry larger than 1e150 in magnitude (its square overflows)"
                          : " contains a NaN or an infinity")
       << ": [" << m.transpose() << "]";
    throw InvalidArgument(os.str());
  }
}

}  // namespace saltus
