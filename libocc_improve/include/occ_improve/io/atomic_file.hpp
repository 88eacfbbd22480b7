#pragma once
// Writing files and output folders so that a crash or failure never leaves a half-written file under its
// real name, and so that nothing a user owns is overwritten or deleted.
//  - A file's content goes to a temporary beside the target (same folder, hence same file system) and is
//    renamed over the target only once complete (rename is atomic on POSIX file systems).
//  - A tool's output folder is filled in a staging folder beside it and moved into place at the end; a
//    folder that already holds files the tool did not write is refused unless the user says -overwrite.
#include <filesystem>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace occ_improve {

/// Calls `write` on a binary stream to a temporary file beside `path`, then renames it to `path`.
/// `write` returns false when it failed. Throws IoError naming `what` and `path` when the temporary
/// cannot be created, `write` fails, the stream fails or the rename fails; the temporary is removed and
/// an existing file at `path` is left as it was, also when `write` throws (Cancelled: it may poll for a
/// stop), which propagates.
void write_file_atomically(const std::string& path, const std::string& what,
                           const std::function<bool(std::ostream&)>& write);

/// `path` absolute and normal, with the symbolic links of its existing part resolved: two names of one
/// file compare equal.
std::filesystem::path comparable_path(const std::string& path);

/// Whether `inner` is `outer` or lies below it, both made absolute with the symbolic links of their
/// existing parts resolved (an output against the run's inputs, an input against an output folder).
bool path_is_within(const std::string& inner, const std::string& outer);

/// The first of `inputs` that writing `path` would replace: the same file (by name or by identity), or an
/// input folder `path` lies in; nullptr when none (the -save check and OutputFolder's both ask this).
const std::string* replaced_input(const std::string& path, const std::vector<std::string>& inputs);

/// Throws IoError "cannot read <what> '<path>': it is a folder" when `path` names a folder: a reader would
/// otherwise open it and report a format error about its (absent) contents.
void throw_if_folder(const std::string& path, const std::string& what);

/// Whether `path` names something that exists and is neither a regular file nor a folder (a pipe, socket or
/// device): opening a pipe without a writer blocks, and its contents have no size to read or magic to check.
bool is_pipe_or_device(const std::string& path);

/// write_file_atomically of a text held in memory (CSV tables, plan summaries).
void write_text_file(const std::string& path, const std::string& what, const std::string& text);

/// Why writing `path` failed, for an error message: "no space left on device" when errno says so,
/// strerror(errno) for another errno ("permission denied", ...), and without errno "no space left on
/// device" when the file system of `path` has no room left. Call it right after the failed operation.
std::string describe_write_failure(const std::string& path);

/// Removes the entries of `folder` named "<prefix><pid>..." that a writer killed mid-write left behind:
/// those whose PID is not running, or is running a process that started after the entry was last
/// modified (the PID was reused). A live writer's entries are kept. Called before each write to the same
/// place (write_file_atomically: "<name>.partial-", OutputFolder: ".<name>.tmp-").
void remove_stale_leftovers(const std::string& folder, const std::string& prefix);

/// One output file of a tool (-save MAP, occ_to_octomap's -o TREE), checked before any work and written in
/// two steps, so that a run that fails anywhere leaves the previous file as it was:
///  - the constructor refuses (IoError/InvalidParameter naming `flag`): a folder, a pipe, socket or device
///    (whose magic cannot be read without blocking or consuming it), a missing or unwritable parent, and an
///    existing file that `is_own` does not recognise as one this project wrote (checked by its magic) unless
///    `overwrite` (the message tells how: `how_to_overwrite`, a tool's "give -overwrite"), and an existing
///    file without any write permission bit (its owner protected it: refused with `overwrite` too); a
///    symbolic link is written through (the link stays, its target changes);
///  - staged() is where the content is written (a temporary beside the target);
///  - commit() renames it over the target (it may be written and committed again: a tool that saves as it
///    goes); the destructor removes a staged file never committed.
class OutputFile {
public:
  OutputFile(const std::string& target, const std::string& flag, bool overwrite,
             const std::function<bool(const std::string& existing)>& is_own, const std::string& kind,
             const std::string& how_to_overwrite = "give -overwrite");
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;
  ~OutputFile();

  /// The temporary to write the content to (a file the writer may itself replace atomically).
  const std::string& staged() const { return staged_; }
  /// Moves the staged file over the target. Throws IoError when there is no staged file or the rename fails.
  void commit();
  /// The target as the user named it.
  const std::string& path() const { return shown_; }

private:
  std::string shown_, target_, staged_;
};

/// The file by which an output folder says which tool wrote it: the tool's name on the first line, then
/// one line per file the tool wrote there.
inline constexpr const char* kOutputMarkerName = ".occ_improve_output";

/// A tool's output folder. Files are written into a staging folder beside the target (file()), and
/// commit() moves them into place:
///  - a target that does not exist, is empty, or holds only what an earlier run of the same tool wrote
///    there (by its marker) is replaced as a whole (atomic rename) and gets a new marker;
///  - any other non-empty folder is refused (IoError naming -overwrite) unless `overwrite` is set; then
///    the staged files are renamed into it one by one, replacing only files of the same names, and no
///    marker is written (the folder still is not the tool's own).
/// A symbolic link to a folder is written through: the link stays and the folder it names is replaced.
/// A run killed between the two renames of a commit leaves the old output as ".<name>.tmp-<pid>.old"; the
/// next OutputFolder on the same target moves it back when the target is missing, and leftovers of dead
/// runs are removed only after a successful commit.
/// The staging folder is removed on destruction unless committed. commit() may be called again after
/// more files are written (a tool that publishes intermediate results); each call replaces the last.
class OutputFolder {
public:
  /// Throws IoError when the parent folder does not exist, `target` is not a folder, the staging folder
  /// cannot be created, or the folder is not the tool's own and `overwrite` is false; and when it is the
  /// tool's own (so would be replaced as a whole) but holds one of `inputs`, the paths the run reads (a map
  /// an earlier run saved there): replacing the folder would delete it.
  OutputFolder(const std::string& target, const std::string& tool, bool overwrite,
               const std::vector<std::string>& inputs = {});
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  ~OutputFolder();

  /// The staged path of output file `name` (a plain file name); commit() moves it into the target.
  /// Throws IoError naming the input when the target is not the tool's own and already holds a file of
  /// that name that is one of `inputs` or lies in an input folder (a folder written into under `overwrite`
  /// replaces files by name; commit() checks again).
  std::string file(const std::string& name);
  /// Moves the staged files into the target (see the class comment). Throws IoError on failure, leaving
  /// the target as it was.
  void commit();
  /// The target as the user named it.
  const std::string& path() const { return shown_; }
  /// The folder the files go to, absolute and with symbolic links resolved.
  const std::filesystem::path& resolved() const { return target_; }

private:
  bool target_is_own() const;
  void recover_interrupted_commit();
  void require_no_input_inside(const std::vector<std::string>& inputs) const;
  void require_not_an_input(const std::string& name) const;
  void replace_whole();
  void move_files_in();

  std::filesystem::path target_, staging_;
  std::string shown_, tool_;
  bool overwrite_;
  std::vector<std::string> inputs_;
  std::vector<std::string> files_;
};

}  // namespace occ_improve
