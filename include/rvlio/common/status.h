#pragma once
// Error values for bad data (docs/design.md "Conventions"): library code never exits or
// prints; it returns a Status whose message names the file, topic or key.
#include <optional>
#include <string>
#include <utility>

#include "rvlio/common/check.h"

namespace rvlio {

// What went wrong, not how a program reports it: the command maps a code to its exit
// status (cli::ExitCode, apps/cli.h), the Python module to an exception type.
enum class StatusCode {
  kOk,
  kInvalidInput,  // the caller's input is wrong: an option, configuration key or value, a
                  // missing or malformed recording, map or trajectory
  kIoError,       // the system refused a write: output folder or file cannot be created,
                  // written, synced or renamed (permissions, full disk)
  kInternal,      // a broken invariant or an estimate that cannot be formed: not the input
};

// Ignoring a Status loses the error: every result is handled or discarded explicitly
// with a comment saying why ignoring it is right.
class [[nodiscard]] Status {
 public:
  Status() = default;
  static Status Ok() { return Status(); }
  static Status InvalidInput(std::string message) {
    return Status(StatusCode::kInvalidInput, std::move(message));
  }
  static Status Internal(std::string message) {
    return Status(StatusCode::kInternal, std::move(message));
  }
  static Status IoError(std::string message) {
    return Status(StatusCode::kIoError, std::move(message));
  }
  bool ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }
  // The same kind of error with another message (e.g. the context prepended).
  Status WithMessage(std::string message) const { return Status(code_, std::move(message)); }

 private:
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

// A value or the Status that explains why there is none.
template <typename T>
class [[nodiscard]] StatusOr {
 public:
  StatusOr(T value) : value_(std::move(value)) {}  // NOLINT: implicit by design
  StatusOr(Status status) : status_(std::move(status)) {  // NOLINT
    RVLIO_CHECK_MSG(!status_.ok(), "StatusOr built from an ok Status without a value");
  }
  bool ok() const { return value_.has_value(); }
  const Status& status() const { return status_; }
  const T& value() const& { RVLIO_CHECK(ok()); return *value_; }
  T& value() & { RVLIO_CHECK(ok()); return *value_; }
  T&& value() && { RVLIO_CHECK(ok()); return std::move(*value_); }
  const T& operator*() const& { return value(); }
  T& operator*() & { return value(); }
  const T* operator->() const { return &value(); }
  T* operator->() { return &value(); }

 private:
  std::optional<T> value_;
  Status status_;
};

}  // namespace rvlio
