// libFuzzer target for the event file readers (binary, text, rpg): any input must be read
// without crashing, undefined behaviour or unbounded memory, and the reader's invariants must
// hold. Built by run_fuzz.sh, not by the normal build.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <string>

#include "ebslam/events/event_io.h"

namespace {

struct Outcome {
  ebslam::EventVector events;
  std::optional<std::string> error;
  ebslam::SensorSize sensor;
  std::size_t non_monotonic = 0;
};

Outcome readAll(const std::string& bytes, const ebslam::EventReadOptions& options,
                std::size_t batch_size) {
  ebslam::EventFileReader reader(std::make_unique<std::istringstream>(bytes), options);
  Outcome outcome;
  ebslam::EventVector batch;
  while (reader.next(batch, batch_size) > 0) {
    if (batch.size() > batch_size) std::abort();
    outcome.events.insert(outcome.events.end(), batch.begin(), batch.end());
  }
  if (!reader.done()) std::abort();
  if (reader.next(batch, batch_size) != 0) std::abort();  // stays done
  if (reader.eventsRead() != outcome.events.size()) std::abort();
  outcome.error = reader.error();
  outcome.sensor = reader.sensor();
  outcome.non_monotonic = reader.nonMonotonicCount();
  return outcome;
}

void check(const std::string& bytes, const ebslam::EventReadOptions& options) {
  const Outcome big = readAll(bytes, options, 4096);
  const Outcome small = readAll(bytes, options, 3);
  // Batch size must not change what is read.
  if (big.events != small.events || big.error != small.error ||
      big.non_monotonic != small.non_monotonic) {
    std::abort();
  }
  if (big.non_monotonic > big.events.size()) std::abort();
  // Every event lies inside the reported sensor (binary header, declared or bounding box).
  for (const ebslam::Event& e : big.events) {
    if (!big.sensor.contains(e)) std::abort();
  }
}

// Whatever was read must survive a write/read round trip through every format.
void roundTrip(const Outcome& read) {
  static const std::string path = "/dev/shm/ebslam_fuzz_events_" + std::to_string(::getpid());
  static const int registered = std::atexit([] { std::remove(path.c_str()); });
  (void)registered;
  if (read.events.empty() || read.sensor.height > 32768 || read.sensor.width > 65535) return;
  for (auto format : {ebslam::EventFileFormat::kBinary, ebslam::EventFileFormat::kText,
                      ebslam::EventFileFormat::kRpgText}) {
    ebslam::writeEventFile(path, read.events, read.sensor, format);
    ebslam::EventReadOptions options;
    options.format = format;
    options.sensor = read.sensor;
    if (format == ebslam::EventFileFormat::kText) options.sensor.reset();  // from its header
    const ebslam::EventReadResult back = ebslam::readEventFile(path, options);
    if (back.error || back.events != read.events) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  ebslam::EventReadOptions options;
  check(bytes, options);  // detected format
  roundTrip(readAll(bytes, options, 1 << 16));
  for (auto format : {ebslam::EventFileFormat::kBinary, ebslam::EventFileFormat::kText,
                      ebslam::EventFileFormat::kRpgText}) {
    options.format = format;
    check(bytes, options);
  }
  options.format = ebslam::EventFileFormat::kText;
  options.sensor = ebslam::SensorSize{128, 128};
  check(bytes, options);
  return 0;
}
