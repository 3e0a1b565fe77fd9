#include "viz/mcap_writer.hpp"

#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "core/atomic_file.hpp"

namespace sweepmap::viz {

namespace {

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
enum Opcode : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

// Little-endian serialisation of the spec's primitive types.
struct Bytes {
  std::vector<uint8_t> b;
  template <class T>
  Bytes& u(T v) {
    for (size_t i = 0; i < sizeof(T); ++i) b.push_back(static_cast<uint8_t>(v >> (8 * i)));
    return *this;
  }
  Bytes& raw(const void* data, size_t n) {
    const auto* p = static_cast<const uint8_t*>(data);
    b.insert(b.end(), p, p + n);
    return *this;
  }
  Bytes& str(const std::string& s) { return u<uint32_t>(s.size()).raw(s.data(), s.size()); }
  Bytes& bytes(const std::vector<uint8_t>& v) {  // a Map or Array: uint32 byte length, content
    return u<uint32_t>(v.size()).raw(v.data(), v.size());
  }
};

std::vector<uint8_t> record(uint8_t opcode, const std::vector<uint8_t>& content) {
  Bytes r;
  r.u(opcode).u<uint64_t>(content.size()).raw(content.data(), content.size());
  return r.b;
}

uint32_t crc(uint32_t crc_so_far, const uint8_t* data, size_t n) {
  return static_cast<uint32_t>(::crc32(crc_so_far, data, static_cast<uInt>(n)));
}

}  // namespace

McapWriter::McapWriter(const std::string& path, const McapWriterOptions& options)
    : path_(path), tmp_path_(tmpPathFor(path)), options_(options) {
  file_ = std::fopen(tmp_path_.c_str(), "wb");
  if (!file_) throw std::runtime_error(path + ": cannot write: " + std::strerror(errno));
  put(std::vector<uint8_t>(kMagic, kMagic + 8));
  put(record(kHeader, Bytes().str(options_.profile).str(options_.library).b));
}

McapWriter::~McapWriter() {
  if (file_) {
    std::fclose(file_);
    std::remove(tmp_path_.c_str());
  }
}

void McapWriter::put(const std::vector<uint8_t>& bytes) {
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) {
    throw std::runtime_error(path_ + ": write failed at byte " + std::to_string(offset_) + ": " +
                             std::strerror(errno));
  }
  data_crc_ = crc(data_crc_, bytes.data(), bytes.size());
  offset_ += bytes.size();
}

uint16_t McapWriter::addSchema(const std::string& name, const std::string& encoding,
                               const std::string& data) {
  if (schemas_.size() >= 65535) throw std::runtime_error(path_ + ": too many schemas");
  schemas_.push_back({static_cast<uint16_t>(schemas_.size() + 1), name, encoding, data});
  schema_written_.push_back(false);
  return schemas_.back().id;
}

uint16_t McapWriter::addChannel(uint16_t schema_id, const std::string& topic,
                                const std::string& message_encoding,
                                const std::map<std::string, std::string>& metadata) {
  if (schema_id > schemas_.size()) throw std::invalid_argument("McapWriter: unknown schema id");
  if (channels_.size() >= 65535) throw std::runtime_error(path_ + ": too many channels");
  channels_.push_back(
      {static_cast<uint16_t>(channels_.size()), schema_id, topic, message_encoding, metadata});
  channel_written_.push_back(false);
  return channels_.back().id;
}

std::vector<uint8_t> McapWriter::schemaRecord(const Schema& s) const {
  return record(kSchema, Bytes().u(s.id).str(s.name).str(s.encoding).str(s.data).b);
}

std::vector<uint8_t> McapWriter::channelRecord(const Channel& c) const {
  Bytes metadata;
  for (const auto& [k, v] : c.metadata) metadata.str(k).str(v);
  return record(kChannel,
                Bytes().u(c.id).u(c.schema_id).str(c.topic).str(c.encoding).bytes(metadata.b).b);
}

void McapWriter::write(uint16_t channel_id, uint64_t log_time_ns, uint64_t publish_time_ns,
                       const void* data, size_t size) {
  if (channel_id >= channels_.size()) throw std::invalid_argument("McapWriter: unknown channel");
  const Channel& c = channels_[channel_id];
  auto append = [this](const std::vector<uint8_t>& r) {
    chunk_.insert(chunk_.end(), r.begin(), r.end());
  };
  // A channel's schema and channel records precede its first message in the data section.
  if (c.schema_id != 0 && !schema_written_[c.schema_id - 1]) {
    append(schemaRecord(schemas_[c.schema_id - 1]));
    schema_written_[c.schema_id - 1] = true;
  }
  if (!channel_written_[channel_id]) {
    append(channelRecord(c));
    channel_written_[channel_id] = true;
  }
  const bool first_in_chunk = chunk_index_.empty();
  chunk_index_[channel_id].push_back({log_time_ns, chunk_.size()});
  Bytes m;
  m.u(channel_id).u(sequences_[channel_id]++).u(log_time_ns).u(publish_time_ns).raw(data, size);
  append(record(kMessage, m.b));
  chunk_start_ = first_in_chunk ? log_time_ns : std::min(chunk_start_, log_time_ns);
  chunk_end_ = first_in_chunk ? log_time_ns : std::max(chunk_end_, log_time_ns);
  first_time_ = message_count_ == 0 ? log_time_ns : std::min(first_time_, log_time_ns);
  last_time_ = message_count_ == 0 ? log_time_ns : std::max(last_time_, log_time_ns);
  ++message_count_;
  ++channel_counts_[channel_id];
  if (chunk_.size() >= options_.chunk_size) flushChunk();
}

void McapWriter::flushChunk() {
  if (chunk_.empty()) return;
  std::vector<uint8_t> stored = chunk_;
  if (options_.zstd) {
    stored.resize(ZSTD_compressBound(chunk_.size()));
    const size_t n = ZSTD_compress(stored.data(), stored.size(), chunk_.data(), chunk_.size(), 3);
    if (ZSTD_isError(n)) throw std::runtime_error(path_ + ": zstd: " + ZSTD_getErrorName(n));
    stored.resize(n);
  }
  Bytes c;
  c.u(chunk_start_).u(chunk_end_).u<uint64_t>(chunk_.size());
  c.u(crc(0, chunk_.data(), chunk_.size())).str(options_.zstd ? "zstd" : "");
  c.u<uint64_t>(stored.size()).raw(stored.data(), stored.size());
  ChunkIndex index{chunk_start_, chunk_end_, offset_, 0, {}, 0, stored.size(), chunk_.size()};
  put(record(kChunk, c.b));
  index.length = offset_ - index.offset;
  const uint64_t index_start = offset_;
  for (auto& [channel, entries] : chunk_index_) {  // channel id order, each by time
    std::stable_sort(entries.begin(), entries.end());
    Bytes pairs;
    for (const auto& [time, at] : entries) pairs.u(time).u(at);
    index.index_offsets[channel] = offset_;
    put(record(kMessageIndex, Bytes().u(channel).bytes(pairs.b).b));
  }
  index.index_length = offset_ - index_start;
  chunk_indexes_.push_back(index);
  chunk_.clear();
  chunk_index_.clear();
}

void McapWriter::writeSummaryAndFooter() {
  const uint64_t summary_start = offset_;
  uint32_t summary_crc = 0;
  std::vector<std::pair<uint8_t, std::pair<uint64_t, uint64_t>>> groups;
  auto group = [&](uint8_t opcode, const std::vector<std::vector<uint8_t>>& records) {
    if (records.empty()) return;
    const uint64_t start = offset_;
    for (const auto& r : records) {
      put(r);
      summary_crc = crc(summary_crc, r.data(), r.size());
    }
    groups.push_back({opcode, {start, offset_ - start}});
  };
  std::vector<std::vector<uint8_t>> schemas, channels, indexes;
  for (const auto& s : schemas_) schemas.push_back(schemaRecord(s));
  for (const auto& c : channels_) channels.push_back(channelRecord(c));
  Bytes counts;
  for (const auto& [id, n] : channel_counts_) counts.u(id).u(n);
  Bytes stats;
  stats.u(message_count_).u<uint16_t>(schemas_.size()).u<uint32_t>(channels_.size());
  stats.u<uint32_t>(0).u<uint32_t>(0).u<uint32_t>(chunk_indexes_.size());
  stats.u(first_time_).u(last_time_).bytes(counts.b);
  for (const auto& i : chunk_indexes_) {
    Bytes offsets;
    for (const auto& [id, at] : i.index_offsets) offsets.u(id).u(at);
    Bytes r;
    r.u(i.start_time).u(i.end_time).u(i.offset).u(i.length).bytes(offsets.b);
    r.u(i.index_length).str(options_.zstd ? "zstd" : "").u(i.compressed_size);
    r.u(i.uncompressed_size);
    indexes.push_back(record(kChunkIndex, r.b));
  }
  group(kSchema, schemas);
  group(kChannel, channels);
  group(kStatistics, {record(kStatistics, stats.b)});
  group(kChunkIndex, indexes);
  const uint64_t summary_offset_start = offset_;
  for (const auto& [opcode, range] : groups) {
    const auto r = record(kSummaryOffset, Bytes().u(opcode).u(range.first).u(range.second).b);
    put(r);
    summary_crc = crc(summary_crc, r.data(), r.size());
  }
  // The footer's CRC covers the summary through the footer's summary_offset_start field.
  Bytes footer_head;
  footer_head.u<uint8_t>(kFooter).u<uint64_t>(20).u(summary_start).u(summary_offset_start);
  summary_crc = crc(summary_crc, footer_head.b.data(), footer_head.b.size());
  put(footer_head.u(summary_crc).b);
  put(std::vector<uint8_t>(kMagic, kMagic + 8));
}

void McapWriter::close() {
  if (closed_) return;
  flushChunk();
  const uint32_t data_crc = data_crc_;
  put(record(kDataEnd, Bytes().u(data_crc).b));
  writeSummaryAndFooter();
  closed_ = true;
  const bool ok = std::fflush(file_) == 0;
  std::fclose(file_);
  file_ = nullptr;
  if (!ok) {
    std::remove(tmp_path_.c_str());
    throw std::runtime_error(path_ + ": write failed: " + std::strerror(errno));
  }
  commitTmpFile(tmp_path_, path_);
}

}  // namespace sweepmap::viz
