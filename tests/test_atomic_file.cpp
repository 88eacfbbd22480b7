// write_file_atomically (atomic_file.hpp): complete files appear under the real name, failed writes
// leave the previous file and no temporary behind.
#include "support/temp_folder.hpp"
#include "occ_improve/atomic_file.hpp"
#include "occ_improve/errors.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace occ_improve {
namespace {

namespace fs = std::filesystem;

class AtomicFile : public test::TempFolderTest {
protected:
  static std::string contents(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
};

TEST_F(AtomicFile, WritesAndReplaces) {
  write_file_atomically(file("a.txt"), "test file", [](std::ostream& out) { return static_cast<bool>(out << "first"); });
  EXPECT_EQ(contents(file("a.txt")), "first");
  write_file_atomically(file("a.txt"), "test file", [](std::ostream& out) { return static_cast<bool>(out << "second"); });
  EXPECT_EQ(contents(file("a.txt")), "second");
  EXPECT_EQ(entry_count(), 1u);
}

TEST_F(AtomicFile, FailedWriterKeepsThePreviousFile) {
  write_file_atomically(file("a.txt"), "test file", [](std::ostream& out) { return static_cast<bool>(out << "kept"); });
  try {
    write_file_atomically(file("a.txt"), "test file", [](std::ostream& out) {
      out << "half";
      return false;
    });
    FAIL() << "a failed writer must throw";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("test file"), std::string::npos) << e.what();
  }
  EXPECT_EQ(contents(file("a.txt")), "kept");
  EXPECT_EQ(entry_count(), 1u) << "the temporary must be removed";
}

TEST_F(AtomicFile, UnwritablePlacesAreIoErrors) {
  auto writer = [](std::ostream& out) { return static_cast<bool>(out << "x"); };
  EXPECT_THROW(write_file_atomically(file("missing/a.txt"), "test file", writer), IoError);
  fs::create_directory(file("folder"));
  EXPECT_THROW(write_file_atomically(file("folder"), "test file", writer), IoError);
  EXPECT_EQ(entry_count(), 1u);
  EXPECT_TRUE(fs::is_empty(file("folder")));
}

}  // namespace
}  // namespace occ_improve
