// libFuzzer target: bytes -> ebslam_msgs/SuperpixelArray + sensor_msgs/Image (its label image)
// -> what Sdasp runs on the pair (toSuperpixels, then the s-DASP segmentation of the core), and
// the edge conversion (toWeightedGraph). Promises: no crash and no sanitizer finding; bad input
// throws std::invalid_argument.
#include <ebslam_msgs/SuperpixelArray.h>
#include <sensor_msgs/Image.h>

#include <dasp/sdasp.h>

#include <cstdint>
#include <cstdlib>

#include "dasp_ros/conversions.h"
#include "fuzz_message.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ebslam_msgs::SuperpixelArray array;
  const std::size_t used = fuzz::readMessage<ebslam_msgs::SuperpixelArray_>(data, size, array);
  if (used == 0) return 0;
  try {
    const dasp::WeightedGraph graph =
        dasp_ros::toWeightedGraph(array.edges, static_cast<int>(array.superpixels.size()));
    for (const dasp::GraphEdge& e : graph.edges) {
      if (e.a < 0 || e.b <= e.a || e.b >= graph.node_count) std::abort();
    }
  } catch (const std::invalid_argument&) {
  }
  sensor_msgs::Image labels;
  if (fuzz::readMessage<sensor_msgs::Image_>(data + used, size - used, labels) == 0) return 0;
  dasp::Superpixels superpixels;
  try {
    superpixels = dasp_ros::toSuperpixels(array, labels);
  } catch (const std::invalid_argument&) {
    return 0;
  }
  try {
    dasp::computeSdasp(superpixels, dasp::SdaspConfig{});
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
