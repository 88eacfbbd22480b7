#pragma once
// The command-line flags of the occ_improve tools, declared once. Every flag any tool takes is one entry of
// one registry (flag_registry()): its kind, value bounds, default and help text. A tool lists the names it
// takes (ToolFlags); that list drives parsing, checking and -h, so a flag means the same thing in every tool
// and -h shows only the flags the tool reads, each with its default.
//
// Parsing refuses, naming the flag and the value: an unknown flag, a missing value, a value that is not a
// number (or not a whole number) where one is needed, a number outside the flag's bounds, a value not among
// a choice flag's choices, and a flag given twice unless the tool lets it repeat.
#include <initializer_list>
#include <limits>
#include <map>
#include <optional>
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

/// What one tool takes.
struct ToolFlags {
  std::string tool;                   ///< "occ_improve_map"
  std::vector<std::string> synopsis;  ///< usage lines after the program name: "[options] INPUT... -o OUTDIR"
  std::string description;            ///< paragraphs after the usage lines
  std::vector<std::string> flags;     ///< registry names in -h order (-h is always taken)
  std::map<std::string, std::string> defaults;  ///< this tool's default where it differs (e.g. -o's folder)
  std::vector<std::string> repeatable;          ///< flags this tool lets repeat (occ_to_octomap's -load/-pose)
  std::string positionals;  ///< -h text of the positional arguments; empty: the tool takes none
};

/// A parsed command line of one tool.
class CommandLine {
public:
  CommandLine(const ToolFlags& tool, std::map<std::string, std::vector<std::string>> given,
              std::vector<std::string> positionals);

  /// Whether the tool takes the flag at all.
  bool declares(const std::string& flag) const;
  /// Whether the flag was given (a switch, or a value flag with or without its value).
  bool has(const std::string& flag) const;
  /// The value given, else the default; nullopt when neither.
  std::optional<std::string> text(const std::string& flag) const;
  /// Every value of a repeatable flag, in command-line order (none: empty).
  std::vector<std::string> values(const std::string& flag) const;
  /// Checked values of integer/number flags (the parser has already refused bad ones).
  std::optional<int> integer(const std::string& flag) const;
  std::optional<double> number(const std::string& flag) const;
  /// The positional arguments, in order.
  const std::vector<std::string>& positionals() const { return positionals_; }
  const ToolFlags& tool() const { return *tool_; }
  /// This command line for one file of a batch (-input_dir): `input` its only positional, -o
  /// `output_folder`, without -input_dir and -output_dir.
  CommandLine for_one_input(const std::string& input, const std::string& output_folder) const;

private:
  const FlagSpec& declared(const std::string& flag) const;

  const ToolFlags* tool_;
  std::map<std::string, std::vector<std::string>> given_;
  std::vector<std::string> positionals_;
};

/// Parses argv (argv[0] is the program) against the tool's flags; throws InvalidParameter naming the flag
/// and the value on anything the table refuses. `tool` must outlive the result.
CommandLine parse_command_line(const ToolFlags& tool, int argc, const char* const* argv);

/// The -h text: usage lines, description, then every flag of the tool by group, with its default.
std::string usage_text(const ToolFlags& tool, const std::string& program);

/// For -v: one line per flag of the tool with the value it runs with ("-k 10 (default)"), then the inputs.
std::string resolved_flags(const CommandLine& command_line);

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

/// The comma-separated finite numbers of a list value ("-fov 57,43"); throws InvalidParameter naming the
/// flag, the value and the item that is not a number.
std::vector<double> parse_number_list(const std::string& flag, const std::string& text);

}  // namespace occ_improve
