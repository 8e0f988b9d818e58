#include "edvs/recording_stream.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "ebslam/events/event_io.h"
#include "ebslam/events/event_packet.h"

namespace edvs {

ebslam::EventVector edvsStreamFromRecording(const ebslam::EventVector& events,
                                            const ebslam::SensorSize& sensor, double rate_hz) {
  if (!(rate_hz > 0)) throw std::invalid_argument("edvsStreamFromRecording: rate must be > 0");
  if (events.size() < 2) {
    throw std::invalid_argument("edvsStreamFromRecording: fewer than two events");
  }
  for (std::size_t i = 1; i < events.size(); ++i) {
    if (events[i].t_us < events[i - 1].t_us) {
      throw std::invalid_argument("edvsStreamFromRecording: times run backwards at event " +
                                  std::to_string(i));
    }
  }
  const double span_us = static_cast<double>(events.back().t_us - events.front().t_us);
  if (!(span_us > 0)) throw std::invalid_argument("edvsStreamFromRecording: zero time span");
  const std::uint32_t side = std::max(sensor.width, sensor.height);
  const std::uint32_t factor = std::max<std::uint32_t>(1, (side + 127) / 128);
  // Mean rate rate_hz: the whole recording spans size / rate_hz seconds.
  const double stretch = static_cast<double>(events.size()) / rate_hz * 1e6 / span_us;
  ebslam::EventVector out;
  out.reserve(events.size());
  for (const ebslam::Event& e : events) {
    ebslam::Event m = e;
    m.x = static_cast<std::uint16_t>(std::min<std::uint32_t>(127, e.x / factor));
    m.y = static_cast<std::uint16_t>(std::min<std::uint32_t>(127, e.y / factor));
    m.t_us = std::llround(static_cast<double>(e.t_us - events.front().t_us) * stretch);
    out.push_back(m);
  }
  return out;
}

ebslam::EventVector readRecording(const std::string& path, ebslam::SensorSize& sensor) {
  ebslam::EventVector events;
  if (path.size() > 5 && path.compare(path.size() - 5, 5, ".evpk") == 0) {
    const std::vector<ebslam::EventPacket> packets = ebslam::readEventPacketFile(path);
    if (packets.empty()) throw std::runtime_error(path + ": no event packets");
    const auto encoding = ebslam::eventEncodingFromName(packets.front().encoding);
    if (!encoding) {
      throw std::runtime_error(path + ": unknown encoding " + packets.front().encoding);
    }
    sensor = ebslam::SensorSize{packets.front().width, packets.front().height};
    ebslam::EventPacketDecoder decoder(*encoding, sensor);
    ebslam::PacketEventVector decoded;
    for (const ebslam::EventPacket& p : packets) {
      if (p.encoding != packets.front().encoding) {
        throw std::runtime_error(path + ": packets of more than one encoding");
      }
      decoded.clear();
      decoder.decode(p.events.data(), p.events.size(), p.time_base, decoded);
      for (const ebslam::PacketEvent& d : decoded) {
        ebslam::Event e;
        e.x = d.x;
        e.y = d.y;
        e.polarity = d.polarity;
        e.t_us = static_cast<std::int64_t>(d.t_ns / 1000);
        events.push_back(e);
      }
    }
  } else {
    ebslam::EventReadResult r = ebslam::readEventFile(path);
    if (r.error) throw std::runtime_error(path + ": " + *r.error);
    sensor = r.sensor;
    events = std::move(r.events);
  }
  std::stable_sort(events.begin(), events.end(),
                   [](const ebslam::Event& a, const ebslam::Event& b) { return a.t_us < b.t_us; });
  return events;
}

}  // namespace edvs
