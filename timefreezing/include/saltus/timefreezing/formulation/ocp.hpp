// What a time-freezing OCP may provide: the concepts that the FESD discretisation
// (discretisation/fesd.hpp) and any later optimisation stage that takes the same OCP struct read
// it with. Every member is optional; a struct with none of them (NoObjective) is a simulation
// under u = decision.
//
// An OCP over a scene with nq coordinates and nu inputs, x = (q, v) of size nx = 2 nq, the
// physical time t [s] (the time-freezing clock state), may provide, each a const member:
//   template <class T> T running_cost(const VecT<T, nx>& x, const VecT<T, nu>& u) const;   [per s]
//       or running_cost(x, u, t) with the clock t (e.g. tracking a time-dependent reference); the
//       three-argument form is used when both exist. Integrated over physical time only (the
//       time-freezing paper, Nurkanović, Albrecht, Brogliato, Diehl, Automatica 2023, eq. 29).
//   template <class T> T terminal_cost(const VecT<T, nx>& x, const T& t) const;
//   template <class T> VecT<T, nu> input(const T& t, const VecT<T, nu>& decision) const;
//       the input law: the input applied at physical time t (default: the decision itself);
//   static constexpr int path_constraint_count = np; path_constraints<T>(x, u) -> VecT<T, np>,
//       path_lower(), path_upper() -> Vec<np>: imposed at every stage point;
//   static constexpr int terminal_constraint_count = nt; terminal_constraints<T>(x, t) -> VecT<T, nt>,
//       terminal_lower(), terminal_upper() -> Vec<nt>.
// Each function is differentiated by forward AD, so it must be a member template in T that takes T
// everywhere (the clock too): a plain double function would be used in the values and not in the
// derivatives. FesdMpcc refuses such an OCP at compile time (HasNonTemplateRunningCost, and a
// running cost whose clock argument is a double).
#pragma once

#include <saltus/hybrid/vocabulary/scene.hpp>

#include <concepts>

namespace saltus::timefreezing {

/// An OCP without costs, constraints or input law: a simulation under u = decision (zero).
struct NoObjective {};

/// running_cost(x, u) at scalar T.
template <class O, class T, int nx, int nu>
concept HasRunningCost = requires(const O& o, const VecT<T, nx>& x, const VecT<T, nu>& u) {
  { o.template running_cost<T>(x, u) } -> std::convertible_to<T>;
};
/// running_cost(x, u, t) at scalar T, the clock t of type T.
template <class O, class T, int nx, int nu>
concept HasTimedRunningCost = requires(const O& o, const VecT<T, nx>& x, const VecT<T, nu>& u, const T& t) {
  { o.template running_cost<T>(x, u, t) } -> std::convertible_to<T>;
};
/// A running_cost that is not a member template (its address can be taken): AD cannot see it.
template <class O>
concept HasNonTemplateRunningCost = requires { &O::running_cost; };
/// terminal_cost(x, t) at scalar T.
template <class O, class T, int nx>
concept HasTerminalCost = requires(const O& o, const VecT<T, nx>& x, const T& t) {
  { o.template terminal_cost<T>(x, t) } -> std::convertible_to<T>;
};
/// input(t, decision) at scalar T: the input law.
template <class O, class T, int nu>
concept HasInputLaw = requires(const O& o, const T& t, const VecT<T, nu>& u) {
  { o.template input<T>(t, u) } -> std::convertible_to<VecT<T, nu>>;
};
/// path_constraint_count (with path_constraints, path_lower, path_upper).
template <class O>
concept HasPathConstraints = requires { O::path_constraint_count; };
/// terminal_constraint_count (with terminal_constraints, terminal_lower, terminal_upper).
template <class O>
concept HasTerminalConstraints = requires { O::terminal_constraint_count; };

/// np: the OCP's path constraints per stage point (0 without).
template <class O>
constexpr int path_constraint_count() {
  if constexpr (HasPathConstraints<O>) return O::path_constraint_count; else return 0;
}
/// nt: the OCP's terminal constraints (0 without).
template <class O>
constexpr int terminal_constraint_count() {
  if constexpr (HasTerminalConstraints<O>) return O::terminal_constraint_count; else return 0;
}

}  // namespace saltus::timefreezing
