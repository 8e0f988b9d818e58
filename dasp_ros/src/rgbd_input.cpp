#include "dasp_ros/rgbd_input.h"

#include <cstdio>
#include <opencv2/core.hpp>

#include "dasp_ros/conversions.h"

namespace dasp_ros {

bool ReasonThrottle::allow(const std::string& reason) {
  std::string key;
  for (char c : reason) {
    if (c < '0' || c > '9') key += c;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  const ros::WallTime now = ros::WallTime::now();
  auto it = last_.find(key);
  if (it != last_.end() && (now - it->second).toSec() < period_s_) return false;
  if (last_.size() > 64) last_.clear();  // bounded: old reasons are simply forgotten
  last_[key] = now;
  return true;
}

RgbdInput::RgbdInput(ros::NodeHandle& nh, const RgbdInputConfig& config, Callback on_frame)
    : on_frame_(std::move(on_frame)),
      topics_{nh.resolveName(kColorTopic), nh.resolveName(kDepthTopic), nh.resolveName(kInfoTopic)},
      transport_(nh),
      started_(ros::WallTime::now()) {
  const uint32_t queue = static_cast<uint32_t>(config.queue_size);
  color_sub_.subscribe(transport_, kColorTopic, queue);
  depth_sub_.subscribe(transport_, kDepthTopic, queue);
  info_sub_.subscribe(nh, kInfoTopic, queue);
  color_sub_.registerCallback(
      std::function<void(const sensor_msgs::ImageConstPtr&)>([this](const auto&) { received(0); }));
  depth_sub_.registerCallback(
      std::function<void(const sensor_msgs::ImageConstPtr&)>([this](const auto&) { received(1); }));
  info_sub_.registerCallback(std::function<void(const sensor_msgs::CameraInfoConstPtr&)>(
      [this](const auto&) { received(2); }));
  if (config.approximate_sync) {
    approximate_sync_ = std::make_unique<message_filters::Synchronizer<ApproximatePolicy>>(
        ApproximatePolicy(queue), color_sub_, depth_sub_, info_sub_);
    approximate_sync_->registerCallback(&RgbdInput::matched, this);
  } else {
    exact_sync_ = std::make_unique<message_filters::Synchronizer<ExactPolicy>>(
        ExactPolicy(queue), color_sub_, depth_sub_, info_sub_);
    exact_sync_->registerCallback(&RgbdInput::matched, this);
  }
}

void RgbdInput::received(int input) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++received_[static_cast<std::size_t>(input)];
  last_received_[static_cast<std::size_t>(input)] = ros::WallTime::now();
}

void RgbdInput::matched(const sensor_msgs::ImageConstPtr& color,
                        const sensor_msgs::ImageConstPtr& depth,
                        const sensor_msgs::CameraInfoConstPtr& info) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++matched_;
    last_matched_ = ros::WallTime::now();
  }
  on_frame_(color, depth, info);
}

std::array<std::size_t, 3> RgbdInput::receivedCounts() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return received_;
}

void RgbdInput::countArrivals(ros::NodeHandle& arrivals_nh) {
  constexpr uint32_t kQueue = 100;  // the callback only counts: it never falls behind
  arrivals_sub_ = arrivals_nh.subscribe<Info>(kInfoTopic, kQueue, [this](const auto&) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++arrived_;
  });
}

std::size_t RgbdInput::arrivedCount() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return arrived_;
}

std::size_t RgbdInput::matchedCount() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return matched_;
}

std::string RgbdInput::stallReason() {
  constexpr double kStallSeconds = 2.0;
  std::lock_guard<std::mutex> lock(mutex_);
  const ros::WallTime now = ros::WallTime::now();
  const ros::WallTime since = last_matched_.isZero() ? started_ : last_matched_;
  if ((now - since).toSec() < kStallSeconds) return "";
  bool any_recent = false;
  for (const ros::WallTime& t : last_received_) {
    any_recent = any_recent || (!t.isZero() && (now - t).toSec() < kStallSeconds);
  }
  if (!any_recent) return "";  // nothing arrives at all: the stream is idle, not broken
  std::string reason;
  for (std::size_t i = 0; i < topics_.size(); ++i) {
    const bool silent =
        last_received_[i].isZero() || (now - last_received_[i]).toSec() >= kStallSeconds;
    if (!silent) continue;
    char text[256];
    if (last_received_[i].isZero()) {
      std::snprintf(text, sizeof(text), "%s has published nothing", topics_[i].c_str());
    } else {
      std::snprintf(text, sizeof(text), "%s silent for %.1f s", topics_[i].c_str(),
                    (now - last_received_[i]).toSec());
    }
    reason += (reason.empty() ? "" : "; ") + std::string(text);
  }
  if (reason.empty()) {
    reason = "colour, depth and camera_info arrive but their stamps never match (" +
             std::string(exact_sync_ ? "exact" : "approximate") + " sync): " +
             (exact_sync_ ? "set ~approximate_sync if the driver stamps them apart"
                          : "are the three from one camera?");
  }
  char text[96];
  std::snprintf(text, sizeof(text), "no RGB-D frame for %.1f s: ", (now - since).toSec());
  return text + reason;
}

dasp::RgbdFrame RgbdInput::convert(const sensor_msgs::Image& color, const sensor_msgs::Image& depth,
                                   const sensor_msgs::CameraInfo& info,
                                   const std::array<std::string, 3>& topics, ImageData data) {
  const std::string& color_topic = topics[0];
  const std::string& depth_topic = topics[1];
  const std::string& info_topic = topics[2];
  dasp::RgbdFrame frame;
  try {
    frame.color = toColorMat(color, data);
  } catch (const std::invalid_argument& e) {
    throw InputError(color_topic, e.what());
  }
  try {
    frame.depth = toDepthMat(depth, data);
  } catch (const std::invalid_argument& e) {
    throw InputError(depth_topic, e.what());
  }
  if (color.width != depth.width || color.height != depth.height) {
    throw InputError(depth_topic, "depth image " + std::to_string(depth.width) + "x" +
                                      std::to_string(depth.height) + " differs from the colour " +
                                      std::to_string(color.width) + "x" +
                                      std::to_string(color.height) + " of " + color_topic +
                                      ": it must be registered to it");
  }
  if ((info.width != 0 || info.height != 0) &&
      (info.width != color.width || info.height != color.height)) {
    throw InputError(info_topic, "camera_info is for " + std::to_string(info.width) + "x" +
                                     std::to_string(info.height) + ", the images are " +
                                     std::to_string(color.width) + "x" +
                                     std::to_string(color.height));
  }
  try {
    frame.intrinsics = toIntrinsics(info);
  } catch (const std::invalid_argument& e) {
    throw InputError(info_topic, e.what());
  }
  if (cv::countNonZero(frame.depth) == 0) {
    throw InputError(depth_topic, "no valid depth pixel in the " + depth.encoding +
                                      " image (all zero, NaN or out of range)");
  }
  return frame;
}

}  // namespace dasp_ros
