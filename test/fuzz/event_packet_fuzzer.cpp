// libFuzzer target: bytes -> a stream of ebslam_msgs/EventPacket (= event_camera_msgs/EventPacket)
// messages -> what every event consumer runs on each (ebslam_msgs::EventPacketConverter: the
// evt3 / libcaer / libcaer_cmp / mono decoders and the clock, as ebslam_ros' EventSubscriber).
// The first input byte picks the encoding of messages whose own encoding string is none of the
// four, so that every decoder sees the bytes. Promises: no crash; a packet is either rejected
// with a reason or gives events inside its width x height, at times ros::Time can hold.
#include <ebslam_msgs/EventPacket.h>

#include <cstdint>
#include <cstdlib>

#include "ebslam_msgs/event_packet_conversions.h"
#include "fuzz_message.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* const kEncodings[] = {"evt3", "libcaer", "libcaer_cmp", "mono"};
  const char* fallback = kEncodings[data[0] % 4];
  ebslam_msgs::EventPacketConverter converter;
  std::size_t pos = 1;
  while (pos < size) {
    ebslam_msgs::EventPacket msg;
    const std::size_t used =
        fuzz::readMessage<ebslam_msgs::EventPacket_>(data + pos, size - pos, msg);
    if (used == 0) break;
    pos += used;
    if (!ebslam::eventEncodingFromName(msg.encoding)) msg.encoding = fallback;
    msg.is_bigendian = false;
    msg.width = 1 + msg.width % 2048;  // sizes a camera has: the rejection is tested elsewhere
    msg.height = 1 + msg.height % 2048;
    ebslam_msgs::EventPacketResult result;
    const ebslam_msgs::EventArray array = converter.toEventArray(msg, &result);
    if (result.rejected) std::abort();  // a known encoding and a valid size always decode
    if (array.width != msg.width || array.height != msg.height) std::abort();
    if (array.events.size() > msg.events.size() * 12) std::abort();  // at most 12 per 16 bits
    for (const auto& e : array.events) {
      if (e.x >= msg.width || e.y >= msg.height || e.ts.isZero()) std::abort();
    }
    if (!array.events.empty() && array.header.stamp != array.events.back().ts) std::abort();
  }
  return 0;
}
