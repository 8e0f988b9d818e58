// libFuzzer target: EventPacketDecoder on `mono` bytes (see fuzz_event_packet_common.h).
#include "fuzz_event_packet_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return fuzz_packets::run(ebslam::EventEncoding::kMono, data, size);
}
