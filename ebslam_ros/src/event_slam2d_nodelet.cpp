// EB-SLAM-2D (thesis 7.2-7.3, alg. 8): an upward-looking eDVS localises itself against a ceiling
// map it builds from the same events. Pose, path, particles, tf, `reset`, dynamic_reconfigure
// and diagnostics: PoseFilterNode (planar_pose_filter_nodelet.h). Map outputs (relative names):
//  - map (nav_msgs/OccupancyGrid, latched, at most every ~map_publish_period of wall time, or of
//    event time with ~map_period_on_stamps): M = O / (Z + Z0)
//    scaled so that its 99 % quantile is 100; -1 where no event and no observation fell;
//  - map/image (sensor_msgs/Image mono8, only while subscribed): mapToImage(M), dark = likely
//    to fire, row r = map y of cell row r (as the grid);
//  - map/normalisation (nav_msgs/OccupancyGrid, latched, published only while subscribed, with
//    `map`): the normalisation map Z (eq. 7.7, how often each cell could have been observed)
//    scaled linearly so that its maximum is 100 (0 = never observed), the localisation
//    exploration map's input (Exploration nodelet; its eq. 7.8 normalisation is invariant to
//    the scale);
//  - service save_map (ebslam_msgs/SaveMap): <prefix>.png + <prefix>.yaml in map_server's
//    layout, loadable by EventParticleFilter's ~map.
// Both are in ~map_frame, stamped with the last event's time.
#include <ebslam_ros_common/ros_param_helpers.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/Image.h>

#include <ebslam/slam/ceiling_camera.h>
#include <ebslam/slam/ebslam2d.h>

#include <ebslam_msgs/SaveMap.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <pluginlib/class_list_macros.hpp>
#include <vector>

#include "ceiling_sensor_params.h"
#include "ebslam_ros/ceiling_map_io.h"
#include "event_slam2d_params.h"
#include "planar_pose_filter_nodelet.h"

namespace ebslam_ros {

class EventSlam2dNodelet : public PlanarPoseFilterNodelet {
 private:
  class Backend : public PoseFilterBackend {
   public:
    Backend(const ebslam::Ebslam2dConfig& config, const ebslam::CeilingCamera& camera,
            const ebslam::Pose2& start)
        : slam_(config, camera, start) {}
    void process(const ebslam::Event* events, std::size_t count) override {
      slam_.process(events, count);
    }
    ebslam::Pose2 estimate() const override { return slam_.estimate(); }
    const ebslam::ParticleSet2D& particles() const override { return slam_.particles(); }
    const ebslam::EventFilterConfig& filterConfig() const override { return slam_.config().filter; }
    void setFilterConfig(const ebslam::EventFilterConfig& config) override {
      slam_.setFilterConfig(config);
    }
    double g0() const override { return slam_.g0(); }
    std::uint64_t processedEvents() const override { return slam_.processedEvents(); }
    void countUnprocessed(std::uint64_t count) override { slam_.countUnprocessed(count); }
    const ebslam::EventSlam2d& slam() const { return slam_; }

   private:
    ebslam::EventSlam2d slam_;
  };

  void onInit() override {
    // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
    ebslam_ros_common::startOrFail(getPrivateNodeHandle(), "EventSlam2d " + getName(), [&] {
      EventSlam2dNodeConfig config = loadEventSlam2dNodeConfig(getPrivateNodeHandle());
      // The sensor's size and lens from its CameraInfo; the ~camera/* parameters as fallback.
      resolveCameraInfo(getNodeHandle(), config.node.sensor);
      logCameraSource(getName(), config.node.sensor);
      map_period_ = ros::WallDuration(config.map_publish_period_s);
      map_period_on_stamps_ = config.map_period_on_stamps;
      map_frame_ = config.node.map_frame;
      const ebslam::CeilingCamera camera(config.node.sensor.camera,
                                         config.node.sensor.ceiling_distance_m);
      const ebslam::Ebslam2dConfig slam = config.slam;
      map_pub_ = getNodeHandle().advertise<nav_msgs::OccupancyGrid>("map", 1, true);
      image_pub_ = getNodeHandle().advertise<sensor_msgs::Image>("map/image", 1);
      normalisation_pub_ =
          getNodeHandle().advertise<nav_msgs::OccupancyGrid>("map/normalisation", 1, true);
      startFilter(
          config.node, slam.filter,
          [slam, camera](const ebslam::Pose2& start, const ebslam::EventFilterConfig& knobs) {
            ebslam::Ebslam2dConfig c = slam;
            c.filter = knobs;
            return std::make_unique<Backend>(c, camera, start);
          });
      save_srv_ = getNodeHandle().advertiseService("save_map", &EventSlam2dNodelet::onSave, this);
      NODELET_INFO("EB-SLAM-2D: map %.1f m with %.3f m cells, N=%d B=%d K=%d", slam.map_size_m,
                   slam.cell_size_wtrig * camera.wTrig(), slam.filter.num_particles,
                   slam.filter.batch_size, slam.filter.resample_every);
    });
  }

  void afterUpdate(const PoseFilterBackend& backend, const ros::Time& stamp) override {
    if (map_period_on_stamps_) {
      // A stamp before the last map's (restart after a time jump) starts the period anew.
      if (!last_map_stamp_.isZero() && stamp >= last_map_stamp_ &&
          (stamp - last_map_stamp_).toSec() < map_period_.toSec()) {
        return;
      }
      last_map_stamp_ = stamp;
    } else {
      const ros::WallTime now = ros::WallTime::now();
      if (now - last_map_ < map_period_) return;
      last_map_ = now;
    }
    publishMap(static_cast<const Backend&>(backend).slam(), stamp);
  }

  void publishMap(const ebslam::EventSlam2d& slam, const ros::Time& stamp) {
    const ebslam::GridMap2f& m = slam.map();
    nav_msgs::OccupancyGrid grid;
    grid.header.stamp = stamp;
    grid.header.frame_id = map_frame_;
    grid.info.map_load_time = stamp;
    grid.info.resolution = static_cast<float>(m.resolution_m);
    grid.info.width = static_cast<std::uint32_t>(m.width);
    grid.info.height = static_cast<std::uint32_t>(m.height);
    grid.info.origin.position.x = m.origin_x_m;
    grid.info.origin.position.y = m.origin_y_m;
    grid.info.origin.orientation.w = 1.0;
    // Full scale at the 99 % quantile of the non-zero cells, as mapToImage.
    std::vector<float> nonzero;
    nonzero.reserve(m.cellCount() / 8);
    for (std::size_t i = 0; i < m.cellCount(); ++i) {
      if (m.data[i] > 0.0f) nonzero.push_back(m.data[i]);
    }
    float scale = 0.0f;
    if (!nonzero.empty()) {
      const auto q = nonzero.begin() + static_cast<std::ptrdiff_t>(0.99 * (nonzero.size() - 1));
      std::nth_element(nonzero.begin(), q, nonzero.end());
      scale = *q > 0.0f ? 100.0f / *q : 0.0f;
    }
    const ebslam::GridMap2f& o = slam.occurrence();
    const ebslam::GridMap2f& z = slam.normalisation();
    grid.data.resize(m.cellCount());
    for (std::size_t i = 0; i < m.cellCount(); ++i) {
      if (o.data[i] <= 0.0f && z.data[i] <= 0.0f) {
        grid.data[i] = -1;
      } else {
        grid.data[i] = static_cast<std::int8_t>(std::min(100.0f, std::round(m.data[i] * scale)));
      }
    }
    map_pub_.publish(grid);
    if (normalisation_pub_.getNumSubscribers() > 0 && !z.data.empty()) {
      const float z_max = *std::max_element(z.data.begin(), z.data.end());
      const float z_scale = z_max > 0.0f ? 100.0f / z_max : 0.0f;
      for (std::size_t i = 0; i < z.cellCount(); ++i) {
        grid.data[i] = static_cast<std::int8_t>(std::min(100.0f, std::round(z.data[i] * z_scale)));
      }
      normalisation_pub_.publish(grid);
    }
    if (image_pub_.getNumSubscribers() > 0) {
      const cv::Mat image = ebslam::mapToImage(m);
      sensor_msgs::Image msg;
      msg.header = grid.header;
      msg.height = static_cast<std::uint32_t>(image.rows);
      msg.width = static_cast<std::uint32_t>(image.cols);
      msg.encoding = "mono8";
      msg.step = msg.width;
      msg.data.resize(static_cast<std::size_t>(msg.step) * msg.height);
      for (int r = 0; r < image.rows; ++r) {
        std::copy_n(image.ptr<std::uint8_t>(r), image.cols, msg.data.data() + r * msg.step);
      }
      image_pub_.publish(msg);
    }
  }

  bool onSave(ebslam_msgs::SaveMap::Request& request, ebslam_msgs::SaveMap::Response& response) {
    std::lock_guard<std::mutex> lock(mutex());
    const auto* backend = static_cast<const Backend*>(this->backend());
    if (backend == nullptr) {
      response.success = false;
      response.message = "no map yet: no events processed since the start or the last reset";
      return true;
    }
    if (request.path_prefix.empty()) {
      response.success = false;
      response.message = "path_prefix is empty";
      return true;
    }
    const ebslam::GridMap2f& m = backend->slam().map();
    try {
      saveMapServerMap(request.path_prefix, ebslam::mapToImage(m), m.resolution_m,
                       {m.origin_x_m, m.origin_y_m});
      response.success = true;
      response.message = "saved " + request.path_prefix + ".png and .yaml";
    } catch (const std::exception& error) {
      response.success = false;
      response.message = error.what();
    }
    NODELET_INFO("save_map: %s", response.message.c_str());
    return true;
  }

  ros::Publisher map_pub_, image_pub_, normalisation_pub_;
  ros::ServiceServer save_srv_;
  ros::WallDuration map_period_{1.0};
  ros::WallTime last_map_;
  bool map_period_on_stamps_ = false;
  ros::Time last_map_stamp_;  // with map_period_on_stamps_
  std::string map_frame_;
};

}  // namespace ebslam_ros

PLUGINLIB_EXPORT_CLASS(ebslam_ros::EventSlam2dNodelet, nodelet::Nodelet)
