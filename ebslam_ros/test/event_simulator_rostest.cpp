// rostest of the EventSimulator nodelet (event_simulator.test): events in the driver's
// conventions, ground truth in map, stamps on the /clock the simulator publishes.
#include <ebslam_msgs/EventArray.h>
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <tf2_ros/transform_listener.h>

#include <vector>

#include "rostest_util.h"

namespace {

TEST(EventSimulator, PublishesEventsGroundTruthAndClock) {
  ros::NodeHandle nh;
  std::vector<ebslam_msgs::EventArray> arrays;
  std::vector<geometry_msgs::PoseStamped> poses;
  std::vector<ros::Time> clock;
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  auto clock_sub = nh.subscribe<rosgraph_msgs::Clock>(
      "/clock", 1000, [&](const rosgraph_msgs::Clock::ConstPtr& m) { clock.push_back(m->clock); });
  auto pose_sub = nh.subscribe<geometry_msgs::PoseStamped>(
      "ground_truth/pose", 1000,
      [&](const geometry_msgs::PoseStamped::ConstPtr& m) { poses.push_back(*m); });
  auto events_sub = nh.subscribe<ebslam_msgs::EventArray>(
      "events", 1000, [&](const ebslam_msgs::EventArray::ConstPtr& m) { arrays.push_back(*m); });
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(40.0);
  // 1 s simulated in 100 messages; the last ground-truth pose is at 501 s.
  while (ros::WallTime::now() < end &&
         (poses.empty() || poses.back().header.stamp < ros::Time(500.999))) {
    ros::spinOnce();
    ros::WallDuration(0.01).sleep();
  }
  ros::WallDuration(0.2).sleep();
  ros::spinOnce();
  ASSERT_GT(arrays.size(), 50u);
  std::size_t events = 0;
  ASSERT_NO_FATAL_FAILURE(ebslam_ros_test::checkEventArrays(
      arrays, "edvs_optical_frame", 128, 128, ros::Time(500.0), ros::Time(501.0), &events));
  EXPECT_GT(events, 1000u);  // the robot moves: edges cross pixels
  ASSERT_GT(poses.size(), 50u);
  EXPECT_EQ(poses.back().header.frame_id, "map");
  EXPECT_NEAR(poses.back().header.stamp.toSec(), 501.0, 1e-6);
  EXPECT_NEAR(poses.front().pose.position.x, 0.0, 5.0);
  ASSERT_FALSE(clock.empty());
  EXPECT_NEAR(clock.back().toSec(), 501.0, 1e-6);
  const auto gt = buffer.lookupTransform("map", "ground_truth", poses.back().header.stamp);
  EXPECT_NEAR(gt.transform.translation.x, poses.back().pose.position.x, 1e-9);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "event_simulator_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
