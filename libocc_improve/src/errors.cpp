#include "occ_improve/errors.hpp"

#include <sstream>

namespace occ_improve::detail {

void require_parameter(bool ok, const char* name, double value, const char* requirement) {
  if (ok) return;
  std::ostringstream message;
  message << name << " = " << value << " is invalid: must be " << requirement;
  throw InvalidParameter(message.str());
}

}  // namespace occ_improve::detail
