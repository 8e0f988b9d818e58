// rostest of the EventParticleFilter and EventSlam2d nodelets (event_particle_filter.test,
// event_slam2d.test, event_particle_filter_bad_map.test). The test publishes the events a
// static upward-looking eDVS sees under test/data/ceiling_lines.yaml (lines at known
// positions) and asserts the outputs' content, frame and stamp, the tf tree, the services, and
// that injected bad input is dropped with the node running on, and that the node's poses equal
// the core filter's (ebslam/slam/ebpf.h, ebslam2d.h) run in this process on the same messages.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <ebslam_msgs/EventArray.h>
#include <ebslam_msgs/ResetPose.h>
#include <ebslam_msgs/SaveMap.h>
#include <geometry_msgs/PoseArray.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Path.h>
#include <nodelet/NodeletList.h>
#include <nodelet/NodeletLoad.h>
#include <nodelet/NodeletUnload.h>
#include <ros/package.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2/utils.h>
#include <tf2_ros/transform_listener.h>
#include <unistd.h>
#include <opencv2/core.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <ebslam/events/event_rate_limiter.h>
#include <ebslam/slam/ceiling_camera.h>
#include <ebslam/slam/ebpf.h>
#include <ebslam/slam/ebslam2d.h>

#include "ebslam_msgs/event_conversions.h"
#include "ebslam_ros/ceiling_map_io.h"
#include "ebslam_ros/conversions.h"

#include "rostest_util.h"

namespace {

// The scene of test/data/ceiling_lines.yaml and the default camera (f = 2.59 / 0.03 px,
// c = 63.5 px, D = 2.59 m), mounted as in the .test files (mount_xyz = [0.1, 0, 0.3]).
const std::vector<double> kLinesX{-2.3, -1.5, -0.85, -0.2, 0.55, 1.3, 2.1};
const std::vector<double> kLinesY{-2.6, -1.7, -0.9, -0.35, 0.4, 1.15, 1.9, 2.5};
constexpr double kStartX = 0.1, kStartY = -0.2, kStartTheta = 0.3;  // base_link, from .test
constexpr double kMountX = 0.1;
constexpr std::int64_t kT0 = 1700000000000000;  // [us]

// Pixels that see a line when base_link is at (x, y, theta).
std::vector<std::pair<int, int>> edgePixels(double x, double y, double theta) {
  const double f = 2.59 / 0.03, w = 2.59 / f;
  const double c = std::cos(theta), s = std::sin(theta);
  const double sx = x + c * kMountX, sy = y + s * kMountX;
  std::vector<std::pair<int, int>> pixels;
  for (int v = 0; v < 128; ++v) {
    for (int u = 0; u < 128; ++u) {
      const double dx = (u - 63.5) * w, dy = (v - 63.5) * w;
      const double wx = sx + c * dx - s * dy, wy = sy + s * dx + c * dy;
      bool edge = false;
      for (double a : kLinesX) edge = edge || std::abs(wx - a) < 0.012;
      for (double b : kLinesY) edge = edge || std::abs(wy - b) < 0.012;
      if (edge) pixels.emplace_back(u, v);
    }
  }
  // A static sensor fires in no particular order; a raster order would look like motion.
  std::shuffle(pixels.begin(), pixels.end(), std::mt19937(1));
  return pixels;
}

// Event time shared by all tests of one run, so that a test never sends the filter back in
// time unless it means to.
std::int64_t g_next_t = kT0;

class PoseFilterTest : public ::testing::Test {
 public:
  void SetUp() override {
    events_pub_ = nh_.advertise<ebslam_msgs::EventArray>("events", 100);
    pose_sub_ = nh_.subscribe("pose", 1000, &PoseFilterTest::onPose, this);
    pixels_ = edgePixels(kStartX, kStartY, kStartTheta);
    ASSERT_GT(pixels_.size(), 500u);
    ebslam_ros_test::spinUntil([&] { return events_pub_.getNumSubscribers() > 0; }, 10.0);
    ASSERT_GT(events_pub_.getNumSubscribers(), 0u) << "the filter nodelet did not subscribe";
    ros::WallDuration(0.3).sleep();
  }

  void onPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg) {
    poses_.push_back(*msg);
  }

  // One message with `count` events cycling over the edge pixels, from t_us in steps of dt_us.
  ebslam_msgs::EventArray makeEvents(std::int64_t t_us, std::size_t count, std::int64_t dt_us = 20,
                                     std::uint32_t size = 128) {
    ebslam_msgs::EventArray msg;
    msg.header.frame_id = "edvs_optical_frame";
    msg.width = msg.height = size;
    msg.events.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
      const auto& p = pixels_[(cursor_++) % pixels_.size()];
      ebslam_msgs::Event& e = msg.events[i];
      e.x = static_cast<std::uint16_t>(p.first);
      e.y = static_cast<std::uint16_t>(p.second);
      e.ts = ebslam_msgs::toRosTime(t_us + static_cast<std::int64_t>(i) * dt_us);
      e.polarity = (i & 1u) != 0;
    }
    if (count > 0) msg.header.stamp = msg.events.back().ts;
    return msg;
  }

  // Publishes and waits for the pose stamped with the message's last event.
  bool publishAndAwait(const ebslam_msgs::EventArray& msg, double seconds = 5.0) {
    events_pub_.publish(msg);
    const ros::Time stamp = msg.events.back().ts;
    return ebslam_ros_test::spinUntil(
        [&] { return !poses_.empty() && poses_.back().header.stamp == stamp; }, seconds);
  }

  // Publishes `n` messages of 2000 events at 100 Hz of event time from t_us; returns the end.
  std::int64_t feed(std::int64_t t_us, int n) {
    for (int k = 0; k < n; ++k) {
      EXPECT_TRUE(publishAndAwait(makeEvents(t_us, 2000, 5))) << "no pose for message " << k;
      t_us += 10000;
    }
    g_next_t = std::max(g_next_t, t_us);
    return t_us;
  }

  // ~pose_tolerance [m]: EB-PF holds the pose on the known map; EB-SLAM-2D's map is built
  // from its own estimate, so a static sensor's pose wanders a little.
  static void expectNear(const geometry_msgs::Pose& pose, double x, double y, double theta,
                         double tolerance_m) {
    double scale = 1.0;
    ros::param::get("~tolerance_scale", scale);
    tolerance_m *= scale;
    EXPECT_NEAR(pose.position.x, x, tolerance_m);
    EXPECT_NEAR(pose.position.y, y, tolerance_m);
    EXPECT_NEAR(std::remainder(tf2::getYaw(pose.orientation) - theta, 2 * M_PI), 0.0, 0.05);
  }

  ros::NodeHandle nh_;
  ros::Publisher events_pub_;
  ros::Subscriber pose_sub_;
  std::vector<geometry_msgs::PoseWithCovarianceStamped> poses_;
  std::vector<std::pair<int, int>> pixels_;
  std::size_t cursor_ = 0;
};

// The node against its core: after a reset, the messages of a moving sensor through the node and
// through the core filter built here from the node's parameters (the .test file's values over the
// core's defaults), one process() call per message as the node makes it: every pose equal to the
// bit, with the last event's stamp. A change in the ROS layer (conversions, input checks, mounting,
// parameters, chunking) that alters a result fails here.
TEST_F(PoseFilterTest, PosesEqualTheCoreFilterOnTheSameMessages) {
  bool slam = false;
  ros::param::get("~slam", slam);
  ebslam_msgs::ResetPose reset;  // to ~initial_pose, a new filter with the node's seed
  ASSERT_TRUE(ros::service::call("reset", reset));
  ASSERT_TRUE(reset.response.success) << reset.response.message;
  constexpr double kVx = 0.15, kVy = -0.1, kOmega = 0.2;  // [m/s], [m/s], [rad/s] in the map
  constexpr int kMessages = 80;                           // 0.8 s of 100 Hz messages
  const std::int64_t t0 = g_next_t;
  std::vector<ebslam_msgs::EventArray> sent;
  const std::size_t first_pose = poses_.size();
  for (int k = 0; k < kMessages; ++k) {
    const double t = 0.01 * k;
    pixels_ = edgePixels(kStartX + kVx * t, kStartY + kVy * t, kStartTheta + kOmega * t);
    cursor_ = 0;
    sent.push_back(makeEvents(t0 + 10000 * k, 2000, 5));
    ASSERT_TRUE(publishAndAwait(sent.back())) << "no pose for message " << k;
  }
  g_next_t = t0 + 10000 * kMessages;
  ASSERT_EQ(poses_.size() - first_pose, sent.size());

  // The core with the node's parameters (pose_filter_params.cpp, ceiling_sensor_params.cpp).
  ros::NodeHandle p(slam ? "/slam" : "/ebpf");
  // Over the core's defaults, which differ between the two (EB-SLAM-2D: N = 10, G0 = 30).
  const auto overlay = [&p](ebslam::EventFilterConfig f) {
    f.num_particles = p.param("num_particles", f.num_particles);
    f.batch_size = p.param("batch_size", f.batch_size);
    f.resample_every = p.param("resample_every", f.resample_every);
    f.beta = p.param("beta", f.beta);
    f.g0 = p.param("g0", f.g0);
    f.experimental.diffusion_scale = p.param("diffusion_scale", f.experimental.diffusion_scale);
    f.initial_spread_m = p.param("initial_spread", f.initial_spread_m);
    f.initial_spread_rad = p.param("initial_spread_rad", f.initial_spread_rad);
    f.latency_compensation_s = p.param("latency_compensation", f.latency_compensation_s);
    f.experimental.reset_scores_on_resample =
        p.param("reset_scores_on_resample", f.experimental.reset_scores_on_resample);
    return f;
  };
  // Every parameter of the node is one mirrored here or one without effect on the poses (the
  // knobs' server copies include the denoiser's, off).
  const std::set<std::string> mirrored{"num_particles",
                                       "batch_size",
                                       "resample_every",
                                       "beta",
                                       "g0",
                                       "diffusion_scale",
                                       "initial_spread",
                                       "initial_spread_rad",
                                       "latency_compensation",
                                       "reset_scores_on_resample",
                                       "gamma",
                                       "map",
                                       "map_size",
                                       "cell_size",
                                       "splat_sigma",
                                       "initial_pose",
                                       "mount_xyz",
                                       "path_length",
                                       "map_publish_period",
                                       "denoise",
                                       "denoise_window",
                                       "denoise_min_support",
                                       "denoise_polarity_match"};
  std::vector<std::string> names;
  ASSERT_TRUE(ros::param::getParamNames(names));
  for (const std::string& name : names) {
    if (name.rfind(p.getNamespace() + "/", 0) != 0) continue;
    EXPECT_EQ(mirrored.count(name.substr(p.getNamespace().size() + 1)), 1u)
        << name << ": a parameter this test does not mirror";
  }
  ASSERT_FALSE(p.param("denoise", false));
  const ebslam::CeilingCamera camera(ebslam::CameraModel{}, 2.59);
  std::vector<double> start_xyz, mount_xyz;
  ASSERT_TRUE(p.getParam("initial_pose", start_xyz) && start_xyz.size() == 3);
  ASSERT_TRUE(p.getParam("mount_xyz", mount_xyz) && mount_xyz.size() == 3);
  const ebslam::Pose2 mount{mount_xyz[0], mount_xyz[1], 0.0};  // ~mount_rpy: zero (looking up)
  const ebslam::Pose2 start =
      ebslam::compose(ebslam::Pose2{start_xyz[0], start_xyz[1], start_xyz[2]}, mount);
  std::unique_ptr<ebslam::EventParticleFilter> ebpf;
  std::unique_ptr<ebslam::EventSlam2d> slam2d;
  if (slam) {
    ebslam::Ebslam2dConfig c;
    c.filter = overlay(c.filter);
    c.map_size_m = p.param("map_size", c.map_size_m);
    c.cell_size_wtrig = p.param("cell_size", c.cell_size_wtrig);
    c.splat_sigma_wtrig = p.param("splat_sigma", c.splat_sigma_wtrig);
    slam2d = std::make_unique<ebslam::EventSlam2d>(c, camera, start);
  } else {
    ebslam::EbpfConfig c;
    c.filter = overlay(c.filter);
    c.gamma = p.param("gamma", c.gamma);
    std::string map;
    ASSERT_TRUE(p.getParam("map", map));
    const ebslam_ros::CeilingEdgeMap edges = ebslam_ros::loadCeilingMap(map);
    ebpf = std::make_unique<ebslam::EventParticleFilter>(
        c, camera,
        ebslam::makeEdgeLikelihoodMap(edges.edges, edges.resolution_m, edges.origin_centre_m,
                                      c.gamma * camera.wTrig()),
        start);
  }
  std::size_t differing = 0;
  for (std::size_t k = 0; k < sent.size(); ++k) {
    const ebslam::EventVector events = ebslam_msgs::fromMsg(sent[k]);
    slam ? slam2d->process(events) : ebpf->process(events);
    const ebslam::Pose2 sensor = slam ? slam2d->estimate() : ebpf->estimate();
    const geometry_msgs::Pose core =
        ebslam_ros::toPoseMsg(ebslam::compose(sensor, ebslam::inverse(mount)));
    const auto& node = poses_[first_pose + k];
    EXPECT_EQ(node.header.stamp, sent[k].header.stamp) << "message " << k;
    const geometry_msgs::Pose& n = node.pose.pose;
    const bool same = n.position.x == core.position.x && n.position.y == core.position.y &&
                      n.position.z == core.position.z && n.orientation.x == core.orientation.x &&
                      n.orientation.y == core.orientation.y &&
                      n.orientation.z == core.orientation.z &&
                      n.orientation.w == core.orientation.w;
    if (!same && differing++ < 3) {
      ADD_FAILURE() << "message " << k << ": node (" << n.position.x << ", " << n.position.y << ", "
                    << tf2::getYaw(n.orientation) << "), core (" << core.position.x << ", "
                    << core.position.y << ", " << tf2::getYaw(core.orientation) << ")";
    }
  }
  EXPECT_EQ(differing, 0u) << "of " << sent.size() << " poses";
  // Not a filter standing still: the poses followed the path.
  const auto& last = poses_.back().pose.pose;
  EXPECT_GT(std::hypot(last.position.x - kStartX, last.position.y - kStartY), 0.08);
}

TEST_F(PoseFilterTest, PosesCarryTheLastEventsStampMapFrameAndSpread) {
  const std::int64_t end = feed(g_next_t, 20);
  const auto& last = poses_.back();
  EXPECT_EQ(last.header.frame_id, "map");
  EXPECT_EQ(ebslam_msgs::toMicroseconds(last.header.stamp), end - 10000 + 1999 * 5);
  expectNear(last.pose.pose, kStartX, kStartY, kStartTheta, 0.05);
  const auto& c = last.pose.covariance;
  EXPECT_GT(c[0], 0.0);
  EXPECT_GT(c[7], 0.0);
  EXPECT_GT(c[35], 0.0);
  EXPECT_LT(c[0], 0.01);  // particles within ~10 cm
  EXPECT_DOUBLE_EQ(c[1], c[6]);
  EXPECT_LE(c[1] * c[1], c[0] * c[7] * (1 + 1e-9));
}

TEST_F(PoseFilterTest, TfTreeRunsMapOdomBaseLinkSensorWithoutGaps) {
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  ros::WallDuration(1.0).sleep();  // the listener connects to the filter's tf publisher
  feed(g_next_t, 10);
  const ros::Time stamp = poses_.back().header.stamp;
  std::string error;
  ASSERT_TRUE(ebslam_ros_test::spinUntil(
      [&] { return buffer.canTransform("map", "edvs_optical_frame", stamp); }, 5.0));
  ASSERT_NO_FATAL_FAILURE(ebslam_ros_test::checkRep105Chain(buffer, "edvs_optical_frame", stamp));
  // map -> base_link agrees with the pose, and the sensor sits on the mount.
  const auto base = buffer.lookupTransform("map", "base_link", stamp);
  EXPECT_NEAR(base.transform.translation.x, poses_.back().pose.pose.position.x, 1e-9);
  EXPECT_NEAR(base.transform.translation.z, 0.0, 1e-9);
  const auto sensor = buffer.lookupTransform("base_link", "edvs_optical_frame", stamp);
  EXPECT_NEAR(sensor.transform.translation.x, kMountX, 1e-9);
  EXPECT_NEAR(sensor.transform.translation.z, 0.3, 1e-9);
}

TEST_F(PoseFilterTest, LazyParticlesAndBoundedPath) {
  std::vector<geometry_msgs::PoseArray> particles;
  std::vector<nav_msgs::Path> paths;
  auto particles_sub = nh_.subscribe<geometry_msgs::PoseArray>(
      "particles", 10,
      [&](const geometry_msgs::PoseArray::ConstPtr& m) { particles.push_back(*m); });
  auto path_sub = nh_.subscribe<nav_msgs::Path>(
      "path", 10, [&](const nav_msgs::Path::ConstPtr& m) { paths.push_back(*m); });
  ebslam_ros_test::spinUntil(
      [&] { return particles_sub.getNumPublishers() > 0 && path_sub.getNumPublishers() > 0; }, 5.0);
  ros::WallDuration(0.3).sleep();
  int num_particles = 0;
  ros::param::get("~expected_particles", num_particles);
  std::int64_t t = g_next_t;
  for (int k = 0; k < 30 && (particles.empty() || paths.empty()); ++k) {
    t = feed(t, 1);
    ros::WallDuration(0.11).sleep();  // path: at most every 0.1 s
  }
  ebslam_ros_test::spinUntil([&] { return !particles.empty() && !paths.empty(); }, 3.0);
  ASSERT_FALSE(particles.empty());
  EXPECT_EQ(particles.back().header.frame_id, "map");
  EXPECT_EQ(static_cast<int>(particles.back().poses.size()), num_particles);
  ASSERT_FALSE(paths.empty());
  EXPECT_EQ(paths.back().header.frame_id, "map");
  EXPECT_LE(paths.back().poses.size(), 50u);  // ~path_length in the .test files
  EXPECT_GT(paths.back().poses.size(), 1u);
}

TEST_F(PoseFilterTest, ResetServiceRestartsAtTheGivenPose) {
  std::int64_t t = feed(g_next_t, 3);
  ebslam_msgs::ResetPose reset;
  reset.request.use_pose = true;
  reset.request.pose.x = 0.6;
  reset.request.pose.y = 0.7;
  reset.request.pose.theta = -0.4;
  ASSERT_TRUE(ros::service::call("reset", reset));
  EXPECT_TRUE(reset.response.success) << reset.response.message;
  // A single event moves the particles only by the per-event diffusion.
  ebslam_msgs::EventArray one = makeEvents(t, 1);
  ASSERT_TRUE(publishAndAwait(one));
  expectNear(poses_.back().pose.pose, 0.6, 0.7, -0.4, 0.01);
  reset.request.use_pose = false;
  reset.request.pose.x = std::nan("");
  ASSERT_TRUE(ros::service::call("reset", reset));
  EXPECT_TRUE(reset.response.success);
  t = feed(t + 10000, 2);
  expectNear(poses_.back().pose.pose, kStartX, kStartY, kStartTheta, 0.05);
  reset.request.use_pose = true;
  ASSERT_TRUE(ros::service::call("reset", reset));
  EXPECT_FALSE(reset.response.success);  // a NaN pose is refused
}

// Bad input: each message is dropped or repaired, the node keeps publishing correct poses.
TEST_F(PoseFilterTest, BadInputIsDroppedAndTheFilterRunsOn) {
  std::int64_t t = feed(g_next_t, 5);
  const std::size_t before = poses_.size();
  // Empty array: no pose.
  ebslam_msgs::EventArray empty = makeEvents(t, 0);
  empty.header.stamp = ebslam_msgs::toRosTime(t);
  events_pub_.publish(empty);
  // Events outside width x height only: nothing to process, no pose.
  ebslam_msgs::EventArray outside = makeEvents(t, 100);
  for (auto& e : outside.events) e.x = 300;
  events_pub_.publish(outside);
  // Sensor size changes mid-stream: the message is dropped.
  events_pub_.publish(makeEvents(t, 100, 20, 240));
  // Mixed: some events outside, the rest processed. Its pose is the positive signal that the
  // node has handled the three messages before it (one connection keeps their order): had any
  // of them given a pose, it would be here too.
  ebslam_msgs::EventArray mixed = makeEvents(t, 2000, 5);
  for (std::size_t i = 0; i < mixed.events.size(); i += 10) mixed.events[i].y = 128;
  ASSERT_TRUE(publishAndAwait(mixed));
  EXPECT_EQ(poses_.size(), before + 1) << "a dropped message gave a pose";
  t += 10000;
  t = feed(t, 2);
  expectNear(poses_.back().pose.pose, kStartX, kStartY, kStartTheta, 0.05);

  // A 5 s gap: poses continue with the new stamps.
  t += 5000000;
  t = feed(t, 2);
  expectNear(poses_.back().pose.pose, kStartX, kStartY, kStartTheta, 0.05);

  // Time runs back by 20 s (a looping bag): the filter restarts, stamps follow the events.
  const std::int64_t back = t - 20000000;
  ASSERT_TRUE(publishAndAwait(makeEvents(back, 2000, 5)));
  EXPECT_EQ(ebslam_msgs::toMicroseconds(poses_.back().header.stamp), back + 1999 * 5);
  expectNear(poses_.back().pose.pose, kStartX, kStartY, kStartTheta, 0.05);
  t = feed(back + 10000, 2);

  // Small backwards jitter inside a message is clamped, not a restart.
  ebslam_msgs::EventArray jitter = makeEvents(t, 2000, 5);
  std::swap(jitter.events[10].ts, jitter.events[11].ts);
  ASSERT_TRUE(publishAndAwait(jitter));
  t += 10000;

  // 10 million events in one message (about 100 s of a fast eDVS): processed in pieces, the
  // last pose carries the last event's stamp, and the node goes on.
  ebslam_msgs::EventArray huge = makeEvents(t, 10000000, 1);
  ASSERT_TRUE(publishAndAwait(huge, 60.0));
  t += 10000000 + 10000;
  t = feed(t, 2);
  expectNear(poses_.back().pose.pose, kStartX, kStartY, kStartTheta, 0.05);

  // Diagnostics name the bad input.
  diagnostic_msgs::DiagnosticArray diagnostics;
  auto diag_sub = nh_.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 10,
      [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) { diagnostics = *m; });
  ASSERT_TRUE(ebslam_ros_test::spinUntil([&] { return !diagnostics.status.empty(); }, 5.0));
  std::map<std::string, std::string> values;
  for (const auto& kv : diagnostics.status[0].values) values[kv.key] = kv.value;
  EXPECT_EQ(values["messages of a wrong sensor size"], "1");
  EXPECT_EQ(values["restarts after time jumps"], "1");
  EXPECT_EQ(values["events outside the sensor"], std::to_string(100 + 200));
  EXPECT_EQ(values["events clamped in time"], "1");
  EXPECT_EQ(values["pauses longer than gap_warning"], "1");
}

// event_particle_filter_moving.test: the sensor moves along a known path (0.6 m forward, 0.3 m
// sideways and 0.45 rad of turn in 3 s) and every event fires at a pixel that sees a line at the
// pose of its time. The estimate must follow the path: a node that ignored its events, or only
// held the start pose, is 0.67 m off at the end.
TEST_F(PoseFilterTest, TracksAMovingSensor) {
  constexpr double kVx = 0.2, kVy = 0.1, kOmega = 0.15;  // [m/s], [m/s], [rad/s] in the map
  constexpr double kDuration = 3.0;                      // [s]
  const auto truth = [&](double t) {
    return std::array<double, 3>{kStartX + kVx * t, kStartY + kVy * t, kStartTheta + kOmega * t};
  };
  const std::int64_t t0 = g_next_t;
  std::map<std::int64_t, std::array<double, 3>> truth_at;  // last event [us] -> pose
  const int messages = static_cast<int>(kDuration / 0.01);
  for (int k = 0; k < messages; ++k) {
    const double t = 0.01 * k;
    const auto pose = truth(t);
    pixels_ = edgePixels(pose[0], pose[1], pose[2]);
    cursor_ = 0;
    const ebslam_msgs::EventArray msg = makeEvents(t0 + 10000 * k, 2000, 5);
    truth_at[ebslam_msgs::toMicroseconds(msg.header.stamp)] = pose;
    ASSERT_TRUE(publishAndAwait(msg)) << "no pose for message " << k;
  }
  g_next_t = t0 + 10000 * messages;
  double worst = 0.0, worst_yaw = 0.0;
  std::size_t compared = 0;
  for (const auto& pose : poses_) {
    const auto it = truth_at.find(ebslam_msgs::toMicroseconds(pose.header.stamp));
    if (it == truth_at.end() || it->first < t0 + 500000) continue;  // after 0.5 s of motion
    const auto& p = pose.pose.pose;
    worst = std::max(worst, std::hypot(p.position.x - it->second[0], p.position.y - it->second[1]));
    worst_yaw = std::max(
        worst_yaw, std::abs(std::remainder(tf2::getYaw(p.orientation) - it->second[2], 2 * M_PI)));
    ++compared;
  }
  EXPECT_GE(compared, 200u);
  double scale = 1.0;
  ros::param::get("~tolerance_scale", scale);
  EXPECT_LT(worst, 0.05 * scale) << "largest position error along the path [m]";
  EXPECT_LT(worst_yaw, 0.05 * scale) << "largest heading error along the path [rad]";
  const auto end = truth(0.01 * (messages - 1));
  expectNear(poses_.back().pose.pose, end[0], end[1], end[2], 0.05);
}

// ~denoise (event_particle_filter_denoise.test): the background-activity filter runs inside the
// node. Isolated noise events (no neighbouring edge pixel, far from each other) are removed, the
// edge events pass, and the pose stays right.
TEST_F(PoseFilterTest, DenoiserInsideTheNodeRemovesIsolatedNoise) {
  bool denoise = false;
  ros::param::get("~denoise_test", denoise);
  if (!denoise) GTEST_SKIP() << "only in event_particle_filter_denoise.test";
  std::vector<std::vector<bool>> edge(128, std::vector<bool>(128, false));
  for (const auto& [u, v] : pixels_) edge[v][u] = true;
  std::vector<std::pair<int, int>> quiet;  // no edge pixel in their 3 x 3 neighbourhood
  for (int v = 2; v < 126; v += 5) {
    for (int u = 2; u < 126; u += 5) {
      bool near = false;
      for (int dv = -1; dv <= 1; ++dv) {
        for (int du = -1; du <= 1; ++du) near = near || edge[v + dv][u + du];
      }
      if (!near) quiet.emplace_back(u, v);
    }
  }
  ASSERT_GT(quiet.size(), 100u);
  diagnostic_msgs::DiagnosticArray diagnostics;
  auto diag_sub = nh_.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 10,
      [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) { diagnostics = *m; });
  const auto value = [&](const std::string& key) -> std::uint64_t {
    for (const auto& kv : diagnostics.status.at(0).values) {
      if (kv.key == key) return std::stoull(kv.value);
    }
    ADD_FAILURE() << "no diagnostics value '" << key << "'";
    return 0;
  };
  std::int64_t t = feed(g_next_t, 5);  // warm-up: every edge pixel has fired
  diagnostics.status.clear();
  ASSERT_TRUE(ebslam_ros_test::spinUntil([&] { return !diagnostics.status.empty(); }, 5.0));
  const std::uint64_t removed0 = value("events removed by the denoiser");
  const std::uint64_t passed0 = value("events passed by the denoiser");
  std::size_t noise = 0, signal = 0;
  for (int k = 0; k < 10; ++k) {
    ebslam_msgs::EventArray msg = makeEvents(t, 2000, 5);
    signal += msg.events.size();
    // Noise every 20 events: one of the quiet pixels, at the time of the event it follows.
    std::vector<ebslam_msgs::Event> extra;
    for (std::size_t i = 0; i < 2000; i += 20) {
      ebslam_msgs::Event e = msg.events[i];
      const auto& q = quiet[(noise * 37) % quiet.size()];
      e.x = static_cast<std::uint16_t>(q.first);
      e.y = static_cast<std::uint16_t>(q.second);
      extra.push_back(e);
      ++noise;
    }
    msg.events.insert(msg.events.end(), extra.begin(), extra.end());
    std::stable_sort(msg.events.begin(), msg.events.end(),
                     [](const auto& a, const auto& b) { return a.ts < b.ts; });
    // The pose carries the last event that passed the denoiser.
    events_pub_.publish(msg);
    const ros::Time first = msg.events.front().ts;
    ASSERT_TRUE(ebslam_ros_test::spinUntil(
        [&] { return !poses_.empty() && poses_.back().header.stamp >= first; }, 5.0))
        << "no pose for message " << k;
    EXPECT_LE(poses_.back().header.stamp, msg.header.stamp);
    t += 10000;
  }
  g_next_t = std::max(g_next_t, t);
  expectNear(poses_.back().pose.pose, kStartX, kStartY, kStartTheta, 0.05);
  // Counters as of the next diagnostics update.
  ros::WallDuration(1.1).sleep();
  diagnostics.status.clear();
  ASSERT_TRUE(ebslam_ros_test::spinUntil([&] { return !diagnostics.status.empty(); }, 5.0));
  for (const auto& kv : diagnostics.status.at(0).values) {
    if (kv.key == "denoiser") {
      EXPECT_EQ(kv.value, "on");
    }
  }
  const std::uint64_t removed = value("events removed by the denoiser") - removed0;
  const std::uint64_t passed = value("events passed by the denoiser") - passed0;
  EXPECT_EQ(removed + passed, noise + signal);
  EXPECT_GE(removed, noise);                // every noise event
  EXPECT_LE(removed, noise + signal / 50);  // and at most 2 % of the edge events
}

TEST(EventSlam2dOutputs, LatchedMapImageAndSaveMap) {
  bool slam = false;
  ros::param::get("~slam", slam);
  if (!slam) GTEST_SKIP() << "EventParticleFilter has no map outputs";
  ros::NodeHandle nh;
  // Feed events through the fixture's helper.
  struct Feeder : PoseFilterTest {
    void TestBody() override {}
  } feeder;
  feeder.SetUp();
  std::vector<sensor_msgs::Image> images;
  auto image_sub = nh.subscribe<sensor_msgs::Image>(
      "map/image", 2, [&](const sensor_msgs::Image::ConstPtr& m) { images.push_back(*m); });
  ebslam_ros_test::spinUntil([&] { return image_sub.getNumPublishers() > 0; }, 5.0);
  ros::WallDuration(0.3).sleep();
  std::int64_t t = g_next_t;
  for (int k = 0; k < 15; ++k) {
    t = feeder.feed(t, 1);
    ros::WallDuration(0.02).sleep();
  }
  nav_msgs::OccupancyGrid grid;
  auto map_sub = nh.subscribe<nav_msgs::OccupancyGrid>(
      "map", 1, [&](const nav_msgs::OccupancyGrid::ConstPtr& m) { grid = *m; });
  ASSERT_TRUE(ebslam_ros_test::spinUntil([&] { return !grid.data.empty(); },
                                         5.0));  // latched
  EXPECT_EQ(grid.header.frame_id, "map");
  EXPECT_EQ(grid.data.size(), static_cast<std::size_t>(grid.info.width) * grid.info.height);
  EXPECT_NEAR(grid.info.resolution, 0.03, 1e-6);
  // Lines seen from the start pose are occupied in the map frame; unseen cells unknown.
  const auto cell = [&](double x, double y) {
    const int c = static_cast<int>((x - grid.info.origin.position.x) / grid.info.resolution);
    const int r = static_cast<int>((y - grid.info.origin.position.y) / grid.info.resolution);
    return static_cast<int>(grid.data[static_cast<std::size_t>(r) * grid.info.width + c]);
  };
  int on_line = 0;
  for (double y = -0.8; y < 0.4; y += 0.03) {
    for (double x = 0.49; x < 0.62; x += 0.03) on_line = std::max(on_line, cell(x, y));
  }
  EXPECT_GE(on_line, 50);
  EXPECT_EQ(cell(8.0, 8.0), -1);
  EXPECT_LE(ebslam_msgs::toMicroseconds(grid.header.stamp), t);
  ASSERT_TRUE(ebslam_ros_test::spinUntil([&] { return !images.empty(); }, 5.0));
  EXPECT_EQ(images.back().encoding, "mono8");
  EXPECT_EQ(images.back().width, grid.info.width);
  EXPECT_EQ(images.back().header.frame_id, "map");

  ebslam_msgs::SaveMap save;
  save.request.path_prefix = ::testing::TempDir() + "slam_map_" + std::to_string(::getpid());
  ASSERT_TRUE(ros::service::call("save_map", save));
  EXPECT_TRUE(save.response.success) << save.response.message;
  const ebslam_ros::CeilingEdgeMap saved =
      ebslam_ros::loadCeilingMap(save.request.path_prefix + ".yaml");
  EXPECT_EQ(saved.edges.cols, static_cast<int>(grid.info.width));
  EXPECT_GT(cv::countNonZero(saved.edges), 100);
  save.request.path_prefix = "/nonexistent_dir/map";
  ASSERT_TRUE(ros::service::call("save_map", save));
  EXPECT_FALSE(save.response.success);
}

// Knobs across a restart (event_particle_filter.test): a knob changed through dynamic_reconfigure
// acts at once but is not written to the parameter server, so a restarted node starts from the
// launch file's value again (ebslam_ros_common/runtime_knobs.h). The test loads a second
// EventParticleFilter into the manager, changes ~num_particles (set by the "launch file") and ~g0
// (not set), unloads it and loads it again with the same parameters.
TEST(KnobsAcrossRestarts, AKnobChangeLastsUntilTheNodeStops) {
  bool knobs_test = false;
  ros::param::get("~knobs_test", knobs_test);
  if (!knobs_test) GTEST_SKIP() << "only in event_particle_filter.test";
  ros::NodeHandle nh;
  const std::string name = "/knobs_ebpf";
  ros::NodeHandle p(name);
  p.setParam("map", ros::package::getPath("ebslam_ros") + "/test/data/ceiling_lines.yaml");
  p.setParam("initial_pose", std::vector<double>{kStartX, kStartY, kStartTheta});
  p.setParam("mount_xyz", std::vector<double>{kMountX, 0.0, 0.3});
  p.setParam("num_particles", 20);  // the launch file's value
  p.setParam("publish_tf", false);  // the fixture's filter owns map -> odom
  const auto load = [&] {
    nodelet::NodeletLoad request;
    request.request.name = name;
    request.request.type = "ebslam_ros/EventParticleFilter";
    for (const std::string topic : {"events", "pose", "particles", "path", "reset"}) {
      request.request.remap_source_args.push_back("/" + topic);
      request.request.remap_target_args.push_back(name + "/" + topic);
    }
    return ros::service::call("/manager/load_nodelet", request) && request.response.success;
  };
  ros::Publisher events_pub = nh.advertise<ebslam_msgs::EventArray>(name + "/events", 10);
  std::vector<geometry_msgs::PoseArray> particles;
  ros::Subscriber particles_sub = nh.subscribe<geometry_msgs::PoseArray>(
      name + "/particles", 10,
      [&](const geometry_msgs::PoseArray::ConstPtr& m) { particles.push_back(*m); });
  std::int64_t t = kT0;
  const std::vector<std::pair<int, int>> pixels = edgePixels(kStartX, kStartY, kStartTheta);
  // The particle count of the pose for one more message.
  const auto particleCount = [&]() -> std::size_t {
    particles.clear();
    ebslam_msgs::EventArray msg;
    msg.header.frame_id = "edvs_optical_frame";
    msg.width = msg.height = 128;
    for (std::size_t i = 0; i < 500; ++i) {
      ebslam_msgs::Event e;
      e.x = static_cast<std::uint16_t>(pixels[i % pixels.size()].first);
      e.y = static_cast<std::uint16_t>(pixels[i % pixels.size()].second);
      e.ts = ebslam_msgs::toRosTime(t + static_cast<std::int64_t>(i) * 10);
      msg.events.push_back(e);
    }
    msg.header.stamp = msg.events.back().ts;
    t += 10000;
    events_pub.publish(msg);
    ebslam_ros_test::spinUntil([&] { return !particles.empty(); }, 20.0);
    return particles.empty() ? 0 : particles.back().poses.size();
  };
  const auto connect = [&] {
    return ebslam_ros_test::spinUntil(
        [&] { return events_pub.getNumSubscribers() > 0 && particles_sub.getNumPublishers() > 0; },
        20.0);
  };

  ASSERT_TRUE(load());
  ASSERT_TRUE(connect());
  ros::WallDuration(0.3).sleep();
  EXPECT_EQ(particleCount(), 20u);
  dynamic_reconfigure::Reconfigure knobs;
  dynamic_reconfigure::IntParameter count;
  count.name = "num_particles";
  count.value = 45;
  dynamic_reconfigure::DoubleParameter g0;
  g0.name = "g0";
  g0.value = 75.0;
  knobs.request.config.ints.push_back(count);
  knobs.request.config.doubles.push_back(g0);
  ASSERT_TRUE(ros::service::call(name + "/set_parameters", knobs));
  EXPECT_EQ(particleCount(), 45u) << "the knob acts at once";
  // The server keeps what the launch file set, and no value nobody set.
  int on_server = 0;
  EXPECT_TRUE(ebslam_ros_test::spinUntil(
      [&] {
        return p.getParam("num_particles", on_server) && on_server == 20 && !p.hasParam("g0");
      },
      5.0))
      << "~num_particles on the server: " << on_server << ", ~g0 "
      << (p.hasParam("g0") ? "set" : "not set");

  nodelet::NodeletUnload unload;
  unload.request.name = name;
  ASSERT_TRUE(ros::service::call("/manager/unload_nodelet", unload) && unload.response.success);
  ASSERT_TRUE(
      ebslam_ros_test::spinUntil([&] { return particles_sub.getNumPublishers() == 0; }, 20.0));
  ASSERT_TRUE(load());
  ASSERT_TRUE(connect());
  ros::WallDuration(0.3).sleep();
  t += 10000000;  // a later stream: the new node has no past
  EXPECT_EQ(particleCount(), 20u) << "the restarted node starts from the launch file's value";
  // Its knobs say so to dynamic_reconfigure clients (an empty request returns the current ones).
  dynamic_reconfigure::Reconfigure current;
  ASSERT_TRUE(ros::service::call(name + "/set_parameters", current));
  for (const auto& i : current.response.config.ints) {
    if (i.name == "num_particles") {
      EXPECT_EQ(i.value, 20);
    }
  }
  for (const auto& d : current.response.config.doubles) {
    if (d.name == "g0") {
      EXPECT_EQ(d.value, 60.0);  // EB-PF's G0
    }
  }
  ASSERT_TRUE(ros::service::call("/manager/unload_nodelet", unload) && unload.response.success);
  EXPECT_TRUE(p.getParam("num_particles", on_server) && on_server == 20);
  EXPECT_FALSE(p.hasParam("g0")) << "a knob value no one set stayed on the server";
}

// ~max_event_rate: a second EventSlam2d loaded into the manager with a cap of 250k events/s gets
// a 1 M events/s stream (30 messages of 10 ms): its poses equal the core run here on the same
// messages thinned by ebslam::EventRateLimiter with the node's cap and ~rate_seed (the thinning
// is deterministic and independent of the node), each stamped with the message's last event, and
// /diagnostics reports the cap, the dropped events and the keep probability.
TEST(RateCap, ThinsAsTheCoreDoesAndReportsIt) {
  bool rate_cap_test = false;
  ros::param::get("~rate_cap_test", rate_cap_test);
  if (!rate_cap_test) GTEST_SKIP() << "only in event_slam2d.test";
  ros::NodeHandle nh;
  const std::string name = "/rate_slam";
  ros::NodeHandle p(name);
  p.setParam("initial_pose", std::vector<double>{kStartX, kStartY, kStartTheta});
  p.setParam("mount_xyz", std::vector<double>{kMountX, 0.0, 0.3});
  p.setParam("map_size", 20.0);
  p.setParam("max_event_rate", 250000.0);
  p.setParam("rate_seed", 5);
  p.setParam("publish_tf", false);  // the fixture's filter owns map -> odom
  nodelet::NodeletLoad load;
  load.request.name = name;
  load.request.type = "ebslam_ros/EventSlam2d";
  for (const std::string topic : {"events", "pose", "particles", "particlecloud", "path", "reset",
                                  "map", "map/image", "map/normalisation", "save_map"}) {
    load.request.remap_source_args.push_back("/" + topic);
    load.request.remap_target_args.push_back(name + "/" + topic);
  }
  ros::Publisher events_pub = nh.advertise<ebslam_msgs::EventArray>(name + "/events", 100);
  std::vector<geometry_msgs::PoseWithCovarianceStamped> poses;
  ros::Subscriber pose_sub = nh.subscribe<geometry_msgs::PoseWithCovarianceStamped>(
      name + "/pose", 100,
      [&](const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) { poses.push_back(*m); });
  std::map<std::string, std::string> values;
  ros::Subscriber diag_sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 10, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
        for (const auto& status : m->status) {
          if (status.name.find("rate_slam") == std::string::npos) continue;
          for (const auto& kv : status.values) values[kv.key] = kv.value;
        }
      });
  ASSERT_TRUE(ros::service::call("/manager/load_nodelet", load) && load.response.success);
  ASSERT_TRUE(ebslam_ros_test::spinUntil(
      [&] { return events_pub.getNumSubscribers() > 0 && pose_sub.getNumPublishers() > 0; }, 20.0));
  ros::WallDuration(0.3).sleep();

  const std::vector<std::pair<int, int>> pixels = edgePixels(kStartX, kStartY, kStartTheta);
  constexpr int kMessages = 30;
  std::vector<ebslam_msgs::EventArray> sent;
  for (int k = 0; k < kMessages; ++k) {
    ebslam_msgs::EventArray msg;
    msg.header.frame_id = "edvs_optical_frame";
    msg.width = msg.height = 128;
    msg.events.resize(10000);  // 1 event per us
    for (std::size_t i = 0; i < msg.events.size(); ++i) {
      const auto& px = pixels[(static_cast<std::size_t>(k) * 10000 + i) % pixels.size()];
      msg.events[i].x = static_cast<std::uint16_t>(px.first);
      msg.events[i].y = static_cast<std::uint16_t>(px.second);
      msg.events[i].polarity = (i & 1u) != 0;
      msg.events[i].ts = ebslam_msgs::toRosTime(kT0 + 10000 * k + static_cast<std::int64_t>(i));
    }
    msg.header.stamp = msg.events.back().ts;
    sent.push_back(msg);
    events_pub.publish(msg);
    ASSERT_TRUE(ebslam_ros_test::spinUntil(
        [&] { return poses.size() == static_cast<std::size_t>(k + 1); }, 10.0))
        << "no pose for message " << k;
  }

  ebslam::Ebslam2dConfig config;
  config.map_size_m = 20.0;
  ebslam::EventRateLimiterConfig cap;
  cap.max_rate_eps = 250000.0;
  cap.seed = 5;
  ebslam::EventRateLimiter limiter(cap);
  const ebslam::Pose2 mount{kMountX, 0.0, 0.0};
  ebslam::EventSlam2d core(config, ebslam::CeilingCamera(ebslam::CameraModel{}, 2.59),
                           ebslam::compose(ebslam::Pose2{kStartX, kStartY, kStartTheta}, mount));
  std::size_t dropped = 0;
  for (int k = 0; k < kMessages; ++k) {
    ebslam::EventVector events = ebslam_msgs::fromMsg(sent[static_cast<std::size_t>(k)]);
    const std::size_t thinned = limiter.thinInPlace(events);
    dropped += thinned;
    ASSERT_FALSE(events.empty());
    core.countUnprocessed(thinned);  // as the node: noise_aware_diffusion counts them
    core.process(events);
    const geometry_msgs::Pose expected =
        ebslam_ros::toPoseMsg(ebslam::compose(core.estimate(), ebslam::inverse(mount)));
    const auto& node = poses[static_cast<std::size_t>(k)];
    EXPECT_EQ(node.header.stamp, sent[static_cast<std::size_t>(k)].events.back().ts) << k;
    EXPECT_EQ(node.pose.pose.position.x, expected.position.x) << "message " << k;
    EXPECT_EQ(node.pose.pose.position.y, expected.position.y) << "message " << k;
    EXPECT_EQ(node.pose.pose.orientation.z, expected.orientation.z) << "message " << k;
  }
  // About 3/4 of the 300000 events dropped (the first window, before the rate is known, keeps
  // twice the cap).
  EXPECT_GT(dropped, 200000u);
  EXPECT_LT(dropped, 230000u);
  ASSERT_TRUE(ebslam_ros_test::spinUntil(
      [&] { return values["events dropped by the rate cap"] == std::to_string(dropped); }, 5.0))
      << "diagnostics report " << values["events dropped by the rate cap"] << " dropped, the core "
      << dropped;
  EXPECT_DOUBLE_EQ(std::stod(values["max event rate [ev/s]"]), 250000.0);
  EXPECT_NEAR(std::stod(values["keep probability"]), limiter.keepProbability(), 1e-6);
  EXPECT_NEAR(std::stod(values["keep probability"]), 0.25, 0.01);
  EXPECT_NEAR(std::stod(values["dropped share (since start)"]), dropped / 300000.0, 1e-6);
  EXPECT_EQ(values["events processed"], std::to_string(300000 - dropped));
  nodelet::NodeletUnload unload;
  unload.request.name = name;
  EXPECT_TRUE(ros::service::call("/manager/unload_nodelet", unload) && unload.response.success);
}

// A map that does not exist or is not an image: the nodelet says why and refuses to load; the
// manager process lives on. The test loads the two nodelets itself (the manager's load_nodelet
// service), after subscribing to /rosout, so that it sees their error messages: a test that
// only found the topics missing would pass with nodelets that never loaded.
// The sensor's geometry from sensor_msgs/CameraInfo, not from ~camera/* (which say 128x128): a
// filter loaded beside a latched camera_info of a DAVIS346 (plumb_bob), and one with
// ~camera_info_url naming a DAVIS346 calibration file, process 346x260 messages whose events all
// lie beyond column 128 (a 128x128 filter has nothing to process in them and publishes no pose)
// and drop 128x128 messages.
TEST(CameraInfoGeometry, SizeAndLensComeFromCameraInfo) {
  bool camera_info_test = false;
  ros::param::get("~camera_info_test", camera_info_test);
  if (!camera_info_test) GTEST_SKIP() << "only in event_particle_filter.test";
  ros::NodeHandle nh;
  ASSERT_TRUE(ros::service::waitForService("/manager/load_nodelet", ros::Duration(30.0)));
  const std::string data = ros::package::getPath("ebslam_ros") + "/test/data/";
  sensor_msgs::CameraInfo info;
  info.header.frame_id = "davis_optical_frame";
  info.width = 346;
  info.height = 260;
  info.distortion_model = "plumb_bob";
  info.D = {-0.12, 0.03, 0.0005, -0.0004, 0.0};
  info.K = {233.4, 0.0, 172.5, 0.0, 233.0, 129.5, 0.0, 0.0, 1.0};
  info.R = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  info.P = {233.4, 0.0, 172.5, 0.0, 0.0, 233.0, 129.5, 0.0, 0.0, 0.0, 1.0, 0.0};
  ros::Publisher info_pub =
      nh.advertise<sensor_msgs::CameraInfo>("/info_topic/camera_info", 1, true);
  info_pub.publish(info);
  std::int64_t t_us = g_next_t + 1000000;
  for (const std::string ns : {"/info_topic", "/info_url"}) {
    SCOPED_TRACE(ns);
    const std::string name = ns + "/ebpf";
    ros::param::set(name + "/map", data + "ceiling_lines.yaml");
    ros::param::set(name + "/initial_pose", std::vector<double>{0.1, -0.2, 0.3});
    ros::param::set(name + "/mount_xyz", std::vector<double>{0.1, 0.0, 0.3});
    ros::param::set(name + "/num_particles", 20);
    ros::param::set(name + "/publish_tf", false);
    ros::param::set(name + "/map_frame", ns.substr(1) + "_map");
    ros::param::set(name + "/sensor_frame", "davis_optical_frame");
    ros::param::set(name + "/camera/width", 128);  // the fallback, overridden by CameraInfo
    if (ns == "/info_url") {
      ros::param::set(name + "/camera_info_url", "file://" + data + "davis346_camera_info.yaml");
    }
    std::vector<geometry_msgs::PoseWithCovarianceStamped> poses;
    ros::Subscriber pose_sub = nh.subscribe<geometry_msgs::PoseWithCovarianceStamped>(
        ns + "/pose", 100,
        [&](const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) { poses.push_back(*m); });
    ros::Publisher events_pub = nh.advertise<ebslam_msgs::EventArray>(ns + "/events", 100);
    nodelet::NodeletLoad load;
    load.request.name = name;
    load.request.type = "ebslam_ros/EventParticleFilter";
    ASSERT_TRUE(ros::service::call("/manager/load_nodelet", load)) << "the filter did not load";
    ASSERT_TRUE(
        ebslam_ros_test::spinUntil([&] { return events_pub.getNumSubscribers() > 0; }, 10.0));
    ros::WallDuration(0.3).sleep();
    const auto message = [&](std::uint32_t width, std::uint32_t height) {
      ebslam_msgs::EventArray msg;
      msg.header.frame_id = "davis_optical_frame";
      msg.width = width;
      msg.height = height;
      std::mt19937 rng(7);
      for (int i = 0; i < 600; ++i) {
        ebslam_msgs::Event e;
        e.x = static_cast<std::uint16_t>(width > 128 ? 128 + rng() % (width - 128) : rng() % width);
        e.y = static_cast<std::uint16_t>(rng() % height);
        e.ts = ebslam_msgs::toRosTime(t_us += 20);
        e.polarity = (i & 1) != 0;
        msg.events.push_back(e);
      }
      msg.header.stamp = msg.events.back().ts;
      return msg;
    };
    const ebslam_msgs::EventArray small = message(128, 128);
    events_pub.publish(small);
    for (int k = 0; k < 3; ++k) {
      const ebslam_msgs::EventArray davis = message(346, 260);
      events_pub.publish(davis);
      EXPECT_TRUE(ebslam_ros_test::spinUntil(
          [&] { return !poses.empty() && poses.back().header.stamp == davis.header.stamp; }, 10.0))
          << "no pose for the 346x260 message " << k;
    }
    ASSERT_FALSE(poses.empty());
    EXPECT_EQ(poses.back().header.frame_id, ns.substr(1) + "_map");
    for (const auto& p : poses) EXPECT_NE(p.header.stamp, small.header.stamp);
    nodelet::NodeletUnload unload;
    unload.request.name = name;
    EXPECT_TRUE(ros::service::call("/manager/unload_nodelet", unload));
  }
  g_next_t = t_us + 1000;
}

TEST(BadMap, NodeRefusesToStartAndLivesOn) {
  bool bad_map = false;
  ros::param::get("~bad_map", bad_map);
  if (!bad_map) GTEST_SKIP() << "only in event_particle_filter_bad_map.test";
  ros::NodeHandle nh;
  std::vector<rosgraph_msgs::Log> logs;
  auto rosout_sub = nh.subscribe<rosgraph_msgs::Log>(
      "/rosout", 100, [&](const rosgraph_msgs::Log::ConstPtr& m) { logs.push_back(*m); });
  ASSERT_TRUE(ros::service::waitForService("/bad_map_manager/load_nodelet", ros::Duration(30.0)));
  // Connected to the /rosout publishers of this node and of the manager.
  ASSERT_TRUE(ebslam_ros_test::spinUntil([&] { return rosout_sub.getNumPublishers() >= 2; }, 30.0))
      << "not connected to the manager's /rosout";
  const std::string data = ros::package::getPath("ebslam_ros") + "/test/data/";
  for (const std::string name : {"missing", "bad_format"}) {
    SCOPED_TRACE(name);
    const std::string yaml = name == "missing" ? "ceiling_missing.yaml" : "ceiling_bad_format.yaml";
    ros::param::set("/" + name + "/map", data + yaml);
    nodelet::NodeletLoad load;
    load.request.name = "/" + name;
    load.request.type = "ebslam_ros/EventParticleFilter";
    load.request.remap_source_args = {"/" + name + "/pose"};
    load.request.remap_target_args = {"/" + name + "/pose"};
    // The manager answers once onInit has returned: false, as a filter that cannot start
    // refuses to load (the startup policy of ros_param_helpers.h).
    EXPECT_FALSE(ros::service::call("/bad_map_manager/load_nodelet", load))
        << "the filter loaded with a bad map";
    // Its reason, naming the map, at ERROR or FATAL from the manager's process.
    const auto reported = [&] {
      for (const auto& m : logs) {
        if (m.level >= rosgraph_msgs::Log::ERROR && m.name == "/bad_map_manager" &&
            m.msg.find(yaml) != std::string::npos) {
          return true;
        }
      }
      return false;
    };
    EXPECT_TRUE(ebslam_ros_test::spinUntil(reported, 30.0)) << "no error naming " << yaml;
    // onInit has returned: a started filter would have advertised its pose by now.
    ros::master::V_TopicInfo topics;
    ASSERT_TRUE(ros::master::getTopics(topics));
    for (const auto& topic : topics) EXPECT_NE(topic.name, "/" + name + "/pose");
  }
  // The manager lives on and answers, without the refused nodelets.
  nodelet::NodeletList list;
  EXPECT_TRUE(ros::service::call("/bad_map_manager/list", list));
  for (const std::string& loaded : list.response.nodelets) {
    EXPECT_NE(loaded, "/missing");
    EXPECT_NE(loaded, "/bad_format");
  }
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "pose_filter_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
