#pragma once
// Stopping on SIGINT/SIGTERM: run_tool's handlers call the library's request_stop(signal) (cancel.hpp),
// so the library's long loops and the tools' own (frames, files, shots; throw_if_stop_requested) stop
// within milliseconds with Cancelled, which run_tool reports as "interrupted by SIG..." and exit code
// 128 + the signal. stop_requested() is the signal received, or 0. The handlers reset themselves, so a
// second signal ends the process at once.
#include "occ_improve/cancel.hpp"

namespace occ_improve {

/// Installs the SIGINT and SIGTERM handlers that request a stop (run_tool does, before the tool runs).
void install_stop_signals();

/// For a tool that still writes what it has after a stop (occ_improve_live): the signal received, or 0,
/// and the request withdrawn so that the writing is not cancelled too; the tool then ends with
/// throw Cancelled(signal). The frame or shot in flight when the signal came is left partly inserted.
int take_stop_request();

}  // namespace occ_improve
