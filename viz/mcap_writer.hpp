// An MCAP file writer (https://mcap.dev/spec, major version 0), written from the specification:
// Debian 12 packages no MCAP library. Messages go into chunks (uncompressed or zstd), each
// followed by its message index records; the summary section repeats every schema and channel
// and holds the statistics and one chunk index per chunk, with a summary offset record per
// group, so readers can seek (McapIndexedReader) as well as stream. CRCs are written for the
// chunks' records, the data section and the summary. The file is written as `path + ".tmp"`
// and renamed by close(), so a reader never sees half a file; the same calls give the same
// bytes.
#pragma once

#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

namespace sweepmap::viz {

struct McapWriterOptions {
  std::string profile;               // header profile ("" : none of the well-known ones)
  std::string library = "sweepmap";  // header library
  bool zstd = true;                  // chunk compression "zstd", else "" (none)
  size_t chunk_size = 4u << 20;      // uncompressed bytes at which a chunk is closed
};

class McapWriter {
 public:
  // Opens `path + ".tmp"`; throws std::runtime_error naming `path`.
  McapWriter(const std::string& path, const McapWriterOptions& options);
  ~McapWriter();  // without close(): the temporary file is removed
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  // Ids start at 1 (schema id 0 means "no schema").
  uint16_t addSchema(const std::string& name, const std::string& encoding, const std::string& data);
  uint16_t addChannel(uint16_t schema_id, const std::string& topic,
                      const std::string& message_encoding,
                      const std::map<std::string, std::string>& metadata = {});
  // Messages in any time order; sequence numbers count per channel from 0.
  void write(uint16_t channel_id, uint64_t log_time_ns, uint64_t publish_time_ns, const void* data,
             size_t size);
  // Writes the last chunk, the summary and the footer, and renames the file into place.
  void close();

  uint64_t messageCount() const { return message_count_; }
  uint64_t bytesWritten() const { return offset_; }

 private:
  struct Schema {
    uint16_t id;
    std::string name, encoding, data;
  };
  struct Channel {
    uint16_t id, schema_id;
    std::string topic, encoding;
    std::map<std::string, std::string> metadata;
  };
  struct ChunkIndex {
    uint64_t start_time, end_time, offset, length;
    std::map<uint16_t, uint64_t> index_offsets;
    uint64_t index_length, compressed_size, uncompressed_size;
  };

  void put(const std::vector<uint8_t>& bytes);
  void flushChunk();
  std::vector<uint8_t> schemaRecord(const Schema& s) const;
  std::vector<uint8_t> channelRecord(const Channel& c) const;
  void writeSummaryAndFooter();

  std::string path_, tmp_path_;
  McapWriterOptions options_;
  std::FILE* file_ = nullptr;
  uint64_t offset_ = 0;
  uint32_t data_crc_ = 0;
  std::vector<Schema> schemas_;
  std::vector<Channel> channels_;
  std::vector<bool> schema_written_, channel_written_;  // by id - 1: in the data section yet
  std::vector<uint8_t> chunk_;                          // the open chunk's records
  std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> chunk_index_;  // time, offset
  uint64_t chunk_start_ = 0, chunk_end_ = 0;
  std::vector<ChunkIndex> chunk_indexes_;
  std::map<uint16_t, uint64_t> channel_counts_;
  std::map<uint16_t, uint32_t> sequences_;
  uint64_t message_count_ = 0, first_time_ = 0, last_time_ = 0;
  bool closed_ = false;
};

}  // namespace sweepmap::viz
