#pragma once
// Shared by the binding files: Status -> Python exception, argument checks,
// and the signal check that lets Ctrl-C stop a long call.
#include <Python.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <chrono>
#include <string>

#include <nlohmann/json.hpp>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"

namespace rvlio::python {

namespace py = pybind11;

// Raises the Python exception of a failed status: ValueError for bad input
// (the message the command-line tool prints after "rvlio CMD: "),
// RuntimeError for an internal error.
[[noreturn]] void Raise(const Status& status);
inline void Check(const Status& status) {
  if (!status.ok()) Raise(status);
}
template <typename T>
T Take(StatusOr<T> value) {
  if (!value.ok()) Raise(value.status());
  return std::move(*value);
}

// FileNotFoundError naming `what` unless `path` exists.
void RequireExisting(const std::string& path, const std::string& what);

// str or os.PathLike -> path text (TypeError otherwise).
std::string PathText(const py::handle& path);

// A JSON value as the Python object json.loads would give.
py::object ToPython(const nlohmann::json& j);

// ValueError with `message`.
[[noreturn]] void ValueError(const std::string& message);

// Reads a length-3 float vector (list, tuple or array); ValueError naming `what`.
Eigen::Vector3d Vector3(const py::handle& value, const char* what);

// Created with the GIL held; Stop() may be called with the GIL released (in a
// long call's progress callback): at most every kPeriod it takes the GIL and
// runs Python's signal handlers (PyErr_CheckSignals), so Ctrl-C raises
// KeyboardInterrupt. Once a handler raised, Stop() stays true; Rethrow() (GIL
// held again) raises that exception.
class SignalCheck {
 public:
  SignalCheck() = default;
  ~SignalCheck();
  SignalCheck(const SignalCheck&) = delete;
  SignalCheck& operator=(const SignalCheck&) = delete;
  bool Stop();
  // Runs `f` with the GIL (the caller has released it); a Python exception
  // it raises stops the call as a signal does, and Rethrow() raises it.
  template <typename F>
  void CallPython(F&& f) {
    if (stopped_) return;
    py::gil_scoped_acquire gil;
    try {
      f();
    } catch (py::error_already_set& e) {
      e.restore();
      Keep();
    }
  }
  void Rethrow();

 private:
  void Keep();  // moves the raised Python error (GIL held) into this object
  static constexpr std::chrono::milliseconds kPeriod{50};
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
  bool stopped_ = false;
  PyObject* type_ = nullptr;
  PyObject* value_ = nullptr;
  PyObject* traceback_ = nullptr;
};

// Python-side views of the library's sensor types.
py::array_t<double> ToArray(const Eigen::Vector3d& v);

}  // namespace rvlio::python
