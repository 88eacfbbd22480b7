#include "occ_improve/atomic_file.hpp"

#include "occ_improve/errors.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>
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

}  // namespace

void remove_stale_leftovers(const std::string& folder, const std::string& prefix) {
  std::error_code ec;
  for (fs::directory_iterator it(folder.empty() ? "." : folder, ec), end; it != end && !ec; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::size_t end_of_pid = std::min(name.find_first_not_of("0123456789", prefix.size()), name.size());
    const std::size_t length = end_of_pid - prefix.size();
    if (length == 0 || length > 9) continue;  // not named by a PID: not ours to judge
    const long pid = std::stol(name.substr(prefix.size(), length));
    std::error_code ignored;
    if (is_stale(it->path(), pid)) fs::remove_all(it->path(), ignored);
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
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw IoError("cannot create '" + temporary + "' to write " + what + " '" + path + "'");
    written = write(out);
    out.close();
    written = written && static_cast<bool>(out);
  }
  std::error_code error;
  if (written) fs::rename(temporary, path, error);
  if (!written || error) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw IoError("cannot write " + what + " '" + path + "'" +
                  (error ? ": " + error.message() : std::string(" (disk full?)")));
  }
}

OutputFolder::OutputFolder(const std::string& target, const std::string& tool, bool overwrite)
    : target_(fs::absolute(target).lexically_normal()), shown_(target), tool_(tool), overwrite_(overwrite) {
  if (target_.filename().empty()) target_ = target_.parent_path();  // "out/" and "." name the folder itself
  const fs::path parent = target_.parent_path();
  std::error_code ec;
  if (!fs::is_directory(parent, ec))
    throw IoError("cannot write output folder '" + shown_ + "': '" + parent.string() +
                  (fs::exists(parent, ec) ? "' is not a folder" : "' does not exist"));
  if (fs::exists(target_, ec) && !fs::is_directory(target_, ec))
    throw IoError("output folder '" + shown_ + "' exists and is not a folder");
  if (!overwrite_ && !target_is_own())
    throw IoError("output folder '" + shown_ + "' already holds files " + tool_ +
                  " did not write: choose another -o, or give -overwrite to write into it (files of the "
                  "same names are replaced, nothing else is touched)");
  const std::string staging_prefix = "." + target_.filename().string() + ".tmp-";
  remove_stale_leftovers(parent.string(), staging_prefix);
  staging_ = parent / (staging_prefix + std::to_string(::getpid()));
  fs::create_directory(staging_, ec);
  if (ec) throw IoError("cannot write output folder '" + shown_ + "': cannot create '" + staging_.string() + "': " +
                        ec.message());
}

OutputFolder::~OutputFolder() {
  std::error_code ec;
  fs::remove_all(staging_, ec);
}

std::string OutputFolder::file(const std::string& name) {
  if (name.empty() || name.find('/') != std::string::npos || name == kOutputMarkerName)
    throw InvalidParameter("output file name '" + name + "' must be a plain file name");
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
  for (const std::string& name : files_) {
    std::error_code ec;
    fs::rename(staging_ / name, target_ / name, ec);
    if (ec) throw IoError("cannot move '" + name + "' into output folder '" + shown_ + "': " + ec.message());
  }
}

}  // namespace occ_improve
