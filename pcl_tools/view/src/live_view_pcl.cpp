// The live view through PCL's ImageViewer (README, "Live view").
#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/tools/live_view.hpp"

#include <X11/Xlib.h>
#include <pcl/visualization/image_viewer.h>
#include <vtkPNGWriter.h>
#include <vtkRenderWindow.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkSmartPointer.h>
#include <vtkWindowToImageFilter.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <string>

namespace occ_improve {

namespace {

constexpr const char* kRegionLayer = "regions";
// Magenta is not in the improvement colour map (blue-green-yellow-red, grey): the boxes stay visible on
// every value.
constexpr double kBoxRed = 1.0, kBoxGreen = 0.0, kBoxBlue = 1.0;

// A connection to the display, open while the window lives. VTK's X11 window aborts the whole process when
// it cannot reach the display, so this one is opened first, and it is kept: an X server such as Xvfb
// resets when its last client disconnects, and VTK's own XOpenDisplay during that reset gets null and
// crashes in libX11 (seen: 1 of 4 full test runs, a segfault at 0x968 in libX11 right after the check).
class DisplayConnection {
public:
  DisplayConnection() : display_(XOpenDisplay(nullptr)) {
    if (display_) return;
    const char* name = std::getenv("DISPLAY");
    throw InvalidInput(std::string("-view: cannot open the X display ") +
                       (name && *name ? "'" + std::string(name) + "'" : std::string("(DISPLAY is not set)")) +
                       ": run on a desktop, or headless under xvfb-run -a");
  }
  ~DisplayConnection() { XCloseDisplay(display_); }
  DisplayConnection(const DisplayConnection&) = delete;
  DisplayConnection& operator=(const DisplayConnection&) = delete;

private:
  Display* display_;
};

}  // namespace

// ImageViewer::spinOnce cannot be called twice here: with PCL 1.13's X11 interactor, the timer that ends
// one spin terminates the interactor, which then destroys the window and closes its display, and the next
// spin's render crashes in libGLX. So the window is driven as spinOnce would be, minus the termination:
// a render, then the interactor's ProcessEvents (pending X events and timers, waiting at most one timer
// period, 10 ms). Only the window's close button terminates the interactor: wasStopped().
struct LiveView::Window {
  explicit Window(const std::string& window_title) : viewer(window_title), title(window_title) {
    // ImageViewer keeps its interactor private; an interactor style (PCL's own, so the keys and mouse
    // behave as in every PCL viewer) is told the interactor, and through it the window.
    style = vtkSmartPointer<pcl::visualization::ImageViewerInteractorStyle>::New();
    viewer.setInteractorStyle(style);
  }
  vtkRenderWindowInteractor* interactor() const { return style->GetInteractor(); }

  DisplayConnection display;  ///< first: opened before the viewer's window, closed after it
  pcl::visualization::ImageViewer viewer;
  vtkSmartPointer<pcl::visualization::ImageViewerInteractorStyle> style;
  LiveFrame shown;  ///< the viewer reads the pixels in place: they live until the next frame replaces them
  std::string title;
};

bool live_view_built() { return true; }

LiveView::LiveView(const std::string& title) : window_(std::make_unique<Window>(title)) {}

LiveView::~LiveView() = default;

void LiveView::show(LiveFrame frame) {
  Window& w = *window_;
  w.shown = std::move(frame);
  const Image& image = w.shown.improvement;
  w.viewer.removeLayer(kRegionLayer);
  w.viewer.addRGBImage(image.pixels.data(), static_cast<unsigned>(image.width), static_cast<unsigned>(image.height));
  // The image is shown top row first, but shapes and text are placed from the window's bottom row up.
  const auto row_up = [&](int v) { return static_cast<unsigned>(image.height - 1 - v); };
  for (std::size_t i = 0; i < w.shown.top_regions.size(); ++i) {
    const Region& r = w.shown.top_regions[i];
    w.viewer.addRectangle(static_cast<unsigned>(r.min_u), static_cast<unsigned>(r.max_u), row_up(r.max_v),
                          row_up(r.min_v), kBoxRed, kBoxGreen, kBoxBlue, kRegionLayer);
    // The rank inside the box's top-left corner (the text's anchor is its bottom-left).
    w.viewer.addText(static_cast<unsigned>(r.min_u) + 3, row_up(std::min(r.min_v + 12, r.max_v)), std::to_string(i + 1),
                     kBoxRed, kBoxGreen, kBoxBlue, kRegionLayer);
  }
  w.viewer.setWindowTitle(w.title + ": " + std::to_string(w.shown.frames) + " frames");
}

bool LiveView::spin_for(std::chrono::milliseconds duration) {
  const auto end = std::chrono::steady_clock::now() + duration;
  do {
    if (window_->viewer.wasStopped()) return false;
    if (std::optional<LiveFrame> frame = take()) {
      show(std::move(*frame));
      window_->interactor()->Render();
    }
    window_->interactor()->ProcessEvents();  // redraws on expose; the close button sets wasStopped()
  } while (std::chrono::steady_clock::now() < end && !stop_requested());  // Ctrl-C: back to the caller at once
  return !window_->viewer.wasStopped();
}

bool LiveView::save_screenshot(const std::string& png_path) {
  if (window_->viewer.wasStopped()) return false;  // closed: VTK has destroyed the window
  if (std::optional<LiveFrame> frame = take()) show(std::move(*frame));
  vtkRenderWindow* render_window = window_->interactor()->GetRenderWindow();
  render_window->Render();
  auto grab = vtkSmartPointer<vtkWindowToImageFilter>::New();
  grab->SetInput(render_window);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();  // the back buffer just rendered: not covered by other windows
  grab->Update();
  auto writer = vtkSmartPointer<vtkPNGWriter>::New();
  writer->SetFileName(png_path.c_str());
  writer->SetInputConnection(grab->GetOutputPort());
  writer->AddText("Software", kLiveViewSoftware);
  writer->Write();
  if (writer->GetErrorCode() != 0) throw IoError("-view_screenshot: cannot write '" + png_path + "'");
  return true;
}

}  // namespace occ_improve
