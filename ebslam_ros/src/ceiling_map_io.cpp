#include "ebslam_ros/ceiling_map_io.h"

#include "ebslam_ros/flat_yaml.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace ebslam_ros {
namespace {

std::string trim(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t\r");
  if (begin == std::string::npos) return "";
  const auto end = s.find_last_not_of(" \t\r");
  return s.substr(begin, end - begin + 1);
}

std::map<std::string, std::string> readMapYaml(const std::string& path) {
  return readFlatYaml(path, "map yaml");
}

const std::string& need(const std::map<std::string, std::string>& values, const std::string& key,
                        const std::string& path) {
  const auto it = values.find(key);
  if (it == values.end()) throw std::runtime_error("map yaml '" + path + "' has no '" + key + "'");
  return it->second;
}

double number(const std::string& text, const std::string& key, const std::string& path) {
  std::istringstream in(text);
  double value = 0.0;
  if (!(in >> value) || !std::isfinite(value)) {
    throw std::runtime_error("map yaml '" + path + "': '" + key + "' = '" + text +
                             "' is not a number");
  }
  return value;
}

std::vector<double> numberList(const std::string& text, const std::string& key,
                               const std::string& path) {
  if (text.size() < 2 || text.front() != '[' || text.back() != ']') {
    throw std::runtime_error("map yaml '" + path + "': '" + key + "' must be a [..] list");
  }
  std::vector<double> values;
  std::stringstream in(text.substr(1, text.size() - 2));
  std::string item;
  while (std::getline(in, item, ',')) values.push_back(number(trim(item), key, path));
  return values;
}

std::string resolve(const std::string& file, const std::string& yaml_path) {
  return resolveBesideYaml(file, yaml_path);
}

cv::Mat readImage(const std::string& path, const std::string& yaml_path) {
  const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (image.empty()) {
    throw std::runtime_error("map image '" + path + "' (from '" + yaml_path +
                             "') does not exist or is not an image");
  }
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3)) {
    throw std::runtime_error("map image '" + path + "' must be 8-bit grey or colour, not " +
                             std::to_string(image.channels()) + " channels of depth " +
                             std::to_string(image.depth()));
  }
  cv::Mat grey;
  if (image.channels() == 3) {
    cv::Mat channels[3];
    cv::split(image, channels);
    grey = (channels[0] + channels[1] + channels[2]) / 3;  // mean, no colour weighting
  } else {
    grey = image;
  }
  return grey;
}

}  // namespace

CeilingEdgeMap loadCeilingMap(const std::string& yaml_path) {
  const auto values = readMapYaml(yaml_path);
  CeilingEdgeMap map;
  if (values.count("edges") != 0) {  // ebslam_simulate_events layout
    const cv::Mat grey = readImage(resolve(need(values, "edges", yaml_path), yaml_path), yaml_path);
    map.edges = grey != 0;
    map.resolution_m = number(need(values, "resolution_m", yaml_path), "resolution_m", yaml_path);
    map.origin_centre_m = {number(need(values, "origin_x_m", yaml_path), "origin_x_m", yaml_path),
                           number(need(values, "origin_y_m", yaml_path), "origin_y_m", yaml_path)};
  } else {  // map_server layout
    const cv::Mat grey = readImage(resolve(need(values, "image", yaml_path), yaml_path), yaml_path);
    map.resolution_m = number(need(values, "resolution", yaml_path), "resolution", yaml_path);
    const std::vector<double> origin =
        numberList(need(values, "origin", yaml_path), "origin", yaml_path);
    if (origin.size() != 3) {
      throw std::runtime_error("map yaml '" + yaml_path + "': origin must be [x, y, yaw]");
    }
    if (std::abs(origin[2]) > 1e-9) {
      throw std::runtime_error("map yaml '" + yaml_path +
                               "': a rotated origin (yaw != 0) is not supported");
    }
    const bool negate =
        values.count("negate") != 0 && number(values.at("negate"), "negate", yaml_path) != 0.0;
    const double occupied = values.count("occupied_thresh") != 0
                                ? number(values.at("occupied_thresh"), "occupied_thresh", yaml_path)
                                : 0.65;
    // Occupancy p = (255 - v) / 255 (v / 255 negated) > occupied: an edge.
    const double limit = 255.0 * (1.0 - occupied);
    map.edges = negate ? grey > 255.0 * occupied : grey < limit;
    cv::flip(map.edges, map.edges, 0);  // map_server's row 0 is the top (largest y)
    map.origin_centre_m = {origin[0] + 0.5 * map.resolution_m, origin[1] + 0.5 * map.resolution_m};
  }
  if (!(map.resolution_m > 0.0)) {
    throw std::runtime_error("map yaml '" + yaml_path + "': resolution must be positive");
  }
  if (cv::countNonZero(map.edges) == 0) {
    throw std::runtime_error("map '" + yaml_path + "' has no edge pixel");
  }
  return map;
}

void saveMapServerMap(const std::string& prefix, const cv::Mat& image, double resolution_m,
                      const Eigen::Vector2d& origin_corner_m) {
  if (image.empty() || image.type() != CV_8UC1) {
    throw std::runtime_error("saveMapServerMap: the image must be non-empty CV_8UC1");
  }
  cv::Mat flipped;
  cv::flip(image, flipped, 0);
  const std::string png = prefix + ".png";
  if (!cv::imwrite(png, flipped)) throw std::runtime_error("cannot write '" + png + "'");
  std::ofstream yaml(prefix + ".yaml");
  const auto slash = png.find_last_of('/');
  yaml.precision(12);
  yaml << "image: " << (slash == std::string::npos ? png : png.substr(slash + 1)) << "\n"
       << "resolution: " << resolution_m << "\n"
       << "origin: [" << origin_corner_m.x() << ", " << origin_corner_m.y() << ", 0.0]\n"
       << "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
  if (!yaml) throw std::runtime_error("cannot write '" + prefix + ".yaml'");
}

}  // namespace ebslam_ros
