#pragma once
// The per-file batch mode of the frame-reading tools, as PCL's tools have it: -input_dir DIR -output_dir
// OUTDIR runs the tool once per frame file of DIR, each into OUTDIR/<file stem>/ (the tool's usual output
// folder, with its rules), beside the tools' default of fusing every input into one map.
#include "occ_improve/tools/flags.hpp"

#include <string>
#include <vector>

namespace occ_improve {

/// What a batch takes from its folder: the frame files, sorted by name, and every other entry, named so
/// that nothing is dropped silently.
struct BatchFiles {
  std::vector<std::string> frames;   ///< paths of the frame files
  std::vector<std::string> skipped;  ///< names of the other entries (subfolders end in '/')
};

/// The entries of `folder` (not its subfolders): a regular file is a frame by its extension (.pcd, .ply,
/// .png, .pgm, .tif, .tiff, any case). Hidden entries, subfolders and other files are skipped; so are, in
/// a dataset folder (one holding *.depth.png or *_depth.tif(f) frames), its other images (its colour).
/// Throws IoError when the folder cannot be listed.
BatchFiles list_batch_files(const std::string& folder);

/// Whether the command line asks for a batch (-input_dir or -output_dir given, in a tool that takes them).
bool batch_requested(const CommandLine& command_line);

/// Runs `run` once per frame file of -input_dir, with CommandLine::for_one_input(file, OUTDIR/<stem>).
/// Refused before any work (InvalidParameter, one line): -input_dir without -output_dir or the reverse,
/// with positional inputs, -o, -save or -sample; an -output_dir equal to or inside -input_dir; a folder
/// without a frame file (InvalidInput); two frame
/// files of one stem; a per-file folder the tool may not write (OutputFolder's rules, -overwrite).
/// A file that fails is reported in one error line on stderr naming it, and the batch goes on; at the end
/// one summary line on stdout (processed, failed with names, skipped with the first 10 names); returns 1 when any file
/// failed, else 0. A stop (Ctrl-C) ends the batch with Cancelled after the summary so far: the folders of
/// the files done stay.
int run_batch(const CommandLine& command_line, int (*run)(const CommandLine& command_line));

}  // namespace occ_improve
