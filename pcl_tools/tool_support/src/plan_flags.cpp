#include "occ_improve/tools/plan_flags.hpp"

#include "occ_improve/errors.hpp"

#include <stdexcept>
#include <string>

namespace occ_improve {

PlanRequest plan_request_from_flags(const CommandLine& command_line) {
  PlanRequest request;
  request.budget_rays = *command_line.integer("-budget");
  const std::string shape = *command_line.text("-shape");
  request.shape = shape == "window"       ? ShotShape::window
                  : shape == "decimation" ? ShotShape::decimation
                  : shape == "rays"       ? ShotShape::rays
                                          : ShotShape::coarse_to_fine;
  const std::string refine = *command_line.text("-refine");
  request.refine_by = refine == "improvement" ? RefineBy::improvement
                      : refine == "both"      ? RefineBy::both
                      : refine == "triangles" ? RefineBy::triangles
                                              : RefineBy::residual;
  const std::string window = *command_line.text("-window");
  const auto x = window.find('x');
  try {
    std::size_t used_w = 0, used_h = 0;
    if (x == std::string::npos) throw std::invalid_argument("no x");
    request.window_width_columns = std::stoi(window.substr(0, x), &used_w);
    request.window_height_columns = std::stoi(window.substr(x + 1), &used_h);
    if (used_w != x || used_h != window.size() - x - 1 || request.window_width_columns < 1 ||
        request.window_height_columns < 1)
      throw std::invalid_argument("not whole");
  } catch (const std::logic_error&) {
    throw InvalidParameter("-window " + window + " is invalid: must be WIDTHxHEIGHT in columns >= 1, e.g. 64x48");
  }
  request.negative_share = *command_line.number("-negative_share");
  request.stop_gain_per_ray_below = *command_line.number("-stop_gain");
  request.stop_view_share = *command_line.number("-stop_share");
  warn_if_ignored(command_line, "-window", "-shape window", request.shape == ShotShape::window);
  warn_if_ignored(command_line, "-refine", "-shape coarse_to_fine", request.shape == ShotShape::coarse_to_fine);
  warn_if_ignored(command_line, "-negative_share", "-shape rays", request.shape == ShotShape::rays);
  warn_if_ignored(command_line, "-stop_share", "-shape coarse_to_fine -refine triangles",
                  request.shape == ShotShape::coarse_to_fine && request.refine_by == RefineBy::triangles);
  return request;
}

void fit_plan_to_grid(const CommandLine& command_line, PlanRequest& request, int width, int height) {
  const long long columns = static_cast<long long>(width) * height;
  const std::string grid = std::to_string(width) + " x " + std::to_string(height);
  if (!command_line.has("-budget") && request.budget_rays > columns) request.budget_rays = static_cast<int>(columns);
  if (request.budget_rays > columns)
    throw InvalidParameter("-budget " + std::to_string(request.budget_rays) + " is more than the grid's " + grid +
                           " = " + std::to_string(columns) + " rays");
  if (request.shape != ShotShape::window) return;
  const std::string window = "-window " + *command_line.text("-window");
  if (request.window_width_columns > width || request.window_height_columns > height)
    throw InvalidParameter(window + " does not fit in the grid of " + grid + " columns");
  const long long area = static_cast<long long>(request.window_width_columns) * request.window_height_columns;
  if (area > request.budget_rays)
    throw InvalidParameter(window + " covers " + std::to_string(area) + " rays, more than -budget " +
                           std::to_string(request.budget_rays) + ": raise -budget or shrink -window");
}

}  // namespace occ_improve
