#pragma once
// Image and camera messages of the simulators and bag writers (RgbdEventSimulator, make_session,
// the simulated calibration bag): one place for the sensor_msgs layout they all publish.
// Event messages are converted by ebslam_msgs/event_conversions.h.

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/Header.h>

#include <opencv2/core.hpp>

#include <string>

namespace ebslam_ros {

/// CameraInfo of a rectified pinhole camera (plumb_bob, zero distortion, R = I, P = [K | 0]);
/// focal lengths and principal point in pixels.
sensor_msgs::CameraInfo toCameraInfoMsg(int width, int height, double fx, double fy, double cx,
                                        double cy, const std_msgs::Header& header);

/// An image as a message of `encoding` (little-endian, rows packed: step = cols x element size),
/// copied row by row so that a non-continuous view (an ROI) is fine. Throws
/// std::invalid_argument for an empty image or one too large for the message's 32-bit sizes.
sensor_msgs::Image toImageMsg(const cv::Mat& image, const std::string& encoding,
                              const std_msgs::Header& header);

}  // namespace ebslam_ros
