#include "occ_improve/tools/batch.hpp"

#include "occ_improve/io/atomic_file.hpp"
#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/tools/input_scope.hpp"
#include "occ_improve/tools/output_files.hpp"

#include <algorithm>
#include <cstdint>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <map>

namespace occ_improve {
namespace fs = std::filesystem;

namespace {

bool has_frame_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".pcd" || ext == ".ply" || is_depth_image_path(path.string());
}

// "a, b, c", or the first `at_most` names and "and N more" (a dataset folder skips a colour image and a
// pose file per frame: counted in full, named in part).
std::string joined_names(const std::vector<std::string>& names, std::size_t at_most = SIZE_MAX) {
  std::string text;
  for (std::size_t i = 0; i < names.size() && i < at_most; ++i) text += (text.empty() ? "" : ", ") + names[i];
  if (names.size() > at_most) text += ", and " + std::to_string(names.size() - at_most) + " more";
  return text;
}

// The per-file output folder of each frame: OUTDIR/<stem>. Two frames of one stem would share a folder.
std::vector<std::string> output_folders(const std::vector<std::string>& frames, const std::string& output_dir) {
  std::map<std::string, std::string> by_stem;
  std::vector<std::string> folders;
  for (const std::string& frame : frames) {
    const std::string stem = fs::path(frame).stem().string();
    const auto [it, added] = by_stem.emplace(stem, frame);
    if (!added)
      throw InvalidParameter("-input_dir: '" + it->second + "' and '" + frame + "' have the same stem '" + stem +
                             "', so would share the output folder: rename one, or move it to another folder");
    folders.push_back((fs::path(output_dir) / stem).string());
  }
  return folders;
}

void require_batch_flags(const CommandLine& c) {
  if (!c.has("-input_dir")) throw InvalidParameter("-output_dir is for batch mode: give -input_dir DIR with it");
  if (!c.has("-output_dir")) throw InvalidParameter("-input_dir needs -output_dir OUTDIR (one folder per input file)");
  if (!c.positionals().empty())
    throw InvalidParameter("give -input_dir or input files, not both (input '" + c.positionals().front() + "')");
  for (const char* flag : {"-o", "-save", "-sample"})
    if (c.declares(flag) && c.has(flag))
      throw InvalidParameter(std::string("-input_dir writes one folder per file into -output_dir: ") + flag +
                             " cannot be given with it");
  const std::string input_dir = *c.text("-input_dir"), output_dir = *c.text("-output_dir");
  std::error_code ec;
  if (!fs::is_directory(input_dir, ec)) throw IoError("-input_dir '" + input_dir + "' is not a folder");
  if (path_is_within(output_dir, input_dir))
    throw InvalidParameter("-output_dir '" + output_dir + "' is inside -input_dir '" + input_dir +
                           "': choose an output outside the inputs");
}

}  // namespace

BatchFiles list_batch_files(const std::string& folder) {
  std::vector<fs::directory_entry> entries;
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; it != end && !ec; it.increment(ec)) entries.push_back(*it);
  if (ec) throw IoError("cannot list -input_dir '" + folder + "': " + ec.message());
  std::sort(entries.begin(), entries.end());
  // A folder whose images name their depth (7-Scenes' *.depth.png, *_depth.png): the others are colour
  // (Open3D's TUM_color.png beside TUM_depth.png failed as a depth frame and the batch exited 1).
  const bool dataset = std::any_of(entries.begin(), entries.end(), [](const fs::directory_entry& e) {
    return is_depth_image_path(e.path().string()) && is_named_depth(e.path().string());
  });
  BatchFiles files;
  for (const fs::directory_entry& e : entries) {
    const std::string name = e.path().filename().string();
    const bool regular = e.is_regular_file(ec);  // follows symbolic links
    // A dataset folder's other images are its colour frames, not depth.
    const bool colour = dataset && is_depth_image_path(name) && !is_named_depth(name);
    if (regular && name[0] != '.' && has_frame_extension(e.path()) && !colour)
      files.frames.push_back(e.path().string());
    else
      files.skipped.push_back(name + (e.is_directory(ec) ? "/" : ""));
  }
  return files;
}

bool batch_requested(const CommandLine& c) {
  return c.declares("-input_dir") && (c.has("-input_dir") || c.has("-output_dir"));
}

int run_batch(const CommandLine& c, int (*run)(const CommandLine& command_line)) {
  require_batch_flags(c);
  const BatchFiles files = list_batch_files(*c.text("-input_dir"));
  if (files.frames.empty())  // a batch that does nothing is a mistaken folder, not a success
    throw InvalidInput("-input_dir '" + *c.text("-input_dir") + "' holds no frame file (.pcd .ply .png .pgm .tif .tiff)" +
                       (files.skipped.empty() ? "" : "; skipped: " + joined_names(files.skipped, 10)));
  const std::string output_dir = *c.text("-output_dir");
  const std::vector<std::string> folders = output_folders(files.frames, output_dir);
  // Every per-file folder is checked before any work (a folder the tool did not write, without
  // -overwrite), so a batch is not refused half-way; the check stages nothing that outlives it.
  create_parent_folders((fs::path(output_dir) / "x").string(), "-output_dir");
  for (std::size_t i = 0; i < files.frames.size(); ++i) {
    try {
      const OutputFolder check(folders[i], c.tool().tool, c.has("-overwrite"), {files.frames[i]});
    } catch (const IoError& e) {
      throw IoError("-output_dir, the folder of '" + files.frames[i] + "': " + e.what());
    }
  }

  std::vector<std::string> failed;
  std::size_t processed = 0;
  const auto summary = [&] {
    return "processed " + std::to_string(processed) + ", failed " + std::to_string(failed.size()) +
           (failed.empty() ? "" : " (" + joined_names(failed) + ")") + ", skipped " + std::to_string(files.skipped.size()) +
           (files.skipped.empty() ? "" : " (" + joined_names(files.skipped, 10) + ")");
  };
  for (std::size_t i = 0; i < files.frames.size(); ++i) {
    const std::string& frame = files.frames[i];
    std::printf("[%zu/%zu] %s -> %s/\n", i + 1, files.frames.size(), frame.c_str(), folders[i].c_str());
    std::fflush(stdout);
    try {
      throw_if_stop_requested();
      const InputScope scope(frame);
      if (run(c.for_one_input(frame, folders[i])) == 0) ++processed;
      else failed.push_back(fs::path(frame).filename().string());
    } catch (const Cancelled&) {
      std::printf("batch interrupted at %s: %s\n", frame.c_str(), summary().c_str());
      throw;
    } catch (const std::exception& e) {  // named, counted; the next file is independent of this one
      std::fflush(stdout);
      std::fprintf(stderr, "%s\n", failure_line(e.what()).c_str());
      failed.push_back(fs::path(frame).filename().string());
    }
    std::fflush(stdout);
  }
  std::printf("batch %s: %s\n", c.text("-input_dir")->c_str(), summary().c_str());
  return failed.empty() ? 0 : 1;
}

}  // namespace occ_improve
