#pragma once
// Helpers shared by ebslam_ros's rostests.

#include <ebslam_msgs/EventArray.h>
#include <geometry_msgs/Pose.h>
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>

#include <Eigen/Geometry>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <map>
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

/// base_link -> edvs_optical_frame of config/ebslam3d.yaml: mount_xyz 0, mount_rpy
/// [-pi/2, 0, -pi/2] (optical z along base_link's x).
inline Eigen::Isometry3d ebslam3dMount() {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = (Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
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

/// Distance [m] of two poses in the x-y plane.
inline double planarDistance(const geometry_msgs::PoseStamped& a,
                             const geometry_msgs::PoseStamped& b) {
  return std::hypot(a.pose.position.x - b.pose.position.x, a.pose.position.y - b.pose.position.y);
}

/// Checks that event times never go back across `arrays` (a looping simulator's time runs on) and
/// sets `*events` to their number. Call inside ASSERT_NO_FATAL_FAILURE.
inline void checkEventTimesRunOn(const std::vector<ebslam_msgs::EventArray>& arrays,
                                 std::size_t* events) {
  ros::Time previous(0);
  *events = 0;
  for (const auto& a : arrays) {
    for (const auto& e : a.events) {
      ASSERT_GE(e.ts, previous) << "event time went back";
      previous = e.ts;
    }
    *events += a.events.size();
  }
}

/// The ground truth of a simulator driving a span of `span_ms` forth and back (~loop) from
/// `start` (pass 0 forwards, pass 1 backwards, poses every 10 ms): continuous (consecutive poses
/// closer than 2 cm), the pose at span + d (pass 1) equal to the pose at span - d (pass 0) for
/// d = 50 ms, 100 ms, ... (at least 4 such pairs), and the path between 10 ms and the span's
/// end longer than `min_motion_m` [m] (so that the mirror means something).
inline void checkForthAndBack(const std::vector<geometry_msgs::PoseStamped>& poses,
                              const ros::Time& start, long span_ms, double min_motion_m) {
  std::map<long, geometry_msgs::PoseStamped> by_ms;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (i > 0) {
      EXPECT_LT(planarDistance(poses[i], poses[i - 1]), 0.02)
          << "jump at " << poses[i].header.stamp;
    }
    by_ms[std::lround((poses[i].header.stamp - start).toSec() * 1000.0)] = poses[i];
  }
  int mirrored = 0;
  for (long d = 50; d < span_ms; d += 50) {
    const auto forth = by_ms.find(span_ms - d), back = by_ms.find(span_ms + d);
    if (forth == by_ms.end() || back == by_ms.end()) continue;
    EXPECT_LT(planarDistance(forth->second, back->second), 1e-6) << "d = " << d << " ms";
    ++mirrored;
  }
  EXPECT_GE(mirrored, 4);
  ASSERT_TRUE(by_ms.count(10) && by_ms.count(span_ms));
  EXPECT_GT(planarDistance(by_ms[10], by_ms[span_ms]), min_motion_m);
}

}  // namespace ebslam_ros_test
