#include "ebslam/events/event_io.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

namespace ebslam {
namespace {

namespace fs = std::filesystem;

// A fresh directory per test, removed afterwards.
class EventIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("ebslam_event_io_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

EventVector randomEvents(std::size_t n, const SensorSize& sensor, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> dt(0, 50);
  EventVector events(n);
  std::int64_t t = 1311876799000000;  // a Unix time in microseconds
  for (auto& e : events) {
    t += dt(rng);
    e.t_us = t;
    e.x = static_cast<std::uint16_t>(rng() % sensor.width);
    e.y = static_cast<std::uint16_t>(rng() % sensor.height);
    e.polarity = (rng() & 1u) != 0;
  }
  return events;
}

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void writeAll(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << bytes;
}

EventReadResult readBytes(const std::string& bytes, std::optional<EventFileFormat> format) {
  EventReadOptions options;
  options.format = format;
  EventFileReader reader(std::make_unique<std::istringstream>(bytes), options);
  EventReadResult result;
  EventVector batch;
  while (reader.next(batch, 7) > 0)
    result.events.insert(result.events.end(), batch.begin(), batch.end());
  result.error = reader.error();
  result.sensor = reader.sensor();
  result.non_monotonic = reader.nonMonotonicCount();
  return result;
}

TEST_F(EventIoTest, BinaryRoundTripKeepsEverything) {
  const SensorSize sensor{128, 128};
  const EventVector events = randomEvents(10000, sensor, 1);
  writeEventFile(path("a.ebe"), events, sensor);
  const EventReadResult result = readEventFile(path("a.ebe"));
  EXPECT_FALSE(result.error) << *result.error;
  EXPECT_EQ(result.sensor.width, 128u);
  EXPECT_EQ(result.sensor.height, 128u);
  EXPECT_EQ(result.events, events);
  EXPECT_EQ(result.non_monotonic, 0u);
  // 32-byte header, 3 blocks (4096 + 4096 + 1808 events) of 24-byte header + 8 bytes per event,
  // 24-byte end marker.
  EXPECT_EQ(fs::file_size(path("a.ebe")), 32u + 3 * 24u + 8u * 10000u + 24u);
}

TEST_F(EventIoTest, BinaryHandlesLargeTimeJumpsAndExtremeValues) {
  const SensorSize sensor{65535, 32768};
  EventVector events = {{0, 0, 0, true},
                        {-5, 65534, 32767, false},
                        {std::int64_t{1} << 40, 1, 2, true},
                        {std::numeric_limits<std::int64_t>::max(), 3, 4, false},
                        {std::numeric_limits<std::int64_t>::min(), 5, 6, true},
                        {(std::int64_t{1} << 40) - 3, 7, 8, false}};
  // All formats, including decimal seconds at the ends of the int64 range (found by fuzzing).
  for (auto format :
       {EventFileFormat::kBinary, EventFileFormat::kText, EventFileFormat::kRpgText}) {
    const std::string p = path(std::string("b_") + toString(format));
    writeEventFile(p, events, sensor, format);
    EventReadOptions options;
    options.format = format;
    if (format == EventFileFormat::kRpgText) options.sensor = sensor;
    const EventReadResult result = readEventFile(p, options);
    EXPECT_FALSE(result.error) << toString(format) << ": " << result.error.value_or("");
    EXPECT_EQ(result.events, events) << toString(format);
    EXPECT_EQ(result.non_monotonic, 2u);  // -5 after 0 and min after max
  }
  // One microsecond beyond the range is a bad timestamp, not a wrap-around.
  const auto r = readBytes("9223372036854.775808 1 1 1\n", EventFileFormat::kRpgText);
  ASSERT_TRUE(r.error);
  EXPECT_NE(r.error->find("bad timestamp"), std::string::npos);
}

TEST_F(EventIoTest, TextAndRpgRoundTrip) {
  const SensorSize sensor{240, 180};
  const EventVector events = randomEvents(500, sensor, 2);
  writeEventFile(path("t.txt"), events, sensor, EventFileFormat::kText);
  EventReadResult text = readEventFile(path("t.txt"));
  EXPECT_FALSE(text.error);
  EXPECT_EQ(text.events, events);
  EXPECT_EQ(text.sensor.width, 240u);
  EXPECT_EQ(text.sensor.height, 180u);
  EXPECT_EQ(detectEventFileFormat(path("t.txt")), EventFileFormat::kText);

  writeEventFile(path("events.txt"), events, sensor, EventFileFormat::kRpgText);
  EXPECT_EQ(detectEventFileFormat(path("events.txt")), EventFileFormat::kRpgText);
  EventReadResult rpg = readEventFile(path("events.txt"));
  EXPECT_FALSE(rpg.error);
  EXPECT_EQ(rpg.events, events);
  EXPECT_EQ(rpg.sensor.width, 240u);
  EXPECT_EQ(rpg.sensor.height, 180u);
}

TEST_F(EventIoTest, TextAcceptsSecondsWithDecimalsAndComments) {
  writeAll(path("s.txt"),
           "# a comment\n\n1.5 3 4 1\r\n  2.0000004 5 6 0\n2.0000005 5 6 -1\n17 1 1 1\n");
  const EventReadResult r = readEventFile(path("s.txt"), EventFileFormat::kText);
  ASSERT_FALSE(r.error) << *r.error;
  ASSERT_EQ(r.events.size(), 4u);
  EXPECT_EQ(r.events[0], (Event{1500000, 3, 4, true}));
  EXPECT_EQ(r.events[1], (Event{2000000, 5, 6, false}));
  EXPECT_EQ(r.events[2], (Event{2000001, 5, 6, false}));  // rounded to nearest microsecond
  EXPECT_EQ(r.events[3], (Event{17, 1, 1, true}));        // integer = microseconds
  EXPECT_EQ(r.non_monotonic, 1u);
  // No header and no size given: bounding box of the events.
  EXPECT_EQ(r.sensor.width, 6u);
  EXPECT_EQ(r.sensor.height, 7u);
}

TEST_F(EventIoTest, RpgSecondsParsedExactly) {
  writeAll(path("events.txt"),
           "49.006624000 192 13 0\n49.012157999 100 95 1\n1311876799.7716 1 2 1\n");
  const EventReadResult r = readEventFile(path("events.txt"));
  ASSERT_FALSE(r.error);
  ASSERT_EQ(r.events.size(), 3u);
  EXPECT_EQ(r.events[0].t_us, 49006624);
  EXPECT_EQ(r.events[1].t_us, 49012158);
  EXPECT_EQ(r.events[2].t_us, 1311876799771600);
  EXPECT_FALSE(r.events[0].polarity);
  EXPECT_TRUE(r.events[1].polarity);
}

TEST_F(EventIoTest, NonMonotonicTimestampsAreReportedNotReordered) {
  const SensorSize sensor{128, 128};
  EventVector events = {{100, 1, 1, true}, {90, 2, 2, true}, {95, 3, 3, false}, {80, 4, 4, true}};
  for (auto format :
       {EventFileFormat::kBinary, EventFileFormat::kText, EventFileFormat::kRpgText}) {
    const std::string p = path(std::string("nm_") + toString(format));
    writeEventFile(p, events, sensor, format);
    const EventReadResult r = readEventFile(p, format);
    EXPECT_FALSE(r.error);
    EXPECT_EQ(r.events, events) << toString(format);
    EXPECT_EQ(r.non_monotonic, 2u) << toString(format);
    ASSERT_TRUE(r.first_non_monotonic_index);
    EXPECT_EQ(*r.first_non_monotonic_index, 1u);
  }
  sortEventsByTime(events);
  EXPECT_EQ(events.front().t_us, 80);
  EXPECT_EQ(events.back().t_us, 100);
}

TEST_F(EventIoTest, BinaryTruncationAtEveryByteKeepsCompleteEvents) {
  const SensorSize sensor{128, 128};
  const EventVector events = randomEvents(40, sensor, 3);
  writeEventFile(path("full.ebe"), events, sensor);
  const std::string bytes = readAll(path("full.ebe"));
  ASSERT_EQ(bytes.size(), 32u + 24u + 8u * 40u + 24u);
  for (std::size_t cut = 0; cut < bytes.size(); ++cut) {
    const EventReadResult r = readBytes(bytes.substr(0, cut), EventFileFormat::kBinary);
    const std::size_t expected = cut < 56 ? 0 : std::min<std::size_t>(40, (cut - 56) / 8);
    ASSERT_TRUE(r.error) << "cut at " << cut;
    ASSERT_EQ(r.events.size(), expected) << "cut at " << cut << ": " << *r.error;
    EXPECT_TRUE(std::equal(r.events.begin(), r.events.end(), events.begin()));
    EXPECT_NE(r.error->find("truncated"), std::string::npos) << *r.error;
  }
  const EventReadResult whole = readBytes(bytes, std::nullopt);
  EXPECT_FALSE(whole.error);
  EXPECT_EQ(whole.events, events);
}

TEST_F(EventIoTest, TruncatedSecondBlockKeepsTheFirst) {
  const SensorSize sensor{128, 128};
  const EventVector events = randomEvents(5000, sensor, 4);
  writeEventFile(path("two.ebe"), events, sensor);
  const std::string bytes = readAll(path("two.ebe"));
  const std::size_t second_block = 32 + 24 + 8 * 4096;
  for (std::size_t cut : {second_block, second_block + 10, second_block + 24 + 8 * 100 + 3}) {
    writeAll(path("cut.ebe"), bytes.substr(0, cut));
    const EventReadResult r = readEventFile(path("cut.ebe"));
    const std::size_t expected =
        cut < second_block + 24 ? 4096 : 4096 + (cut - second_block - 24) / 8;
    EXPECT_EQ(r.events.size(), expected);
    ASSERT_TRUE(r.error);  // even at a block boundary: the end marker is missing
    EXPECT_NE(r.error->find("truncated"), std::string::npos) << *r.error;
  }
}

TEST_F(EventIoTest, CorruptHeaderWrongVersionAndCorruptRecords) {
  const SensorSize sensor{128, 128};
  const EventVector events = randomEvents(5000, sensor, 5);
  writeEventFile(path("c.ebe"), events, sensor);
  const std::string good = readAll(path("c.ebe"));

  std::string bad_magic = good;
  bad_magic[0] = 'X';
  auto r = readBytes(bad_magic, EventFileFormat::kBinary);
  ASSERT_TRUE(r.error);
  EXPECT_NE(r.error->find("magic"), std::string::npos);
  EXPECT_TRUE(r.events.empty());

  std::string bad_width = good;
  bad_width[13] = static_cast<char>(bad_width[13] ^ 0x40);
  r = readBytes(bad_width, EventFileFormat::kBinary);
  ASSERT_TRUE(r.error);
  EXPECT_NE(r.error->find("CRC"), std::string::npos);
  EXPECT_TRUE(r.events.empty());

  // Version 2 with a consistent CRC: rejected by name.
  std::string version2 = good;
  version2[8] = 2;
  {
    // recompute the header CRC as a future writer would
    std::uint32_t c = 0xFFFFFFFFu;
    for (int i = 0; i < 28; ++i) {
      c ^= static_cast<std::uint8_t>(version2[i]);
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    }
    c ^= 0xFFFFFFFFu;
    for (int i = 0; i < 4; ++i) version2[28 + i] = static_cast<char>(c >> (8 * i));
  }
  r = readBytes(version2, EventFileFormat::kBinary);
  ASSERT_TRUE(r.error);
  EXPECT_NE(r.error->find("version 2"), std::string::npos) << *r.error;
  EXPECT_TRUE(r.events.empty());

  // A flipped bit in the second block's records: the first block survives, the second is dropped.
  std::string bad_record = good;
  const std::size_t second_records = 32 + 24 + 8 * 4096 + 24;
  bad_record[second_records + 8 * 10 + 4] ^= 0x01;
  r = readBytes(bad_record, std::nullopt);
  ASSERT_TRUE(r.error);
  EXPECT_NE(r.error->find("block 1"), std::string::npos) << *r.error;
  EXPECT_EQ(r.events.size(), 4096u);
  EXPECT_TRUE(std::equal(r.events.begin(), r.events.end(), events.begin()));

  // A corrupt block header (count field) is caught by its CRC.
  std::string bad_count = good;
  bad_count[32 + 24 + 8 * 4096 + 5] ^= 0x10;
  r = readBytes(bad_count, std::nullopt);
  ASSERT_TRUE(r.error);
  EXPECT_EQ(r.events.size(), 4096u);
}

TEST_F(EventIoTest, GarbageLinesStopTextReadingWithLineNumber) {
  const std::string good = "1 1 1 1\n2 2 2 0\n";
  const std::vector<std::string> garbage = {"hello world\n",
                                            "3 4 5\n",
                                            "3 4 5 6 7\n",
                                            "3 x 5 1\n",
                                            "3 4 5 2\n",
                                            "3 -4 5 1\n",
                                            "3 70000 5 1\n",
                                            "1e999 1 1 1\n",
                                            std::string("3 4\0 5 1\n", 9),
                                            std::string(5000, '7') + "\n"};
  for (const std::string& g : garbage) {
    const auto r = readBytes(good + g + "9 9 9 1\n", EventFileFormat::kText);
    ASSERT_TRUE(r.error) << g;
    EXPECT_NE(r.error->find("line 3"), std::string::npos) << *r.error;
    EXPECT_EQ(r.events.size(), 2u) << g;
  }
  // Events outside a declared sensor are damage too.
  const auto r =
      readBytes("# ebslam events text v1 width=4 height=4\n1 1 1 1\n2 4 1 1\n", std::nullopt);
  ASSERT_TRUE(r.error);
  EXPECT_NE(r.error->find("outside"), std::string::npos);
  EXPECT_EQ(r.events.size(), 1u);
  const auto rpg = readBytes("0.1 239 179 1\n0.2 240 1 1\n", EventFileFormat::kRpgText);
  ASSERT_TRUE(rpg.error);
  EXPECT_EQ(rpg.events.size(), 1u);
}

TEST_F(EventIoTest, TextTruncationAtEveryByteKeepsCompleteLines) {
  const SensorSize sensor{240, 180};
  const EventVector events = randomEvents(30, sensor, 6);
  for (auto format : {EventFileFormat::kText, EventFileFormat::kRpgText}) {
    writeEventFile(path("t"), events, sensor, format);
    const std::string bytes = readAll(path("t"));
    // Byte offset just after the polarity of each event line.
    std::size_t data_start = 0;
    while (bytes[data_start] == '#') data_start = bytes.find('\n', data_start) + 1;
    std::vector<std::size_t> line_ends;
    std::size_t pos = data_start;
    while ((pos = bytes.find('\n', pos)) != std::string::npos) {
      if (bytes[pos - 1] == '0' || bytes[pos - 1] == '1') line_ends.push_back(pos);
      ++pos;
    }
    ASSERT_EQ(line_ends.size(), events.size());
    for (std::size_t cut = 0; cut <= bytes.size(); ++cut) {
      EventReadOptions options;
      options.format = format;
      options.sensor = sensor;
      EventFileReader reader(std::make_unique<std::istringstream>(bytes.substr(0, cut)), options);
      EventVector all;
      EventVector batch;
      while (reader.next(batch, 1000) > 0) all.insert(all.end(), batch.begin(), batch.end());
      const auto complete = static_cast<std::size_t>(
          std::upper_bound(line_ends.begin(), line_ends.end(), cut) - line_ends.begin());
      ASSERT_EQ(all.size(), complete) << toString(format) << " cut " << cut;
      EXPECT_TRUE(std::equal(all.begin(), all.end(), events.begin()));
      const bool at_boundary =
          cut == 0 || bytes[cut - 1] == '\n' ||
          std::find(line_ends.begin(), line_ends.end(), cut) != line_ends.end();
      // A cut inside a header comment still leaves a comment, which is not damage.
      if (!at_boundary && cut > data_start) {
        EXPECT_TRUE(reader.error()) << toString(format) << " cut " << cut;
      }
      if (at_boundary) {
        EXPECT_FALSE(reader.error()) << toString(format) << " cut " << cut;
      }
    }
  }
}

TEST_F(EventIoTest, StreamingReaderAndWriterMatchWholeFileApi) {
  const SensorSize sensor{128, 128};
  const EventVector events = randomEvents(20000, sensor, 7);
  {
    EventFileWriter writer(path("s.ebe"), sensor);
    for (std::size_t i = 0; i < events.size(); i += 333) {
      writer.write(
          EventVector(events.begin() + i, events.begin() + std::min(events.size(), i + 333)));
    }
    writer.write(Event{events.back().t_us, 1, 2, true});
    writer.close();
    EXPECT_EQ(writer.eventsWritten(), events.size() + 1);
    EXPECT_THROW(writer.write(events.front()), std::logic_error);
  }
  EventFileReader reader(path("s.ebe"));
  EXPECT_EQ(reader.format(), EventFileFormat::kBinary);
  EventVector all;
  EventVector batch;
  std::size_t calls = 0;
  while (reader.next(batch, 1000) > 0) {
    EXPECT_LE(batch.size(), 1000u);
    all.insert(all.end(), batch.begin(), batch.end());
    ++calls;
  }
  EXPECT_TRUE(reader.done());
  EXPECT_FALSE(reader.error());
  ASSERT_EQ(all.size(), events.size() + 1);
  EXPECT_TRUE(std::equal(events.begin(), events.end(), all.begin()));
  EXPECT_EQ(calls, 21u);
}

TEST_F(EventIoTest, WriterThatNeverClosedLeavesARecoverableFile) {
  const SensorSize sensor{128, 128};
  const EventVector events = randomEvents(5000, sensor, 8);
  auto writer = std::make_unique<EventFileWriter>(path("crash.ebe"), sensor);
  writer->write(events);  // the first 4096 events form a complete block and are flushed
  // Simulate a crash: copy the file while the writer is still open, before close().
  fs::copy_file(path("crash.ebe"), path("copy.ebe"));
  writer.reset();  // the destructor closes: the original becomes complete
  const EventReadResult complete = readEventFile(path("crash.ebe"));
  EXPECT_FALSE(complete.error);
  EXPECT_EQ(complete.events, events);
  const EventReadResult cut = readEventFile(path("copy.ebe"));
  ASSERT_TRUE(cut.error);
  EXPECT_NE(cut.error->find("end marker"), std::string::npos) << *cut.error;
  EXPECT_GE(cut.events.size(), 4096u);
  EXPECT_TRUE(std::equal(cut.events.begin(), cut.events.end(), events.begin()));
}

TEST_F(EventIoTest, AppendToExistingFiles) {
  const SensorSize sensor{128, 128};
  const EventVector events = randomEvents(9000, sensor, 9);
  const EventVector first(events.begin(), events.begin() + 5000);
  const EventVector second(events.begin() + 5000, events.end());
  for (auto format :
       {EventFileFormat::kBinary, EventFileFormat::kText, EventFileFormat::kRpgText}) {
    const std::string p = path(std::string("append_") + toString(format));
    writeEventFile(p, first, sensor, format);
    {
      EventFileWriter writer = EventFileWriter::openForAppend(
          p,
          format == EventFileFormat::kRpgText ? std::optional<SensorSize>(sensor) : std::nullopt);
      EXPECT_EQ(writer.eventsWritten(), first.size());
      writer.write(second);
      writer.close();
      EXPECT_EQ(writer.eventsWritten(), events.size());
    }
    EventReadOptions options;
    options.sensor =
        format == EventFileFormat::kRpgText ? std::optional<SensorSize>(sensor) : std::nullopt;
    const EventReadResult r = readEventFile(p, options);
    EXPECT_FALSE(r.error) << toString(format) << ": " << r.error.value_or("");
    EXPECT_EQ(r.events, events) << toString(format);
    EXPECT_EQ(r.sensor.width, 128u);
  }
  // Damaged files and mismatching sizes are refused.
  const std::string bytes = readAll(path("append_binary"));
  writeAll(path("cut.ebe"), bytes.substr(0, bytes.size() - 30));
  EXPECT_THROW(EventFileWriter::openForAppend(path("cut.ebe")), std::runtime_error);
  EXPECT_THROW(EventFileWriter::openForAppend(path("append_binary"), SensorSize{64, 64}),
               std::invalid_argument);
  writeAll(path("plain.txt"), "1 2 3 1\n");
  EXPECT_THROW(EventFileWriter::openForAppend(path("plain.txt")), std::invalid_argument);
  EXPECT_THROW(EventFileWriter::openForAppend(path("missing.ebe")), std::runtime_error);
  // A text file without a final newline gets one before the appended events.
  {
    EventFileWriter writer = EventFileWriter::openForAppend(path("plain.txt"), SensorSize{8, 8});
    writer.write(Event{5, 6, 7, false});
    writer.close();
  }
  writeAll(path("plain2.txt"), "1 2 3 1");
  {
    EventFileWriter writer = EventFileWriter::openForAppend(path("plain2.txt"), SensorSize{8, 8});
    writer.write(Event{5, 6, 7, false});
    writer.close();
  }
  for (const char* name : {"plain.txt", "plain2.txt"}) {
    const EventReadResult r = readEventFile(path(name));
    EXPECT_FALSE(r.error);
    EXPECT_EQ(r.events, (EventVector{{1, 2, 3, true}, {5, 6, 7, false}})) << name;
  }
}

TEST_F(EventIoTest, MisuseAndMissingFilesThrow) {
  EXPECT_THROW(readEventFile(path("missing.ebe")), std::runtime_error);
  EXPECT_THROW(EventFileReader(path("missing.ebe")), std::runtime_error);
  EXPECT_THROW(writeEventFile(path("nodir/x.ebe"), {}, SensorSize{}), std::runtime_error);
  EXPECT_THROW(writeEventFile(path("o.ebe"), {{0, 128, 0, true}}, SensorSize{128, 128}),
               std::invalid_argument);
  EXPECT_THROW(writeEventFile(path("o.ebe"), {}, SensorSize{0, 10}), std::invalid_argument);
  EXPECT_THROW(writeEventFile(path("o.ebe"), {}, SensorSize{100, 40000}), std::invalid_argument);
  // An empty binary file written by us has a header only and reads back empty without error.
  writeEventFile(path("empty.ebe"), {}, SensorSize{128, 128});
  const auto r = readEventFile(path("empty.ebe"));
  EXPECT_FALSE(r.error);
  EXPECT_TRUE(r.events.empty());
  EXPECT_EQ(parseEventFileFormat("rpg"), EventFileFormat::kRpgText);
  EXPECT_FALSE(parseEventFileFormat("bag"));
  EXPECT_EQ(eventFileFormatFromExtension("a/b.txt"), EventFileFormat::kText);
  EXPECT_EQ(eventFileFormatFromExtension("a.txt/b"), EventFileFormat::kBinary);
}

// The 8 excerpts of the Event Camera Dataset: 30,000 events each, 240 x 180, strictly valid.
TEST(EventIoRealData, ReadsAllRpgEventExcerpts) {
  const fs::path root = fs::path(EBSLAM_SHARED_DATA_DIR) / "rpg-events";
  if (!fs::is_directory(root)) GTEST_SKIP() << "shared data not found at " << root;
  std::size_t sequences = 0;
  for (const auto& entry : fs::directory_iterator(root)) {
    const fs::path file = entry.path() / "events.txt";
    if (!fs::is_regular_file(file)) continue;
    ++sequences;
    EXPECT_EQ(detectEventFileFormat(file.string()), EventFileFormat::kRpgText) << file;
    const EventReadResult r = readEventFile(file.string());
    EXPECT_FALSE(r.error) << file << ": " << r.error.value_or("");
    EXPECT_EQ(r.events.size(), 30000u) << file;
    EXPECT_EQ(r.sensor.width, 240u);
    EXPECT_EQ(r.sensor.height, 180u);
    EXPECT_EQ(r.non_monotonic, 0u) << file;
    ASSERT_FALSE(r.events.empty());
    // Timestamps are seconds since the start of the recording (tens of seconds).
    EXPECT_GT(r.events.front().t_us, 0);
    EXPECT_LT(r.events.back().t_us - r.events.front().t_us, 60'000'000);
    std::size_t on = 0;
    for (const Event& e : r.events) on += e.polarity ? 1 : 0;
    EXPECT_GT(on, 1000u);
    EXPECT_LT(on, 29000u);
  }
  EXPECT_EQ(sequences, 8u);
}

}  // namespace
}  // namespace ebslam
