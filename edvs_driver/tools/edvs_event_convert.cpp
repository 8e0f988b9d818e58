// Converts event recordings between the project's formats: binary, text (`t x y p`), the Event
// Camera Dataset text (rpg) and rosbag (EventArray messages):
//   edvs_event_convert in.bag out.ebe                      # bag -> binary (format from extension)
//   edvs_event_convert events.txt out.bag --from rpg --topic /edvs/events
//   edvs_event_convert in.ebe out.txt --to text
#include <CLI/CLI.hpp>

#include <cstdio>
#include <optional>

#include "ebslam/events/event_io.h"
#include "edvs_driver/bag_io.h"

namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// "bag" or an ebslam format name; std::nullopt means bag.
std::optional<ebslam::EventFileFormat> resolve(const std::string& name, bool& is_bag) {
  is_bag = name == "bag" || name == "rosbag";
  if (is_bag) return std::nullopt;
  const auto f = ebslam::parseEventFileFormat(name);
  if (!f) throw std::invalid_argument("unknown format '" + name + "' (binary, text, rpg, bag)");
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Convert event files: binary, text, rpg (Event Camera Dataset), bag"};
  std::string in, out, from, to, topic, frame_id = "edvs_optical_frame";
  std::int64_t batch_us = 10000, time_offset_us = 0;
  std::uint32_t width = 0, height = 0;
  app.add_option("input", in, "input file")->required();
  app.add_option("output", out, "output file")->required();
  app.add_option("--from", from, "input format (binary, text, rpg, bag); default: detect");
  app.add_option("--to", to,
                 "output format; default: from the extension (.bag, .txt, else binary)");
  app.add_option("--topic", topic,
                 "bag topic to read (default: every EventArray topic) / write (/events)");
  app.add_option("--frame-id", frame_id, "frame_id of written EventArray messages");
  app.add_option("--batch-us", batch_us, "time window per written EventArray message [us]");
  app.add_option("--time-offset-us", time_offset_us,
                 "added to every event time (e.g. to move file times into ROS time)");
  app.add_option("--width", width, "sensor width for formats without one (rpg: 240)");
  app.add_option("--height", height, "sensor height for formats without one (rpg: 180)");
  CLI11_PARSE(app, argc, argv);

  try {
    bool in_bag = endsWith(in, ".bag");
    std::optional<ebslam::EventFileFormat> in_format;
    if (!from.empty()) in_format = resolve(from, in_bag);
    bool out_bag = endsWith(out, ".bag");
    std::optional<ebslam::EventFileFormat> out_format;
    if (!to.empty()) {
      out_format = resolve(to, out_bag);
    } else if (!out_bag) {
      out_format = ebslam::eventFileFormatFromExtension(out);
    }

    ebslam::EventVector events;
    ebslam::SensorSize sensor;
    int status = 0;
    if (in_bag) {
      edvs_driver::BagReadResult r = edvs_driver::readEventBag(in, topic);
      events = std::move(r.events);
      sensor = r.sensor;
      std::fprintf(stderr, "read %zu events from %zu messages of %zu topic(s)\n", events.size(),
                   r.messages, r.topics.size());
    } else {
      ebslam::EventReadOptions options;
      options.format = in_format;
      if (width > 0 && height > 0) options.sensor = ebslam::SensorSize{width, height};
      ebslam::EventReadResult r = ebslam::readEventFile(in, options);
      if (r.error) {
        std::fprintf(stderr, "warning: %s; converting the %zu events before it\n", r.error->c_str(),
                     r.events.size());
        status = 3;
      }
      events = std::move(r.events);
      sensor = r.sensor;
    }
    if (width > 0 && height > 0) sensor = ebslam::SensorSize{width, height};
    for (ebslam::Event& e : events) e.t_us += time_offset_us;

    if (out_bag) {
      edvs_driver::BagWriteOptions options;
      if (!topic.empty()) options.topic = topic;
      options.frame_id = frame_id;
      options.batch_us = batch_us;
      edvs_driver::writeEventBag(out, events, sensor, options);
    } else {
      ebslam::writeEventFile(out, events, sensor, *out_format);
    }
    std::fprintf(stderr, "wrote %zu events (%ux%u) to %s\n", events.size(), sensor.width,
                 sensor.height, out.c_str());
    return status;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "edvs_event_convert: %s\n", e.what());
    return 1;
  }
}
