#pragma once
// Which input a tool is working on, so that its one error line names it even when the failure's message
// does not (std::bad_alloc).
#include <string>

namespace occ_improve {

/// Names the input a tool is working on while it lives, so that run_tool's error line names it even for
/// a failure whose message does not (std::bad_alloc). Nested scopes name the innermost input.
class InputScope {
public:
  explicit InputScope(const std::string& input);
  InputScope(const InputScope&) = delete;
  InputScope& operator=(const InputScope&) = delete;
  ~InputScope();

private:
  std::string previous_;
  int uncaught_;
};

/// The one error line of a failure ("error: MESSAGE"), naming the input whose InputScope the exception
/// left when MESSAGE does not; that input is then forgotten (a batch goes on to the next file).
std::string failure_line(const std::string& message);

}  // namespace occ_improve
