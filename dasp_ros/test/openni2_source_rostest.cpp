// rostest of dasp_ros/OpenNi2Source with no device connected: a clear error on /rosout and in
// /diagnostics, retries with doubling waits up to ~retry_max, the nodelet keeps running with its
// topics advertised.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <nodelet/NodeletLoad.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>

#include <algorithm>
#include <chrono>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace {

TEST(OpenNi2Source, WithoutADeviceItReportsRetriesWithBackoffAndKeepsRunning) {
  std::mutex mutex;
  std::vector<std::string> errors;
  std::vector<diagnostic_msgs::DiagnosticStatus> statuses;
  ros::NodeHandle nh;
  ros::Subscriber log =
      nh.subscribe<rosgraph_msgs::Log>("/rosout", 1000, [&](const rosgraph_msgs::LogConstPtr& m) {
        if (m->msg.find("OpenNI2 device") == std::string::npos) return;
        std::lock_guard<std::mutex> lock(mutex);
        errors.push_back(m->msg);
        EXPECT_EQ(m->level, rosgraph_msgs::Log::ERROR);
      });
  ros::Subscriber diagnostics = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 100, [&](const diagnostic_msgs::DiagnosticArrayConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        for (const auto& s : m->status) statuses.push_back(s);
      });
  ros::AsyncSpinner spinner(1);
  spinner.start();
  // Load the source once connected to the manager's /rosout (and this node's), so that no
  // message of the first retries is missed.
  const auto connected = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (log.getNumPublishers() < 2 && std::chrono::steady_clock::now() < connected) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_GE(log.getNumPublishers(), 2u) << "not connected to the manager's /rosout";
  ASSERT_TRUE(ros::service::waitForService("/camera/manager/load_nodelet", ros::Duration(30.0)));
  nodelet::NodeletLoad load;
  load.request.name = "/camera/openni2";
  load.request.type = "dasp_ros/OpenNi2Source";
  ASSERT_TRUE(ros::service::call("/camera/manager/load_nodelet", load));
  EXPECT_TRUE(load.response.success);
  auto has = [&](const std::string& text) {
    std::lock_guard<std::mutex> lock(mutex);
    return std::any_of(errors.begin(), errors.end(),
                       [&](const std::string& e) { return e.find(text) != std::string::npos; });
  };
  auto count = [&](const std::string& text) {
    std::lock_guard<std::mutex> lock(mutex);
    return std::count_if(errors.begin(), errors.end(),
                         [&](const std::string& e) { return e.find(text) != std::string::npos; });
  };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (std::chrono::steady_clock::now() < deadline && count("retrying in 0.8 s") < 3) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  // Backoff 0.2, 0.4, 0.8, then capped at ~retry_max = 0.8 s.
  EXPECT_TRUE(has("retrying in 0.4 s"));
  EXPECT_GE(count("retrying in 0.8 s"), 3);
  EXPECT_TRUE(has("no devices found")) << (errors.empty() ? "" : errors.front());
  EXPECT_EQ(count("retrying in 1.6 s"), 0);

  // Still alive: topics advertised, diagnostics say why there are no frames.
  ros::master::V_TopicInfo topics;
  ASSERT_TRUE(ros::master::getTopics(topics));
  std::vector<std::string> names;
  for (const auto& t : topics) names.push_back(t.name);
  for (const char* name : {"/camera/rgb/image_rect_color", "/camera/depth_registered/image_raw",
                           "/camera/rgb/camera_info", "/camera/depth_registered/camera_info"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), name), names.end()) << name;
  }
  const auto diag_deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  bool error_status = false;
  while (!error_status && std::chrono::steady_clock::now() < diag_deadline) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      for (const auto& s : statuses) {
        error_status = error_status || (s.level == diagnostic_msgs::DiagnosticStatus::ERROR &&
                                        s.message.find("no device") != std::string::npos);
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_TRUE(error_status);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "openni2_source_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
