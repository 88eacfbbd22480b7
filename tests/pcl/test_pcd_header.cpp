// validate_pcd_file (pcd_header.hpp): the header values that crash, spin or bloat PCL 1.13's reader are
// refused with a FormatError naming the file and the field, and PCL's own files still read.
#include "occ_improve/pcl/pcd_header.hpp"

#include "occ_improve/errors.hpp"
#include "support/temp_folder.hpp"

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>

namespace occ_improve {
namespace {

// A header with the given lines replaced; fields x y z, 2 x 1 points.
std::string header(const std::string& width = "2", const std::string& height = "1", const std::string& points = "2",
                   const std::string& size = "4 4 4", const std::string& count = "1 1 1",
                   const std::string& data = "ascii") {
  return "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE " + size + "\nTYPE F F F\nCOUNT " + count + "\nWIDTH " + width +
         "\nHEIGHT " + height + "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + points + "\nDATA " + data + "\n";
}

class PcdHeaderTest : public test::TempFolderTest {
protected:
  std::string write(const std::string& bytes) {
    const std::string path = file("cloud.pcd");
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }
  // The FormatError's message for `bytes` ("" when none was thrown).
  std::string refusal(const std::string& bytes) {
    try {
      validate_pcd_file(write(bytes));
    } catch (const FormatError& e) {
      return e.what();
    }
    return "";
  }
  void expect_refused_naming(const std::string& bytes, const std::string& field) {
    const std::string message = refusal(bytes);
    EXPECT_NE(message.find(field), std::string::npos) << "'" << message << "' should name " << field;
    EXPECT_NE(message.find("cloud.pcd"), std::string::npos) << message;
  }
};

TEST_F(PcdHeaderTest, PclWrittenFilesOfEveryEncodingPass) {
  pcl::PointCloud<pcl::PointXYZRGBL> cloud(4, 3);
  for (std::size_t i = 0; i < cloud.size(); ++i) cloud[i].x = cloud[i].y = cloud[i].z = static_cast<float>(i);
  pcl::PCDWriter writer;
  for (int mode = 0; mode < 3; ++mode) {
    const std::string path = file("cloud" + std::to_string(mode) + ".pcd");
    if (mode == 0) writer.writeASCII(path, cloud);
    if (mode == 1) writer.writeBinary(path, cloud);
    if (mode == 2) writer.writeBinaryCompressed(path, cloud);
    const PcdHeader h = validate_pcd_file(path);
    EXPECT_EQ(h.points, 12u);
    EXPECT_EQ(h.width, 4u);
    EXPECT_EQ(h.height, 3u);
    pcl::PCLPointCloud2 blob;
    read_pcd_file(path, blob);
    EXPECT_EQ(blob.width * blob.height, 12u) << "mode " << mode;
  }
}

// PCL reads "1.5abc" as 1.5 and "foo" as 0, and keeps a line of the wrong length as a point of zeros after a
// warning that does not name the file: such a cloud is refused, naming the line, the value and its field.
TEST_F(PcdHeaderTest, AsciiDataMustHoldOneNumberPerValueOnEveryPointsLine) {
  expect_refused_naming(header() + "0 0 1\n0.05 0.05 1.5abc\n", "line 2 (point 2): '1.5abc' for field 'z' is not a number");
  expect_refused_naming(header() + "foo 0.05 1.5\n0 0 1\n", "line 1 (point 1): 'foo' for field 'x' is not a number");
  expect_refused_naming(header() + "0 0 1 2 3\n0 0 1\n", "line 1 (point 1) holds 5 values, the fields take 3");
  expect_refused_naming(header() + "0 0 1\n\n0.25 0\n", "line 3 (point 2) holds 2 values, the fields take 3");
  expect_refused_naming(header() + "0.0000001 0 1\n", "DATA ascii holds 1 points, the header declares POINTS 2");
  expect_refused_naming(header() + "0 0 1\n0 0 1\n0 0 2\n", "line 3 (point 3) is past the POINTS 2");
  // Numbers as PCL writes them (nan, inf, exponents) and as strtod reads them (a leading '+'), CRLF line
  // ends, empty lines between and after.
  EXPECT_EQ(refusal(header() + "nan nan nan\r\n\n1e-3 -2.5E+1 +inf\n\n \n"), "");
  expect_refused_naming(header() + "1 2 3\n4 5 +\n", "'+' for field 'z' is not a number");
  // COUNT > 1: one number per value.
  EXPECT_EQ(refusal(header("2", "1", "2", "4 4 4", "2 1 1") + "0 1 2 3\n4 5 6 7\n"), "");
  expect_refused_naming(header("2", "1", "2", "4 4 4", "2 1 1") + "0 1 2 3\n4 5 6\n", "holds 3 values, the fields take 4");
}

TEST_F(PcdHeaderTest, WidthTimesHeightMustEqualPointsWithoutWrapping) {
  // 65536 x 65536 is 0 in 32 bits: it "equalled" POINTS 0 and crashed fromPCLPointCloud2.
  expect_refused_naming(header("65536", "65536", "0"), "WIDTH x HEIGHT");
  expect_refused_naming(header("3", "1", "2") + "1 2 3\n4 5 6\n", "WIDTH x HEIGHT");
  expect_refused_naming(header("-1", "1", "2"), "WIDTH");
  expect_refused_naming(header("4294967296", "1", "2"), "WIDTH");
}

TEST_F(PcdHeaderTest, CountAndSizeOfMinusOneOrHugeAreRefused) {
  for (const std::string count : {"-1 1 1", "4294967295 1 1", "0 1 1", "1 1"})
    expect_refused_naming(header("2", "1", "2", "4 4 4", count), "COUNT");
  for (const std::string size : {"-1 4 4", "4294967295 4 4", "3 4 4", "2 4 4"})
    expect_refused_naming(header("2", "1", "2", size), size == "2 4 4" ? "TYPE F" : "SIZE");
}

TEST_F(PcdHeaderTest, MalformedLinesAreRefused) {
  expect_refused_naming("", "empty");
  expect_refused_naming(std::string("\x89PNG\r\n\x1a\n\0\0", 10), "not a PCD file");
  expect_refused_naming(header(), "DATA ascii declares");  // no data: fewer values than declared
  expect_refused_naming(header("2", "1", "2", "4 4 4", "1 1 1", "lzma"), "DATA");
  std::string twice = header();
  twice.insert(twice.find("WIDTH"), "WIDTH 2\n");
  expect_refused_naming(twice, "twice");
  std::string unknown = header();
  unknown.insert(unknown.find("WIDTH"), "COLOUR 3\n");
  expect_refused_naming(unknown, "unknown header line");
  std::string no_height = header();
  no_height.erase(no_height.find("HEIGHT"), 9);
  expect_refused_naming(no_height, "no HEIGHT");
}

// Found by the fuzzer: PCL goes on reading header lines after DATA, so a second header (here claiming a
// 4 GiB binary_compressed body) replaced the checked one and PCL allocated gigabytes.
TEST_F(PcdHeaderTest, AHeaderAfterTheDataLineIsRefused) {
  const std::string second = header("2", "1", "2", "4 4 4", "1 1 1", "binary_compressed");
  expect_refused_naming(header() + "\n" + second, "follows the DATA line");
  expect_refused_naming(header() + "# a comment\n" + second, "follows the DATA line");
  EXPECT_EQ(refusal(header() + "1 2 3\n4 5 6\n"), "") << "numbers after DATA are data";
}

// Found by make fuzz: a header line of white space alone (spaces, a tab, the CR of a CRLF line) makes
// PCL 1.13's PCDReader::read dereference null. Refused; an empty line and comments still read.
TEST_F(PcdHeaderTest, AWhiteSpaceLineInTheHeaderIsRefusedAndEmptyLinesStillRead) {
  for (const std::string blank : {"  \n", "\t\n", "\r\n"}) {
    expect_refused_naming(blank + header() + "1 2 3\n4 5 6\n", "only white space");
    expect_refused_naming("# .PCD\n" + blank + header() + "1 2 3\n4 5 6\n", "only white space");
  }
  EXPECT_EQ(refusal("\n# comment\n" + header() + "1 2 3\n4 5 6\n"), "");
  pcl::PCLPointCloud2 blob;
  read_pcd_file(write("\n# comment\n" + header() + "1 2 3\n4 5 6\n"), blob);
  EXPECT_EQ(blob.width * blob.height, 2u);
}

TEST_F(PcdHeaderTest, DeclaredDataMustFitTheFile) {
  expect_refused_naming(header("640", "480", "307200", "4 4 4", "1 1 1", "binary") + std::string(100, '\0'),
                        "DATA binary declares");
  // 10^8 points in a file of a few bytes.
  expect_refused_naming(header("100000000", "1", "100000000") + "1 2 3\n", "DATA ascii declares");
  try {
    validate_pcd_file(write(header("4294967295", "1", "4294967295", "8 8 8", "1 1 1", "binary")));
    FAIL() << "2^32 points of 24 bytes must exceed the cap";
  } catch (const ResourceLimit& e) {
    EXPECT_NE(std::string(e.what()).find("POINTS"), std::string::npos) << e.what();
  }
}

// binary_compressed: [compressed size][uncompressed size][LZF data].
std::string compressed_body(std::uint32_t compressed, std::uint32_t uncompressed, const std::string& data) {
  std::string body(8, '\0');
  std::memcpy(&body[0], &compressed, 4);
  std::memcpy(&body[4], &uncompressed, 4);
  return body + data;
}

TEST_F(PcdHeaderTest, CompressedSizesMustAgreeWithTheHeaderAndTheFile) {
  const std::string h = header("2", "1", "2", "4 4 4", "1 1 1", "binary_compressed");
  expect_refused_naming(h + "\x01", "no size fields");
  expect_refused_naming(h + compressed_body(1000, 24, "xx"), "compressed size 1000");
  // 0xFFFFFFFF made PCL allocate 8.4 GB.
  expect_refused_naming(h + compressed_body(2, 0xFFFFFFFFu, "xx"), "uncompressed size 4294967295");
  // The right sizes, but data that does not expand to 24 bytes.
  expect_refused_naming(h + compressed_body(2, 24, "\x01x"), "does not expand");
  const std::string bomb = header("65536", "2048", "134217728", "4 4 4", "1 1 1", "binary_compressed");
  expect_refused_naming(bomb + compressed_body(4, 134217728u * 12u, "xxxx"), "times the compressed size");
}

}  // namespace
}  // namespace occ_improve
