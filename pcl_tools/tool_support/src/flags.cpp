#include "occ_improve/tools/flags.hpp"

#include "occ_improve/errors.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace occ_improve {

namespace {

bool contains(const std::vector<std::string>& list, const std::string& s) {
  return std::find(list.begin(), list.end(), s) != list.end();
}

// Flags every tool takes without listing them, as PCL's tools do: help and verbosity.
bool is_general_flag(const std::string& name) { return name == "-h" || name == "-help" || name == "--help" || name == "-v"; }

// A flag is a dash and a letter ("-o", "--help"); a dash and a digit or point starts a value: a negative
// number ("-0.5") or a list of them ("-intrinsics -585,585,320,240").
bool looks_like_flag(const std::string& arg) {
  return arg.size() >= 2 && arg[0] == '-' && (std::isalpha(static_cast<unsigned char>(arg[1])) || arg[1] == '-');
}

std::string format_bound(double v) {
  std::ostringstream s;
  s << std::setprecision(12) << v;  // an int's bound in full
  return s.str();
}

// An integer flag's value is an int: its bounds are at most int's, and the requirement says so (a value
// beyond them was refused as not ">= 1").
constexpr double kIntegerMagnitude = 2147483647.0;
double integer_aware_maximum(const FlagSpec& f) { return f.kind == FlagKind::integer ? std::min(f.maximum, kIntegerMagnitude) : f.maximum; }
double integer_aware_minimum(const FlagSpec& f) { return f.kind == FlagKind::integer ? std::max(f.minimum, -kIntegerMagnitude) : f.minimum; }

// "an integer in [1, 2147483647]", "a number in [0, 1]", "a number > 0".
std::string requirement(const FlagSpec& f) {
  std::string r = f.kind == FlagKind::integer ? "an integer" : "a finite number";
  const double minimum = integer_aware_minimum(f), maximum = integer_aware_maximum(f);
  const bool low = std::isfinite(minimum), high = std::isfinite(maximum);
  if (low && high)
    r += std::string(" in ") + (f.minimum_exclusive ? "(" : "[") + format_bound(minimum) + ", " + format_bound(maximum) +
         (f.maximum_exclusive ? ")" : "]");
  else if (low)
    r += (f.minimum_exclusive ? " > " : " >= ") + format_bound(minimum);
  else if (high)
    r += (f.maximum_exclusive ? " < " : " <= ") + format_bound(maximum);
  return r;
}

[[noreturn]] void refuse(const FlagSpec& f, const std::string& value, const std::string& must) {
  throw InvalidParameter(f.name + " " + value + " is invalid: must be " + must);
}

// A decimal number as written on a command line: digits, sign, point and exponent only (strtod also
// reads hex, so "-k 0x10" was 16, and "inf"/"nan", which the finite checks refuse anyway).
bool is_decimal_text(const std::string& text) {
  return !text.empty() && text.find_first_not_of("0123456789+-.eE") == std::string::npos;
}

double checked_number(const FlagSpec& f, const std::string& text) {
  if (!is_decimal_text(text)) refuse(f, text, requirement(f));
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  const bool whole = f.kind != FlagKind::integer || v == std::floor(v);
  if (text.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v) || !whole) refuse(f, text, requirement(f));
  // The bounds the requirement states (an integer flag's are at most int's).
  const double minimum = integer_aware_minimum(f), maximum = integer_aware_maximum(f);
  const bool below = f.minimum_exclusive ? !(v > minimum) : v < minimum;
  const bool above = f.maximum_exclusive ? !(v < maximum) : v > maximum;
  if (below || above) refuse(f, text, requirement(f));
  return v;
}

void check_value(const FlagSpec& f, const std::string& value) {
  switch (f.kind) {
    case FlagKind::integer:
    case FlagKind::number:
      checked_number(f, value);
      break;
    case FlagKind::choice:
      if (!contains(f.choices, value)) {
        std::string list;
        for (const std::string& c : f.choices) list += (list.empty() ? "" : ", ") + c;
        refuse(f, value, "one of " + list);
      }
      break;
    case FlagKind::text:
      if (value.empty()) refuse(f, "''", "a non-empty " + f.value_name);
      break;
    case FlagKind::switch_flag:
      break;
  }
}

}  // namespace

std::vector<double> parse_number_list(const std::string& flag, const std::string& text) {
  std::vector<double> values;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (!is_decimal_text(item) || *end != '\0' || !std::isfinite(v))
      throw InvalidParameter(flag + " " + text + " is invalid: '" + item + "' is not a finite decimal number");
    values.push_back(v);
  }
  if (values.empty()) throw InvalidParameter(flag + " " + text + " is invalid: no number in it");
  // getline drops a trailing empty item: "585,585,320,240," read as four numbers.
  if (text.back() == ',') throw InvalidParameter(flag + " " + text + " is invalid: it ends with a comma");
  return values;
}

CommandLine::CommandLine(const ToolFlags& tool, std::map<std::string, std::vector<std::string>> given,
                         std::vector<std::string> positionals)
    : tool_(&tool), given_(std::move(given)), positionals_(std::move(positionals)) {}

const FlagSpec& CommandLine::declared(const std::string& flag) const {
  if (!contains(tool_->flags, flag) && !is_general_flag(flag)) throw std::logic_error(tool_->tool + " does not declare " + flag);
  return flag_spec(flag);
}

bool CommandLine::declares(const std::string& flag) const {
  return contains(tool_->flags, flag) || is_general_flag(flag);
}

bool CommandLine::has(const std::string& flag) const {
  declared(flag);
  return given_.count(flag) != 0;
}

std::optional<std::string> CommandLine::text(const std::string& flag) const {
  const FlagSpec& f = declared(flag);
  if (const auto it = given_.find(flag); it != given_.end()) return it->second.front();
  if (const auto own = tool_->defaults.find(flag); own != tool_->defaults.end()) return own->second;
  if (!f.default_value.empty()) return f.default_value;
  return std::nullopt;
}

std::vector<std::string> CommandLine::values(const std::string& flag) const {
  declared(flag);
  const auto it = given_.find(flag);
  return it == given_.end() ? std::vector<std::string>{} : it->second;
}

std::optional<double> CommandLine::number(const std::string& flag) const {
  const FlagSpec& f = declared(flag);
  if (f.kind != FlagKind::number && f.kind != FlagKind::integer) throw std::logic_error(flag + " is not a number flag");
  const auto t = text(flag);
  if (!t) return std::nullopt;
  return checked_number(f, *t);
}

std::optional<int> CommandLine::integer(const std::string& flag) const {
  if (declared(flag).kind != FlagKind::integer) throw std::logic_error(flag + " is not an integer flag");
  const auto v = number(flag);
  if (!v) return std::nullopt;
  return static_cast<int>(*v);
}

CommandLine CommandLine::for_one_input(const std::string& input, const std::string& output_folder) const {
  std::map<std::string, std::vector<std::string>> given = given_;
  for (const std::string& flag : batch_flag_names()) given.erase(flag);
  given["-o"] = {output_folder};
  return CommandLine(*tool_, std::move(given), {input});
}

CommandLine parse_command_line(const ToolFlags& tool, int argc, const char* const* argv) {
  std::map<std::string, std::vector<std::string>> given;
  std::vector<std::string> positionals;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (!looks_like_flag(arg)) {
      if (tool.positionals.empty())
        throw InvalidParameter("unexpected argument '" + arg + "': " + tool.tool + " takes no input files (see -h)");
      if (arg.empty()) throw InvalidParameter("an input path is empty ('')");  // names no file (a shell's unset variable)
      positionals.push_back(arg);
      continue;
    }
    if (!contains(tool.flags, arg) && !is_general_flag(arg))
      throw InvalidParameter("unknown option " + arg + " for " + tool.tool + " (see -h)");
    const FlagSpec& f = flag_spec(arg);
    std::vector<std::string>& values = given[arg];
    if (!values.empty() && !contains(tool.repeatable, arg))
      throw InvalidParameter(arg + " is given twice: give it once");
    if (f.kind == FlagKind::switch_flag) {
      values.emplace_back();
      continue;
    }
    const bool value_follows = i + 1 < argc && (!looks_like_flag(argv[i + 1]) ||
                                                f.kind == FlagKind::number || f.kind == FlagKind::integer);
    if (!value_follows) {
      if (f.optional_value) {
        values.emplace_back();
        continue;
      }
      throw InvalidParameter(arg + " needs a value (" + arg + " " + f.value_name + ", see -h)");
    }
    check_value(f, argv[i + 1]);
    values.emplace_back(argv[++i]);
  }
  return CommandLine(tool, std::move(given), std::move(positionals));
}

void warn_if_ignored(const CommandLine& command_line, const char* flag, const char* applies_with, bool applies) {
  if (applies || !command_line.has(flag)) return;
  std::fprintf(stderr, "warning: %s applies with %s only: ignored\n", flag, applies_with);
}

}  // namespace occ_improve
