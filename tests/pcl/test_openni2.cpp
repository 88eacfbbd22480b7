// The OpenNI2 source without hardware: the failure must be a clear occ_improve error, not a PCL
// exception or a crash.
#include "occ_improve/errors.hpp"
#include "occ_improve/pcl/sequence_sources.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace occ_improve {
namespace {

TEST(OpenNI2, NoDeviceIsAClearError) {
  std::shared_ptr<pcl::Grabber> grabber;
  try {
    grabber = open_openni2_grabber("");
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("no OpenNI2 device"), std::string::npos) << e.what();
    return;
  }
  GTEST_SKIP() << "an OpenNI2 device is connected (" << grabber->getName() << "): the no-device path is not testable here";
}

TEST(OpenNI2, MissingRecordingNamesTheFile) {
  try {
    open_openni2_grabber("/nonexistent/recording.oni");
    FAIL() << "expected IoError";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/recording.oni"), std::string::npos) << e.what();
  }
}

TEST(OpenNI2, CorruptRecordingIsAOneLineIoError) {
  const std::string path = (std::filesystem::temp_directory_path() / "occ_improve_corrupt_test.oni").string();
  std::ofstream(path) << "not an OpenNI recording\n";
  try {
    open_openni2_grabber(path);
    FAIL() << "expected IoError";
  } catch (const IoError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(path), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  std::filesystem::remove(path);
}

TEST(OpenNI2, UnknownDeviceUriIsAnIoError) {
  try {
    open_openni2_grabber("no-such-device-uri");
    GTEST_SKIP() << "an OpenNI2 device accepted the URI";
  } catch (const IoError& e) {
    EXPECT_FALSE(std::string(e.what()).empty());
  }
}

}  // namespace
}  // namespace occ_improve
