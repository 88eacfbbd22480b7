#pragma once
// Runs a command-line tool as a user does (through the shell) and captures what it printed, for the
// end-to-end tool tests.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace occ_improve::test {

struct ToolRun {
  int exit_code;       ///< -1 when the tool did not exit normally (a crash)
  std::string output;  ///< stdout and stderr, interleaved as printed
};

/// `executable arguments`, its output captured through `log` (a file outside any folder the test counts).
inline ToolRun run_tool_command(const std::string& executable, const std::string& arguments,
                                const std::filesystem::path& log) {
  const std::string command = executable + " " + arguments + " > " + log.string() + " 2>&1";
  const int status = std::system(command.c_str());
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text.str()};
}

}  // namespace occ_improve::test
