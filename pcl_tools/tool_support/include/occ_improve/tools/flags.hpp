#pragma once
// A tool's command line, parsed against the flags the tool takes (ToolFlags: names from the one registry of
// flag_registry.hpp); that list drives parsing, checking and -h (flag_usage.hpp), so a flag means the same
// thing in every tool and -h shows only the flags the tool reads, each with its default.
//
// Parsing refuses, naming the flag and the value: an unknown flag, a missing value, a value that is not a
// number (or not a whole number) where one is needed, a number outside the flag's bounds, a value not among
// a choice flag's choices, and a flag given twice unless the tool lets it repeat.
#include "occ_improve/tools/flag_registry.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace occ_improve {

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

/// The comma-separated finite numbers of a list value ("-fov 57,43"); throws InvalidParameter naming the
/// flag, the value and the item that is not a number.
std::vector<double> parse_number_list(const std::string& flag, const std::string& text);

/// A flag given where it does nothing (occ_plan -window without -shape window) is said on stderr, not
/// refused: "warning: -window applies with -shape window only: ignored".
void warn_if_ignored(const CommandLine& command_line, const char* flag, const char* applies_with, bool applies);

}  // namespace occ_improve
