// rostest of the EventSimulator nodelet with a scenario file and ~loop (event_simulator_loop.test):
// the scenario's span (0.3 s) is driven forth and back with the time running on: event stamps and
// /clock never go back, the ground truth is continuous and retraces the path backwards in odd
// passes. A scenario with an unknown key stops the nodelet with a message naming the key.
#include <ebslam_msgs/EventArray.h>
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <rosgraph_msgs/Log.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace {

double distance(const geometry_msgs::PoseStamped& a, const geometry_msgs::PoseStamped& b) {
  return std::hypot(a.pose.position.x - b.pose.position.x, a.pose.position.y - b.pose.position.y);
}

TEST(EventSimulatorLoop, DrivesTheScenarioForthAndBackWithTimeRunningOn) {
  ros::NodeHandle nh;
  std::vector<ebslam_msgs::EventArray> arrays;
  std::vector<geometry_msgs::PoseStamped> poses;
  std::vector<ros::Time> clock;
  auto clock_sub = nh.subscribe<rosgraph_msgs::Clock>(
      "/clock", 1000, [&](const rosgraph_msgs::Clock::ConstPtr& m) { clock.push_back(m->clock); });
  auto pose_sub = nh.subscribe<geometry_msgs::PoseStamped>(
      "ground_truth/pose", 1000,
      [&](const geometry_msgs::PoseStamped::ConstPtr& m) { poses.push_back(*m); });
  auto events_sub = nh.subscribe<ebslam_msgs::EventArray>(
      "events", 1000, [&](const ebslam_msgs::EventArray::ConstPtr& m) { arrays.push_back(*m); });
  // Three and a half passes: 1.05 s simulated from 500 s.
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(40.0);
  while (ros::WallTime::now() < end &&
         (poses.empty() || poses.back().header.stamp < ros::Time(501.05))) {
    ros::spinOnce();
    ros::WallDuration(0.01).sleep();
  }
  ASSERT_FALSE(poses.empty());
  ASSERT_GE(poses.back().header.stamp, ros::Time(501.05)) << "the simulation stopped";

  ros::Time previous(0);
  std::size_t events = 0;
  for (const auto& a : arrays) {
    ASSERT_FALSE(a.events.empty());
    EXPECT_EQ(a.header.stamp, a.events.back().ts);
    for (const auto& e : a.events) {
      ASSERT_GE(e.ts, previous) << "event time went back";
      previous = e.ts;
    }
    events += a.events.size();
  }
  EXPECT_GT(events, 1000u);
  for (std::size_t i = 1; i < clock.size(); ++i) ASSERT_GE(clock[i], clock[i - 1]);
  // Ground truth every 10 ms: continuous (the pioneer moves < 1 m/s: < 1 cm per step), and the
  // pose at 500.3 + d s (pass 1, backwards) is the pose at 500.3 - d s (pass 0).
  std::map<long, geometry_msgs::PoseStamped> by_ms;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (i > 0) {
      EXPECT_LT(distance(poses[i], poses[i - 1]), 0.02) << "jump at " << poses[i].header.stamp;
    }
    by_ms[std::lround((poses[i].header.stamp.toSec() - 500.0) * 1000.0)] = poses[i];
  }
  int mirrored = 0;
  for (long d = 50; d <= 250; d += 50) {
    const auto forth = by_ms.find(300 - d), back = by_ms.find(300 + d);
    if (forth == by_ms.end() || back == by_ms.end()) continue;
    EXPECT_LT(distance(forth->second, back->second), 1e-6) << "d = " << d << " ms";
    ++mirrored;
  }
  EXPECT_GE(mirrored, 4);
  // The robot moved in the span (so the mirror test means something).
  ASSERT_TRUE(by_ms.count(10) && by_ms.count(300));
  EXPECT_GT(distance(by_ms[10], by_ms[300]), 0.02);
}

TEST(EventSimulatorLoop, ScenarioWithAnUnknownKeyIsRefusedNamingIt) {
  ros::NodeHandle nh;
  std::vector<std::string> errors;
  auto log_sub =
      nh.subscribe<rosgraph_msgs::Log>("/rosout", 1000, [&](const rosgraph_msgs::Log::ConstPtr& m) {
        if (m->level >= rosgraph_msgs::Log::ERROR) errors.push_back(m->msg);
      });
  ros::WallDuration(0.5).sleep();  // the subscription connects
  ros::NodeHandle("/bad_simulator").setParam("scenario", std::string(BAD_SCENARIO));
  nodelet::Loader loader(false);
  // Refused: a simulator that cannot start does not load (ros_param_helpers.h).
  EXPECT_FALSE(loader.load("/bad_simulator", "ebslam_ros/EventSimulator",
                           {{"events", "/bad_simulator/events"}}, {}));
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(10.0);
  bool named = false;
  while (!named && ros::WallTime::now() < end) {
    ros::spinOnce();
    for (const std::string& e : errors) {
      if (e.find("colour_of_the_ceiling") != std::string::npos) named = true;
    }
    ros::WallDuration(0.01).sleep();
  }
  EXPECT_TRUE(named) << "the bad scenario's unknown key was not reported";
  loader.clear();
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "event_simulator_loop_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
