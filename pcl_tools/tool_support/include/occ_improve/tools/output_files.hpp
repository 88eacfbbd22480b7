#pragma once
// The output folder of the tools (-o) and their single output files (-save MAP.occmap; occ_to_octomap's
// -o TREE.bt), checked before any work starts and committed only after everything else succeeded, so that
// nothing a user owns is lost:
//  - never an input of the run (an input file, or a file inside an input folder), even with -overwrite;
//  - an existing file is replaced only when this project wrote it (its magic), or with -overwrite;
//  - a -save inside the -o folder is written with the folder's files and listed in its marker, so that a
//    rerun with the same command line finds the folder its own.
#include "occ_improve/io/atomic_file.hpp"
#include "occ_improve/tools/flags.hpp"

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace occ_improve {

/// Refuses (InvalidParameter naming `flag`) an output path that is an input of the run: a positional
/// input, -load, -intrinsics_file, -oni, -pcd_dir, -depth_dir or -simulate, or a file inside one of those
/// that is a folder.
void require_not_an_input(const CommandLine& command_line, const std::string& path, const std::string& flag);

/// Every path the run reads from, as given: the positional inputs, -load, -intrinsics_file, -oni,
/// -pcd_dir, -depth_dir and -simulate.
std::vector<std::string> run_inputs(const CommandLine& command_line);

/// Refuses (InvalidParameter naming both flags) two outputs of one run that name the same file: the second
/// would silently replace the first.
void require_distinct_outputs(const std::string& path_a, const std::string& flag_a, const std::string& path_b,
                              const std::string& flag_b);

/// Creates the missing folders above `path` (like mkdir -p of its parent); IoError naming `flag`, the path and
/// the reason (permission denied, a file in the way) when they cannot be created.
void create_parent_folders(const std::string& path, const std::string& flag);

/// Removes the folders create_parent_folders made in this process that are still empty, innermost first:
/// run_tool calls it when a run fails, so a refused or interrupted run leaves no empty folders behind.
void remove_created_folders_left_empty();

/// The output folder named by -o (or the tool's default for it; InvalidParameter when it has none), its
/// missing parents created; refused when it already holds files the tool did not write unless -overwrite
/// was given (see OutputFolder).
OutputFolder open_output_folder(const CommandLine& command_line);

/// An output file named by `flag`: require_not_an_input, its missing parent folders created, then an
/// OutputFile (refused when it exists and `is_own` does not recognise it, unless -overwrite).
std::unique_ptr<OutputFile> open_output_file(const CommandLine& command_line, const std::string& flag,
                                             const std::function<bool(const std::string&)>& is_own,
                                             const std::string& kind);

/// Where -save writes the grid. Nothing when -save was not given; a file staged with the -o folder when
/// -save names a NAME.occmap directly inside it (anything else inside it is refused); otherwise an OutputFile beside its target. Everything is checked
/// at construction, before any work.
class MapSaveTarget {
public:
  MapSaveTarget(const CommandLine& command_line, OutputFolder* folder);
  bool requested() const { return !shown_.empty(); }
  /// Where to write the map now (staged: the target is replaced by commit(), or the folder's commit).
  std::string staged_path();
  /// Moves the map into place (after the folder's commit); nothing for a map inside the folder.
  void commit();
  /// The path as the user named it.
  const std::string& path() const { return shown_; }

private:
  std::string shown_;
  OutputFolder* folder_ = nullptr;  ///< set when the map goes into the output folder
  std::unique_ptr<OutputFile> file_;
};

}  // namespace occ_improve
