// Event packet decoders (evt3, libcaer, libcaer_cmp, mono) on the real recordings of the
// event_camera_codecs repository (excerpts in test/data/event_packets; the whole recordings from
// ../shared/data/event-camera-codecs when present) and on synthetic streams.

#include <gtest/gtest.h>

#include <unistd.h>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <tuple>

#include "ebslam/events/event_packet.h"
#include "event_packet_encoders.h"

namespace ebslam {
namespace {

const std::string kPacketDir = EBSLAM_EVENT_PACKETS_DIR;

struct Sums {
  std::uint64_t count = 0, t = 0, x = 0, y = 0, on = 0;
  std::uint64_t trigger_t = 0, trigger_edge = 0, trigger_id = 0, triggers = 0;
  PacketEvent first{}, last{};
  PacketDecodeStats stats;
  bool monotonic = true;
};

Sums decodeAll(const std::vector<EventPacket>& packets) {
  Sums s;
  if (packets.empty()) return s;
  EventPacketDecoder decoder(*eventEncodingFromName(packets.front().encoding),
                             SensorSize{packets.front().width, packets.front().height});
  PacketEventVector events;
  std::vector<TriggerEvent> triggers;
  for (const EventPacket& p : packets) {
    const PacketDecodeStats st =
        decoder.decode(p.events.data(), p.events.size(), p.time_base, events, &triggers);
    s.stats.events += st.events;
    s.stats.outside += st.outside;
    s.stats.dropped_bytes += st.dropped_bytes;
    s.stats.before_time += st.before_time;
    s.stats.triggers += st.triggers;
  }
  for (std::size_t i = 0; i < events.size(); ++i) {
    const PacketEvent& e = events[i];
    s.t += e.t_ns;
    s.x += e.x;
    s.y += e.y;
    s.on += e.polarity;
    if (i > 0 && e.t_ns < events[i - 1].t_ns) s.monotonic = false;
  }
  for (const TriggerEvent& e : triggers) {
    s.trigger_t += e.t_ns;
    s.trigger_edge += e.edge;
    s.trigger_id += e.id;
  }
  s.triggers = triggers.size();
  s.count = events.size();
  if (!events.empty()) {
    s.first = events.front();
    s.last = events.back();
  }
  return s;
}

void expectEvent(const PacketEvent& e, std::uint64_t t, int x, int y, bool p) {
  EXPECT_EQ(e.t_ns, t);
  EXPECT_EQ(e.x, x);
  EXPECT_EQ(e.y, y);
  EXPECT_EQ(e.polarity, p);
}

// The upstream decoder test asserts these sums for the whole mono recording, which the
// repository ships in full.
TEST(EventPacketFixture, MonoMatchesReferenceChecksums) {
  const Sums s = decodeAll(readEventPacketFile(kPacketDir + "/mono_640x480.evpk"));
  EXPECT_EQ(s.count, 100u);  // 50 ON, 50 OFF
  EXPECT_EQ(s.t, 4950000u);
  EXPECT_EQ(s.x, 34450u);
  EXPECT_EQ(s.y, 26450u);
  EXPECT_EQ(s.on, 50u);
  EXPECT_EQ(s.stats.dropped_bytes + s.stats.outside, 0u);
  EXPECT_TRUE(s.monotonic);
}

// Excerpts (first 40 evt3 packets; libcaer packets 88..111, across the sensor clock's 2^31 us
// rollover). Figures: this decoder's output, which matches the reference checksums on the whole
// recordings (EventPacketRealData below).
TEST(EventPacketFixture, Evt3Excerpt) {
  const auto packets = readEventPacketFile(kPacketDir + "/evt3_prophesee_1280x720.evpk");
  ASSERT_EQ(packets.size(), 40u);
  EXPECT_EQ(packets.front().width, 1280u);
  EXPECT_EQ(packets.front().height, 720u);
  const Sums s = decodeAll(packets);
  EXPECT_EQ(s.count, 34134u);
  EXPECT_EQ(s.t, 493386389004000u);
  EXPECT_EQ(s.x, 16247822u);
  EXPECT_EQ(s.y, 13089248u);
  EXPECT_EQ(s.on, 17659u);
  EXPECT_EQ(s.stats.dropped_bytes + s.stats.outside, 0u);
  EXPECT_TRUE(s.monotonic);
}

TEST(EventPacketFixture, LibcaerExcerptAcrossRollover) {
  const auto packets = readEventPacketFile(kPacketDir + "/libcaer_rollover_640x480.evpk");
  ASSERT_EQ(packets.size(), 24u);
  const Sums s = decodeAll(packets);
  EXPECT_EQ(s.count, 38422u);
  EXPECT_EQ(s.t, 12413334864899029876u);
  EXPECT_EQ(s.x, 12837148u);
  EXPECT_EQ(s.y, 9503022u);
  EXPECT_EQ(s.on, 21105u);
  EXPECT_EQ(s.stats.dropped_bytes + s.stats.outside, 0u);
  // Host time runs on smoothly across the rollover (packets 99 -> 100 of the recording).
  EXPECT_TRUE(s.monotonic);
  EXPECT_LT(s.last.t_ns - s.first.t_ns, 1'000'000'000u);
}

// The whole reference recordings against the checksums the upstream decoder test asserts
// (../shared/data/event-camera-codecs/README.md); converted with
// scripts/event_packets_from_ros2_bag.py (python3, standard library only).
TEST(EventPacketRealData, WholeRecordingsMatchReferenceChecksums) {
  const std::string dir = std::string(EBSLAM_SHARED_DATA_DIR) + "/event-camera-codecs";
  const std::string script =
      std::string(EBSLAM_REPO_ROOT) + "/scripts/event_packets_from_ros2_bag.py";
  if (std::FILE* f = std::fopen((dir + "/README.md").c_str(), "r")) {
    std::fclose(f);
  } else {
    GTEST_SKIP()
        << "reads the event_camera_codecs recordings in ../shared/data/event-camera-codecs";
  }
  const std::string tmp = "/tmp/ebslam_event_packets_" + std::to_string(::getpid()) + ".evpk";
  auto convert = [&](const std::string& db3) {
    const std::string cmd =
        "python3 '" + script + "' '" + dir + "/" + db3 + "' '" + tmp + "' 2>/dev/null";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    auto packets = readEventPacketFile(tmp);
    std::remove(tmp.c_str());
    return packets;
  };
  {
    const auto packets = convert("test_data_evt3_trigger/test_data_evt3_trigger_0.db3");
    EXPECT_EQ(packets.size(), 105u);
    const Sums s = decodeAll(packets);
    EXPECT_EQ(s.t, 1222326831810000u);
    EXPECT_EQ(s.x, 42078718u);
    EXPECT_EQ(s.y, 31656267u);
    EXPECT_EQ(s.on, 41439u);
    EXPECT_EQ(s.trigger_t, 29096982000u);
    EXPECT_EQ(s.trigger_edge, 1u);
    EXPECT_EQ(s.trigger_id, 0u);
    EXPECT_EQ(s.stats.dropped_bytes + s.stats.outside + s.stats.before_time, 0u);
    EXPECT_TRUE(s.monotonic);
    std::printf(
        "evt3: %llu events, %llu triggers, first t=%llu (%u,%u,%d) last t=%llu (%u,%u,%d), %zu "
        "words before the first time\n",
        static_cast<unsigned long long>(s.count), static_cast<unsigned long long>(s.triggers),
        static_cast<unsigned long long>(s.first.t_ns), s.first.x, s.first.y, s.first.polarity,
        static_cast<unsigned long long>(s.last.t_ns), s.last.x, s.last.y, s.last.polarity,
        s.stats.before_time);
  }
  {
    const auto packets = convert("test_data_libcaer_rollover/libcaer_rollover_0.db3");
    EXPECT_EQ(packets.size(), 201u);
    const Sums s = decodeAll(packets);
    EXPECT_EQ(s.t, 15762826572202229126u);  // wraps in uint64, as the reference sums
    EXPECT_EQ(s.x, 111651612u);
    EXPECT_EQ(s.y, 82801007u);
    EXPECT_EQ(s.on, 181908u);
    EXPECT_EQ(s.stats.dropped_bytes + s.stats.outside, 0u);
    EXPECT_TRUE(s.monotonic);
    std::size_t bytes = 0;
    for (const auto& p : packets) bytes += p.events.size();
    EXPECT_EQ(s.count, bytes / 8);  // every 8-byte record is one event: none lost or invented
    std::printf("libcaer: %llu events, first t=%llu (%u,%u,%d) last t=%llu (%u,%u,%d)\n",
                static_cast<unsigned long long>(s.count),
                static_cast<unsigned long long>(s.first.t_ns), s.first.x, s.first.y,
                s.first.polarity, static_cast<unsigned long long>(s.last.t_ns), s.last.x, s.last.y,
                s.last.polarity);
  }
  {
    const Sums s = decodeAll(convert("test_data_mono_cd/test_data_mono_cd_0.db3"));
    EXPECT_EQ(s.t, 4950000u);
    EXPECT_EQ(s.x, 34450u);
    EXPECT_EQ(s.y, 26450u);
    EXPECT_EQ(s.on, 50u);
  }
}

// --- synthetic evt3 -------------------------------------------------------------------------

std::uint16_t w(int code, int rest) { return static_cast<std::uint16_t>((code << 12) | rest); }

std::vector<std::uint8_t> bytesOf(const std::vector<std::uint16_t>& words) {
  std::vector<std::uint8_t> b;
  for (std::uint16_t v : words) {
    b.push_back(static_cast<std::uint8_t>(v & 0xFF));
    b.push_back(static_cast<std::uint8_t>(v >> 8));
  }
  return b;
}

TEST(Evt3Decoder, VectorsTimeAndDroppedWords) {
  EventPacketDecoder d(EventEncoding::kEvt3, SensorSize{640, 480});
  const auto bytes = bytesOf({
      w(0x2, 5),               // ADDR_X before any time: skipped (time unknown)
      w(0x8, 0x123),           // TIME_HIGH
      w(0x6, 0x456),           // TIME_LOW: time valid from here
      w(0x0, 7),               // ADDR_Y y=7
      w(0x2, 0x800 | 10),      // ADDR_X x=10 ON
      w(0x3, 630),             // VECT_BASE_X x=630 OFF
      w(0x4, 0b100000000101),  // VECT_12: x=630, 632, 641 (outside)
      w(0x5, 0b00000011),      // VECT_8 from 642: 642, 643 outside
      w(0xA, (3 << 8) | 1),    // EXT_TRIGGER id 3 rising
      w(0x9, 0),               // undefined code
      w(0xE, 0x19),            // OTHERS
  });
  std::vector<std::uint8_t> odd = bytes;
  odd.push_back(0xAB);  // trailing half word
  PacketEventVector out;
  std::vector<TriggerEvent> triggers;
  const PacketDecodeStats s = d.decode(odd.data(), odd.size(), 0, out, &triggers);
  const std::uint64_t t = ((0x123ull << 12) | 0x456ull) * 1000u;
  ASSERT_EQ(out.size(), 3u);
  expectEvent(out[0], t, 10, 7, true);
  expectEvent(out[1], t, 630, 7, false);
  expectEvent(out[2], t, 632, 7, false);
  EXPECT_EQ(s.events, 3u);
  EXPECT_EQ(s.outside, 3u);
  EXPECT_EQ(s.before_time, 1u);
  EXPECT_EQ(s.dropped_bytes, 3u);
  ASSERT_EQ(triggers.size(), 1u);
  EXPECT_EQ(triggers[0].id, 3);
  EXPECT_EQ(triggers[0].edge, 1);
  EXPECT_EQ(triggers[0].t_ns, t);
}

TEST(Evt3Decoder, TimeHighWrapAcrossPackets) {
  EventPacketDecoder d(EventEncoding::kEvt3, SensorSize{64, 64});
  PacketEventVector out;
  auto a = bytesOf({w(0x8, 0xFFF), w(0x6, 0xFFE), w(0x0, 1), w(0x2, 1)});
  auto b = bytesOf({w(0x8, 0xFFA), w(0x2, 2),  // small step back: a sensor bit error, no wrap
                    w(0x8, 0x001), w(0x6, 0x002), w(0x2, 3)});  // wrap of the 24-bit clock
  d.decode(a.data(), a.size(), 0, out);
  d.decode(b.data(), b.size(), 0, out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].t_ns, ((0xFFFull << 12) | 0xFFEull) * 1000u);
  EXPECT_EQ(out[1].t_ns, ((0xFFAull << 12) | 0xFFEull) * 1000u);
  EXPECT_EQ(out[2].t_ns, ((std::uint64_t{1} << 24) | (0x001u << 12) | 0x002u) * 1000u);
}

// Decoder state spans packets: the real stream cut at arbitrary word boundaries decodes to the
// same events as in its original packets.
TEST(Evt3Decoder, StreamingAcrossArbitraryPacketCuts) {
  const auto packets = readEventPacketFile(kPacketDir + "/evt3_prophesee_1280x720.evpk");
  std::vector<std::uint8_t> stream;
  for (const auto& p : packets) stream.insert(stream.end(), p.events.begin(), p.events.end());
  const Sums whole = decodeAll(packets);
  EventPacketDecoder d(EventEncoding::kEvt3, SensorSize{1280, 720});
  PacketEventVector out;
  std::mt19937 rng(7);
  // The first packet as recorded (it holds the first complete time stamp), then random cuts.
  std::size_t pos = packets.front().events.size();
  d.decode(stream.data(), pos, 0, out);
  while (pos < stream.size()) {
    const std::size_t n = std::min<std::size_t>(2 * (1 + rng() % 3000), stream.size() - pos);
    d.decode(stream.data() + pos, n, 0, out);
    pos += n;
  }
  ASSERT_EQ(out.size(), whole.count);
  expectEvent(out.back(), whole.last.t_ns, whole.last.x, whole.last.y, whole.last.polarity);
}

// --- libcaer_cmp: the real libcaer excerpt, compressed as libcaer_driver does ---------------

TEST(LibcaerCmpDecoder, DecodesTheRealLibcaerExcerptCompressed) {
  const auto packets = readEventPacketFile(kPacketDir + "/libcaer_rollover_640x480.evpk");
  EventPacketDecoder raw(EventEncoding::kLibcaer, SensorSize{640, 480});
  EventPacketDecoder cmp(EventEncoding::kLibcaerCmp, SensorSize{640, 480});
  std::size_t vectors = 0, total = 0;
  for (const auto& p : packets) {
    PacketEventVector expected, got;
    raw.decode(p.events.data(), p.events.size(), p.time_base, expected);
    const std::uint64_t base = expected.front().t_ns;
    const auto bytes = test_encoders::libcaerCmp(expected, base);
    for (std::size_t k = 0; k + 1 < bytes.size(); k += 2) vectors += (bytes[k + 1] >> 4) == 5;
    const PacketDecodeStats s = cmp.decode(bytes.data(), bytes.size(), base, got);
    EXPECT_EQ(s.dropped_bytes + s.outside, 0u);
    auto key = [](const PacketEvent& e) { return std::make_tuple(e.t_ns, e.x, e.y, e.polarity); };
    auto less = [&](const PacketEvent& a, const PacketEvent& b) { return key(a) < key(b); };
    std::stable_sort(expected.begin(), expected.end(), less);
    std::stable_sort(got.begin(), got.end(), less);
    ASSERT_EQ(got.size(), expected.size());
    for (std::size_t i = 0; i < got.size(); ++i) ASSERT_EQ(key(got[i]), key(expected[i])) << i;
    total += got.size();
  }
  EXPECT_GT(total, 30000u);
  EXPECT_GT(vectors, 0u);
}

// --- malformed input ------------------------------------------------------------------------

TEST(EventPacketDecoder, RandomBytesNeverEscapeTheSensorOrThePacket) {
  std::mt19937 rng(11);
  for (auto enc : {EventEncoding::kEvt3, EventEncoding::kLibcaer, EventEncoding::kLibcaerCmp,
                   EventEncoding::kMono}) {
    EventPacketDecoder d(enc, SensorSize{346, 260});
    for (int round = 0; round < 200; ++round) {
      std::vector<std::uint8_t> bytes(rng() % 301);
      for (auto& b : bytes) b = static_cast<std::uint8_t>(rng());
      PacketEventVector out;
      const PacketDecodeStats s = d.decode(bytes.data(), bytes.size(), rng(), out);
      EXPECT_EQ(s.events, out.size());
      for (const auto& e : out) {
        EXPECT_LT(e.x, 346);
        EXPECT_LT(e.y, 260);
      }
    }
  }
}

TEST(EventPacketDecoder, RejectsBadSensorAndNamesEncodings) {
  EXPECT_THROW(EventPacketDecoder(EventEncoding::kMono, SensorSize{0, 10}), std::invalid_argument);
  EXPECT_THROW(EventPacketDecoder(EventEncoding::kMono, SensorSize{10, 70000}),
               std::invalid_argument);
  for (auto enc : {EventEncoding::kEvt3, EventEncoding::kLibcaer, EventEncoding::kLibcaerCmp,
                   EventEncoding::kMono}) {
    EXPECT_EQ(eventEncodingFromName(eventEncodingName(enc)), enc);
  }
  EXPECT_FALSE(eventEncodingFromName("evt2"));
  EXPECT_FALSE(eventEncodingFromName(""));
}

TEST(EventPacketFile, RoundTripAndEveryCutThrows) {
  const auto packets = readEventPacketFile(kPacketDir + "/mono_640x480.evpk");
  const std::string bytes = serializeEventPackets(packets);
  const auto* data = reinterpret_cast<const std::uint8_t*>(bytes.data());
  const auto back = parseEventPackets(data, bytes.size());
  ASSERT_EQ(back.size(), packets.size());
  EXPECT_EQ(back[1].events, packets[1].events);
  EXPECT_EQ(back[1].frame_id, "event_cam");
  EXPECT_EQ(back[1].time_base, 50000u);
  // Every cut either throws or, exactly at a packet boundary, yields the packets before it.
  const std::size_t first_end = serializeEventPackets({packets[0]}).size();
  for (std::size_t cut = 0; cut < bytes.size(); ++cut) {
    try {
      const auto part = parseEventPackets(data, cut);
      EXPECT_TRUE((cut == 24 && part.empty()) || (cut == first_end && part.size() == 1)) << cut;
    } catch (const MalformedEventData&) {
      EXPECT_TRUE(cut != 24 && cut != first_end) << cut;
    }
  }
  EXPECT_THROW(readEventPacketFile("/nonexistent/file.evpk"), std::runtime_error);
}

// --- clock ----------------------------------------------------------------------------------

TEST(EventPacketClock, AnchorsSensorTimeAndPassesEpochTime) {
  EventPacketClock clock;
  EventVector out;
  const std::int64_t stamp = 1'700'000'000'000'000'000;
  clock.append(EventEncoding::kEvt3, {{5'000'000'000, 1, 2, true}, {5'000'001'499, 3, 4, false}},
               stamp, out);
  clock.append(EventEncoding::kEvt3, {{5'001'000'000, 1, 2, true}}, stamp + 999'999'999, out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].t_us, stamp / 1000);
  EXPECT_EQ(out[1].t_us, stamp / 1000 + 1);     // 1.499 us -> 1 us
  EXPECT_EQ(out[2].t_us, stamp / 1000 + 1000);  // sensor spacing, not the later stamp
  // A camera restart (sensor clock back by > 1 s) re-anchors at the packet's stamp.
  clock.append(EventEncoding::kEvt3, {{1000, 0, 0, false}}, stamp + 5'000'000'000, out);
  EXPECT_EQ(out.back().t_us, (stamp + 5'000'000'000) / 1000);
  EventVector epoch;
  EventPacketClock c2;
  EXPECT_EQ(c2.append(EventEncoding::kLibcaer, {{1'000'000'500, 1, 1, true}, {~0ull, 1, 1, true}},
                      0, epoch),
            1u);
  ASSERT_EQ(epoch.size(), 1u);
  EXPECT_EQ(epoch[0].t_us, 1'000'001);
}

}  // namespace
}  // namespace ebslam
