// Errors raised by Saltus. Three tiers, as in the design:
//  - SALTUS_ASSERT: internal invariants, compiled out in release builds;
//  - SALTUS_DEMAND: cheap always-on checks of things that would otherwise give a silent wrong
//    number (a non-SPD mass matrix found while factorising it, a non-finite result);
//  - exceptions for bad user input, each naming the problem and the offending values.
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

/// A numerical result came out non-finite.
class NumericalFailure : public Error {
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

#define SALTUS_ASSERT(cond) assert(cond)

#define SALTUS_DEMAND(cond, ErrorType, ...)                                              \
  do {                                                                                   \
    if (!(cond)) throw ErrorType(::saltus::detail::concat(__VA_ARGS__));                 \
  } while (false)
