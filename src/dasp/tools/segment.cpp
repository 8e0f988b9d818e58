// dasp_segment: superpixels of one RGB-D frame (colour PNG + 16-bit depth PNG in millimetres).
// Writes the label image, an overlay picture and the superpixel list (CSV or JSON).
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdint>
#include <exception>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <string>

#include "dasp/dasp.h"
#include "dasp/features.h"
#include "dasp/metrics.h"
#include "dasp/rgbd_io.h"
#include "peers/method_options_cli.h"
#include "peers/methods.h"

namespace {

bool endsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// 16-bit PNG holds label + 1 (0 = unlabelled); the 32-bit form packs label + 1 little-endian into
// the B, G, R, A bytes of an 8-bit 4-channel PNG.
void writeLabels(const std::string& path, const cv::Mat& labels, bool wide) {
  double max_label = 0.0;
  cv::minMaxLoc(labels, nullptr, &max_label);
  cv::Mat image;
  if (wide) {
    image.create(labels.size(), CV_8UC4);
    for (int y = 0; y < labels.rows; ++y) {
      for (int x = 0; x < labels.cols; ++x) {
        const std::uint32_t v = static_cast<std::uint32_t>(labels.at<int>(y, x) + 1);
        image.at<cv::Vec4b>(y, x) = cv::Vec4b(v & 0xff, (v >> 8) & 0xff, (v >> 16) & 0xff, v >> 24);
      }
    }
  } else {
    if (max_label + 1 > 65535) {
      throw std::invalid_argument("more than 65534 labels: use --labels-32bit");
    }
    labels.convertTo(image, CV_16U, 1.0, 1.0);
  }
  if (!cv::imwrite(path, image)) throw std::runtime_error("cannot write " + path);
}

cv::Mat overlay(const cv::Mat& bgr, const cv::Mat& labels) {
  cv::Mat out = bgr.clone();
  const cv::Mat boundary = dasp::metrics::boundaryMap(labels, cv::Mat());
  for (int y = 0; y < out.rows; ++y) {
    for (int x = 0; x < out.cols; ++x) {
      cv::Vec3b& p = out.at<cv::Vec3b>(y, x);
      if (boundary.at<std::uint8_t>(y, x) != 0) {
        p = cv::Vec3b(0, 0, 255);
      } else if (labels.at<int>(y, x) < 0) {
        p = cv::Vec3b(p[0] / 3, p[1] / 3, p[2] / 3);  // unlabelled: darkened
      }
    }
  }
  return out;
}

void writeList(const std::string& path, const std::vector<dasp::Superpixel>& list) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  if (endsWith(path, ".json")) {
    nlohmann::ordered_json j = nlohmann::ordered_json::array();
    for (const dasp::Superpixel& s : list) {
      j.push_back({{"id", s.id},
                   {"u", s.u},
                   {"v", s.v},
                   {"pixel_count", s.pixel_count},
                   {"color_rgb", {s.color.x(), s.color.y(), s.color.z()}},
                   {"position_m", {s.position.x(), s.position.y(), s.position.z()}},
                   {"normal", {s.normal.x(), s.normal.y(), s.normal.z()}},
                   {"radius_m", s.radius_m},
                   {"density", s.density},
                   {"thickness_m", s.thickness},
                   {"eccentricity", s.eccentricity},
                   {"flatness", s.flatness},
                   {"area_m2", s.area_m2}});
    }
    out << j.dump(1) << "\n";
    return;
  }
  out << "id,u,v,pixel_count,r,g,b,x_m,y_m,z_m,nx,ny,nz,radius_m,density,thickness_m,"
         "eccentricity,flatness,area_m2\n";
  out << std::setprecision(7);
  for (const dasp::Superpixel& s : list) {
    out << s.id << ',' << s.u << ',' << s.v << ',' << s.pixel_count << ',' << s.color.x() << ','
        << s.color.y() << ',' << s.color.z() << ',' << s.position.x() << ',' << s.position.y()
        << ',' << s.position.z() << ',' << s.normal.x() << ',' << s.normal.y() << ','
        << s.normal.z() << ',' << s.radius_m << ',' << s.density << ',' << s.thickness << ','
        << s.eccentricity << ',' << s.flatness << ',' << s.area_m2 << '\n';
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Segment one RGB-D frame into superpixels (DASP or a comparison method) and write the "
      "label image, an overlay picture and the superpixel list."};
  dasp::RgbdFramePaths paths;
  dasp::Intrinsics intrinsics;
  std::string method_name = "DASP";
  dasp::peers::MethodOptions options;
  std::string labels_path, overlay_path, list_path;
  bool wide_labels = false;
  app.add_option("--color", paths.color, "8-bit colour PNG")->required()->check(CLI::ExistingFile);
  app.add_option("--depth", paths.depth, "16-bit depth PNG in millimetres (0 = invalid)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--fx", intrinsics.fx, "focal length x in pixels")->capture_default_str();
  app.add_option("--fy", intrinsics.fy, "focal length y in pixels")->capture_default_str();
  app.add_option("--cx", intrinsics.cx, "principal point x in pixels")->capture_default_str();
  app.add_option("--cy", intrinsics.cy, "principal point y in pixels")->capture_default_str();
  app.add_option("-m,--method", method_name, "DASP, ASP_RGB, ASP_RGBD, SLIC, SEEDS or VCCS")
      ->capture_default_str();
  app.add_option("-k,--count", options.superpixel_count, "number of superpixels K")
      ->capture_default_str();
  dasp::peers::addMethodOptions(app, options);
  app.add_option("--threads", options.threads, "threads inside DASP/ASP (0 = all cores)")
      ->capture_default_str();
  app.add_option("--labels", labels_path,
                 "output label PNG: 16-bit, value = label + 1, 0 = unlabelled");
  app.add_flag("--labels-32bit", wide_labels,
               "write the labels as 8-bit BGRA PNG holding label + 1 as little-endian uint32");
  app.add_option("--overlay", overlay_path, "output PNG: boundaries (red) over the colour image");
  app.add_option("--list", list_path, "output superpixel list, .json or .csv");
  CLI11_PARSE(app, argc, argv);

  try {
    const dasp::peers::Method method = dasp::peers::parseMethod(method_name);
    cv::setNumThreads(options.threads == 0 ? -1 : options.threads);  // OpenCV peers as well
    paths.name = paths.color;
    const dasp::RgbdFrame frame = dasp::loadRgbdFrame(paths, intrinsics);
    const dasp::peers::MethodResult result = dasp::peers::runMethod(method, frame, options);
    std::vector<dasp::Superpixel> list = result.superpixels;
    if (list.empty() && !list_path.empty()) {
      list = dasp::peers::describeSuperpixels(result.labels, dasp::computeFeatures(frame));
    }
    const std::size_t count = dasp::metrics::countSegments(result.labels, cv::Mat());
    std::cout << dasp::peers::methodName(method) << ": " << count
              << " superpixels (K = " << options.superpixel_count << ") in " << std::fixed
              << std::setprecision(1) << result.wall_milliseconds << " ms ("
              << result.cpu_milliseconds << " ms CPU of the calling thread)\n";
    if (!labels_path.empty()) writeLabels(labels_path, result.labels, wide_labels);
    if (!overlay_path.empty() && !cv::imwrite(overlay_path, overlay(frame.color, result.labels))) {
      throw std::runtime_error("cannot write " + overlay_path);
    }
    if (!list_path.empty()) writeList(list_path, list);
  } catch (const std::exception& e) {
    std::cerr << "dasp_segment: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
