#pragma once
// Runs a command-line tool as a user does (through the shell) and captures what it printed, for the
// end-to-end tool tests.
#include "support/file_bytes.hpp"

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
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

/// The whole of a file (empty when it cannot be read).
inline std::string file_contents(const std::filesystem::path& path) { return read_bytes(path); }

/// A tool's outcome with its two streams apart.
struct ToolStreams {
  int exit_code;  ///< -1 when the tool did not exit normally (a crash)
  std::string out, err;
};

/// `executable arguments` run from `folder` (relative paths resolve there), stdout and stderr captured
/// through two logs in that folder, removed afterwards.
inline ToolStreams run_tool_in(const std::filesystem::path& folder, const std::string& executable,
                               const std::string& arguments) {
  const std::string command =
      "cd " + folder.string() + " && " + executable + " " + arguments + " > stdout.log 2> stderr.log";
  const int status = std::system(command.c_str());
  ToolStreams r{WIFEXITED(status) ? WEXITSTATUS(status) : -1, file_contents(folder / "stdout.log"),
                file_contents(folder / "stderr.log")};
  std::filesystem::remove(folder / "stdout.log");
  std::filesystem::remove(folder / "stderr.log");
  return r;
}

}  // namespace occ_improve::test
