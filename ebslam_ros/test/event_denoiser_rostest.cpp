// rostest of the EventDenoiser nodelet (event_denoiser.test) and node (event_denoiser_node.test):
// a line sweeping over a 64 x 64 sensor plus isolated noise events of the other polarity. The
// output must hold exactly the events a core BackgroundActivityFilter with the node's parameters
// passes (fed the same stream in the test), with the input's stamp, frame and size; injected bad
// input (empty arrays, events outside the sensor, a size change, time running back) is handled
// as documented and counted in diagnostics; dynamic_reconfigure changes the filter.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <ebslam_msgs/EventArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <ebslam/events/event_denoiser.h>

#include <algorithm>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "ebslam_msgs/event_conversions.h"

namespace {

constexpr std::uint32_t kSize = 64;
constexpr std::int64_t kT0 = 1700000000000000;  // [us]
constexpr std::int64_t kColumnStepUs = 2000;    // the line moves one column per 2 ms
constexpr int kNoisePerMessage = 6;

// The parameters of the .test files.
ebslam::BackgroundActivityFilterConfig nodeConfig() {
  ebslam::BackgroundActivityFilterConfig c;
  c.window_us = 10000;
  c.min_support = 3;
  c.polarity_match = true;
  return c;
}

// State shared by the tests of one run (they run in order against one node).
struct Stream {
  std::int64_t next_t = kT0;
  ebslam::BackgroundActivityFilter reference{nodeConfig(), {kSize, kSize}};
  std::uint64_t passed = 0, rejected = 0, outside = 0;
  std::mt19937 rng{7};
};
Stream& stream() {
  static Stream s;
  return s;
}

bool isSignal(const ebslam_msgs::Event& e) { return e.polarity != 0; }

class EventDenoiserTest : public ::testing::Test {
 public:
  void SetUp() override {
    events_pub_ = nh_.advertise<ebslam_msgs::EventArray>("events", 100);
    out_sub_ = nh_.subscribe("events_denoised", 100, &EventDenoiserTest::onOutput, this);
    ASSERT_TRUE(waitFor([&] { return events_pub_.getNumSubscribers() > 0; }, 10.0))
        << "the denoiser did not subscribe to `events`";
    ASSERT_TRUE(waitFor([&] { return out_sub_.getNumPublishers() > 0; }, 10.0))
        << "the denoiser does not publish `events_denoised`";
    ros::WallDuration(0.3).sleep();
  }

  template <typename Predicate>
  static bool waitFor(Predicate done, double seconds) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
    while (!done() && ros::WallTime::now() < end) {
      ros::spinOnce();
      ros::WallDuration(0.005).sleep();
    }
    return done();
  }

  void onOutput(const ebslam_msgs::EventArray::ConstPtr& msg) {
    outputs_.push_back(*msg);
    all_stamps_.push_back(msg->header.stamp);
  }

  // One column of the sweeping line (ON events, one per row, 1 us apart) from t_us, and
  // isolated OFF noise events at random pixels in between; time-ordered.
  ebslam_msgs::EventArray sweep(std::uint32_t column, std::int64_t t_us) {
    ebslam_msgs::EventArray msg;
    msg.header.frame_id = "edvs_optical_frame";
    msg.width = msg.height = kSize;
    for (std::uint32_t y = 0; y < kSize; ++y) {
      ebslam_msgs::Event e;
      e.x = static_cast<std::uint16_t>(column % kSize);
      e.y = static_cast<std::uint16_t>(y);
      e.ts = ebslam_msgs::toRosTime(t_us + y);
      e.polarity = true;
      msg.events.push_back(e);
    }
    std::uniform_int_distribution<int> pixel(0, kSize - 1), dt(0, kColumnStepUs - 1);
    for (int k = 0; k < kNoisePerMessage; ++k) {
      ebslam_msgs::Event e;
      e.x = static_cast<std::uint16_t>(pixel(stream().rng));
      e.y = static_cast<std::uint16_t>(pixel(stream().rng));
      e.ts = ebslam_msgs::toRosTime(t_us + dt(stream().rng));
      e.polarity = false;
      msg.events.push_back(e);
    }
    std::stable_sort(msg.events.begin(), msg.events.end(),
                     [](const auto& a, const auto& b) { return a.ts < b.ts; });
    msg.header.stamp = msg.events.back().ts;
    return msg;
  }

  // What the node must output for `msg` (fed to the reference filter): its events that pass,
  // judged at the times of `at` (the same events, times as the node filters them; default: the
  // message's own).
  static std::vector<ebslam_msgs::Event> expected(const ebslam_msgs::EventArray& msg,
                                                  const ebslam_msgs::EventArray* at = nullptr) {
    std::vector<ebslam_msgs::Event> out;
    for (std::size_t i = 0; i < msg.events.size(); ++i) {
      const ebslam_msgs::Event& e = msg.events[i];
      if (e.x >= kSize || e.y >= kSize) {
        ++stream().outside;
        continue;
      }
      const ros::Time t = at ? at->events[i].ts : e.ts;
      const bool pass =
          stream().reference.accept({ebslam_msgs::toMicroseconds(t), e.x, e.y, e.polarity != 0});
      if (pass) out.push_back(e);
      ++(pass ? stream().passed : stream().rejected);
    }
    return out;
  }

  // Publishes `msg` and returns the output carrying its stamp (nullopt after `seconds`).
  std::optional<ebslam_msgs::EventArray> roundTrip(const ebslam_msgs::EventArray& msg,
                                                   double seconds = 5.0) {
    outputs_.clear();
    events_pub_.publish(msg);
    const auto it = [&] {
      return std::find_if(outputs_.begin(), outputs_.end(),
                          [&](const auto& o) { return o.header.stamp == msg.header.stamp; });
    };
    if (!waitFor([&] { return it() != outputs_.end(); }, seconds)) return std::nullopt;
    return *it();
  }

  // Sweeps `columns` columns from the stream's time; checks every output; returns the signal
  // and noise events kept.
  std::pair<std::size_t, std::size_t> sweepAndCheck(std::uint32_t columns) {
    std::size_t signal = 0, noise = 0;
    for (std::uint32_t c = 0; c < columns; ++c) {
      const ebslam_msgs::EventArray in = sweep(c, stream().next_t);
      stream().next_t += kColumnStepUs;
      const auto out = roundTrip(in);
      EXPECT_TRUE(out) << "no output for column " << c;
      if (!out) continue;
      expectSameHeader(*out, in);
      const std::vector<ebslam_msgs::Event> want = expected(in);
      EXPECT_EQ(out->events, want) << "column " << c;
      for (const auto& e : out->events) ++(isSignal(e) ? signal : noise);
    }
    return {signal, noise};
  }

  static void expectSameHeader(const ebslam_msgs::EventArray& out,
                               const ebslam_msgs::EventArray& in) {
    EXPECT_EQ(out.header.stamp, in.header.stamp);
    EXPECT_EQ(out.header.frame_id, in.header.frame_id);
    EXPECT_EQ(out.width, in.width);
    EXPECT_EQ(out.height, in.height);
  }

  // The denoiser's diagnostics values once they show `passed` events passed (or the last ones).
  std::map<std::string, std::string> diagnosticsWhen(std::uint64_t passed) {
    std::map<std::string, std::string> values;
    auto sub = nh_.subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 10, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
          for (const auto& status : m->status) {
            if (status.name.find("denoiser") == std::string::npos) continue;
            values.clear();
            for (const auto& kv : status.values) values[kv.key] = kv.value;
          }
        });
    waitFor([&] { return values["events passed"] == std::to_string(passed); }, 5.0);
    return values;
  }

  ros::NodeHandle nh_;
  ros::Publisher events_pub_;
  ros::Subscriber out_sub_;
  std::vector<ebslam_msgs::EventArray> outputs_;
  std::vector<ros::Time> all_stamps_;  // of every output since the start
};

TEST_F(EventDenoiserTest, KeepsTheLineRemovesTheNoiseWithTheInputsHeader) {
  const auto [signal, noise] = sweepAndCheck(20);
  // Column 0 has no history and row 0 only two earlier neighbours: 19 x 63 of 20 x 64 pass.
  EXPECT_EQ(signal, 19u * 63u);
  EXPECT_EQ(noise, 0u);
}

TEST_F(EventDenoiserTest, EmptyArrayGivesAnEmptyArrayWithItsHeader) {
  ebslam_msgs::EventArray empty;
  empty.header.frame_id = "edvs_optical_frame";
  empty.header.stamp = ebslam_msgs::toRosTime(stream().next_t);
  empty.width = empty.height = kSize;
  const auto out = roundTrip(empty);
  ASSERT_TRUE(out);
  expectSameHeader(*out, empty);
  EXPECT_TRUE(out->events.empty());
  sweepAndCheck(3);
}

TEST_F(EventDenoiserTest, EventsOutsideTheSensorAreDroppedTheRestFiltered) {
  sweepAndCheck(3);
  ebslam_msgs::EventArray in = sweep(3, stream().next_t);
  stream().next_t += kColumnStepUs;
  for (std::size_t i = 0; i < in.events.size(); i += 7) in.events[i].x = kSize + 5;
  in.events[3].y = 1000;
  const auto out = roundTrip(in);
  ASSERT_TRUE(out);
  expectSameHeader(*out, in);
  EXPECT_EQ(out->events, expected(in));
  EXPECT_FALSE(out->events.empty());
  sweepAndCheck(3);
}

TEST_F(EventDenoiserTest, AMessageOfAnotherSensorSizeIsDroppedAndTheStreamGoesOn) {
  ebslam_msgs::EventArray big = sweep(0, stream().next_t);
  big.width = big.height = 128;
  stream().next_t += kColumnStepUs;
  outputs_.clear();
  events_pub_.publish(big);
  // The outputs of the next columns are the positive signal that the node has handled `big`
  // (one connection keeps the order): had it passed, its output would have come first.
  sweepAndCheck(4);
  EXPECT_EQ(std::count(all_stamps_.begin(), all_stamps_.end(), big.header.stamp), 0)
      << "a message of another size must not pass";
}

TEST_F(EventDenoiserTest, TimeRunningBackRestartsTheFilterAndTheStreamGoesOn) {
  sweepAndCheck(4);
  // 30 s back (a looping bag): the filter forgets, so the first column has no support again.
  stream().next_t -= 30000000;
  stream().reference.reset();
  const auto [signal, noise] = sweepAndCheck(5);
  EXPECT_EQ(signal, 4u * 63u);
  EXPECT_EQ(noise, 0u);
  // Jitter of 0.5 ms inside a message (within ~max_backward): filtered at the predecessor's
  // time, its own stamp kept in the output.
  ebslam_msgs::EventArray in = sweep(5, stream().next_t);
  stream().next_t += kColumnStepUs;
  in.events[40].ts = in.events[40].ts - ros::Duration(0.0005);
  ebslam_msgs::EventArray clamped = in;
  clamped.events[40].ts = clamped.events[39].ts;
  const auto out = roundTrip(in);
  ASSERT_TRUE(out);
  EXPECT_EQ(out->events, expected(in, &clamped));
}

TEST_F(EventDenoiserTest, DiagnosticsCountPassedRejectedAndBadInput) {
  sweepAndCheck(2);
  const auto values = diagnosticsWhen(stream().passed);
  ASSERT_FALSE(values.empty()) << "no diagnostics of the denoiser";
  EXPECT_EQ(values.at("events passed"), std::to_string(stream().passed));
  EXPECT_EQ(values.at("events rejected"), std::to_string(stream().rejected));
  EXPECT_EQ(values.at("events outside the sensor"), std::to_string(stream().outside));
  EXPECT_EQ(values.at("messages of a wrong sensor size"), "1");
  EXPECT_EQ(values.at("restarts after time jumps"), "1");
  EXPECT_EQ(values.at("events clamped in time"), "1");
  EXPECT_EQ(values.at("empty messages"), "1");
}

TEST_F(EventDenoiserTest, DynamicReconfigureChangesTheFilter) {
  dynamic_reconfigure::Reconfigure srv;
  dynamic_reconfigure::IntParameter support;
  support.name = "min_support";
  support.value = 8;  // a line never has 8 neighbours: nothing passes
  srv.request.config.ints.push_back(support);
  ASSERT_TRUE(ros::service::waitForService("denoiser/set_parameters", 5000));
  ASSERT_TRUE(ros::service::call("denoiser/set_parameters", srv));
  for (std::uint32_t c = 0; c < 4; ++c) {
    const ebslam_msgs::EventArray in = sweep(c, stream().next_t);
    stream().next_t += kColumnStepUs;
    const auto out = roundTrip(in);
    ASSERT_TRUE(out);
    EXPECT_TRUE(out->events.empty());
  }
  srv.request.config.ints[0].value = 3;
  ASSERT_TRUE(ros::service::call("denoiser/set_parameters", srv));
  // A change forgets the activity: as after a restart.
  stream().reference.reset();
  const auto [signal, noise] = sweepAndCheck(3);
  EXPECT_EQ(signal, 2u * 63u);
  EXPECT_EQ(noise, 0u);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "event_denoiser_rostest");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
