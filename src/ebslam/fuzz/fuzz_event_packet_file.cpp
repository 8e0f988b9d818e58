// libFuzzer target: the event packet file reader (parseEventPackets). Any bytes either parse or
// throw MalformedEventData; what parses survives a serialise/parse round trip unchanged.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "ebslam/events/event_packet.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string bytes("EBSLAM-EVENT-PACKETS v1\n");  // most inputs get past the magic
  bytes.append(reinterpret_cast<const char*>(data), size);
  for (const std::string& input : {bytes, std::string(reinterpret_cast<const char*>(data), size)}) {
    try {
      const auto packets = ebslam::parseEventPackets(
          reinterpret_cast<const std::uint8_t*>(input.data()), input.size());
      const std::string again = ebslam::serializeEventPackets(packets);
      if (again != input) std::abort();
    } catch (const ebslam::MalformedEventData&) {
    }
  }
  return 0;
}
