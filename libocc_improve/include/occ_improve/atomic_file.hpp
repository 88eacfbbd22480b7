#pragma once
// Writing a file so that a crash or failure never leaves a half-written file under its real name: the
// content goes to a temporary beside the target (same folder, hence same file system) and is renamed
// over the target only once complete (rename is atomic on POSIX file systems).
#include <functional>
#include <ostream>
#include <string>

namespace occ_improve {

/// Calls `write` on a binary stream to a temporary file beside `path`, then renames it to `path`.
/// `write` returns false when it failed. Throws IoError naming `what` and `path` when the temporary
/// cannot be created, `write` fails, the stream fails or the rename fails; the temporary is removed and
/// an existing file at `path` is left as it was.
void write_file_atomically(const std::string& path, const std::string& what,
                           const std::function<bool(std::ostream&)>& write);

}  // namespace occ_improve
