// Event image for rviz and image_view (the role of rpg_dvs_ros' dvs_renderer).
// Subscribes `events` (ebslam_msgs/EventArray) and, optionally, `image` (sensor_msgs/Image mono8,
// bgr8 or rgb8 of the same size: the picture drawn under the events). Publishes `event_image`
// (sensor_msgs/Image bgr8, width x height of the events) every 1 / ~publish_rate s of wall time
// while subscribed: the events of the last ~accumulation_time seconds of event time, ON in
// ~on_colour and OFF in ~off_colour ([r, g, b]) over black or the newest `image`; stamp = the
// newest event's ts, frame = the events' frame. Nothing is published before the first event.
// Diagnostics: messages, events, images, bad sizes and the decoder's counters.
#include <diagnostic_updater/diagnostic_updater.h>
#include <ebslam_ros_common/ros_param_helpers.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>

#include <ebslam_msgs/EventArray.h>

#include <array>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <pluginlib/class_list_macros.hpp>
#include <stdexcept>

#include "ebslam_ros/event_input.h"
#include "event_renderer_params.h"

namespace ebslam_ros {

class EventRendererNodelet : public nodelet::Nodelet {
 private:
  static constexpr double kWarnPeriodS = 5.0;
  static constexpr std::uint32_t kMaxSide = 4096;  // [px]

  void onInit() override {
    // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
    ebslam_ros_common::startOrFail(getPrivateNodeHandle(), "event renderer " + getName(), [&] {
      config_ = loadEventRendererConfig(getPrivateNodeHandle());
      input_type_ = readEventInputType(getPrivateNodeHandle());
    });
    ros::NodeHandle& nh = getNodeHandle();
    image_pub_ = nh.advertise<sensor_msgs::Image>("event_image", 1);
    events_sub_.subscribe(
        nh, "events", static_cast<std::uint32_t>(config_.queue_size), input_type_,
        [this](const ebslam_msgs::EventArray::ConstPtr& msg) { onEvents(msg); },
        ros::TransportHints(), getName());
    image_sub_ = nh.subscribe("image", 1, &EventRendererNodelet::onImage, this);
    timer_ = nh.createWallTimer(ros::WallDuration(1.0 / config_.publish_rate_hz),
                                &EventRendererNodelet::render, this);
    diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh, getPrivateNodeHandle());
    diagnostics_->setHardwareID("none");
    diagnostics_->add(getName(), this, &EventRendererNodelet::diagnose);
    diagnostics_timer_ =
        nh.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) {
          std::lock_guard<std::mutex> lock(mutex_);
          diagnostics_->update();
        });
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
    using diagnostic_msgs::DiagnosticStatus;
    if (rejected_size_ > rejected_size_reported_) {
      status.summary(DiagnosticStatus::WARN, "bad input since the last report (see the log)");
    } else if (width_ == 0) {
      status.summary(DiagnosticStatus::OK, "waiting for events");
    } else {
      status.summary(DiagnosticStatus::OK, "rendering");
    }
    rejected_size_reported_ = rejected_size_;
    status.add("messages", messages_);
    status.add("events received", events_in_);
    status.add("messages of a bad sensor size", rejected_size_);
    status.add("images published", images_);
    status.add("events in the accumulation window", events_.size());
    addDecoderDiagnostics(events_sub_, status);
  }

  void onEvents(const ebslam_msgs::EventArray::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++messages_;
    events_in_ += msg->events.size();
    if (msg->events.empty()) return;
    // Bounded so that the rendered image stays small (4096 x 4096 bgr8 = 48 MiB): a bogus size
    // such as 65535 x 65535 would make render() allocate 12 GiB.
    if (msg->width == 0 || msg->height == 0 || msg->width > kMaxSide || msg->height > kMaxSide) {
      ++rejected_size_;
      NODELET_ERROR_THROTTLE(kWarnPeriodS,
                             "EventArray of a %ux%u sensor ignored: width and height must be in "
                             "1..%u",
                             msg->width, msg->height, kMaxSide);
      return;
    }
    if (msg->width != width_ || msg->height != height_) {
      if (width_ != 0) {
        NODELET_WARN_THROTTLE(kWarnPeriodS, "sensor size changed from %ux%u to %ux%u", width_,
                              height_, msg->width, msg->height);
      }
      width_ = msg->width;
      height_ = msg->height;
      events_.clear();
    }
    frame_id_ = msg->header.frame_id;
    const ros::Time newest = msg->events.back().ts;
    if (!events_.empty() && newest < events_.back().ts) events_.clear();  // time jumped back
    for (const ebslam_msgs::Event& e : msg->events) events_.push_back(e);
    // Clamped at time 0: ros::Time throws below it (events stamped near 0, e.g. sim time with
    // no /clock yet).
    const ros::Time oldest = newest.toSec() > config_.accumulation_time_s
                                 ? newest - ros::Duration(config_.accumulation_time_s)
                                 : ros::Time(0, 0);
    while (!events_.empty() && events_.front().ts < oldest) events_.pop_front();
  }

  void onImage(const sensor_msgs::Image::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    background_ = msg;
  }

  void render(const ros::WallTimerEvent&) {
    if (image_pub_.getNumSubscribers() == 0) return;
    std::lock_guard<std::mutex> lock(mutex_);
    if (width_ == 0 || events_.empty()) return;
    sensor_msgs::Image image;
    image.header.stamp = events_.back().ts;
    image.header.frame_id = frame_id_;
    image.width = width_;
    image.height = height_;
    image.encoding = sensor_msgs::image_encodings::BGR8;
    image.step = 3 * width_;
    image.data.assign(static_cast<std::size_t>(image.step) * height_, 0);
    if (background_) drawBackground(*background_, image);
    for (const ebslam_msgs::Event& e : events_) {
      if (e.x >= width_ || e.y >= height_) continue;
      const std::array<int, 3>& rgb = e.polarity ? config_.on_rgb : config_.off_rgb;
      std::uint8_t* p = &image.data[static_cast<std::size_t>(e.y) * image.step + 3 * e.x];
      p[0] = static_cast<std::uint8_t>(rgb[2]);
      p[1] = static_cast<std::uint8_t>(rgb[1]);
      p[2] = static_cast<std::uint8_t>(rgb[0]);
    }
    image_pub_.publish(image);
    ++images_;
  }

  void drawBackground(const sensor_msgs::Image& in, sensor_msgs::Image& out) {
    namespace enc = sensor_msgs::image_encodings;
    const bool mono = in.encoding == enc::MONO8;
    const bool bgr = in.encoding == enc::BGR8;
    const bool rgb = in.encoding == enc::RGB8;
    if (in.width != out.width || in.height != out.height || !(mono || bgr || rgb) ||
        in.step < in.width * (mono ? 1u : 3u) ||
        in.data.size() < static_cast<std::size_t>(in.step) * in.height) {
      NODELET_WARN_THROTTLE(kWarnPeriodS,
                            "`image` (%ux%u %s) not drawn: needs mono8/bgr8/rgb8 of %ux%u",
                            in.width, in.height, in.encoding.c_str(), out.width, out.height);
      return;
    }
    for (std::uint32_t r = 0; r < in.height; ++r) {
      const std::uint8_t* src = &in.data[static_cast<std::size_t>(r) * in.step];
      std::uint8_t* dst = &out.data[static_cast<std::size_t>(r) * out.step];
      for (std::uint32_t c = 0; c < in.width; ++c) {
        if (mono) {
          dst[3 * c] = dst[3 * c + 1] = dst[3 * c + 2] = src[c];
        } else {
          dst[3 * c] = src[3 * c + (rgb ? 2 : 0)];
          dst[3 * c + 1] = src[3 * c + 1];
          dst[3 * c + 2] = src[3 * c + (rgb ? 0 : 2)];
        }
      }
    }
  }

  EventRendererConfig config_;
  std::mutex mutex_;
  std::deque<ebslam_msgs::Event> events_;
  std::uint32_t width_ = 0, height_ = 0;
  std::string frame_id_;
  sensor_msgs::Image::ConstPtr background_;
  ros::Subscriber image_sub_;
  EventInputType input_type_ = EventInputType::kAuto;
  ros::Publisher image_pub_;
  ros::WallTimer timer_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::WallTimer diagnostics_timer_;
  std::uint64_t messages_ = 0, events_in_ = 0, rejected_size_ = 0, rejected_size_reported_ = 0,
                images_ = 0;
  EventSubscriber events_sub_;  // last member: stopped before the state its callbacks use
};

}  // namespace ebslam_ros

PLUGINLIB_EXPORT_CLASS(ebslam_ros::EventRendererNodelet, nodelet::Nodelet)
