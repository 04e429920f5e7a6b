// The library's exceptions as Python exception classes with the same names and messages:
//   saltus.Error (RuntimeError)                      saltus::Error, the base of all
//   saltus.InvalidArgument (Error, ValueError)       bad user input (a size, a NaN, t_final <= t0, ...)
//   saltus.NonSpdMassMatrix, saltus.ContactProblemFailure, saltus.NumericalFailure, saltus.InternalError
//   saltus.GrazingEvent (attributes t, contact, guard, gamma_dot, rate_scale), saltus.SimultaneousActivation,
//   saltus.UnplannedEvent                            from saltus::sensitivity
// Their qualified names are "saltus.<Name>" and the package re-exports them, so that they pickle
// (a Dask worker's exception reaches the client with its type).
#include "common.hpp"

#include <saltus/sensitivity/jump_gain.hpp>
#include <saltus/sensitivity/tracking.hpp>

namespace saltus::python {

namespace {

struct Types {
  PyObject *error, *invalid_argument, *non_spd, *contact_failure, *numerical, *internal, *grazing, *simultaneous,
      *unplanned;
};
Types types{};  // the module holds a reference to each (set once at import)

PyObject* new_type(py::module_& m, const char* name, const char* doc, py::tuple bases) {
  const std::string qualified = std::string("saltus.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
  if (!type) throw py::error_already_set();
  m.add_object(name, py::handle(type));  // steals: the module keeps the reference
  return type;
}

}  // namespace

void bind_errors(py::module_& m) {
  const auto base = [](PyObject* a) { return py::make_tuple(py::handle(a)); };
  types.error = new_type(m, "Error", "Base class of every error Saltus raises (C++ saltus::Error).",
                         base(PyExc_RuntimeError));
  types.invalid_argument = new_type(
      m, "InvalidArgument",
      "A size, a coefficient or a value given by the user is out of its domain (wrong dimension, NaN or infinity, "
      "t_final <= t0, mu < 0, a state below the ground, ...).",
      py::make_tuple(py::handle(types.error), py::handle(PyExc_ValueError)));
  types.non_spd = new_type(m, "NonSpdMassMatrix",
                           "The mass matrix is not symmetric positive definite at the given configuration.",
                           base(types.error));
  types.contact_failure = new_type(m, "ContactProblemFailure",
                                   "A contact problem (impact or contact forces) has no solution within tolerance.",
                                   base(types.error));
  types.numerical = new_type(m, "NumericalFailure",
                             "A computation failed on valid input (no convergence, step-size underflow, too many "
                             "steps, a non-finite result); the message carries the numbers.",
                             base(types.error));
  types.internal = new_type(m, "InternalError", "An internal invariant of Saltus does not hold: a bug, please report.",
                            base(types.error));
  types.grazing = new_type(m, "GrazingEvent",
                           "A (nearly) tangential guard crossing: the event time is not differentiable, no jump "
                           "gain exists. Attributes: t [s], contact (index), guard (kind), gamma_dot, rate_scale.",
                           base(types.error));
  types.simultaneous = new_type(m, "SimultaneousActivation",
                                "A transition fired by several guards at once whose crossings a perturbation "
                                "separates: its gain is conewise linear, not one matrix.",
                                base(types.error));
  types.unplanned = new_type(m, "UnplannedEvent",
                             "The plant saw an event the reference does not have: reference spreading has no "
                             "segment to compare with.",
                             base(types.error));

  // Most derived first: the first matching handler sets the Python error.
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const GrazingEvent& e) {
      py::object ex = py::reinterpret_borrow<py::object>(types.grazing)(e.what());
      ex.attr("t") = e.t();
      ex.attr("contact") = e.guard().contact;
      ex.attr("guard") = to_string(e.guard().kind);
      ex.attr("gamma_dot") = e.gamma_dot();
      ex.attr("rate_scale") = e.rate_scale();
      PyErr_SetObject(types.grazing, ex.ptr());
    } catch (const SimultaneousActivation& e) {
      PyErr_SetString(types.simultaneous, e.what());
    } catch (const UnplannedEvent& e) {
      PyErr_SetString(types.unplanned, e.what());
    } catch (const InvalidArgument& e) {
      PyErr_SetString(types.invalid_argument, e.what());
    } catch (const NonSpdMassMatrix& e) {
      PyErr_SetString(types.non_spd, e.what());
    } catch (const ContactProblemFailure& e) {
      PyErr_SetString(types.contact_failure, e.what());
    } catch (const NumericalFailure& e) {
      PyErr_SetString(types.numerical, e.what());
    } catch (const InternalError& e) {
      PyErr_SetString(types.internal, e.what());
    } catch (const Error& e) {
      PyErr_SetString(types.error, e.what());
    }
  });
}

}  // namespace saltus::python
