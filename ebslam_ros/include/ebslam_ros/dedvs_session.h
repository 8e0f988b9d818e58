#pragma once
// A recorded D-eDVS session (eDVS events, registered depth frames, ground truth in a bag, as
// make_session --rig dedvs writes it and record.launch records the real rig) run through the
// offline EB-SLAM-3D core exactly as ebslam_experiment_ebslam3d runs its D-eDVS source: every
// event fused with the depth frame nearest in time (dedvs_fusion.h), the events with a depth fed
// to EventSlam3d in chunks of record_step_s of event time, one estimate per chunk. The reference
// the ROS pipeline (playback.launch slam:=ebslam3d) is compared with (rostest
// ebslam3d_playback.test, tool dedvs_session_eval, make demo).

#include <ebslam/events/event.h>
#include <ebslam/events/trajectory.h>
#include <ebslam/events/trajectory_evaluation.h>
#include <ebslam/simulation/dedvs_io.h>
#include <ebslam/slam/dedvs_fusion.h>
#include <ebslam/slam/ebslam3d.h>

#include <opencv2/core.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace ebslam_ros {

struct DedvsSessionTopics {
  std::string events = "/edvs/events";                       ///< ebslam_msgs/EventArray
  std::string depth = "/camera/depth_registered/image_raw";  ///< sensor_msgs/Image 16UC1 mm
  std::string ground_truth = "/ground_truth/pose";           ///< geometry_msgs/PoseStamped
};

struct DepthFrameRecord {
  double stamp_s = 0.0;  ///< header.stamp [s] (the depth camera's clock)
  cv::Mat depth_mm;      ///< CV_16UC1 [mm], 0 = no depth
};

struct DedvsSession {
  ebslam::EventVector events;  ///< t_us = event ts [us since the ROS epoch], bag order
  std::vector<DepthFrameRecord> depth_frames;  ///< bag order
  ebslam::Trajectory ground_truth;  ///< eDVS optical frame in the truth's frame, by header.stamp
  std::size_t event_messages = 0;
};

/// Reads the session's topics. Throws std::runtime_error for an unreadable bag, a missing
/// topic, or depth frames that are not 16UC1.
DedvsSession readDedvsSession(const std::string& bag_path, const DedvsSessionTopics& topics = {});

struct OfflineEbslam3dRun {
  ebslam::Trajectory estimate;  ///< eDVS optical frame in the SLAM's map, one pose per chunk
  std::size_t events_with_depth = 0, events_without_depth = 0;
  std::size_t used_events = 0;  ///< events the filter used (its max_event_rate thins them)
};

/// EB-SLAM-3D on the session's events fused with its depth frames (see the file comment); the
/// frames' stamps minus sensors.depth_clock_offset_s are exposure times on the event clock.
/// Throws std::invalid_argument for configurations the core rejects, std::runtime_error for a
/// session without events.
OfflineEbslam3dRun runOfflineEbslam3d(const DedvsSession& session,
                                      const ebslam::DedvsSensors& sensors,
                                      const ebslam::DepthFusionConfig& fusion,
                                      const ebslam::Ebslam3dConfig& slam,
                                      double record_step_s = 0.01);

/// The scoring of ebslam_experiment_ebslam3d (table 8.1): rigid alignment with a time offset
/// searched within +-0.2 s (eq. 8.16-8.19), no body rotation.
ebslam::TrajectoryEvaluation evaluateEdvsTrajectory(const ebslam::Trajectory& estimate,
                                                    const ebslam::Trajectory& ground_truth);

}  // namespace ebslam_ros
