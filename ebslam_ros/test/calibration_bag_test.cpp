// D-eDVS calibration end to end: a simulated calibration run written as the real topics (colour
// with the blinking LED, registered depth, camera_info, events with 20 % outlier events) into a
// bag, calibrated from the bag alone and compared with the simulated truth. Small enough for CI
// (24 poses, about 7 s of simulated time); the full figures (150 poses, 5 seeds) come from
// `dedvs_calibrate_bag --table-seeds 5 --outlier-fraction 0.2`.
#include "ebslam_ros/calibration_bag.h"

#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <string>

namespace {

std::string tempBag(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          (name + "_" + std::to_string(::getpid()) + ".bag"))
      .string();
}

ebslam_ros::SimulatedCalibrationBagOptions smallRun(std::uint64_t seed) {
  ebslam_ros::SimulatedCalibrationBagOptions options;
  options.run.poses = 24;
  options.run.rest_s = 0.25;
  options.run.move_s = 0.05;
  options.run.outlier_event_fraction = 0.2;
  options.run.seed = seed;
  options.run.simulator.seed = seed;
  options.run.simulator.events.seed = seed;
  return options;
}

TEST(CalibrationBag, CalibratesFromASimulatedBag) {
  const std::string path = tempBag("calibration_bag_test");
  const ebslam_ros::SimulatedCalibrationBag written =
      ebslam_ros::writeSimulatedCalibrationBag(path, smallRun(1));
  EXPECT_NEAR(static_cast<double>(written.outlier_events) / written.events, 0.2, 0.001);

  // The bag carries the topics record.launch records.
  {
    rosbag::Bag bag(path, rosbag::bagmode::Read);
    rosbag::View view(bag);
    std::set<std::string> topics;
    for (const rosbag::ConnectionInfo* c : view.getConnections()) topics.insert(c->topic);
    const ebslam_ros::CalibrationBagTopics names;
    for (const std::string& t : {names.events, names.colour, names.depth, names.camera_info,
                                 names.colour_info, names.edvs_info}) {
      EXPECT_EQ(topics.count(t), 1u) << t;
    }
    rosbag::View colour(bag, rosbag::TopicQuery(names.colour));
    EXPECT_EQ(colour.size(), written.frames);
  }

  ebslam_ros::BagCalibrationOptions options;
  options.measure_clock_offset = true;  // the simulated camera's offset is 12 ms
  options.solve.min_correspondences = 15;
  const ebslam_ros::BagCalibration calibration = ebslam_ros::calibrateFromBag(path, options);
  std::filesystem::remove(path);
  EXPECT_EQ(calibration.frames, written.frames);
  EXPECT_NEAR(calibration.frame_rate_hz, 30.0, 0.01);
  ASSERT_TRUE(calibration.measured_clock_offset_s.has_value());
  // The changed-pixel count saturates with the plate's displacement, the event count does
  // not: the measurement is a few ms off (7 ms for the true 12 ms here), well within the slack
  // of the eDVS window in a 250 ms rest.
  EXPECT_NEAR(*calibration.measured_clock_offset_s, written.truth.depth_clock_offset_s, 0.008);
  // Every rest of the plate is a still segment with the LED; nearly all become poses.
  EXPECT_GE(calibration.pairing.segments, 24u);
  EXPECT_GE(calibration.pairing.correspondences.size(), 20u);
  ASSERT_TRUE(calibration.result.has_value()) << calibration.problem;
  EXPECT_TRUE(calibration.problem.empty()) << calibration.problem;
  const ebslam::DedvsCalibrationResult& r = *calibration.result;
  EXPECT_EQ(r.status, ebslam::CalibrationStatus::kOk);
  EXPECT_LE(r.rmse_px, 0.5);
  const ebslam::ExtrinsicError e =
      ebslam::extrinsicError(r.sensors.depth_from_edvs, written.truth.depth_from_edvs);
  // 24 poses determine the rotation less well than the 150 of the full runs (0.03-0.12 deg over
  // 5 seeds, docs/results/dedvs.md): this checks the chain, not the accuracy.
  EXPECT_LT(e.rotation_deg, 0.3);
  EXPECT_LT(e.translation_mm, 3.0);
  EXPECT_NEAR(r.sensors.edvs.focal_px, written.truth.edvs.focal_px, 1.5);
  EXPECT_LT((r.sensors.edvs.principal_point - written.truth.edvs.principal_point).norm(), 1.5);
  EXPECT_EQ(r.sensors.depth_clock_offset_s, *calibration.measured_clock_offset_s);
  // The depth camera comes from camera_info.
  EXPECT_EQ(r.sensors.depth.fx, written.truth.depth.fx);
  EXPECT_EQ(r.sensors.depth.cx, written.truth.depth.cx);
  EXPECT_EQ(r.sensors.depth.width, written.truth.depth.width);
}

TEST(CalibrationBag, AWrongLedFrequencyIsExplained) {
  ebslam_ros::SimulatedCalibrationBagOptions sim = smallRun(2);
  sim.run.poses = 6;
  const std::string path = tempBag("calibration_bag_wrong_frequency");
  ebslam_ros::writeSimulatedCalibrationBag(path, sim);
  ebslam_ros::BagCalibrationOptions options;
  options.led_frequency_hz = 173.0;  // the LED runs at 250 Hz
  const ebslam_ros::BagCalibration calibration = ebslam_ros::calibrateFromBag(path, options);
  std::filesystem::remove(path);
  EXPECT_FALSE(calibration.result.has_value());
  EXPECT_TRUE(calibration.pairing.correspondences.empty());
  EXPECT_NE(calibration.problem.find("not found in the colour frames"), std::string::npos)
      << calibration.problem;
  EXPECT_NE(calibration.problem.find("--led-frequency"), std::string::npos) << calibration.problem;
}

TEST(CalibrationBag, MissingTopicsAreNamed) {
  const std::string path = tempBag("calibration_bag_empty");
  { rosbag::Bag bag(path, rosbag::bagmode::Write); }
  try {
    ebslam_ros::calibrateFromBag(path, {});
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("/edvs/events"), std::string::npos) << error.what();
  }
  std::filesystem::remove(path);
}

}  // namespace
