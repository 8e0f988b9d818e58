#include "ebslam/simulation/dedvs_io.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

namespace ebslam {
namespace {

constexpr char kMagic[8] = {'D', 'E', 'D', 'V', 'S', 'E', 'V', '1'};

std::string frameName(std::size_t index) {
  char name[32];
  std::snprintf(name, sizeof(name), "%06zu.png", index);
  return name;
}

void fail(const std::string& message) { throw std::runtime_error(message); }

}  // namespace

DedvsSensors sensorsOf(const DedvsSimulatorConfig& config) {
  DedvsSensors sensors;
  sensors.edvs = config.edvs;
  sensors.depth = config.depth.camera;
  sensors.depth_from_edvs = config.depth_from_edvs;
  sensors.depth_clock_offset_s = config.depth.clock_offset_s;
  sensors.depth_frame_rate_hz = config.depth.frame_rate_hz;
  return sensors;
}

void writeTrueDepthEvents(const std::string& path, const std::vector<TrueDepthEvent>& events,
                          int width, int height) {
  std::ofstream out(path, std::ios::binary);
  if (!out) fail("writeTrueDepthEvents: cannot open " + path);
  out.write(kMagic, 8);
  const std::uint32_t size[2] = {static_cast<std::uint32_t>(width),
                                 static_cast<std::uint32_t>(height)};
  out.write(reinterpret_cast<const char*>(size), sizeof(size));
  const std::uint64_t count = events.size();
  out.write(reinterpret_cast<const char*>(&count), sizeof(count));
  std::vector<char> buffer(events.size() * 16);
  for (std::size_t i = 0; i < events.size(); ++i) {
    const TrueDepthEvent& e = events[i];
    const std::int64_t t = e.event.t_us;
    const std::uint16_t x = static_cast<std::uint16_t>(e.event.x | (e.event.polarity ? 0x8000 : 0));
    const std::uint16_t y = static_cast<std::uint16_t>(e.event.y | (e.is_noise ? 0x8000 : 0) |
                                                       (e.at_depth_edge ? 0x4000 : 0));
    char* record = buffer.data() + i * 16;
    std::memcpy(record, &t, 8);
    std::memcpy(record + 8, &x, 2);
    std::memcpy(record + 10, &y, 2);
    std::memcpy(record + 12, &e.depth_m, 4);
  }
  out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  if (!out) fail("writeTrueDepthEvents: write failed: " + path);
}

std::vector<TrueDepthEvent> readTrueDepthEvents(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("readTrueDepthEvents: cannot open " + path);
  char magic[8];
  std::uint32_t size[2];
  std::uint64_t count = 0;
  in.read(magic, 8);
  in.read(reinterpret_cast<char*>(size), sizeof(size));
  in.read(reinterpret_cast<char*>(&count), sizeof(count));
  if (!in || std::memcmp(magic, kMagic, 8) != 0)
    fail("readTrueDepthEvents: not a D-eDVS event file: " + path);
  if (count > (1ULL << 34)) fail("readTrueDepthEvents: implausible event count in " + path);
  std::vector<char> buffer(count * 16);
  in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  if (!in) fail("readTrueDepthEvents: truncated file " + path);
  std::vector<TrueDepthEvent> events(count);
  for (std::size_t i = 0; i < count; ++i) {
    const char* record = buffer.data() + i * 16;
    std::int64_t t;
    std::uint16_t x, y;
    TrueDepthEvent& e = events[i];
    std::memcpy(&t, record, 8);
    std::memcpy(&x, record + 8, 2);
    std::memcpy(&y, record + 10, 2);
    std::memcpy(&e.depth_m, record + 12, 4);
    e.event.t_us = t;
    e.event.x = static_cast<std::uint16_t>(x & 0x7fff);
    e.event.polarity = (x & 0x8000) != 0;
    e.event.y = static_cast<std::uint16_t>(y & 0x3fff);
    e.is_noise = (y & 0x8000) != 0;
    e.at_depth_edge = (y & 0x4000) != 0;
    if (e.event.x >= size[0] || e.event.y >= size[1]) {
      fail("readTrueDepthEvents: event " + std::to_string(i) + " outside the sensor in " + path);
    }
  }
  return events;
}

void writeDedvsRun(const std::string& directory, const DedvsRun& run, const DedvsSensors& sensors) {
  namespace fs = std::filesystem;
  fs::create_directories(fs::path(directory) / "depth");
  fs::create_directories(fs::path(directory) / "colour");
  writeTrueDepthEvents((fs::path(directory) / "events.bin").string(), run.events,
                       sensors.edvs.width, sensors.edvs.height);
  std::ofstream frames((fs::path(directory) / "frames.txt").string());
  if (!frames) fail("writeDedvsRun: cannot write frames.txt in " + directory);
  frames << "# index t_true_s stamp_s\n";
  frames.precision(9);
  frames << std::fixed;
  for (std::size_t i = 0; i < run.depth_frames.size(); ++i) {
    const DepthFrame& frame = run.depth_frames[i];
    frames << i << ' ' << frame.t_s << ' ' << frame.stamp_s << '\n';
    if (!cv::imwrite((fs::path(directory) / "depth" / frameName(i)).string(), frame.depth_mm) ||
        !cv::imwrite((fs::path(directory) / "colour" / frameName(i)).string(), frame.colour)) {
      fail("writeDedvsRun: cannot write frame " + std::to_string(i) + " in " + directory);
    }
  }
  writeTumTrajectory((fs::path(directory) / "rig_groundtruth.txt").string(), run.rig_ground_truth);
  writeTumTrajectory((fs::path(directory) / "edvs_groundtruth.txt").string(),
                     run.edvs_ground_truth);
  writeDedvsSensors((fs::path(directory) / "sensors.yaml").string(), sensors);
  if (!run.imu.empty()) {
    std::ofstream imu((fs::path(directory) / "imu.txt").string());
    imu << "# t_s gyro_x gyro_y gyro_z [rad/s] accel_x accel_y accel_z [m/s^2], IMU frame\n";
    imu.precision(9);
    for (const ImuReading& r : run.imu) {
      imu << r.t_s << ' ' << r.gyro.x() << ' ' << r.gyro.y() << ' ' << r.gyro.z() << ' '
          << r.accel.x() << ' ' << r.accel.y() << ' ' << r.accel.z() << '\n';
    }
    if (!imu) fail("writeDedvsRun: cannot write imu.txt in " + directory);
  }
}

DedvsRun readDedvsRun(const std::string& directory, DedvsSensors* sensors) {
  namespace fs = std::filesystem;
  DedvsRun run;
  run.events = readTrueDepthEvents((fs::path(directory) / "events.bin").string());
  std::ifstream frames((fs::path(directory) / "frames.txt").string());
  if (!frames) fail("readDedvsRun: missing frames.txt in " + directory);
  std::string line;
  while (std::getline(frames, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::size_t index = 0;
    DepthFrame frame;
    if (!(fields >> index >> frame.t_s >> frame.stamp_s)) {
      fail("readDedvsRun: malformed line in frames.txt: " + line);
    }
    frame.depth_mm = cv::imread((fs::path(directory) / "depth" / frameName(index)).string(),
                                cv::IMREAD_UNCHANGED);
    frame.colour =
        cv::imread((fs::path(directory) / "colour" / frameName(index)).string(), cv::IMREAD_COLOR);
    if (frame.depth_mm.type() != CV_16UC1) {
      fail("readDedvsRun: depth frame " + std::to_string(index) + " missing or not 16-bit");
    }
    run.depth_frames.push_back(std::move(frame));
  }
  run.rig_ground_truth = readTumTrajectory((fs::path(directory) / "rig_groundtruth.txt").string());
  run.edvs_ground_truth =
      readTumTrajectory((fs::path(directory) / "edvs_groundtruth.txt").string());
  if (sensors != nullptr)
    *sensors = readDedvsSensors((fs::path(directory) / "sensors.yaml").string());
  std::ifstream imu((fs::path(directory) / "imu.txt").string());  // optional
  while (imu && std::getline(imu, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    ImuReading r;
    if (!(fields >> r.t_s >> r.gyro.x() >> r.gyro.y() >> r.gyro.z() >> r.accel.x() >> r.accel.y() >>
          r.accel.z()) ||
        !r.gyro.allFinite() || !r.accel.allFinite() ||
        (!run.imu.empty() && !(r.t_s > run.imu.back().t_s))) {
      fail("readDedvsRun: malformed or out-of-order line in imu.txt: " + line);
    }
    run.imu.push_back(r);
  }
  return run;
}

}  // namespace ebslam
