#include "ebslam_ros/bag_trajectory.h"

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <stdexcept>

namespace ebslam_ros {
namespace {

ebslam::StampedPose toStamped(const ros::Time& stamp, const geometry_msgs::Point& p,
                              const geometry_msgs::Quaternion& q) {
  ebslam::StampedPose pose;
  pose.t_s = stamp.toSec();
  pose.position = {p.x, p.y, p.z};
  pose.orientation = Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized();
  return pose;
}

}  // namespace

BagTrajectory readBagTrajectory(const std::string& bag_path, const std::string& topic) {
  rosbag::Bag bag;
  try {
    bag.open(bag_path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& error) {
    throw std::runtime_error("cannot read bag '" + bag_path + "': " + error.what());
  }
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  if (view.size() == 0) {
    throw std::runtime_error("bag '" + bag_path + "' has no messages on '" + topic + "'");
  }
  BagTrajectory result;
  for (const rosbag::MessageInstance& m : view) {
    std::string frame;
    ebslam::StampedPose pose;
    if (auto a = m.instantiate<geometry_msgs::PoseStamped>()) {
      frame = a->header.frame_id;
      pose = toStamped(a->header.stamp, a->pose.position, a->pose.orientation);
    } else if (auto b = m.instantiate<geometry_msgs::PoseWithCovarianceStamped>()) {
      frame = b->header.frame_id;
      pose = toStamped(b->header.stamp, b->pose.pose.position, b->pose.pose.orientation);
    } else if (auto c = m.instantiate<nav_msgs::Odometry>()) {
      frame = c->header.frame_id;
      pose = toStamped(c->header.stamp, c->pose.pose.position, c->pose.pose.orientation);
    } else if (auto d = m.instantiate<geometry_msgs::TransformStamped>()) {
      frame = d->header.frame_id;
      geometry_msgs::Point p;
      p.x = d->transform.translation.x;
      p.y = d->transform.translation.y;
      p.z = d->transform.translation.z;
      pose = toStamped(d->header.stamp, p, d->transform.rotation);
    } else {
      throw std::runtime_error("topic '" + topic + "' has type " + m.getDataType() +
                               ", not a stamped pose");
    }
    if (result.messages++ == 0) {
      result.frame_id = frame;
    } else if (frame != result.frame_id) {
      throw std::runtime_error("topic '" + topic + "' mixes frames '" + result.frame_id +
                               "' and '" + frame + "'");
    }
    if (!result.trajectory.empty() && pose.t_s <= result.trajectory.back().t_s) {
      ++result.dropped;
      continue;
    }
    result.trajectory.push_back(pose);
  }
  return result;
}

}  // namespace ebslam_ros
