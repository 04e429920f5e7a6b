// libFuzzer target: the impact problem on arbitrary input. The bytes choose a scene, its
// friction, restitution and tangential restitution, and the pre-impact state; the solver must
// either return a result that satisfies the Signorini-Coulomb conditions and does not gain
// energy beyond the law's bound (impact_law.hpp), or throw one of Saltus' typed exceptions
// (InvalidArgument for NaN/Inf or overflowing input, ContactProblemFailure for an unsolved
// problem, NumericalFailure). Anything else (a crash, an untyped exception, a sanitizer report, a
// silent law violation) is a finding: the target aborts.
// Build and run: bench/fuzz/run.sh (command and results in bench/README.md); past findings are
// kept as inputs in bench/fuzz/findings/ (replay: bench/fuzz/out/fuzz_impact_solver <file>).
// The scenes are local (compiled with the fuzzer's instrumentation in this one translation unit,
// contact numerics included): a planar block with three collinear bottom contacts (redundant
// when flat), and a point mass in space on a floor with spatial friction.
#define SALTUS_CONTACT_NO_EXTERN_TEMPLATES
#include <saltus/hybrid/contact/coulomb_solver.hxx>
#include <saltus/hybrid/contact/lemke.hxx>
#include <saltus/hybrid/contact/linear_solve.hxx>
#include <saltus/hybrid/dynamics/impact.hxx>
#include <saltus/hybrid/dynamics/jump_map.hxx>
#include <saltus/hybrid/dynamics/kinematics.hxx>

#include "scenes/three_point_block.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>

namespace {

using namespace saltus;

using scenes::ThreePointBlock;  // examples/scenes/three_point_block.hpp

/// Point mass (2 kg) in space, q = (x, y, z), on the floor z = 0 with spatial friction.
class SpatialPointMass {
 public:
  static constexpr int nq = 3, nu = 0, nc = 1;
  static constexpr const char* name = "spatial_point_mass";
  SpatialPointMass(double mu, double e_n, std::optional<double> e_t) : floor_{"floor", Friction::Spatial, mu, e_n, e_t} {}
  const ContactSpec& contact(int) const { return floor_; }
  template <class T>
  MatT<T, nq, nq> mass_matrix(const VecT<T, nq>&) const { return MatT<T, nq, nq>::Identity() * T(2.0); }
  template <class T>
  VecT<T, nq> bias(const VecT<T, nq>&, const VecT<T, nq>&) const { return VecT<T, nq>(T(0), T(0), T(2 * 9.81)); }
  template <class T>
  MatT<T, nq, nu> input_matrix(const VecT<T, nq>&) const { return MatT<T, nq, nu>::Zero(); }
  template <class T>
  T gap(int, const VecT<T, nq>& q) const { return q[2]; }
  template <class T>
  VecT<T, 2> tangent_position(int, const VecT<T, nq>& q) const { return VecT<T, 2>(q[0], q[1]); }

 private:
  ContactSpec floor_;
};

struct Bytes {
  const std::uint8_t* data;
  std::size_t size, pos = 0;
  double next() {  // 8 bytes as a double (any bit pattern: NaN, Inf, subnormals included)
    double d = 0.0;
    if (pos + 8 <= size) std::memcpy(&d, data + pos, 8);
    pos += 8;
    return d;
  }
  double unit() {  // a byte mapped to [0, 1]
    const double u = pos < size ? data[pos] / 255.0 : 0.5;
    ++pos;
    return u;
  }
};

[[noreturn]] void finding(const char* what, double value) {
  std::fprintf(stderr, "finding: %s (%.17g)\n", what, value);
  std::abort();
}

template <class S>
void check_impact(const S& scene, Bytes& in) {
  constexpr int nx = 2 * S::nq;
  VecT<double, nx> x;
  for (int k = 0; k < nx; ++k) x[k] = in.next();
  // Bounded states exercise the solver; raw bit patterns exercise the input checks.
  const bool raw = in.unit() < 0.2;
  if (!raw)
    for (int k = 0; k < nx; ++k) x[k] = std::isfinite(x[k]) ? std::tanh(x[k] * 1e-3) * 3.0 : 0.0;
  if (!raw && in.unit() < 0.5) {  // on the ground: flat for the block (redundant), z = 0 for the mass
    if constexpr (S::nc == 3) {
      x[1] = 0.1;
      x[2] = 0.0;
    } else {
      x[2] = 0.0;
    }
  }
  ImpactSolver<S> solver(scene);
  // On a finding, the input it came from is printed (a finding aborts right after).
  struct Describe {
    const S& scene;
    const VecT<double, nx>& x;
    void print() const {
      const ContactSpec& c = scene.contact(0);
      std::fprintf(stderr, "scene %s, mu %.17g, e_n %.17g, e_t %s%.17g, x- =", S::name, c.mu, c.restitution,
                   c.tangential_restitution ? "" : "unset ", c.tangential_restitution.value_or(-1.0));
      for (int k = 0; k < nx; ++k) std::fprintf(stderr, " %.17g", x[k]);
      std::fprintf(stderr, "\n");
    }
  } describe{scene, x};
  try {
    const auto& r = solver.solve(x);
    if (!(r.signorini_residual <= 1e-9)) describe.print(), finding("Signorini residual", r.signorini_residual);
    if (!(r.coulomb_residual <= 1e-9)) describe.print(), finding("Coulomb residual", r.coulomb_residual);
    if (r.coefficients.energy_consistent) {
      // The law's bound (impact_law.hpp): (1 + e) dT <= e sum Lambda_n max(zeta_n-, 0), a gain
      // only where a contact already separating at the impact takes an impulse (found by this
      // target with an oracle of plain KE+ <= KE-: a flat block spinning at 3 rad/s, e_n = 1,
      // gains 1.4% through its rising corner; the law allows it and says so).
      double separating_work = 0.0, e = 0.0;
      for (int i = 0; i < S::nc; ++i) {
        if (!r.in_problem[i]) continue;
        e = std::max(e, r.coefficients.normal[i]);
        separating_work += r.impulse[i].normal * std::max(r.normal_velocity_minus[i], 0.0);
      }
      const double bound = e * separating_work / (1 + e);
      if (r.kinetic_energy_plus - r.kinetic_energy_minus > bound + 1e-9 * r.kinetic_energy_minus + 1e-300)
        describe.print(), finding("energy gain beyond the law's bound", r.kinetic_energy_plus / r.kinetic_energy_minus);
    }
    for (int k = 0; k < nx; ++k)
      if (!std::isfinite(r.x_plus[k])) describe.print(), finding("non-finite post-impact state", r.x_plus[k]);
  } catch (const InvalidArgument&) {
  } catch (const ContactProblemFailure&) {
  } catch (const NumericalFailure&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Bytes in{data, size};
  const double choice = in.unit();
  const double mu = 2.0 * in.unit(), e_n = in.unit();
  const std::optional<double> e_t = in.unit() < 0.5 ? std::nullopt : std::optional<double>(in.unit());
  if (choice < 0.5)
    check_impact(ThreePointBlock(mu, e_n, e_t), in);
  else
    check_impact(SpatialPointMass(mu, e_n, e_t), in);
  return 0;
}
