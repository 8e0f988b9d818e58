// libFuzzer target: bytes -> sensor_msgs/CameraInfo -> what Dasp, Sdasp and Tdasp run on their
// camera_info input (toIntrinsics inside RgbdInput::convert, with valid 4 x 3 images). Promise:
// no crash; usable intrinsics are finite with positive focal lengths, anything else throws
// std::invalid_argument (InputError).
#include <sensor_msgs/CameraInfo.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>

#include "dasp_ros/conversions.h"
#include "dasp_ros/rgbd_input.h"
#include "fuzz_message.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  sensor_msgs::CameraInfo info;
  if (fuzz::readMessage<sensor_msgs::CameraInfo_>(data, size, info) == 0) return 0;
  try {
    const dasp::Intrinsics k = dasp_ros::toIntrinsics(info);
    if (!(k.fx > 0.0f) || !(k.fy > 0.0f) || !std::isfinite(k.fx) || !std::isfinite(k.fy) ||
        !std::isfinite(k.cx) || !std::isfinite(k.cy)) {
      std::abort();
    }
  } catch (const std::invalid_argument&) {
  }
  static const sensor_msgs::Image color =
      dasp_ros::toColorImageMsg(cv::Mat(3, 4, CV_8UC3, cv::Scalar(10, 20, 30)), info.header);
  static const sensor_msgs::Image depth =
      dasp_ros::toDepthImageMsg(cv::Mat(3, 4, CV_16UC1, cv::Scalar(1500)), info.header);
  try {
    dasp_ros::RgbdInput::convert(
        color, depth, info,
        {"rgb/image_rect_color", "depth_registered/image_raw", "rgb/camera_info"});
  } catch (const dasp_ros::InputError&) {
  }
  return 0;
}
