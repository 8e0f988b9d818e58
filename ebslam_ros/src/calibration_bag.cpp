#include "ebslam_ros/calibration_bag.h"

#include "ebslam_ros/conversions.h"

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "ebslam/events/event_clock.h"
#include "ebslam_msgs/EventArray.h"
#include "ebslam_msgs/event_conversions.h"
#include "ebslam_msgs/event_packet_conversions.h"

namespace ebslam_ros {
namespace {

const char* const kColourFrame = "camera_rgb_optical_frame";
const char* const kEdvsFrame = "edvs_optical_frame";

// A message's pixels as a cv::Mat header on its data (no copy), checked against its size.
cv::Mat wrap(const sensor_msgs::Image& msg, int type, const std::string& topic) {
  const std::size_t row_bytes = static_cast<std::size_t>(msg.width) * CV_ELEM_SIZE(type);
  if (msg.is_bigendian != 0 || msg.step < row_bytes ||
      msg.data.size() < static_cast<std::size_t>(msg.step) * msg.height || msg.width == 0 ||
      msg.height == 0) {
    throw std::runtime_error(topic + ": image of " + std::to_string(msg.width) + "x" +
                             std::to_string(msg.height) + " (" + msg.encoding +
                             ") has too little data or big-endian pixels");
  }
  return cv::Mat(static_cast<int>(msg.height), static_cast<int>(msg.width), type,
                 const_cast<std::uint8_t*>(msg.data.data()), msg.step);
}

// Colour image -> brightness CV_32FC1 [8-bit grey levels].
cv::Mat greyOf(const sensor_msgs::Image& msg, const std::string& topic) {
  namespace enc = sensor_msgs::image_encodings;
  cv::Mat grey;
  if (msg.encoding == enc::BGR8 || msg.encoding == enc::RGB8) {
    const cv::Mat image = wrap(msg, CV_8UC3, topic);
    std::vector<cv::Mat> channels;
    cv::split(image, channels);
    const int red = msg.encoding == enc::RGB8 ? 0 : 2;
    const int blue = 2 - red;
    grey = cv::Mat(image.rows, image.cols, CV_32FC1);
    cv::Mat r, g, b;
    channels[red].convertTo(r, CV_32F, 0.299);
    channels[1].convertTo(g, CV_32F, 0.587);
    channels[blue].convertTo(b, CV_32F, 0.114);
    grey = r + g + b;
  } else if (msg.encoding == enc::BGRA8 || msg.encoding == enc::RGBA8) {
    const cv::Mat image = wrap(msg, CV_8UC4, topic);
    std::vector<cv::Mat> channels;
    cv::split(image, channels);
    const int red = msg.encoding == enc::RGBA8 ? 0 : 2;
    cv::Mat r, g, b;
    channels[red].convertTo(r, CV_32F, 0.299);
    channels[1].convertTo(g, CV_32F, 0.587);
    channels[2 - red].convertTo(b, CV_32F, 0.114);
    grey = r + g + b;
  } else if (msg.encoding == enc::MONO8) {
    wrap(msg, CV_8UC1, topic).convertTo(grey, CV_32F);
  } else {
    throw std::runtime_error(topic + ": colour encoding '" + msg.encoding +
                             "' is not supported (bgr8, rgb8, bgra8, rgba8, mono8)");
  }
  return grey;
}

// Depth image -> CV_32FC1 [m], 0 or NaN = none.
cv::Mat depthOf(const sensor_msgs::Image& msg, const std::string& topic) {
  namespace enc = sensor_msgs::image_encodings;
  cv::Mat depth;
  if (msg.encoding == enc::TYPE_16UC1 || msg.encoding == enc::MONO16) {
    wrap(msg, CV_16UC1, topic).convertTo(depth, CV_32F, 1e-3);
  } else if (msg.encoding == enc::TYPE_32FC1) {
    wrap(msg, CV_32FC1, topic).copyTo(depth);
  } else {
    throw std::runtime_error(topic + ": depth encoding '" + msg.encoding +
                             "' is not supported (16UC1 millimetres, 32FC1 metres)");
  }
  return depth;
}

}  // namespace

SimulatedCalibrationBag writeSimulatedCalibrationBag(
    const std::string& path, const SimulatedCalibrationBagOptions& options) {
  options.run.validate();
  if (!(options.event_message_rate_hz > 0.0) || !(options.clock_origin_s > 0.0) ||
      (options.compression != "none" && options.compression != "lz4" &&
       options.compression != "bz2")) {
    throw std::invalid_argument(
        "writeSimulatedCalibrationBag: event_message_rate_hz and clock_origin_s must be positive, "
        "compression none, lz4 or bz2");
  }
  const CalibrationBagTopics& topics = options.topics;
  const ebslam::PinholeCamera& camera = options.run.simulator.depth.camera;
  const ebslam::CameraModel& edvs = options.run.simulator.edvs;
  // The frames are kept until the events are complete (the outlier events are added after the
  // simulation), then everything is written in time order, as a recording is: a bag written
  // topic by topic plays (and reads) many times slower, every message loading another chunk.
  struct Frame {
    double stamp_s;
    cv::Mat colour, depth_mm;
  };
  std::vector<Frame> frames;
  const auto on_frame = [&frames](const ebslam::DepthFrame& frame) {
    frames.push_back({frame.stamp_s, frame.colour.clone(), frame.depth_mm.clone()});
  };
  const ebslam::LedCalibrationRun run = ebslam::simulateLedCalibrationRun(options.run, on_frame);
  SimulatedCalibrationBag written;
  written.truth = run.truth;
  written.events = run.events.size();
  written.outlier_events = run.outlier_events;
  written.duration_s = run.duration_s;
  written.frames = frames.size();

  rosbag::Bag bag(path, rosbag::bagmode::Write);
  if (options.compression == "bz2") bag.setCompression(rosbag::compression::BZ2);
  if (options.compression == "lz4") bag.setCompression(rosbag::compression::LZ4);
  std::size_t next_frame = 0;
  // Frames up to (and at) ROS time `until` [s].
  const auto write_frames = [&](double until) {
    for (;
         next_frame < frames.size() && options.clock_origin_s + frames[next_frame].stamp_s <= until;
         ++next_frame) {
      const Frame& frame = frames[next_frame];
      std_msgs::Header header;
      header.stamp = ros::Time(options.clock_origin_s + frame.stamp_s);
      header.frame_id = kColourFrame;
      bag.write(topics.colour, header.stamp, toImageMsg(frame.colour, "bgr8", header));
      bag.write(topics.depth, header.stamp, toImageMsg(frame.depth_mm, "16UC1", header));
      const sensor_msgs::CameraInfo info = toCameraInfoMsg(camera.width, camera.height, camera.fx,
                                                           camera.fy, camera.cx, camera.cy, header);
      bag.write(topics.colour_info, header.stamp, info);
      bag.write(topics.camera_info, header.stamp, info);
    }
  };
  // Event messages as the driver sends them: batches of 1 / event_message_rate_hz.
  ebslam::EventClock clock;
  clock.anchor(0, ebslam_msgs::toMicroseconds(ros::Time(options.clock_origin_s)));
  const auto period_us = static_cast<std::int64_t>(1e6 / options.event_message_rate_hz);
  const ebslam::SensorSize sensor{static_cast<std::uint32_t>(edvs.width),
                                  static_cast<std::uint32_t>(edvs.height)};
  ebslam::EventVector batch;
  std::size_t messages = 0;
  auto flush = [&]() {
    if (batch.empty()) return;
    const ebslam_msgs::EventArray msg = ebslam_msgs::toMsg(batch, sensor, kEdvsFrame);
    write_frames(msg.header.stamp.toSec());
    bag.write(topics.events, msg.header.stamp, msg);
    if (messages++ % 10 == 0) {
      bag.write(topics.edvs_info, msg.header.stamp, toCameraInfoMsg(edvs, msg.header));
    }
    batch.clear();
  };
  std::int64_t batch_end_us = period_us;
  for (const ebslam::Event& e : run.events) {
    while (e.t_us >= batch_end_us) {
      flush();
      batch_end_us += period_us;
    }
    ebslam::Event stamped = e;
    stamped.t_us = clock.stamp(e.t_us).value_or(0);
    batch.push_back(stamped);
  }
  flush();
  write_frames(std::numeric_limits<double>::infinity());
  bag.close();
  return written;
}

BagCalibration calibrateFromBag(const std::string& path, const BagCalibrationOptions& options) {
  const CalibrationBagTopics& topics = options.topics;
  ebslam::RgbdLedConfig rgbd = options.rgbd;
  rgbd.led_frequency_hz = options.led_frequency_hz;
  ebslam::RgbdLedTracker tracker(rgbd);
  ebslam::LedPairingConfig pairing_config = options.pairing;
  pairing_config.depth_clock_offset_s = options.depth_clock_offset_s;
  pairing_config.validate();

  rosbag::Bag bag(path, rosbag::bagmode::Read);
  rosbag::View view(
      bag, rosbag::TopicQuery({topics.events, topics.colour, topics.depth, topics.camera_info}));
  // Times relative to the bag's start (ROS times are large): events [us], frames [s].
  const std::int64_t origin_us = ebslam_msgs::toMicroseconds(view.getBeginTime());
  BagCalibration out;
  std::vector<ebslam::Event> events;
  ebslam::SensorSize sensor{0, 0};  // from the event messages
  std::optional<sensor_msgs::CameraInfo> info;
  // Colour and depth frames waiting for their partner (same header.stamp).
  std::map<std::int64_t, cv::Mat> colour_waiting, depth_waiting;
  std::vector<std::int64_t> frame_stamps_us;
  std::vector<ebslam::RgbdLedObservation> observations;
  std::vector<double> frame_t_s, frame_motion;  // for the clock offset measurement
  const auto add_frame = [&](std::int64_t stamp_us, cv::Mat grey, cv::Mat depth) {
    if (!frame_stamps_us.empty() && stamp_us <= frame_stamps_us.back()) return;  // out of order
    frame_stamps_us.push_back(stamp_us);
    ebslam::RgbdLedFrame frame;
    frame.t_s = static_cast<double>(stamp_us - origin_us) * 1e-6;
    frame.grey = std::move(grey);
    frame.depth_m = std::move(depth);
    if (frame.grey.size() != frame.depth_m.size()) {
      throw std::runtime_error(topics.depth + " (" + std::to_string(frame.depth_m.cols) + "x" +
                               std::to_string(frame.depth_m.rows) + ") is not registered to " +
                               topics.colour + " (" + std::to_string(frame.grey.cols) + "x" +
                               std::to_string(frame.grey.rows) + "): record depth_registered");
    }
    frame_t_s.push_back(frame.t_s);
    if (auto o = tracker.push(std::move(frame))) observations.push_back(*o);
    frame_motion.push_back(std::max(0, tracker.lastChangedPixels()));
  };
  ebslam_msgs::EventPacketConverter event_packets;  // decoder state of the events topic
  for (const rosbag::MessageInstance& m : view) {
    if (m.getTopic() == topics.events) {
      const std::size_t first = events.size();
      const std::optional<ebslam::SensorSize> size =
          ebslam_msgs::appendRecordedEvents(m, event_packets, events);
      if (!size) continue;
      sensor = *size;
      for (std::size_t i = first; i < events.size(); ++i) events[i].t_us -= origin_us;
    } else if (m.getTopic() == topics.camera_info) {
      if (const auto msg = m.instantiate<sensor_msgs::CameraInfo>()) info = *msg;
    } else {
      const auto msg = m.instantiate<sensor_msgs::Image>();
      if (!msg) continue;
      const std::int64_t stamp = ebslam_msgs::toMicroseconds(msg->header.stamp);
      const bool is_colour = m.getTopic() == topics.colour;
      auto& mine = is_colour ? colour_waiting : depth_waiting;
      auto& theirs = is_colour ? depth_waiting : colour_waiting;
      cv::Mat image = is_colour ? greyOf(*msg, topics.colour) : depthOf(*msg, topics.depth);
      const auto partner = theirs.find(stamp);
      if (partner == theirs.end()) {
        mine.emplace(stamp, std::move(image));
        // Frames whose partner never came (dropped) are forgotten after a second.
        while (!mine.empty() && mine.begin()->first < stamp - 1000000) mine.erase(mine.begin());
        continue;
      }
      cv::Mat other = std::move(partner->second);
      theirs.erase(theirs.begin(), std::next(partner));
      if (is_colour) {
        add_frame(stamp, std::move(image), std::move(other));
      } else {
        add_frame(stamp, std::move(other), std::move(image));
      }
    }
  }
  if (auto o = tracker.finish()) observations.push_back(*o);
  out.events = events.size();
  out.frames = frame_stamps_us.size();
  if (events.empty()) {
    throw std::runtime_error("no eDVS events on " + topics.events + " in " + path);
  }
  if (frame_stamps_us.empty()) {
    throw std::runtime_error("no colour frames on " + topics.colour +
                             " with a depth frame of the same stamp on " + topics.depth + " in " +
                             path);
  }
  if (!info || info->K[0] <= 0.0 || info->K[4] <= 0.0) {
    throw std::runtime_error("no valid camera_info on " + topics.camera_info + " in " + path);
  }
  // Events arrive in batches; a batch may overlap the previous one by a little (several
  // driver threads): the extraction needs them sorted.
  std::stable_sort(events.begin(), events.end(),
                   [](const ebslam::Event& a, const ebslam::Event& b) { return a.t_us < b.t_us; });
  if (frame_stamps_us.size() >= 2) {
    std::vector<double> periods;
    for (std::size_t i = 1; i < frame_stamps_us.size(); ++i) {
      periods.push_back(static_cast<double>(frame_stamps_us[i] - frame_stamps_us[i - 1]) * 1e-6);
    }
    std::nth_element(periods.begin(), periods.begin() + periods.size() / 2, periods.end());
    out.frame_rate_hz = 1.0 / periods[periods.size() / 2];
  }

  if (options.measure_clock_offset) {
    out.measured_clock_offset_s = ebslam::estimateDepthClockOffset(events, frame_t_s, frame_motion);
    if (!out.measured_clock_offset_s) {
      out.problem =
          "the depth camera's clock offset could not be measured (the plate's motion in the "
          "colour frames does not match the eDVS event rate): pass it with "
          "--depth-clock-offset instead of --measure-clock-offset";
      return out;
    }
    pairing_config.depth_clock_offset_s = *out.measured_clock_offset_s;
  }
  ebslam::LedExtractionConfig edvs = options.edvs;
  edvs.led_frequency_hz = options.led_frequency_hz;
  edvs.width = static_cast<int>(sensor.width);
  edvs.height = static_cast<int>(sensor.height);
  out.pairing = ebslam::pairLedObservations(events, observations, edvs, pairing_config);

  ebslam::DedvsSensors base;
  base.depth.width = static_cast<int>(info->width);
  base.depth.height = static_cast<int>(info->height);
  base.depth.fx = info->K[0];
  base.depth.fy = info->K[4];
  base.depth.cx = info->K[2];
  base.depth.cy = info->K[5];
  base.edvs = options.solve.initial_edvs;
  if (base.edvs.width != edvs.width || base.edvs.height != edvs.height) {
    base.edvs = base.edvs.scaledTo(edvs.width, edvs.height);
  }
  base.depth_clock_offset_s = pairing_config.depth_clock_offset_s;
  if (out.frame_rate_hz > 0.0) base.depth_frame_rate_hz = out.frame_rate_hz;

  const std::size_t min_poses = options.solve.min_correspondences;
  out.problem = ebslam::diagnoseLedPairing(out.pairing, min_poses, rgbd, out.frame_rate_hz);
  if (!out.problem.empty()) return out;
  ebslam::DedvsCalibrationConfig solve = options.solve;
  if (solve.initial_edvs.width != edvs.width || solve.initial_edvs.height != edvs.height) {
    // Another event sensor than the initial guess': the same lens on its size (f and the
    // kappas scale with the pixel pitch, eq. 8.6's centre moves to the sensor's centre).
    solve.initial_edvs = solve.initial_edvs.scaledTo(edvs.width, edvs.height);
  }
  out.result = ebslam::calibrateDedvs(out.pairing.correspondences, base, solve);
  out.problem = ebslam::adviseCalibration(*out.result);
  out.coverage = ebslam::ledPoseCoverage(out.pairing.correspondences, edvs.width, edvs.height);
  out.pose_advice =
      ebslam::advisePoseDiversity(*out.result, out.coverage, options.max_rotation_std_deg);
  return out;
}

}  // namespace ebslam_ros
