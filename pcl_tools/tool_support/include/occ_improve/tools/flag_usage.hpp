#pragma once
// The -h text of a tool and, for -v, the values its flags run with.
#include "occ_improve/tools/flags.hpp"

#include <string>

namespace occ_improve {

/// The -h text: usage lines, description, then every flag of the tool by group, with its default.
std::string usage_text(const ToolFlags& tool, const std::string& program);

/// For -v: one line per flag of the tool with the value it runs with ("-k 10 (default)"), then the inputs.
std::string resolved_flags(const CommandLine& command_line);

}  // namespace occ_improve
