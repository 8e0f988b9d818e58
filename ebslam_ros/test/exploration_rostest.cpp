// rostest of the Exploration nodelet (exploration.test): stands still without a pose (also with
// poses in a wrong frame), drives once a pose arrives, plans in `map` stamped with the pose's
// stamp, replans after a pose jump, backs out of a front bump, reports stuck when bumped on every
// side, stops when the pose stops, and sends the grid markers while subscribed. Waits are long
// and on events, not on tight wall-clock bounds (shared, loaded machines).
#include <diagnostic_msgs/DiagnosticArray.h>
#include <ebslam_msgs/Bump.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/Twist.h>
#include <gtest/gtest.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace {

class ExplorationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    pose_pub_ = nh_.advertise<geometry_msgs::PoseWithCovarianceStamped>("pose", 10);
    bump_pub_ = nh_.advertise<ebslam_msgs::Bump>("bump", 10);
    z_pub_ = nh_.advertise<nav_msgs::OccupancyGrid>("map/normalisation", 1, true);
    cmd_sub_ = nh_.subscribe<geometry_msgs::Twist>(
        "cmd_vel", 1000, [this](const geometry_msgs::Twist::ConstPtr& m) { cmds_.push_back(*m); });
    plan_sub_ = nh_.subscribe<nav_msgs::Path>(
        "plan", 100, [this](const nav_msgs::Path::ConstPtr& m) { plans_.push_back(*m); });
    diag_sub_ = nh_.subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 100, [this](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
          for (const auto& status : m->status) {
            if (status.name.find("explorer") == std::string::npos) continue;
            diag_.clear();
            for (const auto& kv : status.values) diag_[kv.key] = kv.value;
            diag_message_ = status.message;
          }
        });
    // Connections (the nodelet subscribes and publishes).
    waitFor([&] {
      return pose_pub_.getNumSubscribers() > 0 && bump_pub_.getNumSubscribers() > 0 &&
             z_pub_.getNumSubscribers() > 0 && cmd_sub_.getNumPublishers() > 0 &&
             plan_sub_.getNumPublishers() > 0;
    });
  }

  // Spins until done() or timeout (wall); each step first calls step() (publishing input).
  bool waitFor(const std::function<bool()>& done, double timeout_s = 30.0,
               const std::function<void()>& step = {}) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout_s);
    while (ros::WallTime::now() < end) {
      if (step) step();
      ros::spinOnce();
      if (done()) return true;
      ros::WallDuration(0.05).sleep();
    }
    return false;
  }

  void publishPose(double x, double y, double yaw, const std::string& frame = "map") {
    geometry_msgs::PoseWithCovarianceStamped p;
    p.header.stamp = ros::Time::now();
    p.header.frame_id = frame;
    p.pose.pose.position.x = x;
    p.pose.pose.position.y = y;
    p.pose.pose.orientation.z = std::sin(0.5 * yaw);
    p.pose.pose.orientation.w = std::cos(0.5 * yaw);
    pose_pub_.publish(p);
    if (frame == "map") sent_stamps_.insert(p.header.stamp);
  }

  void publishBump(std::uint32_t segments, double direction) {
    ebslam_msgs::Bump b;
    b.header.stamp = ros::Time::now();
    b.header.frame_id = "base_link";
    b.segment_count = 8;
    b.segments = segments;
    b.direction = direction;
    bump_pub_.publish(b);
  }

  static bool isZero(const geometry_msgs::Twist& t) {
    return t.linear.x == 0.0 && t.linear.y == 0.0 && t.linear.z == 0.0 && t.angular.x == 0.0 &&
           t.angular.y == 0.0 && t.angular.z == 0.0;
  }

  long diagCount(const std::string& key) const {
    const auto it = diag_.find(key);
    return it == diag_.end() ? -1 : std::stol(it->second);
  }

  ros::NodeHandle nh_;
  ros::Publisher pose_pub_, bump_pub_, z_pub_;
  ros::Subscriber cmd_sub_, plan_sub_, diag_sub_;
  std::vector<geometry_msgs::Twist> cmds_;
  std::vector<nav_msgs::Path> plans_;
  std::map<std::string, std::string> diag_;
  std::string diag_message_;
  std::set<ros::Time> sent_stamps_;
};

TEST_F(ExplorationTest, DrivesPlansAndHandlesBadInput) {
  // No pose yet, and poses in another frame: zero commands only.
  cmds_.clear();
  ASSERT_TRUE(waitFor([&] { return cmds_.size() >= 20 && diagCount("poses in a wrong frame") > 0; },
                      60.0, [&] { publishPose(0.0, 0.0, 0.0, "odom"); }));
  for (const auto& c : cmds_) ASSERT_TRUE(isZero(c));
  EXPECT_TRUE(plans_.empty());
  EXPECT_EQ(diag_["state"], "waiting");

  // A normalisation map Z (high on the +x side: the robot should not prefer it) before poses.
  nav_msgs::OccupancyGrid z;
  z.header.stamp = ros::Time::now();
  z.header.frame_id = "map";
  z.info.resolution = 0.1f;
  z.info.width = 40;
  z.info.height = 40;
  z.info.origin.position.x = -2.0;
  z.info.origin.position.y = -2.0;
  z.info.origin.orientation.w = 1.0;
  z.data.resize(40 * 40);
  for (int r = 0; r < 40; ++r) {
    for (int c = 0; c < 40; ++c) z.data[r * 40 + c] = static_cast<std::int8_t>(c < 20 ? 0 : 100);
  }
  z_pub_.publish(z);
  ASSERT_TRUE(waitFor([&] { return diagCount("normalisation maps") > 0; }, 30.0));

  // A standing pose: the explorer plans and commands motion.
  cmds_.clear();
  plans_.clear();
  ASSERT_TRUE(waitFor([&] { return !cmds_.empty() && !isZero(cmds_.back()) && !plans_.empty(); },
                      30.0, [&] { publishPose(0.0, 0.0, 0.0); }));
  const nav_msgs::Path plan = plans_.back();
  EXPECT_EQ(plan.header.frame_id, "map");
  EXPECT_EQ(sent_stamps_.count(plan.header.stamp), 1u) << "plan stamp is not a pose's stamp";
  ASSERT_GE(plan.poses.size(), 2u);
  EXPECT_NEAR(plan.poses.front().pose.position.x, 0.0, 1e-9);
  EXPECT_NEAR(plan.poses.front().pose.position.y, 0.0, 1e-9);
  for (const auto& p : plan.poses) {
    EXPECT_EQ(p.header.frame_id, "map");
    // Inside the 4 m grid centred on the first pose.
    EXPECT_LE(std::abs(p.pose.position.x), 2.1);
    EXPECT_LE(std::abs(p.pose.position.y), 2.1);
  }
  // Away from the high-Z side first: the gain favours little-observed cells.
  EXPECT_LT(plan.poses[1].pose.position.x, 0.05);
  EXPECT_LE(std::abs(cmds_.back().linear.x), 0.3 + 1e-9);
  EXPECT_LE(std::abs(cmds_.back().angular.z), 1.5 + 1e-9);

  // The pose jumps by a metre: the plan is made anew from there.
  plans_.clear();
  ASSERT_TRUE(waitFor(
      [&] {
        return !plans_.empty() &&
               std::abs(plans_.back().poses.at(0).pose.position.x - 1.0) < 1e-9 &&
               std::abs(plans_.back().poses.at(0).pose.position.y - 0.5) < 1e-9;
      },
      30.0, [&] { publishPose(1.0, 0.5, 0.0); }));
  ASSERT_TRUE(waitFor([&] { return diagCount("pose jumps") >= 1; }, 30.0,
                      [&] { publishPose(1.0, 0.5, 0.0); }));

  // A front bump: back out (negative speed, no turn) for ~backout_time.
  cmds_.clear();
  bool bumped = false;
  const auto backing = [&]() -> const geometry_msgs::Twist* {
    for (const auto& c : cmds_) {
      if (c.linear.x < 0.0) return &c;
    }
    return nullptr;
  };
  ASSERT_TRUE(waitFor([&] { return backing() != nullptr; }, 30.0,
                      [&] {
                        publishPose(1.0, 0.5, 0.0);
                        if (!bumped) publishBump(1u, 0.0);
                        bumped = true;
                      }));
  EXPECT_NEAR(backing()->linear.x, -0.1, 1e-9);
  EXPECT_EQ(backing()->angular.z, 0.0);

  // Bumped on every side (front and rear segments): stuck, zero commands.
  ASSERT_TRUE(waitFor([&] { return diag_["state"] == "stuck"; }, 30.0,
                      [&] {
                        publishPose(1.0, 0.5, 0.0);
                        publishBump(0x11u, 0.0);
                      }));
  EXPECT_NE(diag_["message"].find("every side"), std::string::npos) << diag_["message"];
  cmds_.clear();
  ASSERT_TRUE(waitFor([&] { return cmds_.size() >= 5; }, 30.0,
                      [&] {
                        publishPose(1.0, 0.5, 0.0);
                        publishBump(0x11u, 0.0);
                      }));
  for (const auto& c : cmds_) EXPECT_TRUE(isZero(c));
  // A malformed reading (bit beyond segment_count) is dropped and counted.
  ebslam_msgs::Bump bad;
  bad.header.frame_id = "base_link";
  bad.segment_count = 4;
  bad.segments = 0x100u;
  bump_pub_.publish(bad);
  ASSERT_TRUE(waitFor([&] { return diagCount("malformed bump readings") >= 1; }, 30.0,
                      [&] { publishPose(1.0, 0.5, 0.0); }));

  // Free again after the retry: motion resumes.
  ASSERT_TRUE(waitFor([&] { return !cmds_.empty() && !isZero(cmds_.back()); }, 30.0,
                      [&] { publishPose(1.0, 0.5, 0.0); }));

  // The grid markers, once subscribed: Z, E and gain layers in map.
  std::vector<visualization_msgs::MarkerArray> markers;
  ros::Subscriber markers_sub = nh_.subscribe<visualization_msgs::MarkerArray>(
      "grid_markers", 10,
      [&](const visualization_msgs::MarkerArray::ConstPtr& m) { markers.push_back(*m); });
  ASSERT_TRUE(waitFor([&] { return !markers.empty(); }, 30.0, [&] { publishPose(1.0, 0.5, 0.0); }));
  std::map<std::string, visualization_msgs::Marker> layers;
  for (const auto& m : markers.back().markers) layers[m.ns] = m;
  for (const char* ns : {"localisation_Z", "obstacle_E", "gain", "blocked", "bumps"}) {
    ASSERT_EQ(layers.count(ns), 1u) << ns;
    EXPECT_EQ(layers[ns].header.frame_id, "map");
    EXPECT_EQ(sent_stamps_.count(layers[ns].header.stamp), 1u) << ns;
  }
  EXPECT_EQ(layers["localisation_Z"].action, visualization_msgs::Marker::ADD);
  EXPECT_GT(layers["localisation_Z"].points.size(), 10u);
  EXPECT_EQ(layers["localisation_Z"].points.size(), layers["localisation_Z"].colors.size());
  EXPECT_GE(layers["obstacle_E"].points.size(), 2u);  // the start and the jump target
  EXPECT_GT(layers["gain"].points.size(), 10u);
  EXPECT_GT(layers["blocked"].points.size(), 0u);  // cells behind the bumps
  EXPECT_GE(layers["bumps"].points.size(), 1u);
  markers_sub.shutdown();

  // The pose stops: after the timeout only zero commands, and the node says why.
  ASSERT_TRUE(waitFor([&] { return diag_["state"] == "no pose"; }, 30.0))
      << diag_["state"] << ": " << diag_message_ << " (" << cmds_.size() << " commands)";
  cmds_.clear();
  ASSERT_TRUE(waitFor([&] { return cmds_.size() >= 10; }, 30.0));
  for (const auto& c : cmds_) EXPECT_TRUE(isZero(c));
  EXPECT_NE(diag_message_.find("no pose"), std::string::npos) << diag_message_;
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "exploration_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
