// Errors raised by Saltus, in three tiers (as the design's error policy and Drake's
// DEMAND/ASSERT/throw split):
//  1. Bad user input: SALTUS_REQUIRE(cond, message...) throws InvalidArgument naming the argument
//     and its offending value (a size, a NaN, mu < 0, a state below the ground, ...). The domain's
//     own refusals have their own types, thrown directly: NonSpdMassMatrix (the scene's M(q)),
//     ContactProblemFailure (an impact or contact problem without a solution), and in
//     saltus::sensitivity GrazingEvent and SimultaneousActivation.
//  2. Numerical failure on valid input: SALTUS_CHECK_NUMERICS(cond, message...) throws
//     NumericalFailure with the numbers (a step-size underflow and its time, a Newton iteration
//     that did not converge and its residual, a non-finite result and the state).
//  3. Internal invariants: SALTUS_INVARIANT(cond, what) is always on and throws InternalError
//     naming the invariant, the condition and the place: a violation is a bug in Saltus, never
//     a silent wrong number. SALTUS_ASSERT(cond) is the debug-only form for hot paths.
// Every type derives from saltus::Error (a std::runtime_error).
#pragma once

#include <cassert>
#include <sstream>
#include <stdexcept>
#include <string>

namespace saltus {

/// Base class of every error Saltus throws.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A size, a coefficient or a value given by the user is out of its domain
/// (wrong dimension, NaN or infinity, mu < 0, restitution outside [0, 1], ...).
class InvalidArgument : public Error {
 public:
  using Error::Error;
};

/// The mass matrix is not symmetric positive definite at the given configuration.
class NonSpdMassMatrix : public Error {
 public:
  using Error::Error;
};

/// A contact problem (impact or contact forces) has no solution within tolerance.
class ContactProblemFailure : public Error {
 public:
  using Error::Error;
};

/// A computation failed on valid input: no convergence, step-size underflow, too many steps, a
/// non-finite result. The message carries the numbers.
class NumericalFailure : public Error {
 public:
  using Error::Error;
};

/// An internal invariant of Saltus does not hold: a bug, to be reported with the message.
class InternalError : public Error {
 public:
  using Error::Error;
};

namespace detail {
template <class... Args>
std::string concat(const Args&... args) {
  std::ostringstream os;
  os.precision(17);
  (os << ... << args);
  return os.str();
}
}  // namespace detail

}  // namespace saltus

/// Tier 1: the caller's arguments must satisfy `cond`; the message names the argument and value.
#define SALTUS_REQUIRE(cond, ...)                                                                 \
  do {                                                                                            \
    if (!(cond)) throw ::saltus::InvalidArgument(::saltus::detail::concat(__VA_ARGS__));          \
  } while (false)

/// Tier 2: a computation on valid input must satisfy `cond`; the message gives the numbers.
#define SALTUS_CHECK_NUMERICS(cond, ...)                                                          \
  do {                                                                                            \
    if (!(cond)) throw ::saltus::NumericalFailure(::saltus::detail::concat(__VA_ARGS__));         \
  } while (false)

/// Tier 3: an always-on internal invariant; `what` says what should hold (a string literal).
#define SALTUS_INVARIANT(cond, what)                                                               \
  do {                                                                                             \
    if (!(cond))                                                                                   \
      throw ::saltus::InternalError(::saltus::detail::concat("internal invariant violated: ", what, \
                                                            " (", #cond, ") at ", __FILE__, ":",    \
                                                            __LINE__, "; please report"));         \
  } while (false)

/// Debug-only check on a hot path (compiled out with NDEBUG).
#define SALTUS_ASSERT(cond) assert(cond)
