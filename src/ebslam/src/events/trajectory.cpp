#include "ebslam/events/trajectory.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace ebslam {
namespace {

// Quaternion norms further than this from 1 are treated as malformed input, not rounding.
constexpr double kQuaternionNormTolerance = 1e-2;

bool parseDouble(const char*& cursor, double& value) {
  while (*cursor == ' ' || *cursor == '\t' || *cursor == ',') ++cursor;
  if (*cursor == '\0') return false;
  char* end = nullptr;
  errno = 0;
  value = std::strtod(cursor, &end);
  if (end == cursor || errno == ERANGE) return false;
  cursor = end;
  return *cursor == '\0' || *cursor == ' ' || *cursor == '\t' || *cursor == ',' ||
         *cursor == '\r' || *cursor == '\n';
}

std::string location(const std::string& path, std::size_t line) {
  return path + ":" + std::to_string(line) + ": ";
}

}  // namespace

Trajectory readTumTrajectory(const std::string& path, DuplicateTimestampPolicy duplicates) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open trajectory file '" + path + "'");
  Trajectory trajectory;
  std::string line;
  std::size_t line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    double v[8];
    const char* cursor = line.c_str();
    for (int i = 0; i < 8; ++i) {
      if (!parseDouble(cursor, v[i])) {
        throw std::runtime_error(location(path, line_number) + "expected 8 numbers " +
                                 "'timestamp tx ty tz qx qy qz qw', got '" + line + "'");
      }
    }
    while (*cursor == ' ' || *cursor == '\t' || *cursor == '\r' || *cursor == ',') ++cursor;
    if (*cursor != '\0') {
      throw std::runtime_error(location(path, line_number) + "trailing text after 8 numbers in '" +
                               line + "'");
    }
    for (double x : v) {
      if (!std::isfinite(x)) {
        throw std::runtime_error(location(path, line_number) + "non-finite value (NaN/inf) in '" +
                                 line + "'");
      }
    }
    StampedPose pose;
    pose.t_s = v[0];
    pose.position = Eigen::Vector3d(v[1], v[2], v[3]);
    pose.orientation = Eigen::Quaterniond(v[7], v[4], v[5], v[6]);
    const double norm = pose.orientation.norm();
    if (std::abs(norm - 1.0) > kQuaternionNormTolerance) {
      throw std::runtime_error(location(path, line_number) + "quaternion norm " +
                               std::to_string(norm) + " is not 1");
    }
    pose.orientation.normalize();
    if (!trajectory.empty()) {
      const double previous = trajectory.back().t_s;
      if (pose.t_s == previous && duplicates == DuplicateTimestampPolicy::kKeepFirst) continue;
      if (pose.t_s <= previous) {
        std::ostringstream message;
        message.precision(17);
        message << location(path, line_number) << "timestamp " << pose.t_s
                << " does not increase (previous " << previous << ")";
        throw std::runtime_error(message.str());
      }
    }
    trajectory.push_back(pose);
  }
  if (in.bad()) throw std::runtime_error("error reading trajectory file '" + path + "'");
  return trajectory;
}

void writeTumTrajectory(const std::string& path, const Trajectory& trajectory) {
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const StampedPose& p = trajectory[i];
    if (!std::isfinite(p.t_s) || !p.position.allFinite() || !p.orientation.coeffs().allFinite()) {
      throw std::invalid_argument("writeTumTrajectory: pose " + std::to_string(i) +
                                  " has non-finite values");
    }
  }
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (file == nullptr) throw std::runtime_error("cannot create trajectory file '" + path + "'");
  bool ok = std::fprintf(file, "# timestamp tx ty tz qx qy qz qw\n") > 0;
  for (const StampedPose& p : trajectory) {
    if (!ok) break;
    const Eigen::Quaterniond& q = p.orientation;
    ok = std::fprintf(file, "%.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", p.t_s, p.position.x(),
                      p.position.y(), p.position.z(), q.x(), q.y(), q.z(), q.w()) > 0;
  }
  ok = (std::fclose(file) == 0) && ok;
  if (!ok) throw std::runtime_error("error writing trajectory file '" + path + "'");
}

void validateTrajectory(const Trajectory& trajectory, const std::string& what) {
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const StampedPose& p = trajectory[i];
    if (!std::isfinite(p.t_s) || !p.position.allFinite() || !p.orientation.coeffs().allFinite()) {
      throw std::invalid_argument(what + ": pose " + std::to_string(i) +
                                  " has non-finite values (NaN/inf)");
    }
    if (std::abs(p.orientation.norm() - 1.0) > kQuaternionNormTolerance) {
      throw std::invalid_argument(what + ": pose " + std::to_string(i) +
                                  " has a non-unit quaternion");
    }
    if (i > 0 && !(p.t_s > trajectory[i - 1].t_s)) {
      throw std::invalid_argument(what + ": timestamps do not strictly increase at pose " +
                                  std::to_string(i));
    }
  }
}

StampedPose interpolatePose(const Trajectory& trajectory, double t_s) {
  if (trajectory.empty()) throw std::invalid_argument("interpolatePose: empty trajectory");
  if (!(t_s >= trajectory.front().t_s && t_s <= trajectory.back().t_s)) {
    std::ostringstream message;
    message.precision(17);
    message << "interpolatePose: t = " << t_s << " s outside [" << trajectory.front().t_s << ", "
            << trajectory.back().t_s << "]";
    throw std::out_of_range(message.str());
  }
  // First pose with time > t_s; t_s lies in [upper-1, upper).
  auto upper = std::upper_bound(trajectory.begin(), trajectory.end(), t_s,
                                [](double t, const StampedPose& p) { return t < p.t_s; });
  if (upper == trajectory.end()) {
    StampedPose last = trajectory.back();
    last.t_s = t_s;
    return last;
  }
  const StampedPose& a = *(upper - 1);
  const StampedPose& b = *upper;
  const double s = (t_s - a.t_s) / (b.t_s - a.t_s);
  StampedPose result;
  result.t_s = t_s;
  result.position = (1.0 - s) * a.position + s * b.position;
  // Eigen's slerp takes the shortest arc (it flips the sign of b when the dot product < 0).
  result.orientation = a.orientation.slerp(s, b.orientation).normalized();
  return result;
}

}  // namespace ebslam
