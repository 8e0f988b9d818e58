// Converts event files between the project's binary format, plain text `t x y p` and the Event
// Camera Dataset text format, e.g.
//   ebslam_event_convert ../shared/data/rpg-events/shapes_rotation/events.txt shapes.ebe
//   ebslam_event_convert run.ebe run.txt --to text
// Exit status: 0 success, 1 usage or I/O error, 2 the input was damaged (the events before the
// damage were converted and the damage is described on stderr).

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <optional>
#include <string>

#include "ebslam/events/event_io.h"

namespace {

std::optional<ebslam::EventFileFormat> formatOption(const std::string& name) {
  if (name.empty() || name == "auto") return std::nullopt;
  const auto format = ebslam::parseEventFileFormat(name);
  if (!format) throw CLI::ValidationError("format", "unknown format '" + name + "'");
  return format;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Convert event files between binary (.ebe), text (t[us] x y p) and rpg "
      "(Event Camera Dataset, t[s] x y p) formats"};
  std::string input;
  std::string output;
  std::string from = "auto";
  std::string to = "auto";
  std::optional<std::uint32_t> width;
  std::optional<std::uint32_t> height;
  bool sort = false;
  app.add_option("input", input, "input event file")->required()->check(CLI::ExistingFile);
  app.add_option("output", output, "output event file")->required();
  app.add_option("--from", from, "input format: auto (magic/content), binary, text, rpg")
      ->capture_default_str();
  app.add_option("--to", to, "output format: auto (.txt => text, else binary), binary, text, rpg")
      ->capture_default_str();
  app.add_option("--width", width, "sensor width [pixels] (default: from the input)");
  app.add_option("--height", height, "sensor height [pixels] (default: from the input)");
  app.add_flag("--sort", sort,
               "sort events by timestamp (stable) before writing; otherwise file order is kept");
  CLI11_PARSE(app, argc, argv);

  try {
    if (width.has_value() != height.has_value()) {
      throw CLI::ValidationError("--width/--height", "give both or neither");
    }
    ebslam::EventReadOptions options;
    options.format = formatOption(from);
    if (width) options.sensor = ebslam::SensorSize{*width, *height};
    const ebslam::EventFileFormat out_format =
        formatOption(to).value_or(ebslam::eventFileFormatFromExtension(output));

    ebslam::EventFileReader reader(input, options);
    const bool size_known_up_front =
        options.sensor.has_value() || reader.format() != ebslam::EventFileFormat::kText;
    std::size_t converted = 0;
    if (size_known_up_front && !sort) {
      // Streaming: constant memory for any file size.
      ebslam::EventFileWriter writer(output, reader.sensor(), out_format);
      ebslam::EventVector batch;
      while (reader.next(batch, 1 << 16) > 0) writer.write(batch);
      writer.close();
      converted = writer.eventsWritten();
    } else {
      // Text without a declared size (sensor = bounding box) or sorting: whole file.
      ebslam::EventVector events;
      ebslam::EventVector batch;
      while (reader.next(batch, 1 << 16) > 0)
        events.insert(events.end(), batch.begin(), batch.end());
      if (sort) ebslam::sortEventsByTime(events);
      ebslam::writeEventFile(output, events, reader.sensor(), out_format);
      converted = events.size();
    }
    const ebslam::SensorSize sensor = reader.sensor();
    std::printf("%zu events, %s -> %s, sensor %ux%u, %zu with timestamps running backwards%s\n",
                converted, ebslam::toString(reader.format()), ebslam::toString(out_format),
                sensor.width, sensor.height, reader.nonMonotonicCount(),
                sort && reader.nonMonotonicCount() > 0 ? " (sorted)" : "");
    if (reader.error()) {
      std::fprintf(stderr, "%s: %s\n", input.c_str(), reader.error()->c_str());
      return 2;
    }
  } catch (const CLI::Error& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
