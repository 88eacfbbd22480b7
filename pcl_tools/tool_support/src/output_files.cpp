#include "occ_improve/tools/output_files.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/io/map_io.hpp"

#include <cstdio>
#include <filesystem>
#include <vector>

namespace occ_improve {
namespace fs = std::filesystem;

std::vector<std::string> run_inputs(const CommandLine& c) {
  std::vector<std::string> inputs = c.positionals();
  for (const char* flag : {"-load", "-intrinsics_file", "-mask", "-oni", "-pcd_dir", "-depth_dir", "-input_dir", "-simulate"})
    if (c.declares(flag))
      for (const std::string& value : c.values(flag))
        if (!value.empty() && value != "finite") inputs.push_back(value);  // -mask finite: a rule, not a file
  return inputs;
}

void require_not_an_input(const CommandLine& command_line, const std::string& path, const std::string& flag) {
  const std::vector<std::string> inputs = run_inputs(command_line);
  const std::string* input = replaced_input(path, inputs);
  if (!input) return;
  std::error_code ec;
  throw InvalidParameter(flag + " '" + path + "' would overwrite " +
                         (fs::is_directory(*input, ec) ? "a file in the input folder '" : "the input '") + *input +
                         "': choose an output outside the inputs");
}

void require_distinct_outputs(const std::string& path_a, const std::string& flag_a, const std::string& path_b,
                              const std::string& flag_b) {
  if (comparable_path(path_a) == comparable_path(path_b))
    throw InvalidParameter(flag_a + " '" + path_a + "' and " + flag_b + " '" + path_b +
                           "' name the same file: give each output its own name");
}

std::unique_ptr<OutputFile> open_output_file(const CommandLine& command_line, const std::string& flag,
                                             const std::function<bool(const std::string&)>& is_own,
                                             const std::string& kind) {
  const std::string path = *command_line.text(flag);
  require_not_an_input(command_line, path, flag);
  create_parent_folders(path, flag);
  return std::make_unique<OutputFile>(path, flag, command_line.has("-overwrite"), is_own, kind);
}

MapSaveTarget::MapSaveTarget(const CommandLine& command_line, OutputFolder* folder)
    : shown_(command_line.text("-save").value_or("")) {
  if (shown_.empty()) return;
  // The map format holds the grid, not the mask (docs/MAP_FORMAT.md): a plan from the loaded map would
  // aim at the pixels the mask left out (a held-out trial: 3388 of 4096 rays on cropped background).
  if (command_line.declares("-mask") && command_line.has("-mask"))
    std::fprintf(stderr, "warning: -save keeps the grid, not the -mask: give the mask again (a PNG) with -load\n");
  const std::string folder_path = folder ? folder->resolved().string() : std::string();
  if (folder && path_is_within(shown_, folder_path)) {
    // Written with the folder's files and listed in its marker: directly in it, and named so that it can
    // replace none of the tool's outputs (nor the marker).
    const fs::path target = comparable_path(shown_);
    if (target.parent_path() != comparable_path(folder_path) || target.extension() != ".occmap")
      throw InvalidParameter("-save '" + shown_ + "' inside the -o folder must be a NAME.occmap directly in it");
    require_not_an_input(command_line, shown_, "-save");
    folder_ = folder;
    return;
  }
  file_ = open_output_file(command_line, "-save", is_map_file, "a map");
}

std::string MapSaveTarget::staged_path() {
  if (folder_) return folder_->file(fs::path(shown_).filename().string());
  return file_->staged();
}

void MapSaveTarget::commit() {
  if (file_) file_->commit();
}

namespace {

// The folders create_parent_folders made in this process, outermost first: a run that fails removes
// those still empty (remove_created_folders_left_empty), so a refused -o leaves no trace behind it.
std::vector<std::filesystem::path>& created_folders() {
  static std::vector<std::filesystem::path> folders;
  return folders;
}

}  // namespace

void create_parent_folders(const std::string& path, const std::string& flag) {
  const std::filesystem::path parent = std::filesystem::path(path).lexically_normal().parent_path();
  std::error_code ec;
  if (parent.empty() || std::filesystem::exists(parent, ec)) return;
  std::vector<std::filesystem::path> missing;  // innermost first
  for (std::filesystem::path p = parent; !p.empty() && !std::filesystem::exists(p, ec); p = p.parent_path()) {
    missing.push_back(p);
    if (p == p.parent_path()) break;
  }
  created_folders().insert(created_folders().end(), missing.rbegin(), missing.rend());
  std::filesystem::create_directories(parent, ec);
  // Named here: the writability check that follows could only say the folder does not exist.
  if (ec) throw IoError("cannot write " + flag + " '" + path + "': cannot create its folder '" + parent.string() + "': " +
                        ec.message());
}

OutputFolder open_output_folder(const CommandLine& c) {
  const auto folder = c.text("-o");
  if (!folder) throw InvalidParameter("-o OUTDIR is required (see -h)");
  create_parent_folders(*folder, "-o");  // the folder itself is staged and moved into place
  return OutputFolder(*folder, c.tool().tool, c.has("-overwrite"), run_inputs(c));
}

void remove_created_folders_left_empty() {
  auto& folders = created_folders();
  std::error_code ec;
  for (auto it = folders.rbegin(); it != folders.rend(); ++it)
    if (std::filesystem::is_empty(*it, ec) && !ec) std::filesystem::remove(*it, ec);  // never a folder with content
  folders.clear();
}

}  // namespace occ_improve
