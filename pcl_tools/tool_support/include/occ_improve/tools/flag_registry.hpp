#pragma once
// The command-line flags of the occ_improve tools, declared once. Every flag any tool takes is one entry of
// one registry (flag_registry()): its kind, value bounds, default and help text, and the -h group it is
// shown in. A tool lists the names it takes (flags.hpp's ToolFlags).
#include <initializer_list>
#include <limits>
#include <string>
#include <vector>

namespace occ_improve {

enum class FlagKind {
  switch_flag,  ///< no value: present or not
  integer,      ///< a whole number within [minimum, maximum]
  number,       ///< a finite number within the bounds
  choice,       ///< one of `choices`
  text,         ///< any value (paths, lists); the tool checks its shape and names the flag when it is wrong
};

struct FlagSpec {
  std::string name;  ///< "-threads"
  FlagKind kind = FlagKind::switch_flag;
  std::string value_name;     ///< shown in -h: "N", "PATH"
  std::string help;           ///< what it does; lines after the first are continuation lines
  std::string default_value;  ///< taken (and checked) like a given value when the flag is absent; "" = none
  std::string default_note;   ///< shown in -h for a flag without a default value, e.g. "the preset's"
  double minimum = -std::numeric_limits<double>::infinity();
  double maximum = std::numeric_limits<double>::infinity();
  bool minimum_exclusive = false;  ///< "> minimum" rather than ">= minimum"
  bool maximum_exclusive = false;  ///< "< maximum" rather than "<= maximum"
  std::vector<std::string> choices;
  bool optional_value = false;  ///< -device [URI]: the value may be left out
  std::string group;            ///< the -h section
};

/// Every flag of every tool, the general ones every tool takes without listing them included (-h, -help,
/// --help, -v: as PCL's tools take them). Names are unique.
const std::vector<FlagSpec>& flag_registry();
/// The registry's entry (std::logic_error for a name not in it: a programming error).
const FlagSpec& flag_spec(const std::string& name);

/// The names of the flag groups tools share, for ToolFlags::flags: the sensor preset and its overrides
/// (-preset ... -clamp); the camera of depth images (-intrinsics, -intrinsics_file, -depth_encoding); the
/// output folder (-o, -overwrite).
std::vector<std::string> sensor_flag_names();
std::vector<std::string> camera_flag_names();
std::vector<std::string> output_folder_flag_names();
/// The batch mode's -input_dir and -output_dir (batch.hpp).
std::vector<std::string> batch_flag_names();
/// The lists one after the other.
std::vector<std::string> joined(std::initializer_list<std::vector<std::string>> lists);

}  // namespace occ_improve
