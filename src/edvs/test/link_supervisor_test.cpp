// The link supervision (link_supervisor.h) against the pty emulator: a device that is not
// there yet is retried with exponential backoff, a lost device is reopened, a stalled line is
// reopened, a capture ends at its end, and the published clock never runs backwards across
// reconnects.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "edvs/emulator.h"
#include "edvs/link_supervisor.h"

using ebslam::EventVector;
using edvs::DeviceConfig;
using edvs::Emulator;
using edvs::EmulatorConfig;
using edvs::EventFormat;
using edvs::LinkEvent;
using edvs::LinkState;
using edvs::LinkStatus;
using edvs::LinkSupervisor;
using edvs::SupervisorConfig;
using Steady = std::chrono::steady_clock;

namespace {

std::string tempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          (name + "_" + std::to_string(::getpid()) + "_" +
           std::to_string(Steady::now().time_since_epoch().count())))
      .string();
}

DeviceConfig deviceFor(const std::string& uri) {
  DeviceConfig c;
  c.uri = uri;
  c.format = EventFormat::kAbs24;
  c.command_gap_ms = 2;
  return c;
}

/// What a supervisor delivered and logged, shared with its worker thread.
class Recorder {
 public:
  struct Log {
    LinkEvent event;
    std::string message;
    Steady::time_point at;
  };

  LinkSupervisor::Callbacks callbacks() {
    LinkSupervisor::Callbacks c;
    c.on_events = [this](EventVector& batch) {
      std::lock_guard<std::mutex> lock(mutex_);
      events_.insert(events_.end(), batch.begin(), batch.end());
    };
    c.on_stream_end = [this] {
      std::lock_guard<std::mutex> lock(mutex_);
      ++stream_ends_;
    };
    c.on_log = [this](LinkEvent event, const std::string& message) {
      std::lock_guard<std::mutex> lock(mutex_);
      logs_.push_back({event, message, Steady::now()});
    };
    return c;
  }
  EventVector events() {
    std::lock_guard<std::mutex> lock(mutex_);
    return events_;
  }
  std::vector<Log> logs(std::optional<LinkEvent> only = std::nullopt) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<Log> out;
    for (const Log& l : logs_) {
      if (!only || l.event == *only) out.push_back(l);
    }
    return out;
  }
  int streamEnds() {
    std::lock_guard<std::mutex> lock(mutex_);
    return stream_ends_;
  }

 private:
  std::mutex mutex_;
  EventVector events_;
  std::vector<Log> logs_;
  int stream_ends_ = 0;
};

bool waitFor(const std::function<bool()>& done, double timeout_s) {
  const auto end = Steady::now() + std::chrono::duration_cast<Steady::duration>(
                                       std::chrono::duration<double>(timeout_s));
  while (Steady::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return done();
}

void expectNeverBackwards(const EventVector& events) {
  for (std::size_t i = 1; i < events.size(); ++i) {
    ASSERT_GE(events[i].t_us, events[i - 1].t_us) << "at event " << i << " of " << events.size();
  }
}

}  // namespace

TEST(LinkSupervisor, RejectsBadConfig) {
  SupervisorConfig c;
  c.reconnect_min_s = 0;
  EXPECT_THROW(LinkSupervisor(deviceFor("serial:///dev/null"), c, {}), std::invalid_argument);
  c = SupervisorConfig();
  c.reconnect_max_s = 0.1;
  EXPECT_THROW(LinkSupervisor(deviceFor("serial:///dev/null"), c, {}), std::invalid_argument);
  c = SupervisorConfig();
  c.biases[0] = std::int64_t{1} << 24;
  EXPECT_THROW(LinkSupervisor(deviceFor("serial:///dev/null"), c, {}), std::invalid_argument);
  EXPECT_THROW(LinkSupervisor(deviceFor("nowhere"), SupervisorConfig(), {}), std::invalid_argument);
}

TEST(LinkSupervisor, RetriesWithBackoffThenReconnectsAfterTheDeviceDisappears) {
  const std::string link = tempPath("edvs_supervised");
  SupervisorConfig sc;
  sc.reconnect_min_s = 0.1;
  sc.reconnect_max_s = 0.4;
  Recorder rec;
  LinkSupervisor supervisor(deviceFor("serial://" + link), sc, rec.callbacks());
  supervisor.start();

  // No device yet: the delay doubles per failed open up to the cap.
  ASSERT_TRUE(waitFor([&] { return rec.logs(LinkEvent::kOpenFailed).size() >= 5; }, 10.0));
  const auto failed = rec.logs(LinkEvent::kOpenFailed);
  const char* delays[] = {"(retrying in 0.1 s)", "(retrying in 0.2 s)", "(retrying in 0.4 s)",
                          "(retrying in 0.4 s)"};
  const double delay_s[] = {0.1, 0.2, 0.4, 0.4};
  for (int i = 0; i < 4; ++i) {
    EXPECT_NE(failed[i].message.find(link), std::string::npos) << failed[i].message;
    EXPECT_NE(failed[i].message.find(delays[i]), std::string::npos) << failed[i].message;
    // The next attempt waits at least the delay (the cv wait may only end later, never sooner).
    const double gap_s = std::chrono::duration<double>(failed[i + 1].at - failed[i].at).count();
    EXPECT_GE(gap_s, delay_s[i] - 0.01) << "attempt " << i + 1;
  }
  LinkStatus s = supervisor.status();
  EXPECT_GE(s.failed_attempts, 5u);
  EXPECT_EQ(s.connects, 0u);
  EXPECT_NE(s.last_error.find(link), std::string::npos) << s.last_error;

  // The device appears, streams, vanishes for a while and comes back.
  EmulatorConfig ec;
  ec.link_path = link;
  ec.rate_hz = 10000;
  ec.vanish_after_events = 3000;
  ec.return_after_ms = 600;
  Emulator emulator(ec);
  ASSERT_TRUE(waitFor([&] { return supervisor.status().connects >= 1; }, 10.0));
  EXPECT_EQ(rec.logs(LinkEvent::kConnected).size(), 1u);
  ASSERT_TRUE(waitFor([&] { return !rec.logs(LinkEvent::kLost).empty(); }, 10.0));
  ASSERT_TRUE(waitFor([&] { return emulator.appearances() == 2; }, 10.0));
  ASSERT_TRUE(waitFor([&] { return supervisor.status().connects >= 2; }, 10.0));
  const std::size_t before = rec.events().size();
  ASSERT_TRUE(waitFor([&] { return rec.events().size() >= before + 1000; }, 10.0))
      << "no events after the device came back";
  s = supervisor.status();
  EXPECT_EQ(s.state, LinkState::kStreaming);
  EXPECT_EQ(s.reconnects(), 1u);
  EXPECT_EQ(s.disconnects, 1u);
  EXPECT_NE(s.last_disconnect.find("device lost"), std::string::npos) << s.last_disconnect;
  EXPECT_EQ(rec.logs(LinkEvent::kReconnected).size(), 1u);
  EXPECT_EQ(rec.streamEnds(), 1);
  // After a device that was there is lost, the backoff starts again at the minimum.
  const auto lost_at = rec.logs(LinkEvent::kLost).front().at;
  for (const auto& l : rec.logs(LinkEvent::kOpenFailed)) {
    if (l.at < lost_at) continue;
    EXPECT_NE(l.message.find("(retrying in 0.1 s)"), std::string::npos) << l.message;
    break;
  }
  supervisor.stop();
  expectNeverBackwards(rec.events());
}

TEST(LinkSupervisor, StalledLineIsReopened) {
  EmulatorConfig ec;
  ec.link_path = tempPath("edvs_stalled");
  ec.rate_hz = 10000;
  ec.stall_after_events = 1000;
  ec.stall_ms = 1500;
  Emulator emulator(ec);
  SupervisorConfig sc;
  sc.reconnect_min_s = 0.1;
  sc.reconnect_max_s = 0.2;
  sc.stall_reconnect_s = 0.3;
  Recorder rec;
  LinkSupervisor supervisor(deviceFor(emulator.uri()), sc, rec.callbacks());
  supervisor.start();
  ASSERT_TRUE(waitFor([&] { return !rec.logs(LinkEvent::kStalled).empty(); }, 10.0));
  EXPECT_NE(rec.logs(LinkEvent::kStalled).front().message.find("no data for 0.3"),
            std::string::npos);
  ASSERT_TRUE(waitFor([&] { return supervisor.status().connects >= 2; }, 10.0));
  // Once the stall is over, events flow again on a reopened stream.
  ASSERT_TRUE(waitFor([&] { return rec.events().size() >= 3000; }, 10.0)) << rec.events().size();
  const LinkStatus s = supervisor.status();
  EXPECT_EQ(s.state, LinkState::kStreaming);
  EXPECT_GE(s.disconnects, 1u);
  EXPECT_NE(s.last_disconnect.find("reopening the device"), std::string::npos) << s.last_disconnect;
  supervisor.stop();
  expectNeverBackwards(rec.events());
}

TEST(LinkSupervisor, ClockNeverRunsBackwardsAcrossReconnects) {
  EmulatorConfig ec;
  ec.link_path = tempPath("edvs_clock");
  ec.rate_hz = 10000;
  ec.vanish_after_events = 2000;
  ec.return_after_ms = 200;
  Emulator emulator(ec);
  SupervisorConfig sc;
  sc.reconnect_min_s = 0.05;
  sc.reconnect_max_s = 0.1;
  Recorder rec;
  LinkSupervisor::Callbacks callbacks = rec.callbacks();
  // A host clock that runs backwards 1000 s per anchor: each new stream would start before the
  // previous one ended.
  std::mutex anchors_mutex;
  std::vector<std::int64_t> anchors;
  callbacks.now_us = [&] {
    std::lock_guard<std::mutex> lock(anchors_mutex);
    anchors.push_back(std::int64_t{2000000000000} -
                      static_cast<std::int64_t>(anchors.size()) * 1000000000);
    return anchors.back();
  };
  LinkSupervisor supervisor(deviceFor(emulator.uri()), sc, callbacks);
  supervisor.start();
  ASSERT_TRUE(waitFor([&] { return supervisor.status().connects >= 2; }, 10.0));
  const std::size_t before = rec.events().size();
  ASSERT_TRUE(waitFor([&] { return rec.events().size() >= before + 1000; }, 10.0));
  supervisor.stop();
  {
    std::lock_guard<std::mutex> lock(anchors_mutex);
    ASSERT_EQ(anchors.size(), 2u);  // one anchor per stream
  }
  const EventVector events = rec.events();
  ASSERT_GT(events.size(), before);
  EXPECT_GE(events.front().t_us, std::int64_t{2000000000000});
  expectNeverBackwards(events);
  // The second stream continues where the first ended instead of 1000 s earlier.
  EXPECT_GE(events[before].t_us, events[before - 1].t_us);
  EXPECT_LT(events.back().t_us - events.front().t_us, std::int64_t{10000000});
}

TEST(LinkSupervisor, CaptureEndsAtItsEndOrLoops) {
  const EventVector truth = edvs::generateEvents(3, 5000, 500);
  const auto bytes = edvs::encodeEvents(truth, EventFormat::kAbs24);
  const std::string path = tempPath("capture.raw");
  {
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<long>(bytes.size()));
  }
  {
    Recorder rec;
    LinkSupervisor once(deviceFor("file://" + path + "?format=E3&rate=0"), SupervisorConfig(),
                        rec.callbacks());
    once.start();
    ASSERT_TRUE(waitFor([&] { return once.status().state == LinkState::kCaptureEnded; }, 10.0));
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    const LinkStatus s = once.status();
    EXPECT_EQ(s.connects, 1u);  // not reopened
    EXPECT_EQ(s.disconnects, 0u);
    EXPECT_EQ(s.events, truth.size());
    EXPECT_EQ(rec.events().size(), truth.size());
    EXPECT_EQ(rec.logs(LinkEvent::kCaptureEnded).size(), 1u);
    EXPECT_EQ(rec.streamEnds(), 1);
  }
  {
    Recorder rec;
    LinkSupervisor looped(deviceFor("file://" + path + "?format=E3&rate=0&loop=1"),
                          SupervisorConfig(), rec.callbacks());
    looped.start();
    ASSERT_TRUE(waitFor([&] { return looped.status().connects >= 3; }, 10.0));
    EXPECT_EQ(looped.status().disconnects, 0u);  // (stop() below ends a stream: one more)
    looped.stop();
    EXPECT_NE(rec.logs(LinkEvent::kCaptureEnded).front().message.find("replaying it again"),
              std::string::npos);
    expectNeverBackwards(rec.events());
  }
  std::filesystem::remove(path);
}
