// Writes the sample session: one consistent simulated scene seen by both sensors of a floor robot,
// on one clock, as a bag that launch/playback.launch plays through the pipeline.
//  - Motion: a TUM motion-capture run of a wheeled robot (freiburg2_pioneer_*), projected to the
//    floor plane and smoothed as for the 2D event simulator (thesis 6.5.3), started at the origin.
//  - Scene: a room around the path (ebslam::makeRoomScene: dead-leaves textures, a shelf) with
//    boxes on the floor that keep clear of the robot's path; the ceiling, 2.59 m above the eDVS,
//    has the thesis' lines-and-circles texture (the floor-robot setup of 6.5.3).
//  - eDVS: 128 x 128, looking up (optical x = forward, z = up, the EB-PF/EB-SLAM-2D mounting),
//    the thesis' floor-robot lens (f = 86.3 px); events by the D-eDVS simulator.
//  - RGB-D: the PrimeSense-like camera of the D-eDVS simulator looking forward 5 cm below the
//    eDVS, colour registered to depth, frames subsampled to --rgbd-rate.
// Topics (names of live.launch): /camera/rgb/image_rect_color (bgr8), /camera/depth_registered/
// image_raw (16UC1 mm), /camera/rgb/camera_info, /camera/depth_registered/camera_info,
// /edvs/events, /edvs/camera_info, /ground_truth/pose (the eDVS optical frame in map),
// /tf (map -> ground_truth), /tf_static (base_link -> camera_rgb_optical_frame, latched).
// Stamps: the motion capture's own clock (seconds since 1970 in the TUM files).
//   rosrun ebslam_ros make_session --trajectory test/data/sample_session/pioneer_360_excerpt.txt
//     --duration 8 --output test/data/session/session.bag
// With --rig dedvs it writes the hand-held D-eDVS session instead (writeDedvsSession below,
// test/data/dedvs_session/README.md).
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <tf2_msgs/TFMessage.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "ebslam/events/event_clock.h"
#include "ebslam/events/trajectory.h"
#include "ebslam/simulation/dedvs_scene.h"
#include "ebslam/simulation/dedvs_simulator.h"
#include "ebslam/simulation/simulator_scenes.h"
#include "ebslam_msgs/event_conversions.h"
#include "ebslam_ros/conversions.h"

namespace {

struct SessionOptions {
  std::string rig = "floor";  // floor (upward eDVS + RGB-D camera) | dedvs (hand-held D-eDVS)
  std::string trajectory;
  std::string output;
  double t_begin_s = 0.0;
  double duration_s = 8.0;
  double rgbd_rate_hz = 3.0;
  double rgb_rate_hz = 0.0;  // dedvs: colour frames kept per second (0: with every depth frame)
  double event_message_rate_hz = 100.0;
  double ground_truth_rate_hz = 50.0;
  int depth_width = 320;
  int box_count = 8;
  std::uint64_t seed = 1;
  bool imu = true;  // dedvs: the rig IMU's readings on /imu (imu_simulator.h)
  std::string compression = "bz2";
};

constexpr double kEdvsHeightM =
    0.63;  // eDVS above the floor [m]; the Kinect of the pioneer runs is at 0.58 m

// eDVS optical frame -> depth optical frame: eDVS x (robot forward) = depth z, eDVS z (up) =
// depth -y, eDVS y (robot left) = depth -x; the eDVS sits 5 cm above the depth camera.
Eigen::Isometry3d depthFromEdvs() {
  Eigen::Matrix3d r;
  r.col(0) = Eigen::Vector3d(0, 0, 1);
  r.col(1) = Eigen::Vector3d(-1, 0, 0);
  r.col(2) = Eigen::Vector3d(0, -1, 0);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = r;
  t.translation() = Eigen::Vector3d(0.0, -0.05, 0.0);
  return t;
}

Eigen::Isometry3d isometryOf(const ebslam::StampedPose& pose) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = pose.orientation.normalized().toRotationMatrix();
  t.translation() = pose.position;
  return t;
}

ebslam::StampedPose stampedPoseOf(double t_s, const Eigen::Isometry3d& t) {
  ebslam::StampedPose pose;
  pose.t_s = t_s;
  pose.position = t.translation();
  pose.orientation = Eigen::Quaterniond(t.linear());
  return pose;
}

// Floor-robot eDVS poses (camera -> world, z up) starting at the origin with heading 0, lifted to
// the eDVS height.
ebslam::Trajectory edvsTrajectory(const SessionOptions& options, double* clock_origin_s) {
  const ebslam::Trajectory mocap = ebslam::readTumTrajectory(options.trajectory);
  if (mocap.size() < 2) throw std::runtime_error("trajectory has fewer than two poses");
  *clock_origin_s = mocap.front().t_s;
  ebslam::Trajectory floor = ebslam::makeFloorRobotTrajectory(mocap);
  const Eigen::Isometry3d start_inverse = isometryOf(floor.front()).inverse();
  for (ebslam::StampedPose& pose : floor) {
    Eigen::Isometry3d t = start_inverse * isometryOf(pose);
    t.translation().z() += kEdvsHeightM;
    pose = stampedPoseOf(pose.t_s, t);
  }
  return floor;
}

// Boxes on the floor at least 0.6 m from every position of the path, inside the room.
void addBoxesBesidePath(ebslam::Scene& scene, const ebslam::Trajectory& path, int count,
                        std::uint64_t seed) {
  Eigen::Vector2d lo = path.front().position.head<2>(), hi = lo;
  for (const ebslam::StampedPose& p : path) {
    lo = lo.cwiseMin(p.position.head<2>());
    hi = hi.cwiseMax(p.position.head<2>());
  }
  lo -= Eigen::Vector2d(1.3, 1.3);
  hi += Eigen::Vector2d(1.3, 1.3);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  ebslam::DeadLeavesConfig leaves;
  leaves.size_px = 256;
  for (int placed = 0, attempt = 0; placed < count && attempt < 2000; ++attempt) {
    const Eigen::Vector3d size(0.25 + 0.35 * uniform(rng), 0.25 + 0.35 * uniform(rng),
                               0.2 + 0.4 * uniform(rng));
    const Eigen::Vector2d corner(lo.x() + uniform(rng) * (hi.x() - lo.x() - size.x()),
                                 lo.y() + uniform(rng) * (hi.y() - lo.y() - size.y()));
    const Eigen::Vector2d centre = corner + 0.5 * size.head<2>();
    const double clearance = 0.6 + 0.5 * size.head<2>().norm();
    bool clear = true;
    for (std::size_t i = 0; i < path.size() && clear; i += 5) {
      clear = (path[i].position.head<2>() - centre).norm() > clearance;
    }
    if (!clear) continue;
    leaves.seed = seed * 1000 + static_cast<std::uint64_t>(placed) + 1;
    leaves.contrast = 0.4 + 0.4 * uniform(rng);
    const Eigen::Vector3f colour(static_cast<float>(0.3 + 0.7 * uniform(rng)),
                                 static_cast<float>(0.3 + 0.7 * uniform(rng)),
                                 static_cast<float>(0.3 + 0.7 * uniform(rng)));
    ebslam::addBox(scene, Eigen::Vector3d(corner.x(), corner.y(), 0.0),
                   Eigen::Vector3d(corner.x() + size.x(), corner.y() + size.y(), size.z()),
                   ebslam::makeDeadLeavesTexture(leaves), 0.004, colour);
    ++placed;
  }
}

geometry_msgs::Transform transformMsg(const Eigen::Isometry3d& t) {
  geometry_msgs::Transform msg;
  msg.translation.x = t.translation().x();
  msg.translation.y = t.translation().y();
  msg.translation.z = t.translation().z();
  const Eigen::Quaterniond q(t.linear());
  msg.rotation.x = q.x();
  msg.rotation.y = q.y();
  msg.rotation.z = q.z();
  msg.rotation.w = q.w();
  return msg;
}

// The room of a session: walls and boxes beside the eDVS path, no table, the thesis'
// floor-robot texture (lines and circles, 6.5.3) on the ceiling, which the 2D simulator and the
// EB-PF/EB-SLAM-2D defaults use: about 40k events/s on these runs.
ebslam::Scene sessionScene(const SessionOptions& options, const ebslam::Trajectory& rig,
                           const ebslam::Trajectory& edvs) {
  ebslam::RoomSceneConfig room;
  room.seed = options.seed;
  room.ceiling_height_m = kEdvsHeightM + ebslam::kThesisCeilingHeightM;
  room.with_table = false;  // the robot would drive under it and see its underside
  room.box_count = 0;
  ebslam::Scene scene = ebslam::makeRoomScene(rig, room);
  addBoxesBesidePath(scene, edvs, options.box_count, options.seed);
  ebslam::LinesAndCirclesConfig lines;
  lines.seed = options.seed;
  for (ebslam::TexturedPlane& plane : scene.planes) {
    const bool horizontal = std::abs(plane.pose.linear().col(2).z()) > 0.99;
    if (horizontal && plane.pose.translation().z() > room.ceiling_height_m - 0.01) {
      plane.texture = ebslam::makeLinesAndCirclesTexture(lines);
      plane.metres_per_texel = 0.01;
      plane.repeat = true;
    }
  }
  return scene;
}

// The static mounting base_link -> rgb_frame, latched as tf2's static publisher sends it.
void writeStaticMount(rosbag::Bag& bag, const ros::Time& stamp, const std::string& rgb_frame,
                      const Eigen::Isometry3d& depth_from_edvs) {
  tf2_msgs::TFMessage statics;
  geometry_msgs::TransformStamped mount;
  mount.header.stamp = stamp;
  mount.header.frame_id = "base_link";
  mount.child_frame_id = rgb_frame;
  mount.transform =
      transformMsg(depth_from_edvs.inverse());  // base_link = eDVS position, x forward
  statics.transforms.push_back(mount);
  auto header = boost::make_shared<std::map<std::string, std::string>>();
  (*header)["type"] = ros::message_traits::datatype<tf2_msgs::TFMessage>();
  (*header)["md5sum"] = ros::message_traits::md5sum<tf2_msgs::TFMessage>();
  (*header)["message_definition"] = ros::message_traits::definition<tf2_msgs::TFMessage>();
  (*header)["latching"] = "1";
  (*header)["callerid"] = "/make_session";
  bag.write("/tf_static", mount.header.stamp, statics, header);
}

// The eDVS ground truth at ground_truth_rate_hz on /ground_truth/pose and /tf (map ->
// ground_truth, map on the floor under the start pose). Returns the pose count.
std::size_t writeGroundTruth(rosbag::Bag& bag, const ebslam::DedvsRun& run,
                             const SessionOptions& options, double clock_origin_s) {
  std::size_t ground_truth_poses = 0;
  const double step = 1.0 / options.ground_truth_rate_hz;
  double next_t = -1.0;
  for (const ebslam::StampedPose& pose : run.edvs_ground_truth) {
    if (pose.t_s < next_t) continue;
    next_t = pose.t_s + step;
    const ros::Time stamp(clock_origin_s + pose.t_s);
    Eigen::Isometry3d in_map = isometryOf(pose);
    in_map.translation().z() -= kEdvsHeightM;
    geometry_msgs::PoseStamped msg;
    msg.header.stamp = stamp;
    msg.header.frame_id = "map";
    const geometry_msgs::Transform t = transformMsg(in_map);
    msg.pose.position.x = t.translation.x;
    msg.pose.position.y = t.translation.y;
    msg.pose.position.z = t.translation.z;
    msg.pose.orientation = t.rotation;
    bag.write("/ground_truth/pose", stamp, msg);
    tf2_msgs::TFMessage tf;
    geometry_msgs::TransformStamped ts;
    ts.header = msg.header;
    ts.child_frame_id = "ground_truth";
    ts.transform = t;
    tf.transforms.push_back(ts);
    bag.write("/tf", stamp, tf);
    ++ground_truth_poses;
  }
  return ground_truth_poses;
}

// Copies a bag written topic by topic into `output` in time order (compressed as asked).
void copyInTimeOrder(const std::string& unordered_path, const SessionOptions& options) {
  rosbag::Bag unordered(unordered_path, rosbag::bagmode::Read);
  rosbag::Bag ordered(options.output, rosbag::bagmode::Write);
  if (options.compression == "bz2") ordered.setCompression(rosbag::compression::BZ2);
  if (options.compression == "lz4") ordered.setCompression(rosbag::compression::LZ4);
  for (const rosbag::MessageInstance& m : rosbag::View(unordered)) {
    ordered.write(m.getTopic(), m.getTime(), m, m.getConnectionHeader());
  }
}

// The simulated eDVS into /edvs/events messages of a fixed stream-time length, stamped by `clock`
// (simulated us -> ROS us), with /edvs/camera_info every tenth message, as the driver publishes.
class EventBagWriter {
 public:
  EventBagWriter(rosbag::Bag& bag, ebslam::EventClock& clock, const ebslam::CameraModel& camera,
                 std::string frame, double message_rate_hz)
      : bag_(bag),
        clock_(clock),
        camera_(camera),
        frame_(std::move(frame)),
        period_us_(static_cast<std::int64_t>(1e6 / message_rate_hz)) {}

  void add(const std::vector<ebslam::TrueDepthEvent>& events) {
    for (const ebslam::TrueDepthEvent& e : events) {
      if (message_end_us_ == 0) message_end_us_ = e.event.t_us + period_us_;
      while (e.event.t_us >= message_end_us_) {
        flush();
        message_end_us_ += period_us_;
      }
      pending_.push_back(e.event);
    }
  }

  // Writes the pending events as one message (none if there are none).
  void flush() {
    if (pending_.empty()) return;
    for (ebslam::Event& e : pending_) e.t_us = clock_.stamp(e.t_us).value_or(-1);
    const ebslam_msgs::EventArray msg =
        ebslam_msgs::toMsg(pending_,
                           ebslam::SensorSize{static_cast<std::uint32_t>(camera_.width),
                                              static_cast<std::uint32_t>(camera_.height)},
                           frame_);
    bag_.write("/edvs/events", msg.header.stamp, msg);
    if (messages_ % 10 == 0) {
      bag_.write("/edvs/camera_info", msg.header.stamp,
                 ebslam_ros::toCameraInfoMsg(camera_.width, camera_.height, camera_.focal_px,
                                             camera_.focal_px, camera_.principal_point.x(),
                                             camera_.principal_point.y(), msg.header));
    }
    events_ += pending_.size();
    ++messages_;
    pending_.clear();
  }

  std::size_t events() const { return events_; }
  std::size_t messages() const { return messages_; }

 private:
  rosbag::Bag& bag_;
  ebslam::EventClock& clock_;
  const ebslam::CameraModel& camera_;
  const std::string frame_;
  const std::int64_t period_us_;
  ebslam::EventVector pending_;
  std::int64_t message_end_us_ = 0;  // end of the message being filled [simulated us]
  std::size_t events_ = 0, messages_ = 0;
};

void writeSession(const SessionOptions& options) {
  double clock_origin_s = 0.0;
  const ebslam::Trajectory edvs = edvsTrajectory(options, &clock_origin_s);
  const Eigen::Isometry3d depth_from_edvs = depthFromEdvs();
  ebslam::Trajectory rig;
  for (const ebslam::StampedPose& pose : edvs) {
    rig.push_back(stampedPoseOf(pose.t_s, isometryOf(pose) * depth_from_edvs.inverse()));
  }
  const ebslam::Scene scene = sessionScene(options, rig, edvs);

  ebslam::DedvsSimulatorConfig config;
  config.edvs = ebslam::CameraModel{};  // the thesis' floor-robot eDVS (6.5.3)
  config.depth_from_edvs = depth_from_edvs;
  config.depth.camera = config.depth.camera.scaled(options.depth_width / 320.0);
  config.seed = options.seed;
  config.events.seed = options.seed;
  const ebslam::DedvsSimulator simulator(config);

  // Written topic by topic into an uncompressed bag first, then copied in time order: rosbag
  // keeps one decompressed chunk, so a bag whose chunks each hold one topic decompresses a whole
  // chunk for nearly every message it plays (bz2: playback several times slower than real time).
  const std::string unordered_path = options.output + ".unordered";
  rosbag::Bag bag(unordered_path, rosbag::bagmode::Write);

  // Simulated time t [us] is recorded at ROS time clock_origin_s + t.
  ebslam::EventClock clock;
  clock.anchor(0, ebslam_msgs::toMicroseconds(ros::Time(clock_origin_s)));
  const ebslam::CameraModel& edvs_camera = config.edvs;
  const ebslam::PinholeCamera& depth_camera = config.depth.camera;
  const std::string rgb_frame = "camera_rgb_optical_frame";
  const std::string edvs_frame = "edvs_optical_frame";

  writeStaticMount(bag, ros::Time(clock_origin_s + options.t_begin_s), rgb_frame, depth_from_edvs);

  EventBagWriter event_writer(bag, clock, edvs_camera, edvs_frame, options.event_message_rate_hz);
  const auto on_events = [&](const std::vector<ebslam::TrueDepthEvent>& events) {
    event_writer.add(events);
  };
  std::size_t rgbd_frames = 0;
  const int frame_step =
      std::max(1, static_cast<int>(config.depth.frame_rate_hz / options.rgbd_rate_hz + 0.5));
  int frame_index = 0;
  const auto on_depth = [&](const ebslam::DepthFrame& frame) {
    if (frame_index++ % frame_step != 0) return;
    event_writer.flush();  // events before the frame go first, as a live system would receive them
    std_msgs::Header header;
    header.stamp = ros::Time(clock_origin_s + frame.stamp_s);
    header.frame_id = rgb_frame;
    bag.write("/camera/rgb/image_rect_color", header.stamp,
              ebslam_ros::toImageMsg(frame.colour, "bgr8", header));
    bag.write("/camera/depth_registered/image_raw", header.stamp,
              ebslam_ros::toImageMsg(frame.depth_mm, "16UC1", header));
    const sensor_msgs::CameraInfo info =
        ebslam_ros::toCameraInfoMsg(depth_camera.width, depth_camera.height, depth_camera.fx,
                                    depth_camera.fy, depth_camera.cx, depth_camera.cy, header);
    bag.write("/camera/rgb/camera_info", header.stamp, info);
    bag.write("/camera/depth_registered/camera_info", header.stamp, info);
    ++rgbd_frames;
  };
  const double t_end = std::min(edvs.back().t_s, options.t_begin_s + options.duration_s);
  const ebslam::DedvsRun run =
      simulator.simulate(scene, rig, options.t_begin_s, t_end, on_events, on_depth);
  event_writer.flush();

  const std::size_t ground_truth_poses = writeGroundTruth(bag, run, options, clock_origin_s);
  bag.close();
  copyInTimeOrder(unordered_path, options);
  std::filesystem::remove(unordered_path);
  std::printf(
      "session %s: %.2f s, %zu events in %zu messages (%.0f events/s), %zu RGB-D frames "
      "%dx%d, %zu ground-truth poses, %zu scene planes\n",
      options.output.c_str(), t_end - options.t_begin_s, event_writer.events(),
      event_writer.messages(), event_writer.events() / std::max(1e-9, t_end - options.t_begin_s),
      rgbd_frames, depth_camera.width, depth_camera.height, ground_truth_poses,
      scene.planes.size());
}

// The hand-held D-eDVS session (thesis 8.2-8.4): the simulator's rig (eDVS on top of a
// PrimeSense-like depth camera, dedvs_simulator.h defaults: the calibration of
// config/dedvs_sensors.yaml) carried along a TUM hand-held path through a furnished room, both
// exactly as ebslam_experiment_ebslam3d's D-eDVS source simulates them (the path shifted to start
// at 0 s, makeRoomScene with the table, the scene seed for room, events and depth noise), so that
// the offline tool sees the same events. Topics as live.launch records them from the real rig:
// /edvs/events, /edvs/camera_info, /camera/depth_registered/image_raw (every frame, 30 Hz),
// /camera/depth_registered/camera_info, /camera/rgb/image_rect_color and /camera/rgb/camera_info
// (--rgb-rate), /ground_truth/pose (the eDVS optical frame in `world`, 100 Hz), and unless --no-imu
// /imu (sensor_msgs/Imu in imu_link, 200 Hz, the simulator's IMU seeded by --seed) with the static
// tf edvs_optical_frame -> imu_link on /tf_static (its mounting; the playback's EventSlam3d looks
// it up). No other tf: the rig's is the calibration's (the fusion publishes it), the map's is the
// SLAM's.
void writeDedvsSession(const SessionOptions& options) {
  ebslam::Trajectory rig = ebslam::readTumTrajectory(options.trajectory);
  if (rig.size() < 2) throw std::runtime_error("trajectory has fewer than two poses");
  const double clock_origin_s = rig.front().t_s;
  for (ebslam::StampedPose& pose : rig) pose.t_s -= clock_origin_s;
  ebslam::RoomSceneConfig room;
  room.seed = options.seed;
  const ebslam::Scene scene = ebslam::makeRoomScene(rig, room);
  ebslam::DedvsSimulatorConfig config;
  config.seed = options.seed;
  config.events.seed = options.seed;
  config.depth.camera = config.depth.camera.scaled(options.depth_width / 320.0);
  config.imu.seed = options.seed;
  config.simulate_imu = options.imu;
  const ebslam::DedvsSimulator simulator(config);

  const std::string unordered_path = options.output + ".unordered";
  rosbag::Bag bag(unordered_path, rosbag::bagmode::Write);
  ebslam::EventClock clock;
  clock.anchor(0, ebslam_msgs::toMicroseconds(ros::Time(clock_origin_s)));
  const ebslam::CameraModel& edvs_camera = config.edvs;
  const ebslam::PinholeCamera& depth_camera = config.depth.camera;
  const std::string depth_frame = "camera_rgb_optical_frame";  // registered depth: colour's
  const std::string edvs_frame = "edvs_optical_frame";

  EventBagWriter event_writer(bag, clock, edvs_camera, edvs_frame, options.event_message_rate_hz);
  const auto on_events = [&](const std::vector<ebslam::TrueDepthEvent>& events) {
    event_writer.add(events);
  };
  std::size_t depth_frames = 0, colour_frames = 0;
  const double rgb_rate = options.rgb_rate_hz > 0.0 ? options.rgb_rate_hz : 1e9;
  double next_colour_s = -1.0;
  const auto on_depth = [&](const ebslam::DepthFrame& frame) {
    event_writer.flush();  // events before the frame go first, as a live system would receive them
    std_msgs::Header header;
    header.stamp = ros::Time(clock_origin_s + frame.stamp_s);
    header.frame_id = depth_frame;
    const sensor_msgs::CameraInfo info =
        ebslam_ros::toCameraInfoMsg(depth_camera.width, depth_camera.height, depth_camera.fx,
                                    depth_camera.fy, depth_camera.cx, depth_camera.cy, header);
    bag.write("/camera/depth_registered/image_raw", header.stamp,
              ebslam_ros::toImageMsg(frame.depth_mm, "16UC1", header));
    bag.write("/camera/depth_registered/camera_info", header.stamp, info);
    ++depth_frames;
    if (frame.t_s + 1e-6 >= next_colour_s) {
      next_colour_s = std::max(next_colour_s, frame.t_s) + 1.0 / rgb_rate;
      bag.write("/camera/rgb/image_rect_color", header.stamp,
                ebslam_ros::toImageMsg(frame.colour, "bgr8", header));
      bag.write("/camera/rgb/camera_info", header.stamp, info);
      ++colour_frames;
    }
  };
  const double t_end = std::min(rig.back().t_s, options.t_begin_s + options.duration_s);
  const ebslam::DedvsRun run =
      simulator.simulate(scene, rig, options.t_begin_s, t_end, on_events, on_depth);
  event_writer.flush();

  std::size_t ground_truth_poses = 0;
  double next_t = -1.0;
  for (const ebslam::StampedPose& pose : run.edvs_ground_truth) {
    if (pose.t_s < next_t) continue;
    next_t = pose.t_s + 1.0 / options.ground_truth_rate_hz;
    geometry_msgs::PoseStamped msg;
    msg.header.stamp = ros::Time(clock_origin_s + pose.t_s);
    msg.header.frame_id = "world";
    const geometry_msgs::Transform t = transformMsg(isometryOf(pose));
    msg.pose.position.x = t.translation.x;
    msg.pose.position.y = t.translation.y;
    msg.pose.position.z = t.translation.z;
    msg.pose.orientation = t.rotation;
    bag.write("/ground_truth/pose", msg.header.stamp, msg);
    ++ground_truth_poses;
  }
  if (!run.imu.empty()) {
    const ebslam::ImuSimulatorConfig& c = config.imu;
    const double gyro_var = c.gyro_noise_density * c.gyro_noise_density * c.rate_hz;
    const double accel_var = c.accel_noise_density * c.accel_noise_density * c.rate_hz;
    for (const ebslam::ImuReading& r : run.imu) {
      sensor_msgs::Imu msg;
      msg.header.stamp = ros::Time(clock_origin_s + r.t_s);
      msg.header.frame_id = "imu_link";
      msg.orientation_covariance[0] = -1.0;  // no orientation
      msg.angular_velocity.x = r.gyro.x();
      msg.angular_velocity.y = r.gyro.y();
      msg.angular_velocity.z = r.gyro.z();
      msg.linear_acceleration.x = r.accel.x();
      msg.linear_acceleration.y = r.accel.y();
      msg.linear_acceleration.z = r.accel.z();
      for (std::size_t k = 0; k < 3; ++k) {
        msg.angular_velocity_covariance[4 * k] = gyro_var;  // white noise only
        msg.linear_acceleration_covariance[4 * k] = accel_var;
      }
      bag.write("/imu", msg.header.stamp, msg);
    }
    tf2_msgs::TFMessage statics;
    geometry_msgs::TransformStamped mount;
    mount.header.stamp = ros::Time(clock_origin_s + options.t_begin_s);
    mount.header.frame_id = edvs_frame;
    mount.child_frame_id = "imu_link";
    const Eigen::Quaterniond q = ebslam::edvsFromImu(config);
    mount.transform.rotation.w = q.w();
    mount.transform.rotation.x = q.x();
    mount.transform.rotation.y = q.y();
    mount.transform.rotation.z = q.z();
    statics.transforms.push_back(mount);
    auto header = boost::make_shared<std::map<std::string, std::string>>();
    (*header)["type"] = ros::message_traits::datatype<tf2_msgs::TFMessage>();
    (*header)["md5sum"] = ros::message_traits::md5sum<tf2_msgs::TFMessage>();
    (*header)["message_definition"] = ros::message_traits::definition<tf2_msgs::TFMessage>();
    (*header)["latching"] = "1";
    (*header)["callerid"] = "/make_session";
    bag.write("/tf_static", mount.header.stamp, statics, header);
  }
  bag.close();
  copyInTimeOrder(unordered_path, options);
  std::filesystem::remove(unordered_path);
  std::printf(
      "D-eDVS session %s: %.2f s, %zu events in %zu messages (%.0f events/s), %zu depth frames "
      "and %zu colour frames %dx%d, %zu ground-truth poses, %zu scene planes, %zu IMU readings\n",
      options.output.c_str(), t_end - options.t_begin_s, event_writer.events(),
      event_writer.messages(), event_writer.events() / std::max(1e-9, t_end - options.t_begin_s),
      depth_frames, colour_frames, depth_camera.width, depth_camera.height, ground_truth_poses,
      scene.planes.size(), run.imu.size());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Simulated session bag: floor robot with an upward eDVS and a forward RGB-D camera"};
  SessionOptions options;
  app.add_option("--rig", options.rig,
                 "floor: floor robot, upward eDVS + forward RGB-D camera (--trajectory of a "
                 "wheeled robot); dedvs: the hand-held D-eDVS (--trajectory of the depth camera)")
      ->capture_default_str()
      ->check(CLI::IsMember({"floor", "dedvs"}));
  app.add_option("--trajectory", options.trajectory, "TUM motion capture (see --rig)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--output", options.output, "bag to write")->required();
  app.add_option("--t-begin", options.t_begin_s, "start [s after the trajectory start]")
      ->capture_default_str();
  app.add_option("--duration", options.duration_s, "simulated time [s]")->capture_default_str();
  app.add_option("--rgbd-rate", options.rgbd_rate_hz, "RGB-D frames per second kept [Hz]")
      ->capture_default_str();
  app.add_option("--rgb-rate", options.rgb_rate_hz,
                 "dedvs: colour frames kept per second [Hz] (0: every depth frame)")
      ->capture_default_str();
  app.add_option("--ground-truth-rate", options.ground_truth_rate_hz, "ground-truth poses [Hz]")
      ->capture_default_str();
  app.add_option("--depth-width", options.depth_width, "RGB-D width: 320 or 640")
      ->capture_default_str()
      ->check(CLI::IsMember({320, 640}));
  app.add_option("--boxes", options.box_count, "boxes on the floor")->capture_default_str();
  app.add_option("--seed", options.seed, "seed of the room, events and depth noise")
      ->capture_default_str();
  app.add_flag("!--no-imu", options.imu, "dedvs: no /imu topic (the rig IMU's readings)");
  app.add_option("--compression", options.compression, "bag compression")
      ->capture_default_str()
      ->check(CLI::IsMember({"none", "lz4", "bz2"}));
  CLI11_PARSE(app, argc, argv);
  try {
    if (options.duration_s <= 0.0 || options.rgbd_rate_hz <= 0.0 || options.rgb_rate_hz < 0.0 ||
        options.ground_truth_rate_hz <= 0.0) {
      throw std::invalid_argument(
          "--duration, --rgbd-rate and --ground-truth-rate must be positive, --rgb-rate >= 0");
    }
    if (options.rig == "dedvs") {
      writeDedvsSession(options);
    } else {
      writeSession(options);
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "make_session: %s\n", error.what());
    return 1;
  }
  return 0;
}
