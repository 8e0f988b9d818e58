#pragma once
// Core types <-> ROS messages of ebslam_ros: poses and transforms of the pose nodelets (planar
// ebslam::Pose2 with tf2::Transform, 6-DoF poses as Eigen::Isometry3d: ebslam::Pose3::isometry()
// and Pose3::fromIsometry convert the core's), and the image
// and camera messages of the simulators and bag writers (RgbdEventSimulator, make_session, the
// simulated calibration bag). Event messages are converted by ebslam_msgs/event_conversions.h.
// Lengths in metres, angles in radians; rotations are fixed-axis roll, pitch, yaw as tf2's
// setRPY (R = Rz(yaw) Ry(pitch) Rx(roll)).

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/Transform.h>
#include <geometry_msgs/TransformStamped.h>
#include <ros/time.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/Header.h>
#include <tf2/LinearMath/Transform.h>

#include <ebslam/events/pose.h>
#include <ebslam/slam/camera_model.h>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <array>
#include <string>

namespace ebslam_ros {

/// A planar pose (x, y, theta about z) as a pose message at z = 0.
geometry_msgs::Pose toPoseMsg(const ebslam::Pose2& pose);
/// A rigid transform as a pose message (its rotation as a quaternion).
geometry_msgs::Pose toPoseMsg(const Eigen::Isometry3d& transform);
/// A planar pose as a tf2 transform at z = 0.
tf2::Transform toTransform(const ebslam::Pose2& pose);

/// parent -> child at `stamp`.
geometry_msgs::TransformStamped toTransformMsg(const tf2::Transform& transform,
                                               const ros::Time& stamp, const std::string& parent,
                                               const std::string& child);
geometry_msgs::TransformStamped toTransformMsg(const Eigen::Isometry3d& transform,
                                               const ros::Time& stamp, const std::string& parent,
                                               const std::string& child);

/// A transform message as an isometry (quaternion normalised).
Eigen::Isometry3d toIsometry(const geometry_msgs::Transform& transform);
/// Translation `xyz` and fixed-axis roll, pitch, yaw.
Eigen::Isometry3d fromXyzRpy(const std::array<double, 3>& xyz, const std::array<double, 3>& rpy);
/// base_link -> sensor of a pose nodelet's parameter file (e.g. config/ebslam3d.yaml): its
/// mount_xyz and mount_rpy lists as the nodelet reads them (the one place the tools and tests
/// take the EB-SLAM-3D mounting from). Throws std::runtime_error naming the file when it cannot
/// be read or lacks either list, or a list is not three numbers.
Eigen::Isometry3d readMountFromParams(const std::string& params_yaml);

/// CameraInfo of a rectified pinhole camera (plumb_bob, zero distortion, R = I, P = [K | 0]);
/// focal lengths and principal point in pixels.
sensor_msgs::CameraInfo toCameraInfoMsg(int width, int height, double fx, double fy, double cx,
                                        double cy, const std_msgs::Header& header);

/// An event camera's lens as CameraInfo (R = I, P = [K | 0]: event cameras are not rectified):
/// kPlumbBob as "plumb_bob" with D = (k1, k2, p1, p2, k3), kEquidistant as "equidistant" with
/// D = (k1, k2, k3, k4); the thesis' radial lenses as "ebslam_eq63", "ebslam_eq83",
/// "ebslam_eq81" with D = (kappa1 [1/px], kappa2 [1/px^2]) (only ebslam reads these).
sensor_msgs::CameraInfo toCameraInfoMsg(const ebslam::CameraModel& camera,
                                        const std_msgs::Header& header);
/// The lens of a CameraInfo (the inverse of the above; also "rational_polynomial" whose k4-k6
/// are 0, "fisheye" for "equidistant", an empty model with an empty D for a pinhole). Throws
/// std::invalid_argument naming the field for a zero size, a K that is not finite or has skew
/// or non-positive focal lengths, binning or an ROI, an unknown distortion model or a D of
/// the wrong length, and a lens that cannot be inverted over the sensor (CameraModel::validate).
ebslam::CameraModel toCameraModel(const sensor_msgs::CameraInfo& info);

/// An image as a message of `encoding` (little-endian, rows packed: step = cols x element size),
/// copied row by row so that a non-continuous view (an ROI) is fine. Throws
/// std::invalid_argument for an empty image or one too large for the message's 32-bit sizes.
sensor_msgs::Image toImageMsg(const cv::Mat& image, const std::string& encoding,
                              const std_msgs::Header& header);

}  // namespace ebslam_ros
