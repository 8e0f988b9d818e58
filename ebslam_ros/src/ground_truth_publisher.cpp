#include "ebslam_ros/ground_truth_publisher.h"

#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Path.h>

#include <cmath>
#include <utility>

namespace ebslam_ros {

GroundTruthPublisher::GroundTruthPublisher(ros::NodeHandle& nh, std::string map_frame,
                                           std::string ground_truth_frame, std::size_t path_length)
    : map_frame_(std::move(map_frame)),
      ground_truth_frame_(std::move(ground_truth_frame)),
      path_length_(path_length),
      pose_pub_(nh.advertise<geometry_msgs::PoseStamped>("ground_truth/pose", 100)),
      path_pub_(nh.advertise<nav_msgs::Path>("ground_truth/path", 1, true)) {}

void GroundTruthPublisher::publish(const ebslam::StampedPose& pose, const ros::Time& stamp,
                                   bool path_due) {
  geometry_msgs::PoseStamped msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = map_frame_;
  msg.pose.position.x = pose.position.x();
  msg.pose.position.y = pose.position.y();
  msg.pose.position.z = pose.position.z();
  msg.pose.orientation.x = pose.orientation.x();
  msg.pose.orientation.y = pose.orientation.y();
  msg.pose.orientation.z = pose.orientation.z();
  msg.pose.orientation.w = pose.orientation.w();
  pose_pub_.publish(msg);
  geometry_msgs::TransformStamped tf;
  tf.header = msg.header;
  tf.child_frame_id = ground_truth_frame_;
  tf.transform.translation.x = msg.pose.position.x;
  tf.transform.translation.y = msg.pose.position.y;
  tf.transform.translation.z = msg.pose.position.z;
  tf.transform.rotation = msg.pose.orientation;
  tf_broadcaster_.sendTransform(tf);
  path_.push_back(msg);
  while (path_.size() > path_length_) path_.pop_front();
  if (path_due && path_pub_.getNumSubscribers() > 0) {
    nav_msgs::Path path;
    path.header = msg.header;
    path.poses.assign(path_.begin(), path_.end());
    path_pub_.publish(path);
  }
}

void GroundTruthPublisher::publishAlignedFrame(const ebslam::StampedPose& start,
                                               const std::string& frame) {
  const Eigen::Vector3d heading = start.orientation * Eigen::Vector3d::UnitX();
  const double yaw = std::atan2(heading.y(), heading.x());
  geometry_msgs::TransformStamped tf;
  tf.header.stamp = ros::Time::now();
  tf.header.frame_id = map_frame_;
  tf.child_frame_id = frame;
  tf.transform.translation.x = start.position.x();
  tf.transform.translation.y = start.position.y();
  tf.transform.translation.z = 0.0;
  tf.transform.rotation.z = std::sin(0.5 * yaw);
  tf.transform.rotation.w = std::cos(0.5 * yaw);
  static_broadcaster_.sendTransform(tf);
}

}  // namespace ebslam_ros
