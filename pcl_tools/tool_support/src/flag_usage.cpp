#include "occ_improve/tools/flag_usage.hpp"

#include <algorithm>
#include <sstream>

namespace occ_improve {

namespace {

bool contains(const std::vector<std::string>& list, const std::string& s) {
  return std::find(list.begin(), list.end(), s) != list.end();
}

constexpr std::size_t kHelpColumn = 28, kLineWidth = 108;

// The help text's words in lines of at most kLineWidth columns, continuation lines indented to the help
// column (the registry's own line breaks only keep its source lines short).
std::string wrapped(const std::string& text) {
  std::string out;
  std::size_t column = kHelpColumn;
  std::istringstream words(text);
  for (std::string word; words >> word;) {
    if (!out.empty() && column + 1 + word.size() > kLineWidth) {
      out += "\n" + std::string(kHelpColumn, ' ');
      column = kHelpColumn;
    } else if (!out.empty()) {
      out += ' ';
      ++column;
    }
    out += word;
    column += word.size();
  }
  return out;
}

// A one-line-per-flag -h entry: "  -name VALUE   help (default X)", continuation lines indented.
std::string usage_entry(const FlagSpec& f, const ToolFlags& tool) {
  const auto own = tool.defaults.find(f.name);
  const std::string default_value = own != tool.defaults.end() ? own->second : f.default_value;
  std::string help = f.help;
  if (f.kind != FlagKind::switch_flag) {
    if (!default_value.empty()) help += " (default " + default_value + ")";
    else if (!f.default_note.empty()) help += " (default: " + f.default_note + ")";
  }
  if (contains(tool.repeatable, f.name)) help += "; may be repeated";
  std::string head = "  " + f.name + (f.value_name.empty() ? "" : " " + f.value_name);
  head += head.size() + 1 < kHelpColumn ? std::string(kHelpColumn - head.size(), ' ')
                                        : "\n" + std::string(kHelpColumn, ' ');
  return head + wrapped(help) + "\n";
}

}  // namespace

std::string usage_text(const ToolFlags& tool, const std::string& program) {
  std::string out;
  for (std::size_t i = 0; i < tool.synopsis.size(); ++i)
    out += (i == 0 ? "Usage: " : "       ") + program + " " + tool.synopsis[i] + "\n";
  out += "\n" + tool.description;
  if (!tool.description.empty() && tool.description.back() != '\n') out += "\n";
  if (!tool.positionals.empty()) out += "\nInputs (positional):\n" + tool.positionals;
  std::vector<std::string> groups;
  for (const std::string& name : tool.flags)
    if (!contains(groups, flag_spec(name).group)) groups.push_back(flag_spec(name).group);
  for (const std::string& group : groups) {
    out += "\n" + group + ":\n";
    for (const std::string& name : tool.flags)
      if (flag_spec(name).group == group) out += usage_entry(flag_spec(name), tool);
  }
  out += "  -h, -help, --help         this help\n";
  out += usage_entry(flag_spec("-v"), tool);
  return out;
}

std::string resolved_flags(const CommandLine& command_line) {
  std::string out;
  for (const std::string& name : command_line.tool().flags) {
    const FlagSpec& f = flag_spec(name);
    if (f.kind == FlagKind::switch_flag) {
      out += "  " + name + (command_line.has(name) ? " (given)" : " (not given)") + "\n";
      continue;
    }
    const std::vector<std::string> given = command_line.values(name);
    if (!given.empty()) {
      for (const std::string& v : given) out += "  " + name + " " + (v.empty() ? "(no value)" : v) + "\n";
    } else if (const auto value = command_line.text(name)) {
      out += "  " + name + " " + *value + " (default)\n";
    } else {
      out += "  " + name + " (unset" + (f.default_note.empty() ? "" : ": " + f.default_note) + ")\n";
    }
  }
  for (const std::string& p : command_line.positionals()) out += "  input " + p + "\n";
  return out;
}

}  // namespace occ_improve
