#include "occ_improve/io/atomic_file.hpp"

#include "occ_improve/errors.hpp"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>
#include <sys/statvfs.h>
#include <unistd.h>

namespace occ_improve {
namespace fs = std::filesystem;
namespace {

// "<path>.partial-<pid>-<random>": the PID lets a later write tell a dead writer's leftover from a live one.
std::string temporary_name(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  std::random_device random;
  std::ostringstream name;
  name << path << ".partial-" << ::getpid() << '-' << std::hex << random() << counter++;
  return name.str();
}

// When process `pid` started, from /proc (Linux); nullopt when no such process is running.
std::optional<fs::file_time_type::duration> process_start_since_epoch(long pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text;
  if (!stat || !std::getline(stat, text) || text.rfind(')') == std::string::npos) return std::nullopt;
  std::istringstream fields(text.substr(text.rfind(')') + 2));  // after "pid (name) "
  std::string field;
  for (int i = 3; i < 22 && fields >> field;) ++i;  // field 22: start time in clock ticks since boot
  unsigned long long ticks = 0, boot = 0;
  if (!(fields >> ticks)) return std::nullopt;
  std::ifstream proc_stat("/proc/stat");
  for (std::string key; proc_stat >> key;)
    if (key == "btime" && proc_stat >> boot) break;
  const double seconds = static_cast<double>(boot) + static_cast<double>(ticks) / static_cast<double>(::sysconf(_SC_CLK_TCK));
  return std::chrono::duration_cast<fs::file_time_type::duration>(std::chrono::duration<double>(seconds));
}

// A leftover named by the PID of its writer is stale when that PID is not running, or runs a process
// that started after the leftover was last modified (the PID was reused: the writer is gone).
bool is_stale(const fs::path& leftover, long pid) {
  const auto started = process_start_since_epoch(pid);
  if (!started) return true;
  std::error_code ec;
  const fs::file_time_type modified = fs::last_write_time(leftover, ec);
  if (ec) return false;
  const auto modified_since_epoch = std::chrono::duration_cast<fs::file_time_type::duration>(
      std::chrono::system_clock::now().time_since_epoch() - (fs::file_time_type::clock::now() - modified));
  // One second of slack: /proc's start time has clock-tick resolution, btime whole seconds.
  return modified_since_epoch + std::chrono::seconds(1) < *started;
}

// The PID in a leftover's name "<prefix><pid>...", or nullopt when the name is not one (not ours to judge).
std::optional<long> leftover_pid(const std::string& name, const std::string& prefix) {
  if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) return std::nullopt;
  const std::size_t end_of_pid = std::min(name.find_first_not_of("0123456789", prefix.size()), name.size());
  const std::size_t length = end_of_pid - prefix.size();
  if (length == 0 || length > 9) return std::nullopt;
  return std::stol(name.substr(prefix.size(), length));
}

// Whether the file system holding `path` (or its folder, for a file not yet there) has no block left.
bool no_room_left(const fs::path& path) {
  struct statvfs info {};
  const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
  return ::statvfs(folder.c_str(), &info) == 0 && info.f_bavail == 0;
}

}  // namespace

std::string describe_write_failure(const std::string& path) {
  const int error = errno;
  if (error == ENOSPC) return "no space left on device";
  if (error != 0) return std::generic_category().message(error);
  // No errno (a stream that failed without saying why): a full file system is the usual cause.
  return no_room_left(path) ? "no space left on device" : "write failed";
}

void remove_stale_leftovers(const std::string& folder, const std::string& prefix) {
  std::error_code ec;
  for (fs::directory_iterator it(folder.empty() ? "." : folder, ec), end; it != end && !ec; it.increment(ec)) {
    const auto pid = leftover_pid(it->path().filename().string(), prefix);
    std::error_code ignored;
    if (pid && is_stale(it->path(), *pid)) fs::remove_all(it->path(), ignored);
  }
}

namespace {

// The files an earlier run of `tool` listed in `folder`'s marker; nullopt without a marker of `tool`.
std::optional<std::vector<std::string>> files_listed_by(const fs::path& folder, const std::string& tool) {
  std::ifstream in(folder / kOutputMarkerName);
  std::string line;
  if (!in || !std::getline(in, line) || line != tool) return std::nullopt;
  std::vector<std::string> files;
  while (std::getline(in, line))
    if (!line.empty()) files.push_back(line);
  return files;
}

// True when every entry of `folder` is its marker or a regular file the marker lists.
bool holds_only(const fs::path& folder, const std::vector<std::string>& listed) {
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; it != end && !ec; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name == kOutputMarkerName) continue;
    if (!it->is_regular_file(ec) || std::find(listed.begin(), listed.end(), name) == listed.end()) return false;
  }
  return !ec;
}

}  // namespace

void write_file_atomically(const std::string& path, const std::string& what,
                           const std::function<bool(std::ostream&)>& write) {
  const fs::path target(path);
  remove_stale_leftovers(target.parent_path().string(), target.filename().string() + ".partial-");
  const std::string temporary = temporary_name(path);
  bool written = false;
  std::string failure;
  {
    errno = 0;
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out)
      throw IoError("cannot write " + what + " '" + path + "': cannot create '" + temporary +
                    "': " + describe_write_failure(temporary));
    try {
      written = write(out);
    } catch (...) {  // a stop request (Cancelled) or the writer's own error: nothing left behind
      out.close();
      std::error_code ignored;
      fs::remove(temporary, ignored);
      throw;
    }
    out.close();
    written = written && static_cast<bool>(out);
    if (!written) failure = describe_write_failure(temporary);
  }
  std::error_code error;
  if (written) fs::rename(temporary, path, error);
  if (!written || error) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw IoError("cannot write " + what + " '" + path + "': " + (error ? error.message() : failure));
  }
}

namespace {

// `path` made absolute and normal, a symbolic link followed to what it names (so that a later rename
// replaces the named file or folder, not the link). A dangling link is refused: there is nothing to replace.
fs::path resolved_target(const std::string& path, const std::string& what) {
  fs::path target = fs::absolute(path).lexically_normal();
  if (target.filename().empty()) target = target.parent_path();  // "out/" and "." name the folder itself
  std::error_code ec;
  if (!fs::is_symlink(target, ec)) return target;
  const fs::path linked = fs::canonical(target, ec);
  if (ec) throw IoError(what + " '" + path + "' is a symbolic link to nothing (" + ec.message() + ")");
  return linked;
}

// Refuses a parent that is missing, not a folder, unreachable or not writable, naming the real cause.
void require_writable_folder(const fs::path& folder, const std::string& what, const std::string& shown) {
  std::error_code ec;
  const fs::file_status status = fs::status(folder, ec);
  std::string problem;
  if (ec && ec != std::errc::no_such_file_or_directory)
    problem = "cannot reach '" + folder.string() + "': " + ec.message();
  else if (!fs::exists(status))
    problem = "'" + folder.string() + "' does not exist";
  else if (!fs::is_directory(status))
    problem = "'" + folder.string() + "' is not a folder";
  else if (::access(folder.c_str(), W_OK | X_OK) != 0)
    problem = "cannot write in '" + folder.string() + "': " + std::generic_category().message(errno);
  if (!problem.empty()) throw IoError("cannot write " + what + " '" + shown + "': " + problem);
}

// "<folder>/.<name>.staged-<pid>-<random><extension>": hidden, named by its writer's PID (for
// remove_stale_leftovers) and keeping the target's extension (writers that choose the format by it).
fs::path staged_name(const fs::path& target) {
  std::random_device random;
  std::ostringstream name;
  name << "." << target.filename().string() << ".staged-" << ::getpid() << '-' << std::hex << random()
       << target.extension().string();
  return target.parent_path() / name.str();
}

}  // namespace

fs::path comparable_path(const std::string& path) {
  std::error_code ec;
  const fs::path resolved = fs::weakly_canonical(fs::absolute(path), ec);
  return ec ? fs::absolute(path).lexically_normal() : resolved;
}

bool path_is_within(const std::string& inner, const std::string& outer) {
  const fs::path relative = comparable_path(inner).lexically_relative(comparable_path(outer));
  return !relative.empty() && *relative.begin() != "..";
}

const std::string* replaced_input(const std::string& path, const std::vector<std::string>& inputs) {
  const fs::path target = comparable_path(path);
  for (const std::string& input : inputs) {
    std::error_code ec;
    const fs::path source = comparable_path(input);
    if (target == source || fs::equivalent(target, source, ec) || (fs::is_directory(source, ec) && path_is_within(path, input)))
      return &input;
  }
  return nullptr;
}

void throw_if_folder(const std::string& path, const std::string& what) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw IoError("cannot read " + what + " '" + path + "': it is a folder");
}

bool is_pipe_or_device(const std::string& path) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  return !ec && fs::exists(status) && !fs::is_regular_file(status) && !fs::is_directory(status);
}

void write_text_file(const std::string& path, const std::string& what, const std::string& text) {
  write_file_atomically(path, what, [&](std::ostream& out) {
    return static_cast<bool>(out.write(text.data(), static_cast<std::streamsize>(text.size())));
  });
}

OutputFile::OutputFile(const std::string& target, const std::string& flag, bool overwrite,
                       const std::function<bool(const std::string&)>& is_own, const std::string& kind,
                       const std::string& how_to_overwrite)
    : shown_(target) {
  const fs::path resolved = resolved_target(target, flag);
  const std::string what = flag + " file";
  std::error_code ec;
  if (fs::is_directory(resolved, ec))
    throw IoError("cannot write " + what + " '" + target + "': it is a folder; name a file");
  // is_own reads the file's magic: a pipe would block it (forever, Ctrl-C or not), a device give it bytes.
  if (is_pipe_or_device(resolved.string()))
    throw IoError("cannot write " + what + " '" + target + "': it is not a regular file (a pipe, socket or device); name a file");
  require_writable_folder(resolved.parent_path(), what, target);
  if (fs::exists(resolved, ec) && !overwrite && !is_own(resolved.string()))
    throw IoError(flag + " '" + target + "' exists and is not " + kind + " written by occ_improve: choose another name, or " +
                  how_to_overwrite + " to replace it");
  // A file nobody may write is one its owner protected: the rename that replaces a file would ignore that
  // (as root too), so it is refused, -overwrite or not, as a read-only output folder is.
  constexpr fs::perms kWriteBits = fs::perms::owner_write | fs::perms::group_write | fs::perms::others_write;
  if (fs::exists(resolved, ec) && (fs::status(resolved, ec).permissions() & kWriteBits) == fs::perms::none)
    throw IoError(flag + " '" + target + "' is read-only: make it writable (chmod u+w) to replace it, or choose "
                  "another name");
  remove_stale_leftovers(resolved.parent_path().string(), "." + resolved.filename().string() + ".staged-");
  target_ = resolved.string();
  staged_ = staged_name(resolved).string();
  errno = 0;
  if (!std::ofstream(staged_, std::ios::binary))  // the writability check, for real
    throw IoError("cannot write " + what + " '" + target + "': " + describe_write_failure(staged_));
}

OutputFile::~OutputFile() {
  std::error_code ignored;
  fs::remove(staged_, ignored);
}

void OutputFile::commit() {
  std::error_code ec;
  fs::rename(staged_, target_, ec);
  if (ec) throw IoError("cannot move the new '" + shown_ + "' into place: " + ec.message());
}

OutputFolder::OutputFolder(const std::string& target, const std::string& tool, bool overwrite,
                           const std::vector<std::string>& inputs)
    : target_(resolved_target(target, "output folder")), shown_(target), tool_(tool), overwrite_(overwrite),
      inputs_(inputs) {
  const fs::path parent = target_.parent_path();
  require_writable_folder(parent, "output folder", shown_);
  std::error_code ec;
  if (fs::exists(target_, ec) && !fs::is_directory(target_, ec))
    throw IoError("output folder '" + shown_ + "' exists and is not a folder");
  // A folder the user made read-only stays so: replacing it by the staged one (its parent is writable)
  // would give a writable folder in its place.
  if (fs::exists(target_, ec)) require_writable_folder(target_, "output folder", shown_);
  recover_interrupted_commit();
  require_no_input_inside(inputs);
  if (!overwrite_ && !target_is_own())
    throw IoError("output folder '" + shown_ + "' already holds files " + tool_ +
                  " did not write: choose another -o, or give -overwrite to write into it (files of the "
                  "same names are replaced, nothing else is touched)");
  staging_ = parent / ("." + target_.filename().string() + ".tmp-" + std::to_string(::getpid()));
  // Entries named by this PID are a dead run's whose PID was reused (the old output, if needed, was moved
  // back above): they must not be published with this run's files or block its rename.
  fs::remove_all(staging_, ec);
  fs::remove_all(fs::path(staging_.string() + ".old"), ec);
  fs::create_directory(staging_, ec);
  if (ec) throw IoError("cannot write output folder '" + shown_ + "': cannot create '" + staging_.string() + "': " +
                        ec.message());
}

void OutputFolder::require_no_input_inside(const std::vector<std::string>& inputs) const {
  if (!target_is_own()) return;  // not replaced as a whole: refused, or written into file by file
  for (const std::string& input : inputs) {
    if (path_is_within(input, target_.string()))
      throw IoError("output folder '" + shown_ + "' holds the input '" + input +
                    "', which replacing the folder would delete: choose another -o");
  }
}

// A folder that is not the tool's own takes the staged files under -overwrite by name, replacing files of
// the same names: never one the run reads (an input named like an output, or a file in an input folder).
// (The tool's own folder is replaced as a whole: require_no_input_inside guards it.)
void OutputFolder::require_not_an_input(const std::string& name) const {
  const fs::path published = target_ / name;
  std::error_code ec;
  if (!fs::exists(published, ec)) return;
  if (const std::string* input = replaced_input(published.string(), inputs_))
    throw IoError("output file '" + name + "' in output folder '" + shown_ + "' would replace " +
                  (fs::is_directory(*input, ec) ? "a file in the input folder '" : "the input '") + *input +
                  "': choose another -o");
}

// A run killed between replace_whole's two renames left the previous output as ".<name>.tmp-<pid>.old" and
// no target: the newest such leftover of a dead run becomes the target again.
void OutputFolder::recover_interrupted_commit() {
  std::error_code ec;
  if (fs::exists(target_, ec)) return;
  const std::string prefix = "." + target_.filename().string() + ".tmp-";
  fs::path newest;
  fs::file_time_type newest_time{};
  for (fs::directory_iterator it(target_.parent_path(), ec), end; it != end && !ec; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    const auto pid = leftover_pid(name, prefix);
    if (!pid || name != prefix + std::to_string(*pid) + ".old") continue;
    std::error_code time_error;
    const fs::file_time_type time = fs::last_write_time(it->path(), time_error);
    if (time_error || !is_stale(it->path(), *pid) || (!newest.empty() && time <= newest_time)) continue;
    newest = it->path();
    newest_time = time;
  }
  if (!newest.empty()) fs::rename(newest, target_, ec);
}

OutputFolder::~OutputFolder() {
  std::error_code ec;
  fs::remove_all(staging_, ec);
}

std::string OutputFolder::file(const std::string& name) {
  if (name.empty() || name.find('/') != std::string::npos || name == kOutputMarkerName)
    throw InvalidParameter("output file name '" + name + "' must be a plain file name");
  if (!target_is_own()) require_not_an_input(name);  // early; move_files_in checks again before any rename
  std::error_code ec;
  fs::create_directory(staging_, ec);  // again after a commit, for the next one
  if (std::find(files_.begin(), files_.end(), name) == files_.end()) files_.push_back(name);
  return (staging_ / name).string();
}

bool OutputFolder::target_is_own() const {
  std::error_code ec;
  if (!fs::exists(target_, ec) || fs::is_empty(target_, ec)) return true;
  const auto listed = files_listed_by(target_, tool_);
  return listed && holds_only(target_, *listed);
}

void OutputFolder::commit() {
  // Decided again at each commit: a user may have put a file of their own into the folder meanwhile.
  if (target_is_own())
    replace_whole();
  else if (overwrite_)
    move_files_in();
  else
    throw IoError("output folder '" + shown_ + "' now holds files " + tool_ + " did not write: give -overwrite");
  files_.clear();  // a further commit publishes what is staged after this one
  // Only now, with the new output in place, may what dead runs left beside it go.
  remove_stale_leftovers(target_.parent_path().string(), "." + target_.filename().string() + ".tmp-");
}

void OutputFolder::replace_whole() {
  std::string marker = tool_ + "\n";
  for (const std::string& name : files_) marker += name + "\n";
  write_file_atomically((staging_ / kOutputMarkerName).string(), "output marker",
                        [&](std::ostream& out) { return static_cast<bool>(out << marker); });
  std::error_code ec;
  fs::path old;
  if (fs::exists(target_, ec)) {
    old = staging_;
    old += ".old";
    fs::rename(target_, old, ec);
    if (ec) throw IoError("cannot replace output folder '" + shown_ + "': " + ec.message());
    // Dated now, so that a concurrent run does not judge it a dead run's leftover by the old output's date.
    fs::last_write_time(old, fs::file_time_type::clock::now(), ec);
  }
  fs::rename(staging_, target_, ec);
  if (ec) {
    std::error_code ignored;
    if (!old.empty()) fs::rename(old, target_, ignored);
    throw IoError("cannot move the outputs into '" + shown_ + "': " + ec.message());
  }
  // Everything in `old` was this tool's own output (target_is_own), so it may go.
  if (!old.empty()) fs::remove_all(old, ec);
}

void OutputFolder::move_files_in() {
  for (const std::string& name : files_) require_not_an_input(name);  // the folder may have turned foreign since
  for (const std::string& name : files_) {
    std::error_code ec;
    fs::rename(staging_ / name, target_ / name, ec);
    if (ec) throw IoError("cannot move '" + name + "' into output folder '" + shown_ + "': " + ec.message());
  }
}

}  // namespace occ_improve
