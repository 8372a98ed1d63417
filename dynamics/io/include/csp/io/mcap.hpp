// MCAP (https://mcap.dev/spec), the container Foxglove and Rerun open: a writer and a reader of the
// format only, no robot knowledge (run/mcap_export.hpp maps a session log onto it; docs/mcap.md).
//
// Hand-written because no MCAP library is packaged in Debian, and the subset CSP needs (uncompressed
// chunks, their message indexes, the summary with chunk indexes and statistics, CRCs) is small.
// The CRC32 is zlib's (Debian's zlib1g), the one MCAP specifies (the ISO-HDLC / zip polynomial).
#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace csp::mcap {

// A file that is no readable MCAP: the message names the file, the byte offset and what was wrong.
class McapError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The 8 bytes an MCAP file begins and ends with: 0x89 "MCAP" '0' (the major version) "\r\n".
inline constexpr std::string_view kMagic{"\x89MCAP0\r\n", 8};

enum class Opcode : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

using KeyValues = std::map<std::string, std::string>;   // the spec's Map<string, string>

struct Schema {
  uint16_t id = 0;   // never 0
  std::string name, encoding, data;
};

struct Channel {
  uint16_t id = 0;
  uint16_t schema_id = 0;   // 0: no schema
  std::string topic, message_encoding;
  KeyValues metadata;
};

struct Message {
  uint16_t channel_id = 0;
  uint32_t sequence = 0;
  uint64_t log_time = 0, publish_time = 0;   // ns
  std::string data;
};

struct Metadata {
  std::string name;
  KeyValues entries;
};

// CRC32 as the spec uses it (zlib's crc32), continued from `crc` (0 to start).
uint32_t crc32(std::string_view bytes, uint32_t crc = 0);

// Writes an MCAP file: magic and Header at construction; Schema and Channel records in the data
// section as they are added; Messages in uncompressed Chunks (each followed by its Message Index
// records); Metadata; at close() the Data End (with the data section's CRC), the summary (Schema,
// Channel, Statistics, Chunk Index, Metadata Index groups), the Summary Offset records, the Footer
// (with the summary's CRC) and the magic. Throws McapError naming the file when it cannot write.
class Writer {
 public:
  Writer(const std::string& path, const std::string& profile, const std::string& library);
  ~Writer();   // closes if close() was not called, without throwing
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  uint16_t add_schema(const std::string& name, const std::string& encoding, const std::string& data);
  uint16_t add_channel(uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
                       const KeyValues& metadata = {});
  // The next message of the channel (its sequence counts from 0); publish_time = log_time.
  void write_message(uint16_t channel_id, uint64_t log_time, std::string_view data);
  void write_metadata(const Metadata& metadata);
  void close();

 private:
  static constexpr std::size_t kChunkBytes = 1 << 20;   // a chunk's records before it is written out

  struct ChunkIndex {
    uint64_t start_time, end_time, offset, length, message_index_length, records_size;
    std::map<uint16_t, uint64_t> message_index_offsets;
  };
  struct MetadataIndex {
    uint64_t offset, length;
    std::string name;
  };

  void write_data(std::string_view bytes);   // to the file, into the data section's CRC
  void write_chunk();
  std::string summary_section(uint64_t summary_start, std::string& offsets) const;

  std::string path_;
  std::ofstream out_;
  uint64_t offset_ = 0;
  uint32_t data_crc_ = 0;
  bool closed_ = false;
  std::vector<Schema> schemas_;
  std::vector<Channel> channels_;
  std::vector<uint32_t> sequence_;                      // per channel id
  std::map<uint16_t, uint64_t> message_counts_;
  uint64_t message_count_ = 0, start_time_ = 0, end_time_ = 0;
  std::string chunk_;                                   // the open chunk's records
  uint64_t chunk_start_ = 0, chunk_end_ = 0;
  std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> chunk_index_;   // log_time, offset in chunk
  std::vector<ChunkIndex> chunks_;
  std::vector<MetadataIndex> metadata_;
};

// What an MCAP file holds, read from start to end (the data section; the summary is checked, not
// needed). Messages in file order.
struct File {
  std::string profile, library;
  std::vector<Schema> schemas;
  std::vector<Channel> channels;
  std::vector<Message> messages;
  std::vector<Metadata> metadata;

  const Channel* channel(const std::string& topic) const;   // null if no channel has the topic
};

// Reads an MCAP file whole: every record's length is checked against what holds it, every CRC that
// is not 0 is checked, records the spec has no use for here (attachments, unknown opcodes) are
// skipped. Throws McapError "FILE: byte N: what" for a missing file, a bad magic, a truncated or
// overlong record, a CRC mismatch, a message on an unknown channel, and a compressed chunk (naming
// its compression: CSP reads uncompressed MCAP only).
File read_file(const std::string& path);

// True if the file at `path` begins with the MCAP magic.
bool is_mcap_file(const std::string& path);

}  // namespace csp::mcap
