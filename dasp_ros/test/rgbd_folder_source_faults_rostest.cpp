// The RGB-D folder source on faulty input: a source that cannot start stops with a FATAL reason
// naming it; frames of half the calibration size get scaled intrinsics; each skipped frame is
// named once, however often a loop skips it.
#include <gtest/gtest.h>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <string>
#include <vector>

namespace {

// Everything logged to /rosout by any node of this test (the manager and this process).
class RosoutLog {
 public:
  RosoutLog() {
    sub_ = nh_.subscribe<rosgraph_msgs::Log>(
        "/rosout", 1000, [this](const rosgraph_msgs::LogConstPtr& m) { messages_.push_back(*m); });
  }
  // Messages of at least `level` whose text contains `text`.
  int count(std::uint8_t level, const std::string& text) const {
    int n = 0;
    for (const auto& m : messages_) n += m.level == level && m.msg.find(text) != std::string::npos;
    return n;
  }
  std::size_t publishers() const { return sub_.getNumPublishers(); }

 private:
  ros::NodeHandle nh_;
  ros::Subscriber sub_;
  std::vector<rosgraph_msgs::Log> messages_;
};

void spinFor(double seconds) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::WallTime::now() < end) {
    ros::spinOnce();
    ros::WallDuration(0.005).sleep();
  }
}

// Spins until done() or `seconds` of wall time; returns done().
template <typename Predicate>
bool spinUntil(Predicate done, double seconds) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (!done() && ros::WallTime::now() < end) spinFor(0.01);
  return done();
}

TEST(RgbdFolderSourceFaults, ScalesIntrinsicsAndNamesEachSkippedFrameOnce) {
  RosoutLog log;
  // The manager's log must be connected before the source starts (it waits for rgb/image).
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(10.0);
  while (log.publishers() < 2 && ros::WallTime::now() < deadline) spinFor(0.05);
  spinFor(0.5);

  ros::NodeHandle nh;
  std::vector<sensor_msgs::Image> images;
  std::vector<sensor_msgs::CameraInfo> infos;
  auto image_sub = nh.subscribe<sensor_msgs::Image>(
      "faults/rgb/image", 100, [&](const sensor_msgs::ImageConstPtr& m) { images.push_back(*m); });
  auto info_sub = nh.subscribe<sensor_msgs::CameraInfo>(
      "faults/rgb/camera_info", 100,
      [&](const sensor_msgs::CameraInfoConstPtr& m) { infos.push_back(*m); });
  // 20 Hz over three frames: at least three cycles, each skipping the two bad frames again,
  // and the reports of the first (generous timeout: a loaded machine is slow, not wrong).
  EXPECT_TRUE(spinUntil(
      [&] {
        return images.size() >= 3 && infos.size() >= 3 &&
               log.count(rosgraph_msgs::Log::WARN, "320x240 pixels") >= 1 &&
               log.count(rosgraph_msgs::Log::ERROR, "skipping frame truncated2") >= 1 &&
               log.count(rosgraph_msgs::Log::ERROR, "skipping frame wide3") >= 1;
      },
      60.0));
  spinFor(0.2);  // messages of the cycle in transit

  ASSERT_GE(images.size(), 3u) << "the 320x240 frame is published on every cycle";
  ASSERT_GE(infos.size(), 3u);
  for (const auto& image : images) {
    EXPECT_EQ(image.width, 320u) << "the 400x240 frame (another aspect ratio) is refused";
    EXPECT_EQ(image.height, 240u);
  }
  for (const auto& info : infos) {
    EXPECT_EQ(info.header.frame_id, "test_optical_frame");
    EXPECT_EQ(info.width, 320u);
    // 640x480 defaults (525, 525, 319.5, 239.5) scaled by 1/2 about the pixel centres.
    EXPECT_DOUBLE_EQ(info.K[0], 262.5);
    EXPECT_DOUBLE_EQ(info.K[4], 262.5);
    EXPECT_DOUBLE_EQ(info.K[2], 159.5);
    EXPECT_DOUBLE_EQ(info.K[5], 119.5);
  }
  EXPECT_EQ(log.count(rosgraph_msgs::Log::WARN, "320x240 pixels"), 1) << "scaling is reported";
  EXPECT_EQ(log.count(rosgraph_msgs::Log::ERROR, "skipping frame truncated2"), 1);
  EXPECT_EQ(log.count(rosgraph_msgs::Log::ERROR, "skipping frame wide3"), 1);
}

// Loads the source in this process with the given private parameters; returns load()'s result.
bool loadSource(const std::string& name, const std::string& folder) {
  ros::NodeHandle private_nh(name);
  if (!folder.empty()) private_nh.setParam("folder", folder);
  static nodelet::Loader loader(false);
  return loader.load(name, "dasp_ros/RgbdFolderSource", {}, {});
}

TEST(RgbdFolderSourceFaults, StopsWithAFatalReasonWhenItCannotStart) {
  RosoutLog log;
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(10.0);
  while (log.publishers() < 1 && ros::WallTime::now() < deadline) spinFor(0.05);
  spinFor(0.3);
  EXPECT_FALSE(loadSource("/source_without_folder", ""));
  EXPECT_FALSE(loadSource("/source_of_missing_folder", "/nonexistent/rgbd/folder"));
  EXPECT_FALSE(loadSource("/source_of_empty_folder", "/"));
  EXPECT_TRUE(spinUntil(
      [&] {
        return log.count(rosgraph_msgs::Log::FATAL, "/source_without_folder/folder is not set") >=
                   1 &&
               log.count(rosgraph_msgs::Log::FATAL, "/nonexistent/rgbd/folder") >= 1 &&
               log.count(rosgraph_msgs::Log::FATAL, "no <name>_rgb.png") >= 1;
      },
      30.0));
  EXPECT_EQ(log.count(rosgraph_msgs::Log::FATAL, "/source_without_folder/folder is not set"), 1);
  EXPECT_EQ(log.count(rosgraph_msgs::Log::FATAL, "/nonexistent/rgbd/folder"), 1);
  EXPECT_EQ(log.count(rosgraph_msgs::Log::FATAL, "no <name>_rgb.png"), 1);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "rgbd_folder_source_faults_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
