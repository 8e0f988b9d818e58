// EB-PF (thesis 6.4-6.5): localisation of an upward-looking eDVS under a ceiling with a known
// edge map. Topics, frames and services: PlanarPoseFilterNodelet (planar_pose_filter_nodelet.h)
// and README.md.
// The map (~map) is a yaml in map_server's or ebslam_simulate_events' layout (ceiling_map_io.h).
#include <ebslam_ros_common/ros_param_helpers.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>

#include <ebslam/slam/ceiling_camera.h>
#include <ebslam/slam/ebpf.h>

#include <memory>
#include <pluginlib/class_list_macros.hpp>

#include "ceiling_sensor_params.h"
#include "ebslam_ros/ceiling_map_io.h"
#include "event_particle_filter_params.h"
#include "planar_pose_filter_nodelet.h"

namespace ebslam_ros {

class EventParticleFilterNodelet : public PlanarPoseFilterNodelet {
 private:
  class Backend : public PoseFilterBackend {
   public:
    Backend(const ebslam::EbpfConfig& config, const ebslam::CeilingCamera& camera,
            ebslam::GridMap2f likelihood, const ebslam::Pose2& start)
        : filter_(config, camera, std::move(likelihood), start) {}
    void process(const ebslam::Event* events, std::size_t count) override {
      filter_.process(events, count);
    }
    ebslam::Pose2 estimate() const override { return filter_.estimate(); }
    const ebslam::ParticleSet2D& particles() const override { return filter_.particles(); }
    const ebslam::EventFilterConfig& filterConfig() const override {
      return filter_.config().filter;
    }
    void setFilterConfig(const ebslam::EventFilterConfig& config) override {
      filter_.setFilterConfig(config);
    }
    double g0() const override { return filter_.g0(); }
    std::uint64_t processedEvents() const override { return filter_.processedEvents(); }
    bool localisesOnMap() const override { return true; }
    void reseed(const ebslam::Pose2& sensor, const Eigen::Matrix3d& covariance) override {
      filter_.reseed(sensor, covariance);
    }
    void globalLocalisation() override { filter_.globalLocalisation(); }
    void applyOdometry(const ebslam::Pose2& sensor_delta) override {
      filter_.applyOdometry(sensor_delta);
    }
    ebslam::TrackingState trackingState() const override { return filter_.state(); }
    std::uint64_t recoveries() const override { return filter_.recoveries(); }
    std::uint64_t convergences() const override { return filter_.convergences(); }
    CovarianceModel covarianceModel() const override {
      const ebslam::EbpfLocalisationConfig& l = filter_.config().localisation;
      return {l.covariance_scale, l.covariance_floor_m, l.covariance_floor_rad};
    }

   private:
    ebslam::EventParticleFilter filter_;
  };

  void onInit() override {
    // A configuration that cannot work: FATAL and the nodelet is not loaded (ros_param_helpers.h).
    ebslam_ros_common::startOrFail(getPrivateNodeHandle(), "EventParticleFilter " + getName(), [&] {
      EventParticleFilterNodeConfig config =
          loadEventParticleFilterNodeConfig(getPrivateNodeHandle());
      // The sensor's size and lens from its CameraInfo; the ~camera/* parameters as fallback.
      resolveCameraInfo(getNodeHandle(), config.node.sensor);
      logCameraSource(getName(), config.node.sensor);
      const ebslam::CeilingCamera camera(config.node.sensor.camera,
                                         config.node.sensor.ceiling_distance_m);
      const CeilingEdgeMap map = loadCeilingMap(config.map_yaml);
      likelihood_ = ebslam::makeEdgeLikelihoodMap(map.edges, map.resolution_m, map.origin_centre_m,
                                                  config.filter.gamma * camera.wTrig());
      NODELET_INFO("EB-PF on ceiling map '%s' (%dx%d cells of %.3f m), N=%d B=%d K=%d",
                   config.map_yaml.c_str(), map.edges.cols, map.edges.rows, map.resolution_m,
                   config.filter.filter.num_particles, config.filter.filter.batch_size,
                   config.filter.filter.resample_every);
      const ebslam::EbpfConfig ebpf = config.filter;
      enableMapLocalisation(config.use_odometry);
      startFilter(
          config.node, ebpf.filter,
          [this, ebpf, camera](const ebslam::Pose2& start, const ebslam::EventFilterConfig& knobs) {
            ebslam::EbpfConfig c = ebpf;
            c.filter = knobs;
            return std::make_unique<Backend>(c, camera, likelihood_, start);
          });
    });
  }

  ebslam::GridMap2f likelihood_;
};

}  // namespace ebslam_ros

PLUGINLIB_EXPORT_CLASS(ebslam_ros::EventParticleFilterNodelet, nodelet::Nodelet)
