#include "edvs_driver/ros_params.h"

#include <ebslam_ros_common/ros_param_helpers.h>

#include <stdexcept>

namespace edvs_driver {

using edvs::biasName;
using edvs::DeviceUri;
using edvs::EdvsDevice;
using edvs::kNumBiases;
using edvs::parseDeviceUri;
using edvs::parseEventFormat;
using edvs::parseFirmware;
using edvs::parseSyncMode;
using edvs::Transport;

namespace {

[[noreturn]] void bad(const std::string& name, const std::string& why) {
  throw std::invalid_argument("parameter ~" + name + ": " + why);
}

}  // namespace

void validate(const DriverParams& p) {
  if (p.frame_id.empty()) bad("frame_id", "must not be empty");
  if (p.publish_rate_hz < 0) bad("publish_rate", "must be >= 0 Hz");
  if (p.batch_size < 0) bad("batch_size", "must be >= 0 events");
  if (p.publish_rate_hz == 0 && p.batch_size == 0) {
    bad("publish_rate", "publish_rate and batch_size are both 0: nothing would be published");
  }
  if (p.link.reconnect_min_s <= 0) bad("reconnect_min_delay", "must be > 0 s");
  if (p.link.reconnect_max_s < p.link.reconnect_min_s)
    bad("reconnect_max_delay", "must be >= the minimum");
  if (p.stall_warn_s <= 0) bad("stall_timeout", "must be > 0 s");
  if (p.link.stall_reconnect_s < p.stall_warn_s)
    bad("stall_reconnect_timeout", "must be >= stall_timeout");
  if (p.device.on_bit != 0 && p.device.on_bit != 1) bad("on_bit", "must be 0 or 1");
  if (p.device.banner_timeout_ms <= 0) bad("banner_timeout", "must be > 0 ms");
  for (int i = 0; i < kNumBiases; ++i) {
    const auto& v = p.link.biases[static_cast<std::size_t>(i)];
    if (v && (*v < 0 || *v > 0xFFFFFF)) {
      bad(std::string("bias_") + biasName(i), "must be -1 (keep) or 0..16777215");
    }
  }
}

DriverParams loadDriverParams(const ros::NodeHandle& pnh) {
  DriverParams p;
  p.device.uri = ebslam_ros_common::param<std::string>(pnh, "uri", p.device.uri);
  const std::string firmware = ebslam_ros_common::param<std::string>(pnh, "firmware", "current");
  const auto fw = parseFirmware(firmware);
  if (!fw)
    ebslam_ros_common::failParam(pnh, "firmware", "'" + firmware + "' is not current or legacy");
  p.device.firmware = *fw;
  const std::string format = ebslam_ros_common::param<std::string>(pnh, "format", "E2");
  const auto f = parseEventFormat(format, p.device.firmware);
  if (!f)
    ebslam_ros_common::failParam(pnh, "format",
                                 "'" + format + "' is not E0..E4 or none/delta/ts16/ts24/ts32");
  p.device.format = *f;
  const std::string sync = ebslam_ros_common::param<std::string>(pnh, "sync_mode", "none");
  const auto s = parseSyncMode(sync);
  if (!s)
    ebslam_ros_common::failParam(pnh, "sync_mode", "'" + sync + "' is not none, master or slave");
  p.device.sync = *s;
  p.device.on_bit = ebslam_ros_common::param(pnh, "on_bit", p.device.on_bit);
  p.device.banner_timeout_ms =
      ebslam_ros_common::param(pnh, "banner_timeout", p.device.banner_timeout_ms);
  p.device.command_gap_ms = ebslam_ros_common::param(pnh, "command_gap", p.device.command_gap_ms);
  p.device.infer_wraps_from_host_time = ebslam_ros_common::param(
      pnh, "infer_wraps_from_host_time", p.device.infer_wraps_from_host_time);
  if (p.device.command_gap_ms < 0)
    ebslam_ros_common::failParam(pnh, "command_gap", "must be >= 0 ms");
  p.frame_id = ebslam_ros_common::param<std::string>(pnh, "frame_id", p.frame_id);
  p.camera_name = ebslam_ros_common::param<std::string>(pnh, "camera_name", p.camera_name);
  p.camera_info_url =
      ebslam_ros_common::param<std::string>(pnh, "camera_info_url", p.camera_info_url);
  p.publish_rate_hz = ebslam_ros_common::param(pnh, "publish_rate", p.publish_rate_hz);
  p.batch_size = ebslam_ros_common::param(pnh, "batch_size", p.batch_size);
  p.link.reconnect_min_s =
      ebslam_ros_common::param(pnh, "reconnect_min_delay", p.link.reconnect_min_s);
  p.link.reconnect_max_s =
      ebslam_ros_common::param(pnh, "reconnect_max_delay", p.link.reconnect_max_s);
  p.stall_warn_s = ebslam_ros_common::param(pnh, "stall_timeout", p.stall_warn_s);
  p.link.stall_reconnect_s =
      ebslam_ros_common::param(pnh, "stall_reconnect_timeout", p.link.stall_reconnect_s);
  for (int i = 0; i < kNumBiases; ++i) {
    const int v = ebslam_ros_common::param(pnh, std::string("bias_") + biasName(i), -1);
    if (v >= 0) p.link.biases[static_cast<std::size_t>(i)] = v;
  }
  // The URI is parsed here too, so a typo fails at start-up with the parameter's name; its
  // format= and firmware= override ~format and ~firmware.
  try {
    const DeviceUri uri = parseDeviceUri(p.device.uri);
    if (p.device.uri.find("firmware=") != std::string::npos) p.device.firmware = uri.firmware;
    if (uri.format) p.device.format = *uri.format;
    EdvsDevice probe(p.device, [](const DeviceUri&) -> std::unique_ptr<Transport> {
      throw std::logic_error("not opened");
    });
  } catch (const std::invalid_argument& e) {
    ebslam_ros_common::failParam(pnh, "uri", std::string(": ") + e.what());
  }
  try {
    validate(p);
  } catch (const std::invalid_argument& e) {
    // validate() names parameters as ~name; a log needs the full name.
    std::string message = e.what();
    const std::string::size_type tilde = message.find('~');
    if (tilde != std::string::npos) message.replace(tilde, 1, pnh.getNamespace() + "/");
    throw std::invalid_argument(message);
  }
  return p;
}

}  // namespace edvs_driver
