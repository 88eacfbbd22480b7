#pragma once
// One error policy for the whole library: every failure throws a type from this small hierarchy,
// rooted in std::runtime_error, with a message that names the offending parameter, file or value.
// The library never aborts or exits.
#include <stdexcept>
#include <string>

namespace occ_improve {

/// Root of every exception thrown by occ_improve.
class Error : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

/// A parameter is out of its accepted range (the message names the parameter and the range).
class InvalidParameter : public Error {
public:
  using Error::Error;
};

/// Input data cannot be used as a whole (empty, wrong size, wrong organisation).
class InvalidInput : public Error {
public:
  using Error::Error;
};

/// A file cannot be opened, read or written.
class IoError : public Error {
public:
  using Error::Error;
};

/// A file was read but is not in the expected format (corrupt, truncated, wrong version).
class FormatError : public Error {
public:
  using Error::Error;
};

/// A request would exceed a configured resource limit (for example the grid memory cap).
class ResourceLimit : public Error {
public:
  using Error::Error;
};

/// A call stopped because a stop was requested (cancel.hpp: request_stop, e.g. from a SIGINT handler).
/// Nothing is wrong with the input; reason() is what request_stop was given (the tools: the signal
/// number), and the message says "interrupted by SIGINT" / "SIGTERM" for those two.
class Cancelled : public Error {
public:
  explicit Cancelled(int reason);
  int reason() const { return reason_; }

private:
  int reason_;
};

namespace detail {
/// Throws InvalidParameter("<name> = <value> is invalid: must be <requirement>") unless `ok`.
void require_parameter(bool ok, const char* name, double value, const char* requirement);
}  // namespace detail

}  // namespace occ_improve
