#pragma once
// The shot-planning flags as the planner's request.
#include "occ_improve/planning/planner.hpp"
#include "occ_improve/tools/flags.hpp"

namespace occ_improve {

/// The plan flags -budget, -shape, -refine, -window, -negative_share, -stop_gain as a PlanRequest (one
/// reading for occ_plan and occ_improve_live -simulate). InvalidParameter naming a malformed -window.
PlanRequest plan_request_from_flags(const CommandLine& command_line);

/// The checks of PlanRequest::validate that depend on the grid, made first with the flags' names (the
/// library's message names its struct fields): a -budget given beyond the grid's rays, a -window that does
/// not fit in the grid or covers more than -budget rays: InvalidParameter. The default budget (4096) is
/// lowered to a smaller grid's ray count: a tiny frame was refused for a budget the user never set.
void fit_plan_to_grid(const CommandLine& command_line, PlanRequest& request, int width, int height);

}  // namespace occ_improve
