#pragma once
// The shared main() of the command-line tools.
#include "occ_improve/tools/flag_usage.hpp"

namespace occ_improve {

/// The shared main() of the command-line tools: prints usage_text on -h/-help/--help (exit 0) and on no
/// argument at all (exit 1), otherwise parses the command line against `flags`, installs the stop-signal
/// handlers and runs `run`. Any exception, a refused flag, std::bad_alloc and non-standard ones included,
/// becomes ONE line "error: ..." on stderr naming the input being worked on (InputScope) and exit code 1;
/// Cancelled becomes "interrupted by SIG..." and exit code 128 + the signal number.
int run_tool(int argc, char** argv, const ToolFlags& flags, int (*run)(const CommandLine& command_line));

}  // namespace occ_improve
