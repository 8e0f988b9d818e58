// libFuzzer target: EventPacketDecoder on `libcaer` bytes (see fuzz_event_packet_common.h).
#include "fuzz_event_packet_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return fuzz_packets::run(ebslam::EventEncoding::kLibcaer, data, size);
}
