#pragma once
// The synchronised RGB-D input of the segmentation nodelets: colour image, registered depth image
// and the colour camera_info (rgbd_launch / openni2_launch names), matched by exact stamps or
// approximately, images through image_transport. Reports which input is missing when frames stop
// matching, and converts a matched triple into a dasp::RgbdFrame naming the topic at fault.

#include <dasp/dasp.h>
#include <image_transport/image_transport.h>
#include <image_transport/subscriber_filter.h>
#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/sync_policies/exact_time.h>
#include <message_filters/synchronizer.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <array>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include "dasp_ros/conversions.h"
#include "dasp_ros/ros_params.h"

namespace dasp_ros {

/// Relative input names (the community's RGB-D driver convention).
inline constexpr const char* kColorTopic = "rgb/image_rect_color";
inline constexpr const char* kDepthTopic = "depth_registered/image_raw";
inline constexpr const char* kInfoTopic = "rgb/camera_info";

/// A message that cannot be used, with the (resolved) topic it came from.
class InputError : public std::invalid_argument {
 public:
  InputError(std::string topic, const std::string& reason)
      : std::invalid_argument(topic + ": " + reason), topic_(std::move(topic)) {}
  const std::string& topic() const { return topic_; }

 private:
  std::string topic_;
};

/// Throttles log messages per reason rather than per call site, so that a new kind of bad input
/// is reported at once while a repeating one is reported once per period. The key is the text
/// without its digits (numbers such as stamps and sizes vary between repetitions).
class ReasonThrottle {
 public:
  explicit ReasonThrottle(double period_s = 1.0) : period_s_(period_s) {}
  /// True when a message with this reason may be logged now.
  bool allow(const std::string& reason);

 private:
  double period_s_;
  std::mutex mutex_;
  std::map<std::string, ros::WallTime> last_;
};

class RgbdInput {
 public:
  using Callback =
      std::function<void(const sensor_msgs::ImageConstPtr&, const sensor_msgs::ImageConstPtr&,
                         const sensor_msgs::CameraInfoConstPtr&)>;

  RgbdInput(ros::NodeHandle& nh, const RgbdInputConfig& config, Callback on_frame);

  /// Registered RGB-D frame of a matched triple; throws InputError naming the topic at fault
  /// (encoding, empty or short image, sizes that differ, zero or non-finite intrinsics,
  /// camera_info of another size, no valid depth pixel). `data`: ImageData::kShare when the
  /// frame does not outlive the messages (bgr8 and millimetre depth are then not copied).
  dasp::RgbdFrame convert(const sensor_msgs::Image& color, const sensor_msgs::Image& depth,
                          const sensor_msgs::CameraInfo& info,
                          ImageData data = ImageData::kCopy) const {
    return convert(color, depth, info, topics_, data);
  }
  /// As above, naming the topics colour, depth, camera_info (ROS-free: the fuzz targets run it).
  static dasp::RgbdFrame convert(const sensor_msgs::Image& color, const sensor_msgs::Image& depth,
                                 const sensor_msgs::CameraInfo& info,
                                 const std::array<std::string, 3>& topics,
                                 ImageData data = ImageData::kCopy);

  /// Empty while frames match; otherwise why they do not, e.g. which input has been silent for
  /// how long while the others arrive. Call about once a second.
  std::string stallReason();

  const std::string& colorTopic() const { return topics_[0]; }
  const std::string& depthTopic() const { return topics_[1]; }
  const std::string& infoTopic() const { return topics_[2]; }
  /// Messages received per input since the start.
  std::array<std::size_t, 3> receivedCounts() const;
  std::size_t matchedCount() const;

  /// Also counts the camera_infos as they arrive, through a subscription on `arrivals_nh` (a
  /// nodelet's multi-threaded handle, so that the count goes on while a frame is processed):
  /// frames that arrive while the node is busy and are dropped by the subscription queues
  /// are counted rather than lost silently.
  void countArrivals(ros::NodeHandle& arrivals_nh);
  /// camera_infos counted since countArrivals (0 without it).
  std::size_t arrivedCount() const;

 private:
  using Image = sensor_msgs::Image;
  using Info = sensor_msgs::CameraInfo;
  using ExactPolicy = message_filters::sync_policies::ExactTime<Image, Image, Info>;
  using ApproximatePolicy = message_filters::sync_policies::ApproximateTime<Image, Image, Info>;

  void received(int input);
  void matched(const sensor_msgs::ImageConstPtr& color, const sensor_msgs::ImageConstPtr& depth,
               const sensor_msgs::CameraInfoConstPtr& info);

  Callback on_frame_;
  std::array<std::string, 3> topics_;
  image_transport::ImageTransport transport_;
  image_transport::SubscriberFilter color_sub_, depth_sub_;
  message_filters::Subscriber<Info> info_sub_;
  std::unique_ptr<message_filters::Synchronizer<ExactPolicy>> exact_sync_;
  std::unique_ptr<message_filters::Synchronizer<ApproximatePolicy>> approximate_sync_;

  mutable std::mutex mutex_;
  std::array<std::size_t, 3> received_{};
  std::array<ros::WallTime, 3> last_received_{};
  std::size_t matched_ = 0, arrived_ = 0;
  ros::Subscriber arrivals_sub_;
  ros::WallTime last_matched_;
  ros::WallTime started_;
};

}  // namespace dasp_ros
