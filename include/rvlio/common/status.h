#pragma once
// Error values for bad data (docs/design.md "Conventions"): library code never exits or
// prints; it returns a Status whose message names the file, topic or key.
#include <optional>
#include <string>
#include <utility>

#include "rvlio/common/check.h"

namespace rvlio {

enum class StatusCode { kOk = 0, kInvalidInput = 2, kInternal = 1 };

class Status {
 public:
  Status() = default;
  static Status Ok() { return Status(); }
  static Status InvalidInput(std::string message) {
    return Status(StatusCode::kInvalidInput, std::move(message));
  }
  static Status Internal(std::string message) {
    return Status(StatusCode::kInternal, std::move(message));
  }
  bool ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }
  // Exit status of the command-line contract: 0 ok, 2 bad input, 1 internal.
  int exit_code() const { return static_cast<int>(code_); }

 private:
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

// A value or the Status that explains why there is none.
template <typename T>
class StatusOr {
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
