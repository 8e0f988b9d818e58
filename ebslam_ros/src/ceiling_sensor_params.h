#pragma once
// The upward-looking eDVS of the floor-robot nodelets (EB-PF, EB-SLAM-2D, the event and
// closed-loop simulators): ~camera/* and ~ceiling_distance.

#include <ros/node_handle.h>

#include <ebslam/slam/camera_model.h>

namespace ebslam_ros {

/// The upward-looking eDVS (thesis 6.5.1): lens and ceiling distance.
struct CeilingSensorConfig {
  ebslam::CameraModel camera;        ///< ~camera/{width, height, focal_px, cx, cy, kappa1, kappa2}
  double ceiling_distance_m = 2.59;  ///< ~ceiling_distance: sensor to ceiling D [m]
};

CeilingSensorConfig loadCeilingSensorConfig(const ros::NodeHandle& private_nh);

}  // namespace ebslam_ros
