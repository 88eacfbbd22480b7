// write_file_atomically (atomic_file.hpp): complete files appear under the real name, failed writes
// leave the previous file and no temporary behind.
#include "support/temp_folder.hpp"
#include "occ_improve/io/atomic_file.hpp"
#include "occ_improve/errors.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

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

// A writer that throws (a stop request while a map is saved) left its temporary behind.
TEST_F(AtomicFile, AThrowingWriterLeavesNothingAndKeepsThePreviousFile) {
  write_file_atomically(file("a.txt"), "test file", [](std::ostream& out) { return static_cast<bool>(out << "kept"); });
  EXPECT_THROW(write_file_atomically(file("a.txt"), "test file",
                                     [](std::ostream& out) -> bool {
                                       out << "half";
                                       throw Cancelled(2);
                                     }),
               Cancelled);
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

// OutputFolder: what a tool did not write is never replaced or removed.
class OutputFolderTest : public AtomicFile {
protected:
  void put(const std::string& name, const std::string& text) { std::ofstream(file(name), std::ios::binary) << text; }
  void publish(const std::string& target, bool overwrite, const std::string& text) {
    OutputFolder out(target, "tool_a", overwrite);
    std::ofstream(out.file("result.txt")) << text;
    out.commit();
  }
};

TEST_F(OutputFolderTest, NewFolderGetsTheFilesAndAMarker) {
  publish(file("out"), false, "one");
  EXPECT_EQ(contents(file("out/result.txt")), "one");
  EXPECT_EQ(contents(file("out/") + kOutputMarkerName), "tool_a\nresult.txt\n");
  EXPECT_EQ(entry_count(), 1u) << "no staging folder may remain";
}

TEST_F(OutputFolderTest, OwnPreviousOutputIsReplaced) {
  publish(file("out"), false, "one");
  publish(file("out"), false, "two");
  EXPECT_EQ(contents(file("out/result.txt")), "two");
  EXPECT_EQ(entry_count(), 1u);
}

TEST_F(OutputFolderTest, ForeignFolderIsRefusedAndKept) {
  fs::create_directory(file("data"));
  put("data/frame.depth.png", "frame");
  try {
    OutputFolder out(file("data"), "tool_a", false);
    FAIL() << "a folder the tool did not write must be refused";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("-overwrite"), std::string::npos) << e.what();
  }
  EXPECT_EQ(contents(file("data/frame.depth.png")), "frame");
  EXPECT_EQ(entry_count(), 1u);
}

// An empty folder the user made read-only was replaced by the staged (writable) one, its parent being
// writable. Root writes anywhere, so as root the check runs in a child process as nobody.
TEST_F(OutputFolderTest, AReadOnlyFolderIsRefusedAndKeepsItsMode) {
  fs::create_directory(file("locked"));
  fs::permissions(file("locked"), fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                                      fs::perms::group_exec | fs::perms::others_read | fs::perms::others_exec);
  fs::permissions(folder_, fs::perms::all);  // the parent: writable by anyone, as in the trial
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    if (::geteuid() == 0 && (::setgid(65534) != 0 || ::setuid(65534) != 0)) ::_exit(3);
    try {
      OutputFolder out(file("locked"), "tool_a", false);
      ::_exit(1);
    } catch (const IoError& e) {
      ::_exit(std::string(e.what()).find("cannot write") != std::string::npos ? 0 : 2);
    }
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "1: the read-only folder was taken; 2: another error; 3: no nobody user";
  EXPECT_EQ(fs::status(file("locked")).permissions() & fs::perms::owner_write, fs::perms::none);
  fs::permissions(file("locked"), fs::perms::owner_all);
}

TEST_F(OutputFolderTest, AnotherToolsOutputIsForeign) {
  publish(file("out"), false, "one");
  EXPECT_THROW(OutputFolder(file("out"), "tool_b", false), IoError);
}

TEST_F(OutputFolderTest, UserFileInOwnOutputMakesItForeign) {
  publish(file("out"), false, "one");
  put("out/notes.txt", "mine");
  EXPECT_THROW(publish(file("out"), false, "two"), IoError);
  publish(file("out"), true, "two");
  EXPECT_EQ(contents(file("out/notes.txt")), "mine");
  EXPECT_EQ(contents(file("out/result.txt")), "two");
}

// Under -overwrite a foreign folder takes the outputs by name: an input of the run named like an output
// (the input depth image beside its folder's other files), or a file in an input folder, is refused by
// name before anything is staged, and stays as it was.
TEST_F(OutputFolderTest, OverwriteNeverReplacesAnInput) {
  fs::create_directory(file("data"));
  put("data/result.txt", "the input");
  put("data/other.txt", "mine");
  {
    OutputFolder out(file("data"), "tool_a", true, {file("data/result.txt")});
    try {
      out.file("result.txt");
      FAIL() << "an output named like an input must be refused";
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find("would replace the input '" + file("data/result.txt") + "'"), std::string::npos)
          << e.what();
    }
    std::ofstream(out.file("new.txt")) << "new";  // another name is fine
    out.commit();
  }
  EXPECT_EQ(contents(file("data/result.txt")), "the input");
  EXPECT_EQ(contents(file("data/new.txt")), "new");
  OutputFolder into_input_folder(file("data"), "tool_a", true, {file("data")});
  EXPECT_THROW(into_input_folder.file("other.txt"), IoError);
  EXPECT_EQ(contents(file("data/other.txt")), "mine");
}

// The tool's own folder inside an input folder (`tool seq/ -o seq/out`, run twice) is replaced as a whole:
// the by-name check of a foreign folder does not apply (it refused the second run).
TEST_F(OutputFolderTest, OwnFolderInsideAnInputFolderIsReplacedAgain) {
  fs::create_directory(file("seq"));
  put("seq/frame.depth.png", "frame");
  for (const char* text : {"one", "two"}) {
    OutputFolder out(file("seq/out"), "tool_a", false, {file("seq")});
    std::ofstream(out.file("result.txt")) << text;
    out.commit();
  }
  EXPECT_EQ(contents(file("seq/out/result.txt")), "two");
  EXPECT_EQ(contents(file("seq/frame.depth.png")), "frame");
}

TEST_F(OutputFolderTest, OverwriteReplacesOnlySameNames) {
  fs::create_directory(file("data"));
  put("data/frame.depth.png", "frame");
  put("data/result.txt", "old");
  publish(file("data"), true, "new");
  EXPECT_EQ(contents(file("data/frame.depth.png")), "frame");
  EXPECT_EQ(contents(file("data/result.txt")), "new");
  EXPECT_FALSE(fs::exists(file("data/") + kOutputMarkerName)) << "a foreign folder is not marked as the tool's";
}

TEST_F(OutputFolderTest, UncommittedOutputLeavesNothing) {
  {
    OutputFolder out(file("out"), "tool_a", false);
    std::ofstream(out.file("result.txt")) << "half";
  }
  EXPECT_EQ(entry_count(), 0u);
}

TEST_F(OutputFolderTest, AFileOrAMissingParentIsRefused) {
  put("file", "x");
  EXPECT_THROW(OutputFolder(file("file"), "tool_a", true), IoError);
  EXPECT_THROW(OutputFolder(file("missing/out"), "tool_a", true), IoError);
  EXPECT_EQ(contents(file("file")), "x");
}

// A save killed mid-write left *.partial-* files and .OUT.tmp-PID folders that nothing removed.
TEST_F(OutputFolderTest, LeftoversOfDeadWritersAreRemovedOnTheNextWrite) {
  const std::string own = std::to_string(::getpid());
  put("a.txt.partial-999999999-1f", "dead writer");  // beyond Linux's pid_max: no such process
  put("a.txt.partial-" + own + "-2f", "a live writer: this process");
  put("a.txt.partial-" + own + "-3f", "this PID, but from before this process started");
  fs::last_write_time(file("a.txt.partial-" + own + "-3f"), fs::file_time_type::clock::now() - std::chrono::hours(24 * 365));
  put("b.txt.partial-999999999-1f", "another target's: not this write's to judge");
  write_file_atomically(file("a.txt"), "test file", [](std::ostream& out) { return static_cast<bool>(out << "x"); });
  EXPECT_FALSE(fs::exists(file("a.txt.partial-999999999-1f")));
  EXPECT_TRUE(fs::exists(file("a.txt.partial-" + own + "-2f")));
  EXPECT_FALSE(fs::exists(file("a.txt.partial-" + own + "-3f")));
  EXPECT_TRUE(fs::exists(file("b.txt.partial-999999999-1f")));

  fs::create_directories(file(".out.tmp-999999999"));
  put(".out.tmp-999999999/depth.png", "half");
  fs::create_directories(file(".out.tmp-999999999.old"));
  publish(file("out"), false, "one");
  EXPECT_FALSE(fs::exists(file(".out.tmp-999999999")));
  EXPECT_FALSE(fs::exists(file(".out.tmp-999999999.old")));
  EXPECT_EQ(contents(file("out/result.txt")), "one");
}

// A run killed between the two renames of a commit left the old output only as .out.tmp-PID.old, and the
// next run, even one that failed, deleted it: it is now moved back, and leftovers go only after a commit.
TEST_F(OutputFolderTest, AnInterruptedCommitIsRecoveredEvenByARunThatFails) {
  fs::create_directories(file(".out.tmp-999999999.old"));  // beyond Linux's pid_max: a dead writer
  put(".out.tmp-999999999.old/result.txt", "old output");
  put(".out.tmp-999999999.old/" + std::string(kOutputMarkerName), "tool_a\nresult.txt\n");
  fs::create_directories(file(".out.tmp-999999999"));
  put(".out.tmp-999999999/result.txt", "the dead run's new output");
  { OutputFolder failing_run(file("out"), "tool_a", false); }  // fails before its commit
  EXPECT_EQ(contents(file("out/result.txt")), "old output");
  EXPECT_FALSE(fs::exists(file(".out.tmp-999999999.old")));
  EXPECT_TRUE(fs::exists(file(".out.tmp-999999999/result.txt")));  // kept: no successful commit yet
  publish(file("out"), false, "new");
  EXPECT_EQ(contents(file("out/result.txt")), "new");
  EXPECT_FALSE(fs::exists(file(".out.tmp-999999999")));
}

// -o on a symbolic link replaced the link by a folder.
TEST_F(OutputFolderTest, ASymbolicLinkIsWrittenThrough) {
  fs::create_directories(file("real"));
  fs::create_directory_symlink(file("real"), file("link"));
  publish(file("link"), false, "one");
  publish(file("link"), false, "two");
  EXPECT_TRUE(fs::is_symlink(file("link")));
  EXPECT_EQ(contents(file("real/result.txt")), "two");
  fs::create_directory_symlink(file("nowhere"), file("dangling"));
  EXPECT_THROW(OutputFolder(file("dangling"), "tool_a", false), IoError);
}

class OutputFileTest : public OutputFolderTest {
protected:
  static bool starts_with_map(const std::string& path) { return contents(path).rfind("MAP", 0) == 0; }
  void save(const std::string& target, bool overwrite, const std::string& text) {
    OutputFile out(target, "-save", overwrite, starts_with_map, "a map");
    std::ofstream(out.staged()) << text;
    out.commit();
  }
};

// -save overwrote anything, a user's cloud or notes included.
TEST_F(OutputFileTest, OnlyItsOwnKindOfFileIsReplacedUnlessOverwrite) {
  save(file("m.map"), false, "MAP one");
  save(file("m.map"), false, "MAP two");
  EXPECT_EQ(contents(file("m.map")), "MAP two");
  put("notes.txt", "mine");
  try {
    save(file("notes.txt"), false, "MAP three");
    FAIL() << "a foreign file was replaced";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("-overwrite"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("-save"), std::string::npos) << e.what();
  }
  EXPECT_EQ(contents(file("notes.txt")), "mine");
  save(file("notes.txt"), true, "MAP three");
  EXPECT_EQ(contents(file("notes.txt")), "MAP three");
  EXPECT_EQ(entry_count(), 2u);  // no staged file left
}

// A map occ_improve wrote, then made read-only by its owner, was replaced by the rename (as root too): a
// file without any write bit is refused, -overwrite or not, and stays as it was.
TEST_F(OutputFileTest, AReadOnlyFileIsNeverReplaced) {
  save(file("m.map"), false, "MAP kept");
  fs::permissions(file("m.map"), fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  for (bool overwrite : {false, true}) {
    try {
      save(file("m.map"), overwrite, "MAP new");
      FAIL() << "a read-only file was replaced, overwrite " << overwrite;
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find("'" + file("m.map") + "' is read-only"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(contents(file("m.map")), "MAP kept");
  fs::permissions(file("m.map"), fs::perms::owner_write, fs::perm_options::add);
  save(file("m.map"), false, "MAP new");
  EXPECT_EQ(contents(file("m.map")), "MAP new");
}

// The check of an existing file's magic opened a named pipe for reading, which blocks until a writer comes
// (a Python save() hung, Ctrl-C or not): a pipe is refused before anything reads it, -overwrite or not.
TEST_F(OutputFileTest, APipeIsRefusedWithoutReadingIt) {
  ASSERT_EQ(::mkfifo(file("pipe.map").c_str(), 0644), 0);
  for (bool overwrite : {false, true}) {
    try {
      save(file("pipe.map"), overwrite, "MAP");
      FAIL() << "a pipe was taken, overwrite " << overwrite;
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
    }
  }
  EXPECT_TRUE(fs::is_fifo(file("pipe.map")));
}

// The message says how to replace a foreign file in the caller's terms (Python: overwrite=True).
TEST_F(OutputFileTest, TheOverwriteHintIsTheCallers) {
  put("notes.txt", "mine");
  try {
    OutputFile out(file("notes.txt"), "save", false, starts_with_map, "a map", "pass overwrite=True");
    FAIL() << "a foreign file was taken";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("or pass overwrite=True to replace it"), std::string::npos) << e.what();
  }
}

TEST_F(OutputFileTest, FoldersMissingParentsAndUncommittedWritesLeaveNothing) {
  fs::create_directories(file("dir"));
  EXPECT_THROW(save(file("dir"), true, "MAP"), IoError);
  EXPECT_THROW(save(file("missing/m.map"), true, "MAP"), IoError);
  put("m.map", "MAP old");
  {
    OutputFile out(file("m.map"), "-save", false, starts_with_map, "a map");
    std::ofstream(out.staged()) << "MAP new, never committed";
  }
  EXPECT_EQ(contents(file("m.map")), "MAP old");
  EXPECT_EQ(entry_count(), 2u);
}

TEST_F(OutputFileTest, ASymbolicLinkIsWrittenThrough) {
  put("real.map", "MAP old");
  fs::create_symlink(file("real.map"), file("link.map"));
  save(file("link.map"), false, "MAP new");
  EXPECT_TRUE(fs::is_symlink(file("link.map")));
  EXPECT_EQ(contents(file("real.map")), "MAP new");
}

}  // namespace
}  // namespace occ_improve
