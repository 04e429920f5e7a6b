// Progress lines of a long C++ call (an OCP's solver, analyse_reference) in Python: a std::ostream
// whose complete lines go to a Python callable, taken with the GIL, while the call runs without it.
// Used by the module's optimal_control.cpp and by analyse_reference (tracking.hpp).
#pragma once

#include <pybind11/pybind11.h>

#include <saltus/hybrid/vocabulary/errors.hpp>

#include <optional>
#include <streambuf>
#include <string>

namespace saltus::python {

namespace py = pybind11;

/// A stream buffer that hands every complete line to a Python callable (under the GIL). An
/// exception the callable raises is kept and raised by rethrow() after the solve (an ostream would
/// swallow it).
class PythonLines : public std::streambuf {
 public:
  explicit PythonLines(py::object sink) : sink_(std::move(sink)) {}
  ~PythonLines() override {
    py::gil_scoped_acquire gil;
    sink_ = py::object();
  }
  void rethrow() {
    flush_line();
    if (error_) throw *error_;
  }

 protected:
  int_type overflow(int_type c) override {
    if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
    if (traits_type::to_char_type(c) == '\n')
      flush_line();
    else
      line_ += traits_type::to_char_type(c);
    return c;
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    for (std::streamsize k = 0; k < n; ++k) overflow(traits_type::to_int_type(s[k]));
    return n;
  }

 private:
  void flush_line() {
    if (line_.empty()) return;
    py::gil_scoped_acquire gil;
    if (!error_) {
      try {
        sink_(line_);
      } catch (py::error_already_set& e) {
        error_ = std::move(e);
      }
    }
    line_.clear();
  }
  py::object sink_;
  std::string line_;
  std::optional<py::error_already_set> error_;
};

/// The progress callable: `progress`, or the logger "saltus" at INFO when None.
inline py::object progress_sink(py::object progress) {
  if (progress.is_none()) progress = py::module_::import("logging").attr("getLogger")("saltus").attr("info");
  SALTUS_REQUIRE(PyCallable_Check(progress.ptr()), "progress must be a callable taking one line (str) or None");
  return progress;
}

}  // namespace saltus::python
