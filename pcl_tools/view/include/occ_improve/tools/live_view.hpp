#pragma once
// occ_improve_live -view: a window that shows the improvement map (the colours of improvement.png, the
// same render_improvement) and the top regions' bounding boxes as frames arrive, through PCL's
// pcl::visualization::ImageViewer. Built only where VTK and pcl_visualization are found (CMake option
// OCC_IMPROVE_WITH_VIEW); elsewhere opening a view throws, naming the missing component.
//
// Threads: post() may be called from any thread (the pipeline's worker renders each frame there);
// everything else belongs to the thread that opened the view (VTK's window is not thread-safe).
#include "occ_improve/maps/improvement.hpp"
#include "occ_improve/planning/ranking.hpp"
#include "occ_improve/sim/render.hpp"

#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace occ_improve {

/// What one refresh of the window shows.
struct LiveFrame {
  Image improvement;                ///< render_improvement of the map
  std::vector<Region> top_regions;  ///< best first; drawn as boxes labelled with their rank
  std::uint64_t frames = 0;         ///< frames processed so far (window title)
};

/// Whether this build has the view (VTK and pcl_visualization were found).
bool live_view_built();

/// The PNG text (key "Software") a screenshot carries, by which a later run knows the file as its own.
inline constexpr const char* kLiveViewSoftware = "occ_improve_live -view";
/// A PNG file that carries kLiveViewSoftware in its first 4 KiB (where the writer puts its text chunk).
bool is_live_view_screenshot(const std::string& path);

class LiveView {
public:
  /// Opens the window. Throws InvalidParameter when the build has no view, InvalidInput when no X display
  /// can be opened (DISPLAY unset or unreachable): checked first, since VTK aborts the process there.
  explicit LiveView(const std::string& title);
  ~LiveView();
  LiveView(const LiveView&) = delete;
  LiveView& operator=(const LiveView&) = delete;

  /// Any thread: renders the map and keeps it as the next frame to show (a newer post replaces one not
  /// yet shown, so a slow window never holds the stream back).
  void post(const ImprovementMap& map, std::vector<Region> top_regions, std::uint64_t frames);

  /// Opening thread: shows the newest posted frame and handles the window's events for about `duration`.
  /// False once the user closed the window, which ends the run. Returns early on a stop request (Ctrl-C).
  bool spin_for(std::chrono::milliseconds duration);

  /// Opening thread: shows the newest posted frame now and writes the window's pixels to `png_path`
  /// (vtkWindowToImageFilter + vtkPNGWriter, with kLiveViewSoftware as its text). False (nothing written)
  /// when the window was closed; throws IoError when the file cannot be written.
  bool save_screenshot(const std::string& png_path);

private:
  std::optional<LiveFrame> take();
  void show(LiveFrame frame);

  std::mutex mutex_;
  std::optional<LiveFrame> pending_;  ///< guarded by mutex_
  struct Window;
  std::unique_ptr<Window> window_;
};

}  // namespace occ_improve
