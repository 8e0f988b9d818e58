// Example subscriber: reads `superpixels` (ebslam_msgs/SuperpixelArray) and `segmentation`
// (ebslam_msgs/Segmentation) of the same frame and prints, per segment, its number of
// superpixels and its 3D centre (the pixel-weighted mean of its superpixels' centres, metres, in
// the header's frame). ~frames: exit after this many frames (0 = run until shut down).
//   rosrun dasp_ros example_segment_centres superpixels:=/camera/superpixels
//   segmentation:=/camera/segmentation
#include <ebslam_msgs/Segmentation.h>
#include <ebslam_msgs/SuperpixelArray.h>
#include <message_filters/subscriber.h>
#include <message_filters/time_synchronizer.h>
#include <ros/ros.h>

#include <cstdio>
#include <map>

namespace {

class SegmentCentres {
 public:
  explicit SegmentCentres(int max_frames) : max_frames_(max_frames) {}

  void print(const ebslam_msgs::SuperpixelArrayConstPtr& array,
             const ebslam_msgs::SegmentationConstPtr& segments) {
    if (segments->segment_ids.size() != array->superpixels.size()) {
      ROS_WARN("segmentation and superpixels of %.3f differ in size", array->header.stamp.toSec());
      return;
    }
    struct Sum {
      int superpixels = 0;
      double pixels = 0.0, x = 0.0, y = 0.0, z = 0.0;
    };
    std::map<int, Sum> sums;
    for (std::size_t i = 0; i < array->superpixels.size(); ++i) {
      const ebslam_msgs::Superpixel& sp = array->superpixels[i];
      Sum& s = sums[segments->segment_ids[i]];
      const double w = sp.pixel_count;  // weight of the superpixel's centre [px]
      ++s.superpixels;
      s.pixels += w;
      s.x += w * sp.position.x;
      s.y += w * sp.position.y;
      s.z += w * sp.position.z;
    }
    std::printf("frame %.3f in %s: %zu superpixels, %zu segments\n", array->header.stamp.toSec(),
                array->header.frame_id.c_str(), array->superpixels.size(), sums.size());
    for (const auto& [id, s] : sums) {
      std::printf("segment %d: %d superpixels, centre (%.3f, %.3f, %.3f) m\n", id, s.superpixels,
                  s.x / s.pixels, s.y / s.pixels, s.z / s.pixels);
    }
    std::fflush(stdout);
    if (max_frames_ > 0 && ++frames_ >= max_frames_) ros::shutdown();
  }

 private:
  int max_frames_;
  int frames_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "segment_centres");
  ros::NodeHandle nh, pnh("~");
  SegmentCentres printer(pnh.param("frames", 0));
  message_filters::Subscriber<ebslam_msgs::SuperpixelArray> superpixels(nh, "superpixels", 5);
  message_filters::Subscriber<ebslam_msgs::Segmentation> segmentation(nh, "segmentation", 5);
  message_filters::TimeSynchronizer<ebslam_msgs::SuperpixelArray, ebslam_msgs::Segmentation> sync(
      superpixels, segmentation, 10);
  sync.registerCallback(&SegmentCentres::print, &printer);
  ros::spin();
  return 0;
}
