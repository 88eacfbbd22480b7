// The live view of a build without VTK or pcl_visualization: -view says so and the run stops before any
// work (README, "Live view").
#include "occ_improve/errors.hpp"
#include "occ_improve/tools/live_view.hpp"

namespace occ_improve {

struct LiveView::Window {};

bool live_view_built() { return false; }

LiveView::LiveView(const std::string&) {
  throw InvalidParameter("-view: this occ_improve_live was built without the live view (VTK and PCL's "
                         "visualization were not found, or OCC_IMPROVE_WITH_VIEW is OFF)");
}

LiveView::~LiveView() = default;
bool LiveView::spin_for(std::chrono::milliseconds) { return false; }
bool LiveView::save_screenshot(const std::string&) { return false; }
void LiveView::show(LiveFrame) {}

}  // namespace occ_improve
