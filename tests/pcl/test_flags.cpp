// The flag table (flags.hpp): one registry, checked parsing naming flag and value, -h from the same table.
#include "occ_improve/tools/flag_usage.hpp"

#include "occ_improve/errors.hpp"

#include "support/command_line_args.hpp"

#include <gtest/gtest.h>

#include <initializer_list>
#include <set>
#include <string>
#include <vector>

namespace occ_improve {
namespace {

const ToolFlags kTool{"tool",
                      {"[options] INPUT..."},
                      "A test tool.\n",
                      {"-o", "-q", "-threads", "-contour", "-fps", "-mode", "-load", "-pose", "-device", "-budget"},
                      {{"-budget", "128"}},
                      {"-pose"},
                      "  INPUT  anything\n"};

using test::Args;

CommandLine parse(std::initializer_list<std::string> args, const ToolFlags& tool = kTool) {
  Args a(args);
  return parse_command_line(tool, a.argc(), a.argv.data());
}

std::string error_of(std::initializer_list<std::string> args) {
  return test::invalid_parameter_of([&] { parse(args); });
}

TEST(FlagRegistry, NamesAreUniqueAndEveryValueFlagStatesItsDefault) {
  std::set<std::string> names;
  for (const FlagSpec& f : flag_registry()) {
    EXPECT_TRUE(names.insert(f.name).second) << f.name << " twice";
    EXPECT_FALSE(f.help.empty()) << f.name;
    EXPECT_FALSE(f.group.empty()) << f.name;
    if (f.kind != FlagKind::switch_flag) {
      EXPECT_FALSE(f.value_name.empty()) << f.name;
      EXPECT_TRUE(!f.default_value.empty() || !f.default_note.empty()) << f.name << " states no default";
    }
    if (f.kind == FlagKind::choice) {
      EXPECT_FALSE(f.choices.empty()) << f.name;
    }
  }
  EXPECT_THROW(flag_spec("-no_such_flag"), std::logic_error);
}

TEST(FlagRegistry, EveryDefaultValuePassesItsOwnCheck) {
  for (const FlagSpec& f : flag_registry()) {
    if (f.default_value.empty()) continue;
    const ToolFlags one{"tool", {""}, "", {f.name}, {}, {}, ""};
    const CommandLine c = parse({}, one);
    if (f.kind == FlagKind::integer || f.kind == FlagKind::number) {
      EXPECT_NO_THROW(c.number(f.name)) << f.name;
    }
    EXPECT_EQ(c.text(f.name), f.default_value);
  }
}

TEST(CommandLine, ValuesDefaultsAndPositionals) {
  const CommandLine c = parse({"a.pcd", "-threads", "3", "-contour", "-0.05", "-o", "out", "b.pcd", "-q"});
  EXPECT_EQ(c.positionals(), (std::vector<std::string>{"a.pcd", "b.pcd"}));
  EXPECT_EQ(c.integer("-threads"), 3);
  EXPECT_DOUBLE_EQ(*c.number("-contour"), -0.05);  // a negative number is a value, not a flag
  EXPECT_EQ(c.text("-o"), "out");
  EXPECT_TRUE(c.has("-q"));
  EXPECT_EQ(c.text("-mode"), "clamped");  // the registry's default
  EXPECT_EQ(c.integer("-budget"), 128);   // this tool's own default
  EXPECT_FALSE(c.has("-budget"));
  EXPECT_FALSE(c.text("-load"));  // no default
  EXPECT_THROW(c.has("-seed"), std::logic_error);  // not declared: a programming error
}

TEST(CommandLine, RepeatableAndOptionalValues) {
  const CommandLine c = parse({"-pose", "0,0,0,0,0,0,1", "-pose", "1,0,0,0,0,0,1", "-device"});
  EXPECT_EQ(c.values("-pose").size(), 2u);
  EXPECT_TRUE(c.has("-device"));
  EXPECT_EQ(c.text("-device"), "");
  EXPECT_EQ(parse({"-device", "usb://1", "-q"}).text("-device"), "usb://1");
}

TEST(CommandLine, RefusalsNameTheFlagAndTheValue) {
  const auto refused = [](std::initializer_list<std::string> args, const std::string& expected) {
    const std::string message = error_of(args);
    EXPECT_NE(message.find(expected), std::string::npos) << "got: '" << message << "', expected '" << expected << "'";
  };
  refused({"-bogus"}, "unknown option -bogus");
  refused({"-nplane"}, "unknown option -nplane");
  refused({"-threads"}, "-threads needs a value");
  refused({"-o"}, "-o needs a value");
  refused({"-o", "-q"}, "-o needs a value");  // a flag is not a folder name
  refused({"-fps", "abc"}, "-fps abc is invalid: must be a finite number in [0, 1000]");
  refused({"-fps", "-1"}, "-fps -1 is invalid");
  refused({"-contour", "abc"}, "-contour abc is invalid: must be a finite number in [-1e+30, 0)");
  refused({"-contour", "0"}, "-contour 0 is invalid");
  refused({"-contour", "-bogus"}, "-contour -bogus is invalid");
  // Held as a float: -1e300 became -inf and was refused naming the library's field, not the flag.
  refused({"-contour", "-1e300"}, "-contour -1e300 is invalid");
  refused({"-threads", "2.5"}, "-threads 2.5 is invalid: must be an integer in [0, 1024]");
  refused({"-threads", "5000"}, "-threads 5000 is invalid");
  refused({"-threads", "1e99"}, "-threads 1e99 is invalid");
  refused({"-fps", "nan"}, "-fps nan is invalid");
  refused({"-budget", "0"}, "-budget 0 is invalid: must be an integer in [1, 2147483647]");
  // Beyond an int: the requirement names int's bound (it said ">= 1", which 1e12 meets).
  refused({"-budget", "1e12"}, "-budget 1e12 is invalid: must be an integer in [1, 2147483647]");
  refused({"-budget", "2147483648"}, "-budget 2147483648 is invalid: must be an integer in [1, 2147483647]");
  refused({"-mode", "fast"}, "-mode fast is invalid: must be one of clamped, exact");
  refused({"-threads", "1", "-threads", "2"}, "-threads is given twice");
  refused({"-load", ""}, "-load '' is invalid");
  refused({"-o", ""}, "-o '' is invalid: must be a non-empty");
  refused({""}, "an input path is empty");
  // strtod reads hex: -budget 0x10 was 16 rays.
  refused({"-budget", "0x10"}, "-budget 0x10 is invalid: must be an integer in [1, 2147483647]");
  refused({"-fps", "0x1p3"}, "-fps 0x1p3 is invalid");
  refused({"-fps", " 2"}, "-fps  2 is invalid");
  EXPECT_EQ(error_of({"-threads", "0", "-fps", "2.5", "-mode", "exact"}), "");
  EXPECT_EQ(error_of({"-budget", "1e3", "-fps", "+.5"}), "");
}

TEST(CommandLine, AToolWithoutInputsRefusesPositionals) {
  const ToolFlags no_inputs{"tool", {""}, "", {"-q"}, {}, {}, ""};
  try {
    parse({"stray"}, no_inputs);
    FAIL();
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("'stray'"), std::string::npos) << e.what();
  }
}

TEST(Usage, ListsOnlyTheToolsFlagsEachWithItsDefault) {
  const std::string usage = usage_text(kTool, "tool");
  for (const std::string& flag : kTool.flags) EXPECT_NE(usage.find("  " + flag), std::string::npos) << flag;
  EXPECT_EQ(usage.find("-preset"), std::string::npos);
  EXPECT_NE(usage.find("(default 128)"), std::string::npos);  // the tool's own default of -budget
  EXPECT_NE(usage.find("(default 0)"), std::string::npos);    // -threads
  EXPECT_NE(usage.find("may be repeated"), std::string::npos);
  EXPECT_NE(usage.find("Usage: tool [options] INPUT..."), std::string::npos);
  for (std::size_t start = 0, end; (end = usage.find('\n', start)) != std::string::npos; start = end + 1)
    EXPECT_LE(end - start, 110u) << usage.substr(start, end - start);
}

// A flag that does nothing in this run (occ_plan -window without -shape window) is said, not refused, and
// only when given: its default is not the user's.
TEST(CommandLine, AFlagGivenWhereItDoesNothingIsSaid) {
  testing::internal::CaptureStderr();
  warn_if_ignored(parse({"-budget", "5"}), "-budget", "-simulate", false);
  warn_if_ignored(parse({"-budget", "5"}), "-budget", "-simulate", true);
  warn_if_ignored(parse({}), "-budget", "-simulate", false);
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "warning: -budget applies with -simulate only: ignored\n");
}

TEST(NumberLists, NameTheFlagAndTheItem) {
  EXPECT_EQ(parse_number_list("-fov", "57,43"), (std::vector<double>{57, 43}));
  try {
    parse_number_list("-fov", "57,abc");
    FAIL();
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("-fov 57,abc is invalid: 'abc'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_number_list("-fov", ""), InvalidParameter);
  EXPECT_THROW(parse_number_list("-fov", "0x39,43"), InvalidParameter);
  // A trailing comma was read away ("585,585,320,240," as four numbers).
  try {
    parse_number_list("-intrinsics", "585,585,320,240,");
    FAIL();
  } catch (const InvalidParameter& e) {
    EXPECT_NE(std::string(e.what()).find("ends with a comma"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace occ_improve
