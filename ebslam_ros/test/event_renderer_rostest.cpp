// rostest of the EventRenderer nodelet (event_renderer.test): colours, window, frame, stamp and a
// background image; a wrong-size background is not drawn.
#include <ebslam_msgs/EventArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/Image.h>

#include <vector>

#include "rostest_util.h"

namespace {

ebslam_msgs::Event event(const ros::Time& t, int x, int y, bool on) {
  ebslam_msgs::Event e;
  e.ts = t;
  e.x = static_cast<std::uint16_t>(x);
  e.y = static_cast<std::uint16_t>(y);
  e.polarity = on;
  return e;
}

const std::uint8_t* pixel(const sensor_msgs::Image& image, int x, int y) {
  return &image.data[static_cast<std::size_t>(y) * image.step + 3 * x];
}

// The renderer's event input and image output, connected.
struct RendererIo {
  ros::NodeHandle nh;
  ros::Publisher events = nh.advertise<ebslam_msgs::EventArray>("events", 10);
  std::vector<sensor_msgs::Image> images;
  ros::Subscriber sub = nh.subscribe<sensor_msgs::Image>(
      "event_image", 10, [this](const sensor_msgs::Image::ConstPtr& m) { images.push_back(*m); });

  bool connect() {
    if (!ebslam_ros_test::spinUntil(
            [&] { return events.getNumSubscribers() > 0 && sub.getNumPublishers() > 0; }, 10.0)) {
      return false;
    }
    ros::WallDuration(0.3).sleep();  // the renderer's side of the connection
    return true;
  }
};

TEST(EventRenderer, DrawsTheWindowsEventsInTheirColours) {
  RendererIo io;
  ASSERT_TRUE(io.connect());
  ros::Publisher& events = io.events;
  std::vector<sensor_msgs::Image>& images = io.images;
  ros::Publisher background = io.nh.advertise<sensor_msgs::Image>("image", 1, true);
  ebslam_msgs::EventArray msg;
  msg.header.frame_id = "edvs_optical_frame";
  msg.width = 128;
  msg.height = 64;
  const ros::Time t0(100.0);
  msg.events = {event(t0, 1, 2, true), event(t0 + ros::Duration(0.1), 3, 4, true),
                event(t0 + ros::Duration(0.12), 5, 6, false)};
  msg.header.stamp = msg.events.back().ts;
  events.publish(msg);
  ASSERT_TRUE(ebslam_ros_test::spinUntil([&] { return !images.empty(); }, 5.0));
  const sensor_msgs::Image& image = images.back();
  EXPECT_EQ(image.encoding, "bgr8");
  EXPECT_EQ(image.width, 128u);
  EXPECT_EQ(image.height, 64u);
  EXPECT_EQ(image.header.frame_id, "edvs_optical_frame");
  EXPECT_EQ(image.header.stamp, msg.events.back().ts);
  EXPECT_EQ(pixel(image, 1, 2)[0], 0);    // older than the 0.05 s window: gone
  EXPECT_EQ(pixel(image, 3, 4)[0], 255);  // ON: blue (bgr)
  EXPECT_EQ(pixel(image, 5, 6)[2], 255);  // OFF: red
  EXPECT_EQ(pixel(image, 5, 6)[0], 0);

  // A grey background of the right size is drawn under the events; one of another size is not.
  sensor_msgs::Image grey;
  grey.width = 128;
  grey.height = 64;
  grey.encoding = "mono8";
  grey.step = 128;
  grey.data.assign(128 * 64, 77);
  background.publish(grey);
  ros::WallDuration(0.3).sleep();
  images.clear();
  ASSERT_TRUE(ebslam_ros_test::spinUntil([&] { return !images.empty(); }, 5.0));
  EXPECT_EQ(pixel(images.back(), 10, 10)[1], 77);
  EXPECT_EQ(pixel(images.back(), 3, 4)[0], 255);
  grey.width = 20;
  grey.step = 20;
  grey.data.assign(20 * 64, 77);
  background.publish(grey);
  ros::WallDuration(0.3).sleep();
  images.clear();
  ASSERT_TRUE(ebslam_ros_test::spinUntil([&] { return !images.empty(); }, 5.0));
  EXPECT_EQ(pixel(images.back(), 10, 10)[1], 0);
}

// Events stamped within the window of time 0 (sim time before the first /clock): the window's
// start would be negative, which ros::Time cannot hold; the image is still drawn.
TEST(EventRenderer, EventsNearTimeZeroAreDrawn) {
  RendererIo io;
  ASSERT_TRUE(io.connect());
  ros::Publisher& events = io.events;
  std::vector<sensor_msgs::Image>& images = io.images;
  ebslam_msgs::EventArray msg;
  msg.header.frame_id = "edvs_optical_frame";
  msg.width = 128;
  msg.height = 64;
  const ros::Time early(0, 1000);  // 1 us
  msg.events = {event(early, 7, 8, true)};
  msg.header.stamp = early;
  events.publish(msg);
  const auto drawn = [&] {
    for (const auto& image : images) {
      if (image.header.stamp == early && pixel(image, 7, 8)[0] == 255) return true;
    }
    return false;
  };
  EXPECT_TRUE(ebslam_ros_test::spinUntil(drawn, 5.0)) << "no image of the events near time 0";
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "event_renderer_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
