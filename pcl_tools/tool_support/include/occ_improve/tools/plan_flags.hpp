#pragma once
// The shot-planning flags as the planner's request.
#include "occ_improve/planning/planner.hpp"
#include "occ_improve/tools/flags.hpp"

namespace occ_improve {

/// The plan flags -budget, -shape, -refine, -window, -negative_share, -stop_gain as a PlanRequest (one
/// reading for occ_plan and occ_improve_live -simulate). InvalidParameter naming a malformed -window.
PlanRequest plan_request_from_flags(const CommandLine& command_line);

}  // namespace occ_improve
