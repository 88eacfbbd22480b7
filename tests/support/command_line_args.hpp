#pragma once
// argv for the tools' command-line parser in tests: "tool" then the given arguments, and the message of
// the InvalidParameter a parse raises.
#include "occ_improve/errors.hpp"

#include <initializer_list>
#include <string>
#include <vector>

namespace occ_improve::test {

struct Args {
  std::vector<std::string> storage;
  std::vector<const char*> argv;
  Args(std::initializer_list<std::string> args) : storage{"tool"} {
    storage.insert(storage.end(), args.begin(), args.end());
    for (const auto& s : storage) argv.push_back(s.c_str());
  }
  int argc() const { return static_cast<int>(argv.size()); }
};

/// The message of the InvalidParameter that `parse()` throws, "" when it throws none.
template <typename Parse>
std::string invalid_parameter_of(Parse&& parse) {
  try {
    parse();
  } catch (const InvalidParameter& e) {
    return e.what();
  }
  return "";
}

}  // namespace occ_improve::test
