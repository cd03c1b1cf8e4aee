#pragma once
// A data-dependent outcome: success, or failure with a one-line reason. The library returns a Status
// wherever input data can be wrong; CHECK is reserved for programmer errors. [[nodiscard]]: a
// returned Status must be looked at; where dropping one is right, `(void)` with a comment says why.

#include <string>
#include <utility>

namespace photopose {

class [[nodiscard]] Status {
 public:
  Status() = default;
  static Status Ok() { return Status(); }
  static Status Error(std::string message) { return Status(std::move(message)); }

  bool ok() const { return !failed_; }
  const std::string& message() const { return message_; }

 private:
  explicit Status(std::string message) : failed_(true), message_(std::move(message)) {}
  bool failed_ = false;
  std::string message_;
};

// How an `IsValid(std::string* why)` says no: `why` (when not null) gets the reason, and false is
// returned (`if (x < 0) return InvalidBecause(why, "x must be >= 0");`).
inline bool InvalidBecause(std::string* why, std::string reason) {
  if (why != nullptr) *why = std::move(reason);
  return false;
}

// The outcome of `value.IsValid(&why)` (the XxxOptions convention, `bool IsValid(std::string*)`)
// as a Status: Ok, or an Error reading `prefix` + why ("invalid options: the loss scale must be
// positive").
template <typename Validated>
Status Validate(const Validated& value, const std::string& prefix = "") {
  std::string why;
  if (value.IsValid(&why)) return Status::Ok();
  return Status::Error(prefix + why);
}

}  // namespace photopose

// Returns the Status of `expr` from the enclosing function when it is an error.
#define PHOTOPOSE_RETURN_IF_ERROR(expr) \
  do {                                  \
    ::photopose::Status status_ = (expr); \
    if (!status_.ok()) return status_;  \
  } while (false)
