#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "viz/mcap_writer.hpp"

namespace sweepmap::viz {
namespace {

std::vector<uint8_t> writeSmall(const std::string& path, bool zstd) {
  McapWriterOptions o;
  o.zstd = zstd;
  o.chunk_size = 64;  // several chunks
  McapWriter w(path, o);
  const uint16_t schema = w.addSchema("foxglove.Log", "jsonschema", "{}");
  const uint16_t channel = w.addChannel(schema, "/status", "json");
  for (int i = 0; i < 10; ++i) {
    const std::string msg = "{\"i\":" + std::to_string(i) + "}";
    w.write(channel, 1000 + i, 1000 + i, msg.data(), msg.size());
  }
  w.close();
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

uint64_t u64At(const std::vector<uint8_t>& b, size_t at) {
  uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | b[at + i];
  return v;
}

TEST(McapWriter, FileHasMagicBothEndsAndAFooterPointingAtTheSummary) {
  const std::string path = testing::TempDir() + "/small.mcap";
  const auto b = writeSmall(path, false);
  const uint8_t magic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
  ASSERT_GT(b.size(), 16u + 29u);
  EXPECT_TRUE(std::equal(magic, magic + 8, b.begin()));
  EXPECT_TRUE(std::equal(magic, magic + 8, b.end() - 8));
  const size_t footer = b.size() - 8 - 29;  // opcode, length, 8 + 8 + 4
  EXPECT_EQ(b[footer], 0x02);
  const uint64_t summary_start = u64At(b, footer + 9);
  const uint64_t summary_offset_start = u64At(b, footer + 17);
  ASSERT_LT(summary_start, summary_offset_start);
  EXPECT_EQ(b[summary_start], 0x03);         // the schema group first
  EXPECT_EQ(b[summary_offset_start], 0x0E);  // then the summary offsets
  EXPECT_EQ(b[summary_start - 13], 0x0F);    // after the data end record
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
}

TEST(McapWriter, SameCallsGiveTheSameBytes) {
  const std::string dir = testing::TempDir();
  EXPECT_EQ(writeSmall(dir + "/a.mcap", true), writeSmall(dir + "/b.mcap", true));
}

}  // namespace
}  // namespace sweepmap::viz
