#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <fstream>

#include "core/event_log.hpp"

namespace sweepmap {
namespace {

namespace fs = std::filesystem;

class EventLogTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::temp_directory_path() /
        ("sweepmap_eventlog_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // Writes three events and returns the file size after each one.
  std::vector<uint64_t> writeThree(const std::string& p) {
    EventLogWriter w(p);
    std::vector<uint64_t> ends;
    w.write(100, "A", std::vector<uint8_t>{1, 2, 3});
    w.flush();
    ends.push_back(fs::file_size(p));
    w.write(200, "BB", std::vector<uint8_t>(1000, 7));
    w.flush();
    ends.push_back(fs::file_size(p));
    w.write(300, "C", std::vector<uint8_t>{});
    w.close();
    ends.push_back(fs::file_size(p));
    return ends;
  }

  fs::path dir_;
};

// A disk that refuses a write (here the file-size limit, EFBIG, as a full disk's ENOSPC)
// leaves a log that ends with its last complete event, and the error says where.
TEST_F(EventLogTest, AWriteTheDiskRefusesCutsTheLogBackToAnEventBoundary) {
  const std::string p = path("full.lcmlog");
  rlimit old{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
  const auto previous = std::signal(SIGXFSZ, SIG_IGN);
  rlimit small = old;
  small.rlim_cur = 1000;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  std::string error;
  {
    EventLogWriter w(p);
    try {
      for (int i = 0; i < 10; ++i) w.write(i, "CHAN", std::vector<uint8_t>(100, 1));  // 132 B
      w.flush();
    } catch (const std::runtime_error& e) {
      error = e.what();
    }
  }
  setrlimit(RLIMIT_FSIZE, &old);
  std::signal(SIGXFSZ, previous);
  EXPECT_NE(error.find("last complete event, at byte 924"), std::string::npos) << error;
  EXPECT_EQ(fs::file_size(p), 7u * 132u);
  EventLogReader r(p);
  LogEvent e;
  int events = 0;
  while (r.next(&e)) ++events;  // throws on a cut event
  EXPECT_EQ(events, 7);
}

TEST_F(EventLogTest, RoundTrip) {
  writeThree(path("a.lcmlog"));
  EventLogReader r(path("a.lcmlog"));
  LogEvent e;
  ASSERT_TRUE(r.next(&e));
  EXPECT_EQ(e.eventnum, 0);
  EXPECT_EQ(e.utime, 100);
  EXPECT_EQ(e.channel, "A");
  EXPECT_EQ(e.data, (std::vector<uint8_t>{1, 2, 3}));
  ASSERT_TRUE(r.next(&e));
  EXPECT_EQ(e.channel, "BB");
  EXPECT_EQ(e.data.size(), 1000u);
  ASSERT_TRUE(r.next(&e));
  EXPECT_EQ(e.utime, 300);
  EXPECT_TRUE(e.data.empty());
  EXPECT_FALSE(r.next(&e));
}

TEST_F(EventLogTest, TruncatedLogReportsOffsetOfBrokenEvent) {
  const auto ends = writeThree(path("t.lcmlog"));
  fs::resize_file(path("t.lcmlog"), ends[1] - 10);  // cut inside the second event
  EventLogReader r(path("t.lcmlog"));
  LogEvent e;
  ASSERT_TRUE(r.next(&e));
  try {
    r.next(&e);
    FAIL() << "truncation not detected";
  } catch (const LogError& err) {
    EXPECT_EQ(err.offset(), ends[0]);
    EXPECT_NE(std::string(err.what()).find("byte " + std::to_string(ends[0])), std::string::npos);
  }
}

TEST_F(EventLogTest, CorruptSyncReported) {
  const auto ends = writeThree(path("c.lcmlog"));
  {
    std::fstream f(path("c.lcmlog"), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(ends[1]));
    f.put('\x00');
  }
  EventLogReader r(path("c.lcmlog"));
  LogEvent e;
  ASSERT_TRUE(r.next(&e));
  ASSERT_TRUE(r.next(&e));
  try {
    r.next(&e);
    FAIL() << "corruption not detected";
  } catch (const LogError& err) {
    EXPECT_EQ(err.offset(), ends[1]);
  }
}

TEST_F(EventLogTest, CorruptLengthReported) {
  writeThree(path("l.lcmlog"));
  {
    std::fstream f(path("l.lcmlog"), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(24);  // data length of the first event
    const char huge[4] = {'\x7f', '\x00', '\x00', '\x00'};
    f.write(huge, 4);
  }
  EventLogReader r(path("l.lcmlog"));
  LogEvent e;
  EXPECT_THROW(r.next(&e), LogError);
}

// Corrupt regions in the middle (a broken header, garbage that even holds a false sync word)
// and a cut last event: with resync every event outside them is read, and the ranges are
// exactly the bytes from each bad event to the next good one (or the end).
TEST_F(EventLogTest, ResyncKeepsEveryEventOutsideCorruptRegions) {
  const std::string p = path("r.lcmlog");
  std::vector<uint64_t> starts;
  {
    EventLogWriter w(p);
    for (int i = 0; i < 100; ++i) {
      w.flush();
      starts.push_back(fs::exists(p) ? fs::file_size(p) : 0);
      w.write(1000 + i, i % 2 ? "ODD" : "EVEN", std::vector<uint8_t>(50 + i, uint8_t(i)));
    }
    w.close();
  }
  const uint64_t size = fs::file_size(p);
  std::string bytes;
  {
    std::ifstream in(p, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  bytes[starts[30] + 2] ^= 0x40;  // event 30's sync word
  for (uint64_t i = starts[60] + 20; i < starts[62] + 10; ++i) bytes[i] = char(i * 37);
  bytes.replace(starts[61], 4, std::string("\xED\xA1\xDA\x01", 4));  // a false sync word
  bytes.resize(size - 20);                                           // the last event cut
  std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;

  EventLogReader r(p);
  r.setResync(true);
  LogEvent e;
  std::vector<int64_t> times;
  while (r.next(&e)) {
    times.push_back(e.utime);
    EXPECT_EQ(e.data.size(), size_t(50 + e.utime - 1000));
  }
  std::vector<int64_t> want;
  for (int i = 0; i < 99; ++i) {
    if (i != 30 && i != 60 && i != 61 && i != 62) want.push_back(1000 + i);
  }
  EXPECT_EQ(times, want);
  ASSERT_EQ(r.skipped().size(), 3u);
  EXPECT_EQ(r.skipped()[0].begin, starts[30]);
  EXPECT_EQ(r.skipped()[0].end, starts[31]);
  EXPECT_EQ(r.skipped()[0].why, "bad sync word (corrupt log)");
  EXPECT_EQ(r.skipped()[1].begin, starts[60]);
  EXPECT_EQ(r.skipped()[1].end, starts[63]);
  EXPECT_EQ(r.skipped()[2].begin, starts[99]);
  EXPECT_EQ(r.skipped()[2].end, size - 20);
  EXPECT_NE(r.skipped()[2].why.find("truncated"), std::string::npos);

  // Without resync the first bad event stops the reader, as before.
  EventLogReader strict(p);
  int n = 0;
  try {
    while (strict.next(&e)) ++n;
    FAIL() << "corruption not detected";
  } catch (const LogError& err) {
    EXPECT_EQ(err.offset(), starts[30]);
  }
  EXPECT_EQ(n, 30);
}

// Issue 21: a data length grown by one bit (+65536) used to swallow the 64 KiB after it. Now
// the event that claims them is the only one lost, strict readers stop at it, and the
// skipped range says why.
TEST_F(EventLogTest, ADamagedLengthCostsOnlyItsOwnEvent) {
  const std::string p = path("len.lcmlog");
  std::vector<uint64_t> starts;
  {
    EventLogWriter w(p);
    for (int i = 0; i < 300; ++i) {
      w.flush();
      starts.push_back(fs::exists(p) ? fs::file_size(p) : 0);
      w.write(1000 + i, "CHAN", std::vector<uint8_t>(400, uint8_t(i)));
    }
  }
  {
    std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(starts[10] + 24 + 1));  // data length, bit 16
    f.put('\x01');
  }
  EventLogReader r(p);
  r.setResync(true);
  LogEvent e;
  std::vector<int64_t> times;
  while (r.next(&e)) times.push_back(e.utime);
  EXPECT_EQ(times.size(), 299u);
  EXPECT_EQ(std::count(times.begin(), times.end(), 1010), 0);
  ASSERT_EQ(r.skipped().size(), 1u);
  EXPECT_EQ(r.skipped()[0].begin, starts[10]);
  EXPECT_EQ(r.skipped()[0].end, starts[11]);
  EXPECT_NE(r.skipped()[0].why.find("a damaged length"), std::string::npos) << r.skipped()[0].why;
  EventLogReader strict(p);
  int n = 0;
  EXPECT_THROW(while (strict.next(&e))++ n, LogError);
  EXPECT_EQ(n, 10);
}

// Megabytes of sync words (each a candidate header) are skipped as one range, without one
// file read per candidate.
TEST_F(EventLogTest, ResyncOverRepeatedSyncWordsIsOneRange) {
  const std::string p = path("syncs.lcmlog");
  {
    EventLogWriter w(p);
    w.write(1, "A", std::vector<uint8_t>{1});
  }
  const uint64_t first = fs::file_size(p);
  {
    std::ofstream out(p, std::ios::binary | std::ios::app);
    for (int i = 0; i < (4 << 20) / 4; ++i) out.write("\xED\xA1\xDA\x01", 4);
  }
  {
    EventLogWriter tail(path("tail.lcmlog"));
    tail.write(2, "B", std::vector<uint8_t>{2});
  }
  {
    std::ifstream in(path("tail.lcmlog"), std::ios::binary);
    std::ofstream out(p, std::ios::binary | std::ios::app);
    out << in.rdbuf();
  }
  EventLogReader r(p);
  r.setResync(true);
  LogEvent e;
  std::vector<std::string> channels;
  while (r.next(&e)) channels.push_back(e.channel);
  EXPECT_EQ(channels, (std::vector<std::string>{"A", "B"}));
  ASSERT_EQ(r.skipped().size(), 1u);
  EXPECT_EQ(r.skipped()[0].begin, first);
  EXPECT_EQ(r.skipped()[0].end, first + (4u << 20));
}

// Issue 21: `decode /dev/zero` read until bad_alloc, a FIFO hung the reader: only regular
// files are logs.
TEST_F(EventLogTest, OnlyRegularFilesAreRead) {
  EXPECT_THROW(EventLogReader("/dev/zero"), LogError);
  EXPECT_THROW(EventLogReader(dir_.string()), LogError);
  const std::string fifo = path("fifo");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  try {
    EventLogReader r(fifo);
    FAIL() << "a FIFO was opened as a log";
  } catch (const LogError& err) {
    EXPECT_NE(std::string(err.what()).find("not a regular file"), std::string::npos);
  }
}

TEST_F(EventLogTest, MissingFileNamed) {
  try {
    EventLogReader r(path("nope.lcmlog"));
    FAIL();
  } catch (const LogError& err) {
    EXPECT_NE(std::string(err.what()).find("nope.lcmlog"), std::string::npos);
  }
}

// A log written by LCM's own tools (lcm-proj/lcm test/python/example.lcmlog).
TEST(EventLogReal, ReadsLcmExampleLog) {
  const std::string p = std::string(SWEEPMAP_SHARED_DIR) + "/data/real/lcm_example.lcmlog";
  if (!fs::exists(p)) GTEST_SKIP() << p << " not present (../shared is not beside this checkout)";
  EventLogReader r(p);
  LogEvent e;
  int n = 0;
  int64_t last = 0;
  while (r.next(&e)) {
    EXPECT_EQ(e.channel, "JOINT_TEST");
    EXPECT_GE(e.utime, last);
    last = e.utime;
    ++n;
  }
  EXPECT_EQ(n, 10);
  EXPECT_EQ(r.offset(), r.size());
}

}  // namespace
}  // namespace sweepmap
