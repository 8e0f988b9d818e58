// dasp_evaluate: runs superpixel methods over a folder of RGB-D frames with object labels (the
// layout of ../shared/data/osd/learn) for several K and writes per-frame and mean metrics as CSV
// and JSON. Mask per frame: object label > 0 and depth > 0. Plots:
// scripts/results/make_dasp_results.py.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <algorithm>
#include <atomic>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "dasp/features.h"
#include "dasp/rgbd_io.h"
#include "peers/method_options_cli.h"
#include "peers/methods.h"

namespace {

struct Row {
  std::string frame;
  int frame_index = 0;
  std::string method;
  int method_index = 0;
  int k = 0;
  double time_ms = 0.0;  // thread CPU time of the method call
  double wall_ms = 0.0;
  std::map<std::string, double> metrics;
  std::string error;  // non-empty: the method threw on this frame
};

std::string number(double v) {
  std::ostringstream s;
  s << std::setprecision(8) << v;
  return s.str();
}

void writeCsv(const std::filesystem::path& path, const std::vector<std::string>& header,
              const std::vector<std::vector<std::string>>& rows) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path.string());
  for (std::size_t i = 0; i < header.size(); ++i) out << (i ? "," : "") << header[i];
  out << "\n";
  for (const auto& row : rows) {
    for (std::size_t i = 0; i < row.size(); ++i) out << (i ? "," : "") << row[i];
    out << "\n";
  }
}

// What to run: the methods (with the names they get in the outputs), the counts K, their options.
struct Job {
  std::vector<dasp::peers::Method> methods;
  std::vector<std::string> output_names;
  std::vector<int> counts;
  dasp::peers::MethodOptions options;
  dasp::Intrinsics intrinsics;
};

// Every method at every K on one frame.
std::vector<Row> evaluateFrame(const dasp::RgbdFramePaths& paths, int frame_index, const Job& job) {
  const dasp::RgbdFrame frame = dasp::loadRgbdFrame(paths, job.intrinsics);
  const cv::Mat gt = *dasp::loadLabelImage(paths);
  const dasp::PixelFeatures features = dasp::computeFeatures(frame);
  const dasp::peers::FrameReference ref = dasp::peers::makeFrameReference(frame, gt, features);
  std::vector<Row> rows;
  for (std::size_t m = 0; m < job.methods.size(); ++m) {
    for (int k : job.counts) {
      Row row;
      row.frame = paths.name;
      row.frame_index = frame_index;
      row.method = job.output_names[m];
      row.method_index = static_cast<int>(m);
      row.k = k;
      try {
        dasp::peers::MethodOptions o = job.options;
        o.superpixel_count = k;
        o.threads = 1;
        const dasp::peers::MethodResult result = runMethod(job.methods[m], frame, o);
        row.time_ms = result.cpu_milliseconds;
        row.wall_ms = result.wall_milliseconds;
        row.metrics = dasp::peers::evaluateLabels(result.labels, ref, k);
      } catch (const std::exception& e) {
        row.error = e.what();
      }
      rows.push_back(std::move(row));
    }
  }
  return rows;
}

// All frames, `threads` at a time; rows sorted by method, K and frame. A frame that cannot be
// read is reported and skipped.
std::vector<Row> evaluateFrames(const std::vector<dasp::RgbdFramePaths>& frames, const Job& job,
                                int threads) {
  std::vector<Row> rows;
  std::mutex mutex;
  std::atomic<std::size_t> next{0};
  auto worker = [&]() {
    for (std::size_t f = next++; f < frames.size(); f = next++) {
      std::vector<Row> local;
      try {
        local = evaluateFrame(frames[f], static_cast<int>(f), job);
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(mutex);
        std::cerr << "dasp_evaluate: frame " << frames[f].name << ": " << e.what() << "\n";
        continue;
      }
      std::lock_guard<std::mutex> lock(mutex);
      std::cerr << "frame " << frames[f].name << " done (" << f + 1 << "/" << frames.size()
                << ")\n";
      for (Row& r : local) rows.push_back(std::move(r));
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
  for (std::thread& t : pool) t.join();
  std::sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) {
    return std::tie(a.method_index, a.k, a.frame_index) <
           std::tie(b.method_index, b.k, b.frame_index);
  });
  return rows;
}

// per_frame.csv and per_frame.json.
void writePerFrame(const std::filesystem::path& out_dir, const std::vector<Row>& rows) {
  const std::vector<std::string>& names = dasp::peers::metricNames();
  std::vector<std::string> header = {"frame", "method", "k", "time_ms", "wall_ms"};
  header.insert(header.end(), names.begin(), names.end());
  header.push_back("error");
  std::vector<std::vector<std::string>> table;
  nlohmann::json per_frame = nlohmann::json::array();
  for (const Row& r : rows) {
    std::vector<std::string> line = {r.frame, r.method, std::to_string(r.k),
                                     r.error.empty() ? number(r.time_ms) : "",
                                     r.error.empty() ? number(r.wall_ms) : ""};
    nlohmann::json j = {{"frame", r.frame}, {"method", r.method}, {"k", r.k}};
    if (r.error.empty()) {
      j["time_ms"] = r.time_ms;
      j["wall_ms"] = r.wall_ms;
    }
    for (const std::string& n : names) {
      const auto it = r.metrics.find(n);
      line.push_back(it == r.metrics.end() ? "" : number(it->second));
      if (it != r.metrics.end()) j[n] = it->second;
    }
    std::string error = r.error;
    std::replace(error.begin(), error.end(), ',', ';');
    line.push_back(error);
    if (!r.error.empty()) j["error"] = r.error;
    table.push_back(std::move(line));
    per_frame.push_back(std::move(j));
  }
  writeCsv(out_dir / "per_frame.csv", header, table);
  std::ofstream(out_dir / "per_frame.json") << per_frame.dump(1) << "\n";
}

// mean.csv: means over the frames where the method succeeded; returns them as JSON.
nlohmann::json writeMeans(const std::filesystem::path& out_dir, const std::vector<Row>& rows,
                          const Job& job) {
  const std::vector<std::string>& names = dasp::peers::metricNames();
  std::vector<std::string> mean_header = {"method",        "k",       "frames",
                                          "failed_frames", "time_ms", "wall_ms"};
  mean_header.insert(mean_header.end(), names.begin(), names.end());
  std::vector<std::vector<std::string>> mean_table;
  nlohmann::json means = nlohmann::json::array();
  for (std::size_t m = 0; m < job.methods.size(); ++m) {
    for (int k : job.counts) {
      std::map<std::string, double> sum;
      int ok = 0;
      int failed = 0;
      for (const Row& r : rows) {
        if (r.method_index != static_cast<int>(m) || r.k != k) continue;
        if (!r.error.empty()) {
          ++failed;
          continue;
        }
        ++ok;
        sum["time_ms"] += r.time_ms;
        sum["wall_ms"] += r.wall_ms;
        for (const auto& [n, v] : r.metrics) sum[n] += v;
      }
      const std::string& method = job.output_names[m];
      std::vector<std::string> line = {method, std::to_string(k), std::to_string(ok),
                                       std::to_string(failed)};
      nlohmann::json j = {{"method", method}, {"k", k}, {"frames", ok}, {"failed_frames", failed}};
      for (const std::string& n : std::vector<std::string>{"time_ms", "wall_ms"}) {
        line.push_back(ok ? number(sum[n] / ok) : "");
        if (ok) j[n] = sum[n] / ok;
      }
      for (const std::string& n : names) {
        line.push_back(ok ? number(sum[n] / ok) : "");
        if (ok) j[n] = sum[n] / ok;
      }
      mean_table.push_back(std::move(line));
      means.push_back(std::move(j));
    }
  }
  writeCsv(out_dir / "mean.csv", mean_header, mean_table);
  return means;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Evaluate superpixel methods on a folder of RGB-D frames with object labels "
      "(<name>_rgb.png, <name>_depth_mm.png, <name>_label_object.png) and write per-frame and "
      "mean metrics (CSV and JSON)."};
  std::string data_dir;
  std::string out_dir = "dasp_eval";
  std::vector<std::string> method_names = {"DASP", "ASP_RGB", "ASP_RGBD", "SLIC", "SEEDS", "VCCS"};
  Job job;
  job.counts = {250, 500, 1000, 2000};
  int threads = 1;
  int max_frames = 0;
  app.add_option("--data", data_dir, "dataset folder")->required()->check(CLI::ExistingDirectory);
  app.add_option("--out", out_dir, "output folder")->capture_default_str();
  app.add_option("--methods", method_names, "DASP ASP_RGB ASP_RGBD SLIC SEEDS VCCS")
      ->capture_default_str();
  app.add_option("-k,--counts", job.counts, "superpixel counts K")->capture_default_str();
  dasp::peers::addMethodOptions(app, job.options);
  std::string name_suffix;
  app.add_option("--name-suffix", name_suffix,
                 "appended to every method name in the outputs (to merge runs with other "
                 "options, e.g. DASP_wd1)");
  app.add_option("--fx", job.intrinsics.fx)->capture_default_str();
  app.add_option("--fy", job.intrinsics.fy)->capture_default_str();
  app.add_option("--cx", job.intrinsics.cx)->capture_default_str();
  app.add_option("--cy", job.intrinsics.cy)->capture_default_str();
  app.add_option("-j,--threads", threads,
                 "frames processed in parallel; every method itself runs single-threaded")
      ->capture_default_str();
  app.add_option("--max-frames", max_frames, "evaluate only the first N frames (0 = all)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  try {
    for (const std::string& name : method_names) {
      job.methods.push_back(dasp::peers::parseMethod(name));
      // The names in the outputs, with the suffix of this run.
      job.output_names.push_back(dasp::peers::methodName(job.methods.back()) + name_suffix);
    }
    for (int k : job.counts) {
      if (k < 1) throw std::invalid_argument("every K must be >= 1");
    }
    if (threads < 1) threads = 1;
    // Parallelism is over frames; OpenCV's own worker threads would distort the per-method times.
    cv::setNumThreads(1);
    std::vector<dasp::RgbdFramePaths> frames = dasp::listRgbdFolder(data_dir);
    frames.erase(std::remove_if(frames.begin(), frames.end(),
                                [](const dasp::RgbdFramePaths& f) { return f.label.empty(); }),
                 frames.end());
    if (max_frames > 0 && static_cast<std::size_t>(max_frames) < frames.size()) {
      frames.resize(max_frames);
    }
    if (frames.empty()) throw std::invalid_argument("no labelled frame in " + data_dir);
    std::filesystem::create_directories(out_dir);

    const std::vector<Row> rows = evaluateFrames(frames, job, threads);
    writePerFrame(out_dir, rows);
    const nlohmann::json means = writeMeans(out_dir, rows, job);
    const dasp::peers::MethodOptions& options = job.options;
    nlohmann::json summary = {{"data", data_dir},
                              {"frames", frames.size()},
                              {"iterations", options.iterations},
                              {"seed", options.seed},
                              {"dasp_weight_depth", options.experimental.weight_depth},
                              {"depth_jump_ratio", options.depth_jump_ratio},
                              {"max_slant_factor", options.experimental.max_slant_factor},
                              {"depth_exponent", options.experimental.depth_exponent},
                              {"parallel_frames", threads},
                              {"mask", "object label > 0 and depth > 0"},
                              {"time_ms", "thread CPU time of the method call (single-threaded)"},
                              {"means", means}};
    std::ofstream(std::filesystem::path(out_dir) / "mean.json") << summary.dump(1) << "\n";
    std::cout << "wrote " << rows.size() << " rows for " << frames.size() << " frames to "
              << out_dir << "\n";
  } catch (const std::exception& e) {
    std::cerr << "dasp_evaluate: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
