// libFuzzer target: bytes -> sensor_msgs/Image -> what Dasp, Sdasp and Tdasp run on their image
// inputs (RgbdInput::convert: colour and registered depth image; toLabelMat: Sdasp's
// superpixels/labels). Promise: no crash and no sanitizer finding; a bad image throws
// std::invalid_argument (InputError), a good one converts to a Mat of its size.
#include <sensor_msgs/Image.h>

#include <cstdint>
#include <cstdlib>

#include "dasp_ros/conversions.h"
#include "dasp_ros/rgbd_input.h"
#include "fuzz_message.h"

namespace {

void checkSize(const cv::Mat& mat, const sensor_msgs::Image& image, int type) {
  if (mat.cols != static_cast<int>(image.width) || mat.rows != static_cast<int>(image.height) ||
      mat.type() != type) {
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  sensor_msgs::Image image;
  if (fuzz::readMessage<sensor_msgs::Image_>(data, size, image) == 0) return 0;
  try {
    checkSize(dasp_ros::toColorMat(image), image, CV_8UC3);
  } catch (const std::invalid_argument&) {
  }
  try {
    checkSize(dasp_ros::toDepthMat(image), image, CV_16UC1);
  } catch (const std::invalid_argument&) {
  }
  try {
    checkSize(dasp_ros::toLabelMat(image), image, CV_32SC1);
  } catch (const std::invalid_argument&) {
  }
  // The image as both colour and depth input, with a camera_info of its size.
  sensor_msgs::CameraInfo info;
  info.width = image.width;
  info.height = image.height;
  info.K = {525.0, 0.0, 319.5, 0.0, 525.0, 239.5, 0.0, 0.0, 1.0};
  try {
    const dasp::RgbdFrame frame = dasp_ros::RgbdInput::convert(
        image, image, info,
        {"rgb/image_rect_color", "depth_registered/image_raw", "rgb/camera_info"});
    checkSize(frame.color, image, CV_8UC3);
    checkSize(frame.depth, image, CV_16UC1);
  } catch (const dasp_ros::InputError&) {
  }
  return 0;
}
