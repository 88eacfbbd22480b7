// save_pcd_binary writes PCL's own binary PCD bytes through write_file_atomically.
#include "occ_improve/errors.hpp"
#include "occ_improve/pcl/map_cloud.hpp"
#include "occ_improve/pcl/pcd_writer.hpp"
#include "support/temp_folder.hpp"

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <fstream>
#include <iterator>

namespace occ_improve {
namespace {

class PcdWriter : public test::TempFolderTest {
protected:
  std::string bytes(const std::string& name) const {
    std::ifstream in(file(name), std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
};

TEST_F(PcdWriter, WritesTheBytesOfPclsBinaryWriter) {
  pcl::PointCloud<pcl::PointXYZRGBL> cloud(7, 3);  // padding after xyz and after the label
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    cloud[i].x = 0.5f * static_cast<float>(i);
    cloud[i].y = -1.0f;
    cloud[i].z = 2.0f + static_cast<float>(i);
    cloud[i].r = static_cast<std::uint8_t>(10 * i);
    cloud[i].label = static_cast<std::uint32_t>(i % 4);
  }
  save_pcd_binary(file("ours.pcd"), cloud);
  ASSERT_EQ(pcl::io::savePCDFileBinary(file("pcl.pcd"), cloud), 0);
  EXPECT_EQ(bytes("ours.pcd"), bytes("pcl.pcd"));
  pcl::PointCloud<pcl::PointXYZRGBL> back;
  ASSERT_EQ(pcl::io::loadPCDFile(file("ours.pcd"), back), 0);
  ASSERT_EQ(back.width, 7u);
  ASSERT_EQ(back.height, 3u);
  EXPECT_EQ(back[5].z, 7.0f);
  EXPECT_EQ(back[5].label, 1u);
  EXPECT_EQ(back[5].r, 50);
}

TEST_F(PcdWriter, AFolderInTheWayIsAnIoErrorNamingThePath) {
  std::filesystem::create_directory(file("taken.pcd"));
  pcl::PointCloud<pcl::PointXYZ> cloud(2, 1);
  try {
    save_pcd_binary(file("taken.pcd"), cloud);
    FAIL() << "wrote over a folder";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("taken.pcd"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace occ_improve
