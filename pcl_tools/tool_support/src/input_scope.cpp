#include "occ_improve/tools/input_scope.hpp"

#include <algorithm>
#include <exception>

namespace occ_improve {

namespace {

std::string& current_input() {
  static std::string input;
  return input;
}
// The innermost input whose scope an exception left: recorded while unwinding, read by run_tool.
std::string& failed_input() {
  static std::string input;
  return input;
}

}  // namespace

std::string failure_line(const std::string& message) {
  std::string line = message;
  std::replace(line.begin(), line.end(), '\n', ' ');
  const std::string& input = failed_input();
  if (!input.empty() && line.find(input) == std::string::npos) line += " (input '" + input + "')";
  failed_input().clear();
  return "error: " + line;
}

InputScope::InputScope(const std::string& input) : previous_(current_input()), uncaught_(std::uncaught_exceptions()) {
  current_input() = input;
}

InputScope::~InputScope() {
  if (std::uncaught_exceptions() > uncaught_ && failed_input().empty()) failed_input() = current_input();
  current_input() = previous_;
}

}  // namespace occ_improve
