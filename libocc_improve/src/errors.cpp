#include "occ_improve/errors.hpp"

#include <cmath>
#include <csignal>
#include <sstream>
#include <string>

namespace occ_improve {

namespace {
std::string cancelled_message(int reason) {
  if (reason == SIGINT) return "interrupted by SIGINT";
  if (reason == SIGTERM) return "interrupted by SIGTERM";
  return "cancelled (stop requested, reason " + std::to_string(reason) + ")";
}
}  // namespace

Cancelled::Cancelled(int reason) : Error(cancelled_message(reason)), reason_(reason) {}

}  // namespace occ_improve

namespace occ_improve::detail {

void require_parameter(bool ok, const char* name, double value, const char* requirement) {
  if (ok) return;
  std::ostringstream message;
  message << name << " = ";
  // A whole number as written (budget_rays = 2147483647, not 2.14748e+09); others at 6 significant digits.
  if (std::abs(value) < 1e15 && value == std::floor(value))
    message << static_cast<long long>(value);
  else
    message << value;
  message << " is invalid: must be " << requirement;
  throw InvalidParameter(message.str());
}

}  // namespace occ_improve::detail
