// libFuzzer target: EventPacketDecoder on `evt3` bytes (see fuzz_event_packet_common.h).
#include "fuzz_event_packet_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return fuzz_packets::run(ebslam::EventEncoding::kEvt3, data, size);
}
