#pragma once
// Helpers shared by ebslam_ros's rostests.

#include <ebslam_msgs/EventArray.h>
#include <geometry_msgs/Pose.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>

#include <Eigen/Geometry>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ebslam_ros_test {

/// A pose message as an isometry (quaternion normalised).
inline Eigen::Isometry3d toIsometry(const geometry_msgs::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() =
      Eigen::Quaterniond(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z)
          .normalized()
          .toRotationMatrix();
  t.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return t;
}

/// Spins (5 ms steps) until `done()` or `seconds` of wall time have passed; returns done().
template <typename Predicate>
bool spinUntil(Predicate done, double seconds) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (!done() && ros::WallTime::now() < end) {
    ros::spinOnce();
    ros::WallDuration(0.005).sleep();
  }
  return done();
}

/// Checks the arrays in the driver's conventions: `frame`, a width x height sensor, each array
/// stamped with its last event, event times non-decreasing within [begin, end]. Adds their
/// event count to `*events`. Call inside ASSERT_NO_FATAL_FAILURE.
inline void checkEventArrays(const std::vector<ebslam_msgs::EventArray>& arrays,
                             const std::string& frame, std::uint32_t width, std::uint32_t height,
                             const ros::Time& begin, const ros::Time& end, std::size_t* events) {
  ros::Time previous(0);
  for (const auto& a : arrays) {
    EXPECT_EQ(a.header.frame_id, frame);
    EXPECT_EQ(a.width, width);
    EXPECT_EQ(a.height, height);
    ASSERT_FALSE(a.events.empty());
    EXPECT_EQ(a.header.stamp, a.events.back().ts);
    for (const auto& e : a.events) {
      EXPECT_LT(static_cast<std::uint32_t>(e.x), width);
      EXPECT_LT(static_cast<std::uint32_t>(e.y), height);
      EXPECT_GE(e.ts, previous);
      EXPECT_GE(e.ts, begin);
      EXPECT_LE(e.ts, end);
      previous = e.ts;
    }
    *events += a.events.size();
  }
}

/// Checks the REP 105 chain at `stamp`: sensor_frame -> base_link -> odom -> map, map a root.
/// Call inside ASSERT_NO_FATAL_FAILURE.
inline void checkRep105Chain(const tf2_ros::Buffer& buffer, const std::string& sensor_frame,
                             const ros::Time& stamp) {
  std::string parent;
  ASSERT_TRUE(buffer._getParent(sensor_frame, stamp, parent));
  EXPECT_EQ(parent, "base_link");
  ASSERT_TRUE(buffer._getParent("base_link", stamp, parent));
  EXPECT_EQ(parent, "odom");
  ASSERT_TRUE(buffer._getParent("odom", stamp, parent));
  EXPECT_EQ(parent, "map");
  EXPECT_FALSE(buffer._getParent("map", stamp, parent));
}

}  // namespace ebslam_ros_test
