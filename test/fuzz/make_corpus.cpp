// Writes the seed corpus of the fuzz targets: serialised valid messages and the known bad cases
// (the 65536 x 65537 image whose byte count overflowed 32 bits, events stamped 0, time jumps).
//   make_corpus <corpus folder>   (writes <folder>/<target>/seed_*)
#include <dasp/dasp.h>
#include <ebslam_msgs/DepthEventArray.h>
#include <ebslam_msgs/EventArray.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "dasp_ros/conversions.h"
#include "ebslam_msgs/event_conversions.h"
#include "fuzz_message.h"

namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

void write(const fs::path& folder, const std::string& name, const Bytes& bytes) {
  fs::create_directories(folder);
  std::ofstream out(folder / ("seed_" + name), std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

Bytes operator+(Bytes a, const Bytes& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

std_msgs::Header header() {
  std_msgs::Header h;
  h.stamp = ros::Time(1700000000, 0);
  h.frame_id = "camera_rgb_optical_frame";
  return h;
}

constexpr std::int64_t kT0 = 1700000000000000;  // [us]

ebslam_msgs::EventArray events(std::int64_t t_us, int count, std::int64_t step_us) {
  ebslam_msgs::EventArray msg;
  msg.header.frame_id = "edvs_optical_frame";
  msg.width = msg.height = 128;
  for (int i = 0; i < count; ++i) {
    ebslam_msgs::Event e;
    e.x = static_cast<std::uint16_t>((7 * i) % 128);
    e.y = static_cast<std::uint16_t>((11 * i) % 128);
    e.ts = ebslam_msgs::toRosTime(t_us + i * step_us);
    e.polarity = i % 2 == 0;
    msg.events.push_back(e);
  }
  msg.header.stamp = msg.events.back().ts;
  return msg;
}

ebslam_msgs::DepthEventArray depthEvents(std::int64_t t_us, int count, std::int64_t step_us) {
  const ebslam_msgs::EventArray plain = events(t_us, count, step_us);
  ebslam_msgs::DepthEventArray msg;
  msg.header = plain.header;
  msg.width = plain.width;
  msg.height = plain.height;
  for (std::size_t i = 0; i < plain.events.size(); ++i) {
    ebslam_msgs::DepthEvent d;
    d.x = plain.events[i].x;
    d.y = plain.events[i].y;
    d.ts = plain.events[i].ts;
    d.polarity = plain.events[i].polarity;
    d.depth = i % 5 == 4 ? std::numeric_limits<float>::quiet_NaN() : 1.0f + 0.01f * i;
    d.point.x = 0.01f * d.x;
    d.point.y = 0.01f * d.y;
    d.point.z = d.depth;
    msg.events.push_back(d);
  }
  return msg;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_corpus <corpus folder>\n");
    return 2;
  }
  const fs::path root = argv[1];

  // Images: each supported encoding, and sizes that overflow 32-bit arithmetic.
  const fs::path images = root / "image_fuzzer";
  cv::Mat colour(3, 4, CV_8UC3);
  cv::randu(colour, 0, 255);
  write(images, "bgr8", fuzz::toBytes(dasp_ros::toColorImageMsg(colour, header())));
  sensor_msgs::Image rgb = dasp_ros::toColorImageMsg(colour, header());
  rgb.encoding = "rgb8";
  write(images, "rgb8", fuzz::toBytes(rgb));
  write(images, "depth16",
        fuzz::toBytes(
            dasp_ros::toDepthImageMsg(cv::Mat(3, 4, CV_16UC1, cv::Scalar(1234)), header())));
  sensor_msgs::Image metres = dasp_ros::toDepthImageMsg(cv::Mat(3, 4, CV_16UC1), header());
  metres.encoding = "32FC1";
  metres.step = 16;
  metres.data.assign(48, 0);
  for (std::size_t i = 0; i < 12; ++i) {
    const float value = i == 5 ? std::numeric_limits<float>::quiet_NaN() : 0.5f + 0.25f * i;
    std::memcpy(&metres.data[4 * i], &value, 4);
  }
  write(images, "depth32f", fuzz::toBytes(metres));
  write(images, "labels",
        fuzz::toBytes(dasp_ros::toLabelImageMsg(cv::Mat(3, 4, CV_32SC1, cv::Scalar(2)), header())));
  sensor_msgs::Image overflow = dasp_ros::toColorImageMsg(colour, header());
  overflow.width = 65536;
  overflow.height = 65537;
  overflow.step = 3 * 65536;
  overflow.data.assign(64, 7);  // the data claims 64 bytes; step x height wraps to 65536 in 32 bits
  write(images, "overflow_65536x65537", fuzz::toBytes(overflow));

  // Camera info: K set, K zero with P set, zero.
  const sensor_msgs::CameraInfo info =
      dasp_ros::toCameraInfo(dasp::Intrinsics{525.0f, 525.0f, 1.5f, 1.0f}, 4, 3, header());
  write(root / "camera_info_fuzzer", "k", fuzz::toBytes(info));
  sensor_msgs::CameraInfo p_only = info;
  p_only.K.fill(0.0);
  write(root / "camera_info_fuzzer", "p_only", fuzz::toBytes(p_only));

  // Event streams: a byte of ~max_backward, then messages (in order, a jump back, a stamp 0).
  const Bytes good = fuzz::toBytes(events(kT0, 20, 50)) + fuzz::toBytes(events(kT0 + 1000, 20, 50));
  write(root / "event_array_fuzzer", "in_order", Bytes{10} + good);
  write(root / "event_array_fuzzer", "jump_back",
        Bytes{10} + good + fuzz::toBytes(events(kT0 - 25000, 20, 50)));
  ebslam_msgs::EventArray zero = events(kT0 + 2000, 5, 50);
  zero.events[2].ts = ros::Time();
  write(root / "event_array_fuzzer", "zero_stamp", Bytes{10} + good + fuzz::toBytes(zero));
  const Bytes depth_good =
      fuzz::toBytes(depthEvents(kT0, 20, 50)) + fuzz::toBytes(depthEvents(kT0 + 1000, 20, 50));
  write(root / "depth_event_array_fuzzer", "in_order", Bytes{10} + depth_good);
  write(root / "depth_event_array_fuzzer", "jump_back",
        Bytes{10} + depth_good + fuzz::toBytes(depthEvents(kT0 - 25000, 20, 50)));

  // Superpixels of a small synthetic frame (a tilted plane) with their label image.
  dasp::RgbdFrame frame;
  frame.color = cv::Mat(12, 16, CV_8UC3);
  cv::randu(frame.color, 0, 255);
  frame.depth = cv::Mat(12, 16, CV_16UC1);
  for (int r = 0; r < 12; ++r) {
    for (int c = 0; c < 16; ++c) frame.depth.at<std::uint16_t>(r, c) = 1000 + 10 * c + 5 * r;
  }
  frame.intrinsics = dasp::Intrinsics{20.0f, 20.0f, 7.5f, 5.5f};
  dasp::DaspConfig config;
  config.superpixel_count = 6;
  const dasp::Superpixels superpixels = dasp::computeDasp(frame, config);
  write(root / "superpixel_array_fuzzer", "plane",
        fuzz::toBytes(dasp_ros::toSuperpixelArrayMsg(superpixels, header())) +
            fuzz::toBytes(dasp_ros::toLabelImageMsg(superpixels.labels, header())));
  return 0;
}
