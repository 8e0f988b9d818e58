#pragma once
// Conversions between ROS messages and the ROS-free dasp core types. Every function throws
// std::invalid_argument with the reason when a message cannot be represented (wrong encoding,
// sizes that do not match, non-finite intrinsics); nodelets catch it and log throttled.

#include <dasp/dasp.h>
#include <ebslam_msgs/SuperpixelArray.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/Header.h>

namespace dasp_ros {

/// Pinhole intrinsics from CameraInfo's K (P when K is zero). Distortion is ignored: the
/// PrimeSense colour and registered depth images are published rectified.
dasp::Intrinsics toIntrinsics(const sensor_msgs::CameraInfo& info);
/// A CameraInfo with K, P, R = I, plumb_bob with zero distortion.
sensor_msgs::CameraInfo toCameraInfo(const dasp::Intrinsics& intrinsics, int width, int height,
                                     const std_msgs::Header& header);

/// Colour image (bgr8, rgb8, bgra8, rgba8, mono8) -> CV_8UC3 BGR. The data are copied.
cv::Mat toColorMat(const sensor_msgs::Image& image);
/// Depth image (16UC1 or mono16: millimetres; 32FC1: metres) -> CV_16UC1 millimetres, 0 = invalid
/// (NaN, non-positive and beyond 65.535 m become 0).
cv::Mat toDepthMat(const sensor_msgs::Image& image);
/// Registered colour + depth + intrinsics -> RgbdFrame; sizes must agree.
dasp::RgbdFrame toRgbdFrame(const sensor_msgs::Image& color, const sensor_msgs::Image& depth,
                            const sensor_msgs::CameraInfo& info);

/// CV_8UC3 BGR -> bgr8 image message.
sensor_msgs::Image toColorImageMsg(const cv::Mat& color, const std_msgs::Header& header);
/// CV_16UC1 millimetres -> 16UC1 image message (REP 118 allows millimetres in 16UC1).
sensor_msgs::Image toDepthImageMsg(const cv::Mat& depth_mm, const std_msgs::Header& header);
/// CV_32SC1 label image (-1 = no superpixel) <-> 32SC1 image message.
sensor_msgs::Image toLabelImageMsg(const cv::Mat& labels, const std_msgs::Header& header);
cv::Mat toLabelMat(const sensor_msgs::Image& image);

/// Superpixel list -> SuperpixelArray (without edges; graph edges are added by the caller).
ebslam_msgs::SuperpixelArray toSuperpixelArrayMsg(const dasp::Superpixels& superpixels,
                                                  const std_msgs::Header& header);
/// SuperpixelArray + label image message -> Superpixels (ids must index the array).
dasp::Superpixels toSuperpixels(const ebslam_msgs::SuperpixelArray& msg,
                                const sensor_msgs::Image& labels);

}  // namespace dasp_ros
