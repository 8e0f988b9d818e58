#include "dasp/rgbd_io.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

namespace dasp {
namespace {

namespace fs = std::filesystem;

constexpr const char* kColorSuffix = "_rgb.png";
constexpr const char* kDepthSuffix = "_depth_mm.png";
constexpr const char* kLabelSuffix = "_label_object.png";

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Splits "learn12" into ("learn", 12) so that frames sort by number, not by text.
std::pair<std::string, long> naturalKey(const std::string& name) {
  std::size_t digits = name.size();
  while (digits > 0 && std::isdigit(static_cast<unsigned char>(name[digits - 1]))) --digits;
  const long number = digits < name.size() ? std::stol(name.substr(digits)) : -1;
  return {name.substr(0, digits), number};
}

cv::Mat readImage(const std::string& path, int flags) {
  cv::Mat image = cv::imread(path, flags);
  if (image.empty()) throw std::runtime_error("cannot read image '" + path + "'");
  return image;
}

}  // namespace

std::vector<RgbdFramePaths> listRgbdFolder(const std::string& folder) {
  if (!fs::is_directory(folder)) {
    throw std::invalid_argument("RGB-D folder '" + folder + "' does not exist");
  }
  std::vector<RgbdFramePaths> frames;
  for (const auto& entry : fs::directory_iterator(folder)) {
    const std::string file = entry.path().filename().string();
    if (!endsWith(file, kColorSuffix)) continue;
    RgbdFramePaths paths;
    paths.name = file.substr(0, file.size() - std::string(kColorSuffix).size());
    paths.color = entry.path().string();
    paths.depth = (fs::path(folder) / (paths.name + kDepthSuffix)).string();
    if (!fs::exists(paths.depth)) continue;
    const fs::path label = fs::path(folder) / (paths.name + kLabelSuffix);
    if (fs::exists(label)) paths.label = label.string();
    frames.push_back(std::move(paths));
  }
  std::sort(frames.begin(), frames.end(), [](const RgbdFramePaths& a, const RgbdFramePaths& b) {
    return naturalKey(a.name) < naturalKey(b.name);
  });
  return frames;
}

RgbdFrame loadRgbdFrame(const RgbdFramePaths& paths, const Intrinsics& intrinsics) {
  RgbdFrame frame;
  frame.color = readImage(paths.color, cv::IMREAD_COLOR);
  frame.depth = readImage(paths.depth, cv::IMREAD_ANYDEPTH);
  frame.intrinsics = intrinsics;
  if (frame.depth.type() != CV_16UC1) {
    throw std::invalid_argument("depth image '" + paths.depth +
                                "' is not a 16-bit single-channel PNG in millimetres");
  }
  if (frame.color.size() != frame.depth.size()) {
    throw std::invalid_argument("colour '" + paths.color + "' and depth '" + paths.depth +
                                "' differ in size");
  }
  return frame;
}

std::optional<cv::Mat> loadLabelImage(const RgbdFramePaths& paths) {
  if (paths.label.empty()) return std::nullopt;
  cv::Mat raw = readImage(paths.label, cv::IMREAD_ANYDEPTH);
  if (raw.channels() != 1) {
    throw std::invalid_argument("label image '" + paths.label + "' is not single-channel");
  }
  cv::Mat labels;
  raw.convertTo(labels, CV_32S);
  return labels;
}

}  // namespace dasp
