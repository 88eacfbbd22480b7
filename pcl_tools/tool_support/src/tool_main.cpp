#include "occ_improve/tools/tool_main.hpp"

#include "occ_improve/cancel.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/tools/batch.hpp"
#include "occ_improve/tools/input_scope.hpp"
#include "occ_improve/tools/output_files.hpp"
#include "occ_improve/tools/signals.hpp"

#include <pcl/console/print.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <new>

namespace occ_improve {

namespace {

// The exit code, ending the process at once when a stop abandoned a PCL read (frame_io.hpp: its thread
// runs on, and destroying the program's statics under it could crash the exit) or left a large structure
// to the process's end (signals.hpp). Everything of ours is done by then (the staged outputs were removed
// or committed while unwinding).
int finish(int code) {
  if (code != 0) remove_created_folders_left_empty();
  if (pcl_read_abandoned() || process_ends_at_once()) {
    std::fflush(nullptr);
    std::_Exit(code);
  }
  return code;
}

// One line on stderr: the message, and the input being worked on when the message does not name it. After
// a stop signal the run ends as interrupted (128 + signal) whatever failed next: the user asked it to stop
// (a long read that no poll interrupts, then the error the next step found).
int report_failure(const std::string& message) {
  std::fprintf(stderr, "%s\n", failure_line(message).c_str());
  if (const int signal = stop_requested()) {
    std::fprintf(stderr, "%s\n", Cancelled(signal).what());
    return finish(128 + signal);
  }
  return finish(1);
}

bool help_requested(int argc, const char* const* argv) {
  for (int i = 1; i < argc; ++i)
    if (std::strcmp(argv[i], "-h") == 0 || std::strcmp(argv[i], "-help") == 0 || std::strcmp(argv[i], "--help") == 0)
      return true;
  return false;
}

}  // namespace

int run_tool(int argc, char** argv, const ToolFlags& flags, int (*run)(const CommandLine& command_line)) {
  const std::string program = std::filesystem::path(argv[0]).filename().string();
  if (help_requested(argc, argv) || argc < 2) {
    std::fputs(usage_text(flags, program).c_str(), argc < 2 ? stderr : stdout);
    return argc < 2 ? 1 : 0;
  }
  install_stop_signals();
  try {
    const CommandLine command_line = parse_command_line(flags, argc, argv);
    if (command_line.has("-v")) {
      pcl::console::setVerbosityLevel(pcl::console::L_DEBUG);
      std::fprintf(stderr, "%s with:\n%s", program.c_str(), resolved_flags(command_line).c_str());
    }
    const int code = batch_requested(command_line) ? run_batch(command_line, run) : run(command_line);
    // A signal that came too late for any poll (during the final renames, say) still ends in 128 + signal,
    // as the README promises; the run had finished, so what it wrote is in place.
    if (const int signal = stop_requested()) {
      std::fprintf(stderr, "%s after the run had finished (its outputs are committed)\n", Cancelled(signal).what());
      return finish(128 + signal);
    }
    return finish(code);
  } catch (const Cancelled& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return finish(128 + e.reason());
  } catch (const std::bad_alloc&) {
    return report_failure("out of memory (std::bad_alloc)");
  } catch (const std::exception& e) {
    return report_failure(e.what());
  } catch (...) {
    return report_failure("unknown exception");
  }
}

}  // namespace occ_improve
