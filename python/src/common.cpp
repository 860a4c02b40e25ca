#include "common.h"

#include <filesystem>

namespace rvlio::python {

void Raise(const Status& status) {
  switch (status.code()) {
    case StatusCode::kInternal: throw std::runtime_error(status.message());
    case StatusCode::kIoError:
      PyErr_SetString(PyExc_OSError, status.message().c_str());
      throw py::error_already_set();
    case StatusCode::kOk:  // callers raise only errors; an ok Status here is a bug
    case StatusCode::kInvalidInput: break;
  }
  throw py::value_error(status.message());
}

void ValueError(const std::string& message) { throw py::value_error(message); }

void RequireExisting(const std::string& path, const std::string& what) {
  std::error_code ec;
  if (std::filesystem::exists(path, ec)) return;
  const std::string message = what + " '" + path + "' does not exist";
  PyErr_SetString(PyExc_FileNotFoundError, message.c_str());
  throw py::error_already_set();
}

std::string PathText(const py::handle& path) {
  if (py::isinstance<py::str>(path)) return path.cast<std::string>();
  py::object fspath = py::module_::import("os").attr("fspath");
  return fspath(path).cast<std::string>();  // TypeError for anything else
}

py::object ToPython(const nlohmann::json& j) {
  switch (j.type()) {
    case nlohmann::json::value_t::null: return py::none();
    case nlohmann::json::value_t::boolean: return py::bool_(j.get<bool>());
    case nlohmann::json::value_t::number_integer: return py::int_(j.get<int64_t>());
    case nlohmann::json::value_t::number_unsigned: return py::int_(j.get<uint64_t>());
    case nlohmann::json::value_t::number_float: return py::float_(j.get<double>());
    case nlohmann::json::value_t::string: return py::str(j.get<std::string>());
    case nlohmann::json::value_t::array: {
      py::list l;
      for (const auto& item : j) l.append(ToPython(item));
      return std::move(l);
    }
    case nlohmann::json::value_t::object: {
      py::dict d;
      for (const auto& [key, value] : j.items()) d[py::str(key)] = ToPython(value);
      return std::move(d);
    }
    default: return py::none();
  }
}

Eigen::Vector3d Vector3(const py::handle& value, const char* what) {
  py::array_t<double, py::array::forcecast> a;
  try {
    a = py::array_t<double, py::array::forcecast>::ensure(value);
  } catch (const py::error_already_set&) {
    a = py::array_t<double, py::array::forcecast>();
  }
  if (!a || a.ndim() != 1 || a.shape(0) != 3)
    ValueError(std::string(what) + " must be 3 numbers, got " + py::repr(value).cast<std::string>());
  auto r = a.unchecked<1>();
  return {r(0), r(1), r(2)};
}

py::array_t<double> ToArray(const Eigen::Vector3d& v) {
  py::array_t<double> a(3);
  auto w = a.mutable_unchecked<1>();
  for (int i = 0; i < 3; ++i) w(i) = v[i];
  return a;
}

SignalCheck::~SignalCheck() {
  // Only reached with the GIL held (the owner lives in a bound function).
  Py_XDECREF(type_);
  Py_XDECREF(value_);
  Py_XDECREF(traceback_);
}

bool SignalCheck::Stop() {
  if (stopped_) return true;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_ < kPeriod) return false;
  last_ = now;
  py::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() != 0) Keep();
  return stopped_;
}

void SignalCheck::Keep() {
  PyErr_Fetch(&type_, &value_, &traceback_);
  stopped_ = true;
}

void SignalCheck::Rethrow() {
  if (!stopped_) return;
  PyErr_Restore(type_, value_, traceback_);
  type_ = value_ = traceback_ = nullptr;
  stopped_ = false;
  throw py::error_already_set();
}

}  // namespace rvlio::python
