#pragma once
// Access to the real data in ../shared/data for tests. The folder is found through the environment
// variable OCC_IMPROVE_DATA_DIR, else the path configured at build time. Tests that need it call
// OCC_REQUIRE_DATA(path) and are skipped with a clear message where it is absent.
#include <gtest/gtest.h>

#include <string>

namespace occ_improve::test {

/// The data folder ("" when it does not exist).
std::string data_dir();
/// Full path of a file under the data folder ("" when the file is absent).
std::string data_file(const std::string& relative);

}  // namespace occ_improve::test

#define OCC_REQUIRE_DATA(var, relative)                                                                      \
  const std::string var = ::occ_improve::test::data_file(relative);                                         \
  if (var.empty()) {                                                                                         \
    GTEST_SKIP() << "real data '" << (relative) << "' not found (set OCC_IMPROVE_DATA_DIR to the shared/data " \
                 << "folder to run this test)";                                                              \
  }
