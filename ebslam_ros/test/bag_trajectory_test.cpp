#include "ebslam_ros/bag_trajectory.h"

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <std_msgs/String.h>
#include <unistd.h>

#include <string>

namespace {

TEST(BagTrajectory, ReadsPoseTopicsByStampAndDropsRepeats) {
  const std::string path = ::testing::TempDir() + "poses_" + std::to_string(::getpid()) + ".bag";
  {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    for (int i = 0; i < 5; ++i) {
      geometry_msgs::PoseWithCovarianceStamped p;
      p.header.stamp = ros::Time(100 + (i == 3 ? 1 : i));  // the fourth repeats an earlier stamp
      p.header.frame_id = "map";
      p.pose.pose.position.x = i;
      p.pose.pose.orientation.z = 1.0;
      bag.write("/slam/pose", ros::Time(1 + i), p);
      geometry_msgs::PoseStamped g;
      g.header.stamp = ros::Time(100 + i);
      g.header.frame_id = "map";
      g.pose.orientation.w = 1.0;
      bag.write("/ground_truth/pose", ros::Time(1 + i), g);
    }
    std_msgs::String s;
    bag.write("/text", ros::Time(1), s);
  }
  const ebslam_ros::BagTrajectory slam = ebslam_ros::readBagTrajectory(path, "/slam/pose");
  EXPECT_EQ(slam.messages, 5u);
  EXPECT_EQ(slam.dropped, 1u);
  ASSERT_EQ(slam.trajectory.size(), 4u);
  EXPECT_EQ(slam.frame_id, "map");
  EXPECT_DOUBLE_EQ(slam.trajectory[3].t_s, 104.0);
  EXPECT_DOUBLE_EQ(slam.trajectory[3].position.x(), 4.0);
  EXPECT_NEAR(std::abs(slam.trajectory[0].orientation.z()), 1.0, 1e-12);
  EXPECT_EQ(ebslam_ros::readBagTrajectory(path, "/ground_truth/pose").trajectory.size(), 5u);
  EXPECT_THROW(ebslam_ros::readBagTrajectory(path, "/nothing"), std::runtime_error);
  EXPECT_THROW(ebslam_ros::readBagTrajectory(path, "/text"), std::runtime_error);
  EXPECT_THROW(ebslam_ros::readBagTrajectory(path + ".missing", "/slam/pose"), std::runtime_error);
}

}  // namespace
