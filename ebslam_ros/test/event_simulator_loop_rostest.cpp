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

#include <string>
#include <vector>

#include "rostest_util.h"

namespace {

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
  ebslam_ros_test::spinUntil(
      [&] { return !poses.empty() && poses.back().header.stamp >= ros::Time(501.05); }, 40.0);
  ASSERT_FALSE(poses.empty());
  ASSERT_GE(poses.back().header.stamp, ros::Time(501.05)) << "the simulation stopped";

  for (const auto& a : arrays) {
    ASSERT_FALSE(a.events.empty());
    EXPECT_EQ(a.header.stamp, a.events.back().ts);
  }
  std::size_t events = 0;
  ASSERT_NO_FATAL_FAILURE(ebslam_ros_test::checkEventTimesRunOn(arrays, &events));
  EXPECT_GT(events, 1000u);
  for (std::size_t i = 1; i < clock.size(); ++i) ASSERT_GE(clock[i], clock[i - 1]);
  // Ground truth every 10 ms over passes of 0.3 s (the pioneer moves < 1 m/s: < 1 cm per step);
  // the robot moves more than 2 cm in the span.
  ASSERT_NO_FATAL_FAILURE(ebslam_ros_test::checkForthAndBack(poses, ros::Time(500.0), 300, 0.02));
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
