#include "dasp/rgbd_io.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <string>

namespace {

namespace fs = std::filesystem;

class RgbdFolderTest : public testing::Test {
 protected:
  void SetUp() override {
    folder_ =
        fs::temp_directory_path() /
        ("dasp_rgbd_io_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(folder_);
  }
  void TearDown() override { fs::remove_all(folder_); }

  void writeFrame(const std::string& name, cv::Size color_size, cv::Size depth_size, bool label) {
    cv::imwrite((folder_ / (name + "_rgb.png")).string(),
                cv::Mat(color_size, CV_8UC3, cv::Scalar(1, 2, 3)));
    cv::imwrite((folder_ / (name + "_depth_mm.png")).string(),
                cv::Mat(depth_size, CV_16UC1, cv::Scalar(1234)));
    if (label) {
      cv::imwrite((folder_ / (name + "_label_object.png")).string(),
                  cv::Mat(color_size, CV_16UC1, cv::Scalar(7)));
    }
  }

  fs::path folder_;
};

TEST_F(RgbdFolderTest, ListsFramesInNaturalOrderAndLoadsThem) {
  writeFrame("learn10", {8, 6}, {8, 6}, true);
  writeFrame("learn2", {8, 6}, {8, 6}, false);
  cv::imwrite((folder_ / "learn3_rgb.png").string(), cv::Mat(6, 8, CV_8UC3));  // no depth: left out
  const auto frames = dasp::listRgbdFolder(folder_.string());
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].name, "learn2");
  EXPECT_EQ(frames[1].name, "learn10");
  EXPECT_TRUE(frames[0].label.empty());
  EXPECT_FALSE(dasp::loadLabelImage(frames[0]).has_value());

  const dasp::RgbdFrame frame = dasp::loadRgbdFrame(frames[1], {500, 501, 3.5f, 2.5f});
  EXPECT_EQ(frame.color.type(), CV_8UC3);
  EXPECT_EQ(frame.depth.type(), CV_16UC1);
  EXPECT_EQ(frame.depth.at<uint16_t>(5, 7), 1234);
  EXPECT_EQ(frame.color.at<cv::Vec3b>(0, 0), cv::Vec3b(1, 2, 3));
  EXPECT_EQ(frame.intrinsics.fy, 501.0f);
  const auto labels = dasp::loadLabelImage(frames[1]);
  ASSERT_TRUE(labels.has_value());
  EXPECT_EQ(labels->type(), CV_32SC1);
  EXPECT_EQ(labels->at<int>(3, 3), 7);
}

TEST_F(RgbdFolderTest, BadFramesGiveClearErrors) {
  EXPECT_THROW(dasp::listRgbdFolder((folder_ / "missing").string()), std::invalid_argument);
  writeFrame("a1", {8, 6}, {4, 3}, false);
  const auto frames = dasp::listRgbdFolder(folder_.string());
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_THROW(dasp::loadRgbdFrame(frames[0]), std::invalid_argument);  // sizes differ

  cv::imwrite((folder_ / "a1_depth_mm.png").string(), cv::Mat(6, 8, CV_8UC1, cv::Scalar(9)));
  EXPECT_THROW(dasp::loadRgbdFrame(frames[0]), std::invalid_argument);  // 8-bit depth

  fs::remove(folder_ / "a1_depth_mm.png");
  EXPECT_THROW(dasp::loadRgbdFrame(frames[0]), std::runtime_error);  // file vanished
  {
    std::FILE* f = std::fopen((folder_ / "a1_depth_mm.png").c_str(), "wb");
    std::fputs("\x89PNG truncated", f);
    std::fclose(f);
  }
  EXPECT_THROW(dasp::loadRgbdFrame(frames[0]), std::runtime_error);  // corrupt file
}

}  // namespace
