// ebslam_ros/conversions.h: poses and transforms of the pose nodelets (round trips through the
// messages), image and camera messages of the simulators and bag writers.
#include "ebslam_ros/conversions.h"

#include <gtest/gtest.h>

#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2_geometry_msgs/tf2_geometry_msgs.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <stdexcept>
#include <vector>

namespace ebslam_ros {
namespace {

std_msgs::Header header() {
  std_msgs::Header h;
  h.stamp = ros::Time(12, 345);
  h.frame_id = "camera_depth_optical_frame";
  return h;
}

TEST(Conversions, ImageRoundTripsAnRoiRowByRow) {
  cv::Mat depth(7, 9, CV_16UC1);
  for (int r = 0; r < depth.rows; ++r) {
    for (int c = 0; c < depth.cols; ++c) depth.at<std::uint16_t>(r, c) = 1000 + 10 * r + c;
  }
  const cv::Mat roi = depth(cv::Rect(2, 1, 5, 4));  // not continuous
  ASSERT_FALSE(roi.isContinuous());
  const sensor_msgs::Image msg = toImageMsg(roi, "16UC1", header());
  EXPECT_EQ(msg.header.stamp, ros::Time(12, 345));
  EXPECT_EQ(msg.header.frame_id, "camera_depth_optical_frame");
  EXPECT_EQ(msg.width, 5u);
  EXPECT_EQ(msg.height, 4u);
  EXPECT_EQ(msg.step, 10u);
  EXPECT_EQ(msg.encoding, "16UC1");
  EXPECT_EQ(msg.is_bigendian, 0);
  ASSERT_EQ(msg.data.size(), 40u);
  const cv::Mat back(static_cast<int>(msg.height), static_cast<int>(msg.width), CV_16UC1,
                     const_cast<std::uint8_t*>(msg.data.data()), msg.step);
  EXPECT_EQ(cv::countNonZero(back != roi), 0);

  const cv::Mat colour(3, 4, CV_8UC3, cv::Scalar(10, 20, 30));
  const sensor_msgs::Image bgr = toImageMsg(colour, "bgr8", header());
  EXPECT_EQ(bgr.step, 12u);
  ASSERT_EQ(bgr.data.size(), 36u);
  EXPECT_EQ(bgr.data[0], 10);
  EXPECT_EQ(bgr.data[35], 30);
}

TEST(Conversions, EmptyImageIsRefused) {
  EXPECT_THROW(toImageMsg(cv::Mat(), "mono8", header()), std::invalid_argument);
}

TEST(Conversions, EveryEventCameraLensRoundTripsThroughCameraInfo) {
  ebslam::CameraModel plumb = ebslam::CameraModel::preset("davis346");
  plumb.focal_y_px = plumb.focal_px * 1.01;
  plumb.distortion_model = ebslam::DistortionModel::kPlumbBob;
  plumb.lens_coefficients = {-0.3, 0.1, 0.001, -0.002, -0.01};
  ebslam::CameraModel fisheye = ebslam::CameraModel::preset("hd720");
  fisheye.distortion_model = ebslam::DistortionModel::kEquidistant;
  fisheye.lens_coefficients = {-0.02, 0.004, -0.001, 0.0002, 0.0};
  ebslam::CameraModel thesis;  // eq. 6.3 kappas
  thesis.kappa1 = -1e-3;
  thesis.kappa2 = 1e-6;
  ebslam::CameraModel eq81 = thesis;
  eq81.distortion_model = ebslam::DistortionModel::kDivideEq81;
  eq81.kappa1 = 6e-4;
  for (const ebslam::CameraModel& c : {plumb, fisheye, thesis, eq81}) {
    const sensor_msgs::CameraInfo info = toCameraInfoMsg(c, header());
    EXPECT_EQ(info.header.frame_id, "camera_depth_optical_frame");
    EXPECT_EQ(info.width, static_cast<std::uint32_t>(c.width));
    EXPECT_EQ(info.K[4], c.fy());
    const ebslam::CameraModel back = toCameraModel(info);
    EXPECT_EQ(back.width, c.width);
    EXPECT_EQ(back.height, c.height);
    EXPECT_EQ(back.fx(), c.fx());
    EXPECT_EQ(back.fy(), c.fy());
    EXPECT_EQ(back.principal_point, c.principal_point);
    EXPECT_EQ(back.distortion_model, c.distortion_model) << info.distortion_model;
    if (c.hasOpenCvLens()) {
      for (std::size_t i = 0; i < info.D.size(); ++i) {
        EXPECT_EQ(back.lens_coefficients[i], c.lens_coefficients[i]);
      }
    } else {
      EXPECT_EQ(back.kappa1, c.kappa1);
      EXPECT_EQ(back.kappa2, c.kappa2);
    }
    // Same rays everywhere.
    for (const Eigen::Vector2d& pixel : {Eigen::Vector2d(0, 0), Eigen::Vector2d(c.width - 1, 3)}) {
      EXPECT_EQ(*back.backprojectRay(pixel), *c.backprojectRay(pixel));
    }
  }
  EXPECT_EQ(toCameraInfoMsg(plumb, header()).distortion_model, "plumb_bob");
  EXPECT_EQ(toCameraInfoMsg(fisheye, header()).D.size(), 4u);
  EXPECT_EQ(toCameraInfoMsg(fisheye, header()).distortion_model, "equidistant");
}

TEST(Conversions, CameraInfoAUserWouldSendIsReadOrRefusedByName) {
  sensor_msgs::CameraInfo info = toCameraInfoMsg(346, 260, 250.0, 250.0, 172.5, 129.5, header());
  EXPECT_NO_THROW(toCameraModel(info));
  info.D.clear();  // plumb_bob without coefficients: a pinhole
  EXPECT_TRUE(toCameraModel(info).isSquarePinhole());
  info.distortion_model = "rational_polynomial";
  info.D = {-0.1, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  EXPECT_EQ(toCameraModel(info).distortion_model, ebslam::DistortionModel::kPlumbBob);
  const auto refused = [](const sensor_msgs::CameraInfo& bad, const std::string& word) {
    try {
      toCameraModel(bad);
      ADD_FAILURE() << "accepted: " << word;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  sensor_msgs::CameraInfo bad = info;
  bad.D[5] = 0.3;
  refused(bad, "k4..k6");
  bad = info;
  bad.distortion_model = "kannala_brandt";
  refused(bad, "unknown distortion model");
  bad = info;
  bad.distortion_model = "plumb_bob";
  bad.D = {0.1, 0.2};
  refused(bad, "coefficients in D");
  bad = info;
  bad.width = 0;  // an uncalibrated camera_info_manager default
  refused(bad, "width");
  bad = info;
  bad.K[0] = std::nan("");
  refused(bad, "K is not finite");
  bad = info;
  bad.K[1] = 0.5;
  refused(bad, "skew");
  bad = info;
  bad.binning_x = 2;
  refused(bad, "binning");
  bad = info;
  bad.distortion_model = "plumb_bob";
  bad.D = {-3.0, 0.0, 0.0, 0.0, 0.0};  // folds inside the sensor
  refused(bad, "cannot be inverted");
}

TEST(Conversions, CameraInfoOfARectifiedPinhole) {
  const sensor_msgs::CameraInfo info =
      toCameraInfoMsg(320, 240, 285.5, 286.0, 159.5, 119.25, header());
  EXPECT_EQ(info.header.frame_id, "camera_depth_optical_frame");
  EXPECT_EQ(info.width, 320u);
  EXPECT_EQ(info.height, 240u);
  EXPECT_EQ(info.distortion_model, "plumb_bob");
  ASSERT_EQ(info.D.size(), 5u);
  for (double d : info.D) EXPECT_EQ(d, 0.0);
  EXPECT_EQ(info.K[0], 285.5);
  EXPECT_EQ(info.K[2], 159.5);
  EXPECT_EQ(info.K[4], 286.0);
  EXPECT_EQ(info.K[5], 119.25);
  EXPECT_EQ(info.K[8], 1.0);
  EXPECT_EQ(info.R[0] + info.R[4] + info.R[8], 3.0);
  EXPECT_EQ(info.P[0], 285.5);
  EXPECT_EQ(info.P[2], 159.5);
  EXPECT_EQ(info.P[3], 0.0);
  EXPECT_EQ(info.P[5], 286.0);
  EXPECT_EQ(info.P[6], 119.25);
  EXPECT_EQ(info.P[10], 1.0);
}

// Random rigid transforms (fixed seed): rotations from the whole sphere, translations in +-5 m.
std::vector<Eigen::Isometry3d> randomIsometries(int count) {
  std::mt19937 rng(44);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), metres(-5.0, 5.0);
  std::vector<Eigen::Isometry3d> out;
  for (int i = 0; i < count; ++i) {
    out.push_back(fromXyzRpy({metres(rng), metres(rng), metres(rng)},
                             {angle(rng), 0.5 * angle(rng), angle(rng)}));
  }
  return out;
}

void expectNear(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double tolerance) {
  EXPECT_LT((a.translation() - b.translation()).norm(), tolerance);
  EXPECT_LT((a.linear() - b.linear()).norm(), tolerance);
}

TEST(Conversions, IsometryRoundTripsThroughPoseAndTransformMessages) {
  for (const Eigen::Isometry3d& t : randomIsometries(200)) {
    const geometry_msgs::Pose pose = toPoseMsg(t);
    geometry_msgs::Transform transform;
    transform.translation.x = pose.position.x;
    transform.translation.y = pose.position.y;
    transform.translation.z = pose.position.z;
    transform.rotation = pose.orientation;
    expectNear(toIsometry(transform), t, 1e-12);
    const geometry_msgs::TransformStamped stamped =
        toTransformMsg(t, ros::Time(3, 4), "base_link", "edvs_optical_frame");
    EXPECT_EQ(stamped.header.stamp, ros::Time(3, 4));
    EXPECT_EQ(stamped.header.frame_id, "base_link");
    EXPECT_EQ(stamped.child_frame_id, "edvs_optical_frame");
    expectNear(toIsometry(stamped.transform), t, 1e-12);
  }
}

TEST(Conversions, XyzRpyIsTf2sFixedAxisConvention) {
  for (const std::array<double, 3>& rpy : std::vector<std::array<double, 3>>{
           {-M_PI / 2, 0.0, -M_PI / 2}, {0.3, -0.2, 2.9}, {1.0, 1.2, -0.4}}) {
    tf2::Quaternion q;
    q.setRPY(rpy[0], rpy[1], rpy[2]);
    const tf2::Transform tf(q, tf2::Vector3(1.0, -2.0, 0.5));
    geometry_msgs::Transform msg = tf2::toMsg(tf);
    expectNear(fromXyzRpy({1.0, -2.0, 0.5}, rpy), toIsometry(msg), 1e-12);
  }
}

TEST(Conversions, PlanarPoseMatchesItsTransformAndPoseMessage) {
  for (const ebslam::Pose2& p :
       std::vector<ebslam::Pose2>{{0.0, 0.0, 0.0}, {1.5, -2.25, 3.0}, {-0.1, 4.0, -M_PI / 2}}) {
    const geometry_msgs::Pose msg = toPoseMsg(p);
    EXPECT_EQ(msg.position.x, p.x);
    EXPECT_EQ(msg.position.y, p.y);
    EXPECT_EQ(msg.position.z, 0.0);
    tf2::Quaternion q;
    tf2::fromMsg(msg.orientation, q);
    tf2::Matrix3x3 r(q);
    double roll = 0, pitch = 0, yaw = 0;
    r.getRPY(roll, pitch, yaw);
    EXPECT_NEAR(std::remainder(yaw - p.theta, 2 * M_PI), 0.0, 1e-12);
    EXPECT_NEAR(roll, 0.0, 1e-12);
    EXPECT_NEAR(pitch, 0.0, 1e-12);
    const geometry_msgs::TransformStamped t =
        toTransformMsg(toTransform(p), ros::Time(1), "map", "base_link");
    EXPECT_EQ(t.transform.translation.x, p.x);
    EXPECT_EQ(t.transform.translation.y, p.y);
    EXPECT_EQ(t.transform.translation.z, 0.0);
    EXPECT_NEAR(std::abs(t.transform.rotation.z * msg.orientation.z +
                         t.transform.rotation.w * msg.orientation.w),
                1.0, 1e-12);
    // The planar transform and the 6-DoF path agree.
    expectNear(toIsometry(t.transform), fromXyzRpy({p.x, p.y, 0.0}, {0.0, 0.0, p.theta}), 1e-12);
  }
}

TEST(Conversions, MountFromTheEbslam3dParameterFile) {
  // config/ebslam3d.yaml: the eDVS looks along base_link's x (optical z), its x to the right.
  const Eigen::Isometry3d mount = readMountFromParams(EBSLAM3D_CONFIG);
  EXPECT_LT(mount.translation().norm(), 1e-12);
  EXPECT_LT((mount.linear().col(2) - Eigen::Vector3d::UnitX()).norm(), 1e-6);
  EXPECT_LT((mount.linear().col(0) + Eigen::Vector3d::UnitY()).norm(), 1e-6);
  EXPECT_THROW(readMountFromParams("/nonexistent/ebslam3d.yaml"), std::runtime_error);
}

}  // namespace
}  // namespace ebslam_ros
