#pragma once

#include <optional>
#include <string>
#include <vector>

#include "dasp/dasp.h"

namespace dasp {

/// The files of one RGB-D frame on disk: an 8-bit colour PNG and a 16-bit depth PNG in millimetres
/// (0 = invalid), registered to the colour image, plus an optional 16-bit label PNG.
struct RgbdFramePaths {
  std::string name;   ///< Frame name, e.g. "learn3".
  std::string color;  ///< <name>_rgb.png
  std::string depth;  ///< <name>_depth_mm.png
  std::string label;  ///< <name>_label_object.png, empty when absent.
};

/// Lists the frames of a folder in the layout of the OSD data set (`<name>_rgb.png`,
/// `<name>_depth_mm.png`, optional `<name>_label_object.png`), sorted by the number in the name
/// (learn2 before learn10). Frames with a colour image but no depth image are left out.
/// Throws std::invalid_argument if the folder does not exist.
std::vector<RgbdFramePaths> listRgbdFolder(const std::string& folder);

/// Loads one frame. Throws std::runtime_error naming the file when a file cannot be read, and
/// std::invalid_argument when the images do not fit together (sizes differ, depth not 16-bit
/// single channel, colour not 8-bit). Colour comes back BGR (CV_8UC3), depth CV_16UC1 mm.
RgbdFrame loadRgbdFrame(const RgbdFramePaths& paths, const Intrinsics& intrinsics = {});

/// Loads the label image of a frame (CV_32SC1), or nullopt when the frame has none.
std::optional<cv::Mat> loadLabelImage(const RgbdFramePaths& paths);

}  // namespace dasp
