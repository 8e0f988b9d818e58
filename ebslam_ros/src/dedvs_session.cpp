#include "ebslam_ros/dedvs_session.h"

#include <ebslam_msgs/EventArray.h>
#include <geometry_msgs/PoseStamped.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "ebslam_msgs/event_conversions.h"
#include "ebslam_msgs/event_packet_conversions.h"

namespace ebslam_ros {

DedvsSession readDedvsSession(const std::string& bag_path, const DedvsSessionTopics& topics) {
  rosbag::Bag bag;
  try {
    bag.open(bag_path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& error) {
    throw std::runtime_error("cannot read bag '" + bag_path + "': " + error.what());
  }
  DedvsSession session;
  rosbag::View view(bag, rosbag::TopicQuery({topics.events, topics.depth, topics.ground_truth}));
  ebslam_msgs::EventPacketConverter event_packets;  // decoder state of the events topic
  for (const rosbag::MessageInstance& m : view) {
    if (m.getTopic() == topics.events) {
      if (ebslam_msgs::appendRecordedEvents(m, event_packets, session.events)) {
        ++session.event_messages;
      }
    } else if (m.getTopic() == topics.depth) {
      auto msg = m.instantiate<sensor_msgs::Image>();
      if (!msg) continue;
      if (msg->encoding != sensor_msgs::image_encodings::TYPE_16UC1 &&
          msg->encoding != sensor_msgs::image_encodings::MONO16) {
        throw std::runtime_error("depth image of encoding '" + msg->encoding +
                                 "' in the session: 16UC1 (mm) expected");
      }
      DepthFrameRecord frame;
      frame.stamp_s = msg->header.stamp.toSec();
      frame.depth_mm.create(static_cast<int>(msg->height), static_cast<int>(msg->width), CV_16UC1);
      for (int r = 0; r < frame.depth_mm.rows; ++r) {
        std::memcpy(frame.depth_mm.ptr(r), &msg->data[static_cast<std::size_t>(r) * msg->step],
                    static_cast<std::size_t>(msg->width) * 2u);
      }
      session.depth_frames.push_back(std::move(frame));
    } else if (auto pose = m.instantiate<geometry_msgs::PoseStamped>()) {
      ebslam::StampedPose p;
      p.t_s = pose->header.stamp.toSec();
      p.position = {pose->pose.position.x, pose->pose.position.y, pose->pose.position.z};
      const auto& q = pose->pose.orientation;
      p.orientation = Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized();
      if (session.ground_truth.empty() || p.t_s > session.ground_truth.back().t_s) {
        session.ground_truth.push_back(p);
      }
    }
  }
  if (session.events.empty()) throw std::runtime_error("no events on " + topics.events);
  if (session.depth_frames.empty()) throw std::runtime_error("no depth frames on " + topics.depth);
  if (session.ground_truth.size() < 2) {
    throw std::runtime_error("fewer than two ground-truth poses on " + topics.ground_truth);
  }
  return session;
}

OfflineEbslam3dRun runOfflineEbslam3d(const DedvsSession& session,
                                      const ebslam::DedvsSensors& sensors,
                                      const ebslam::DepthFusionConfig& fusion_config,
                                      const ebslam::Ebslam3dConfig& slam_config,
                                      double record_step_s) {
  if (session.events.empty()) throw std::runtime_error("the session has no events");
  ebslam::DepthEventFusion fusion(sensors, fusion_config);
  ebslam::EventSlam3d slam(slam_config);
  const auto step_us = static_cast<std::int64_t>(std::llround(record_step_s * 1e6));
  OfflineEbslam3dRun run;
  ebslam::PointEventVector chunk;
  auto flush = [&] {
    if (chunk.empty()) return;
    slam.process(chunk);
    ebslam::StampedPose p;
    p.t_s = 1e-6 * static_cast<double>(chunk.back().t_us);
    p.position = slam.estimate().position;
    p.orientation = slam.estimate().orientation;
    if (run.estimate.empty() || p.t_s > run.estimate.back().t_s) run.estimate.push_back(p);
    chunk.clear();
  };
  auto add = [&](const ebslam::PointEvent& e) {
    if (!chunk.empty() && e.t_us >= chunk.front().t_us + step_us) flush();
    chunk.push_back(e);
  };
  // As the experiment tool: an event is fused once the frame after it has arrived, so it takes
  // the frame nearest in time (exposure = stamp - the depth clock offset).
  std::size_t next = 0;
  auto fuseUpTo = [&](double t_end_s) {
    for (; next < session.events.size() &&
           1e-6 * static_cast<double>(session.events[next].t_us) <= t_end_s;
         ++next) {
      const ebslam::FusedEvent f = fusion.fuse(session.events[next]);
      if (!std::isfinite(f.depth_m)) {
        ++run.events_without_depth;
        continue;
      }
      ++run.events_with_depth;
      ebslam::PointEvent p;
      p.t_us = f.event.t_us;
      p.point = f.point;
      add(p);
    }
  };
  for (const DepthFrameRecord& frame : session.depth_frames) {
    fusion.addDepthFrame(frame.depth_mm, frame.stamp_s);
    fuseUpTo(frame.stamp_s - sensors.depth_clock_offset_s);
  }
  fuseUpTo(INFINITY);
  flush();
  run.used_events = static_cast<std::size_t>(slam.processedEvents());
  return run;
}

ebslam::TrajectoryEvaluation evaluateEdvsTrajectory(const ebslam::Trajectory& estimate,
                                                    const ebslam::Trajectory& ground_truth) {
  ebslam::TrajectoryEvaluationConfig config;
  config.max_time_offset_s = 0.2;
  config.estimate_body_rotation = false;
  return ebslam::evaluateTrajectory(estimate, ground_truth, config);
}

}  // namespace ebslam_ros
