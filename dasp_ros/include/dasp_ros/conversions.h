#pragma once
// Conversions between ROS messages and the ROS-free dasp core types. Every function throws
// std::invalid_argument with the reason when a message cannot be represented (wrong encoding,
// sizes that do not match, non-finite intrinsics); nodelets catch it and log throttled.

#include <dasp/dasp.h>
#include <dasp/superpixel_graph.h>
#include <ebslam_msgs/SuperpixelArray.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>

#include <vector>

namespace dasp_ros {

/// Pinhole intrinsics from CameraInfo's K (P when K is zero). Distortion is ignored: the
/// PrimeSense colour and registered depth images are published rectified.
dasp::Intrinsics toIntrinsics(const sensor_msgs::CameraInfo& info);
/// Pinhole intrinsics of a camera that reports only its field of view (OpenNI2 devices):
/// fx = (width / 2) / tan(hfov / 2), fy likewise with the vertical field of view, principal
/// point at the image centre ((width - 1) / 2, (height - 1) / 2). Angles in radians; throws
/// std::invalid_argument for angles outside (0, pi) or a non-positive size.
dasp::Intrinsics intrinsicsFromFieldOfView(double horizontal_fov_rad, double vertical_fov_rad,
                                           int width, int height);
/// A CameraInfo with K, P, R = I, plumb_bob with zero distortion.
sensor_msgs::CameraInfo toCameraInfo(const dasp::Intrinsics& intrinsics, int width, int height,
                                     const std_msgs::Header& header);

/// How an image message's data reach a cv::Mat when no conversion is needed: copied, or shared
/// (the Mat points into the message, valid only while the message lives and unchanged: for a
/// callback that keeps nothing, it saves a copy of every frame).
enum class ImageData : bool { kCopy, kShare };

/// Colour image (bgr8, rgb8, bgra8, rgba8, mono8) -> CV_8UC3 BGR. bgr8 data are copied or shared
/// (`data`), the others converted.
cv::Mat toColorMat(const sensor_msgs::Image& image, ImageData data = ImageData::kCopy);
/// Depth image (16UC1 or mono16: millimetres; 32FC1: metres) -> CV_16UC1 millimetres, 0 = invalid
/// (NaN, non-positive and beyond 65.535 m become 0). Millimetre data are copied or shared.
cv::Mat toDepthMat(const sensor_msgs::Image& image, ImageData data = ImageData::kCopy);
/// Registered colour + depth + intrinsics -> RgbdFrame; sizes must agree.
dasp::RgbdFrame toRgbdFrame(const sensor_msgs::Image& color, const sensor_msgs::Image& depth,
                            const sensor_msgs::CameraInfo& info);

/// CV_8UC3 BGR -> bgr8 image message.
sensor_msgs::Image toColorImageMsg(const cv::Mat& color, const std_msgs::Header& header);
/// CV_16UC1 millimetres -> 16UC1 image message (REP 118 allows millimetres in 16UC1).
sensor_msgs::Image toDepthImageMsg(const cv::Mat& depth_mm, const std_msgs::Header& header);
/// CV_32SC1 label image (-1 = no superpixel) <-> 32SC1 image message.
sensor_msgs::Image toLabelImageMsg(const cv::Mat& labels, const std_msgs::Header& header);
cv::Mat toLabelMat(const sensor_msgs::Image& image, ImageData data = ImageData::kCopy);

/// Superpixel list -> SuperpixelArray (without edges; graph edges are added by the caller).
ebslam_msgs::SuperpixelArray toSuperpixelArrayMsg(const dasp::Superpixels& superpixels,
                                                  const std_msgs::Header& header);
/// SuperpixelArray + label image message -> Superpixels (ids must index the array, and every
/// label must be -1 or index it). The labels are copied or shared (`data`).
dasp::Superpixels toSuperpixels(const ebslam_msgs::SuperpixelArray& msg,
                                const sensor_msgs::Image& labels,
                                ImageData data = ImageData::kCopy);

/// Graph edges (a < b, weight) <-> SuperpixelEdge messages. toWeightedGraph throws when an
/// edge names a node >= node_count or is not ordered a < b.
std::vector<ebslam_msgs::SuperpixelEdge> toEdgeMsgs(const dasp::WeightedGraph& graph);
dasp::WeightedGraph toWeightedGraph(const std::vector<ebslam_msgs::SuperpixelEdge>& edges,
                                    int node_count);

/// One oriented disc per superpixel (CYLINDER: centre at the 3D mean, axis along the plane-fit
/// normal, diameter 2 radius, height max(thickness, 2 mm), its mean colour), preceded by a
/// DELETEALL marker so that superpixels of the previous frame disappear. Namespace "superpixels".
visualization_msgs::MarkerArray toMarkerArray(const std::vector<dasp::Superpixel>& superpixels,
                                              const std_msgs::Header& header);

/// Superpixel centres as an unorganised cloud: x y z [m], normal_x normal_y normal_z, rgb (PCL's
/// packed float), id (uint32, index into the SuperpixelArray).
sensor_msgs::PointCloud2 toCentreCloud(const std::vector<dasp::Superpixel>& superpixels,
                                       const std_msgs::Header& header);

}  // namespace dasp_ros
