#include "csp/io/mcap.hpp"

#include <zlib.h>

#include <algorithm>
#include <filesystem>
#include <iterator>
#include <limits>

namespace csp::mcap {
namespace {

// Little-endian fields (the spec's serialization).
template <typename Unsigned>
void append(std::string& out, Unsigned value) {
  for (std::size_t i = 0; i < sizeof(Unsigned); ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xFF));
}

void append_string(std::string& out, std::string_view text) {
  append(out, static_cast<uint32_t>(text.size()));
  out.append(text);
}

void append_key_values(std::string& out, const KeyValues& map) {
  std::string entries;
  for (const auto& [key, value] : map) {
    append_string(entries, key);
    append_string(entries, value);
  }
  append_string(out, entries);   // a map is its byte length, then its entries
}

void append_record(std::string& out, Opcode opcode, std::string_view content) {
  out.push_back(static_cast<char>(opcode));
  append(out, static_cast<uint64_t>(content.size()));
  out.append(content);
}

std::string record_bytes(Opcode opcode, std::string_view content) {
  std::string record;
  append_record(record, opcode, content);
  return record;
}

std::string schema_record(const Schema& schema) {
  std::string content;
  append(content, schema.id);
  append_string(content, schema.name);
  append_string(content, schema.encoding);
  append_string(content, schema.data);
  return record_bytes(Opcode::kSchema, content);
}

std::string channel_record(const Channel& channel) {
  std::string content;
  append(content, channel.id);
  append(content, channel.schema_id);
  append_string(content, channel.topic);
  append_string(content, channel.message_encoding);
  append_key_values(content, channel.metadata);
  return record_bytes(Opcode::kChannel, content);
}

void append_id_counts(std::string& out, const std::map<uint16_t, uint64_t>& map) {
  std::string entries;
  for (const auto& [id, value] : map) {
    append(entries, id);
    append(entries, value);
  }
  append_string(out, entries);
}

}  // namespace

uint32_t crc32(std::string_view bytes, uint32_t crc) {
  // zlib takes uInt lengths: feed it in pieces a uInt holds.
  while (!bytes.empty()) {
    const std::size_t piece = std::min<std::size_t>(bytes.size(), std::numeric_limits<uInt>::max());
    crc = static_cast<uint32_t>(::crc32(crc, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(piece)));
    bytes.remove_prefix(piece);
  }
  return crc;
}

// ---------------------------------------------------------------------------------------- writing

Writer::Writer(const std::string& path, const std::string& profile, const std::string& library)
    : path_(path), out_(path, std::ios::binary | std::ios::trunc) {
  if (!out_) throw McapError(path + ": cannot be opened for writing");
  write_data(kMagic);
  std::string header;
  append_string(header, profile);
  append_string(header, library);
  write_data(record_bytes(Opcode::kHeader, header));
}

Writer::~Writer() {
  if (closed_) return;
  try {
    close();
  } catch (const std::exception&) {
    // A destructor must not throw; close() reports the error to a caller who calls it.
  }
}

void Writer::write_data(std::string_view bytes) {
  out_.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out_) throw McapError(path_ + ": byte " + std::to_string(offset_) + ": write failed");
  data_crc_ = crc32(bytes, data_crc_);
  offset_ += bytes.size();
}

uint16_t Writer::add_schema(const std::string& name, const std::string& encoding, const std::string& data) {
  const Schema schema{static_cast<uint16_t>(schemas_.size() + 1), name, encoding, data};   // ids from 1
  write_data(schema_record(schema));
  schemas_.push_back(schema);
  return schema.id;
}

uint16_t Writer::add_channel(uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
                             const KeyValues& metadata) {
  const Channel channel{static_cast<uint16_t>(channels_.size()), schema_id, topic, message_encoding, metadata};
  write_data(channel_record(channel));
  channels_.push_back(channel);
  sequence_.push_back(0);
  return channel.id;
}

void Writer::write_message(uint16_t channel_id, uint64_t log_time, std::string_view data) {
  if (channel_id >= channels_.size()) throw McapError(path_ + ": a message on channel " + std::to_string(channel_id) + ", which was not added");
  std::string content;
  append(content, channel_id);
  append(content, sequence_[channel_id]++);
  append(content, log_time);
  append(content, log_time);   // publish_time: the log's time is the only one a joint log has
  content.append(data);
  if (chunk_.empty()) chunk_start_ = chunk_end_ = log_time;
  chunk_start_ = std::min(chunk_start_, log_time);
  chunk_end_ = std::max(chunk_end_, log_time);
  chunk_index_[channel_id].emplace_back(log_time, chunk_.size());
  append_record(chunk_, Opcode::kMessage, content);
  if (message_count_ == 0) start_time_ = end_time_ = log_time;
  start_time_ = std::min(start_time_, log_time);
  end_time_ = std::max(end_time_, log_time);
  ++message_count_;
  ++message_counts_[channel_id];
  if (chunk_.size() >= kChunkBytes) write_chunk();
}

void Writer::write_chunk() {
  if (chunk_.empty()) return;
  std::string content;
  append(content, chunk_start_);
  append(content, chunk_end_);
  append(content, static_cast<uint64_t>(chunk_.size()));   // uncompressed_size
  append(content, crc32(chunk_));                           // uncompressed_crc
  append_string(content, "");                               // compression: none
  append(content, static_cast<uint64_t>(chunk_.size()));   // records, uint64 length-prefixed
  content.append(chunk_);
  const std::string record = record_bytes(Opcode::kChunk, content);
  ChunkIndex index{chunk_start_, chunk_end_, offset_, record.size(), 0, chunk_.size(), {}};
  write_data(record);
  const uint64_t indexes_start = offset_;
  for (const auto& [channel_id, entries] : chunk_index_) {
    std::string index_content;
    append(index_content, channel_id);
    append(index_content, static_cast<uint32_t>(entries.size() * 16));   // Array<Tuple<Timestamp, uint64>>
    for (const auto& [log_time, chunk_offset] : entries) {
      append(index_content, log_time);
      append(index_content, chunk_offset);
    }
    index.message_index_offsets[channel_id] = offset_;
    write_data(record_bytes(Opcode::kMessageIndex, index_content));
  }
  index.message_index_length = offset_ - indexes_start;
  chunks_.push_back(std::move(index));
  chunk_.clear();
  chunk_index_.clear();
}

void Writer::write_metadata(const Metadata& metadata) {
  write_chunk();   // a Metadata record lies outside chunks
  std::string content;
  append_string(content, metadata.name);
  append_key_values(content, metadata.entries);
  const std::string record = record_bytes(Opcode::kMetadata, content);
  metadata_.push_back({offset_, record.size(), metadata.name});
  write_data(record);
}

// The summary section's records, grouped by opcode, and in `offsets` one Summary Offset record per group.
std::string Writer::summary_section(uint64_t summary_start, std::string& offsets) const {
  std::string summary;
  const auto group = [&](Opcode opcode, const std::string& records) {
    if (records.empty()) return;
    std::string content;
    append(content, static_cast<uint8_t>(opcode));
    append(content, summary_start + summary.size());
    append(content, static_cast<uint64_t>(records.size()));
    append_record(offsets, Opcode::kSummaryOffset, content);
    summary += records;
  };
  std::string records;
  for (const Schema& schema : schemas_) records += schema_record(schema);
  group(Opcode::kSchema, records);
  records.clear();
  for (const Channel& channel : channels_) records += channel_record(channel);
  group(Opcode::kChannel, records);

  std::string statistics;
  append(statistics, message_count_);
  append(statistics, static_cast<uint16_t>(schemas_.size()));
  append(statistics, static_cast<uint32_t>(channels_.size()));
  append(statistics, uint32_t{0});   // attachments
  append(statistics, static_cast<uint32_t>(metadata_.size()));
  append(statistics, static_cast<uint32_t>(chunks_.size()));
  append(statistics, start_time_);
  append(statistics, end_time_);
  append_id_counts(statistics, message_counts_);
  group(Opcode::kStatistics, record_bytes(Opcode::kStatistics, statistics));

  records.clear();
  for (const ChunkIndex& chunk : chunks_) {
    std::string content;
    append(content, chunk.start_time);
    append(content, chunk.end_time);
    append(content, chunk.offset);
    append(content, chunk.length);
    append_id_counts(content, chunk.message_index_offsets);
    append(content, chunk.message_index_length);
    append_string(content, "");
    append(content, chunk.records_size);   // compressed_size
    append(content, chunk.records_size);   // uncompressed_size
    append_record(records, Opcode::kChunkIndex, content);
  }
  group(Opcode::kChunkIndex, records);

  records.clear();
  for (const MetadataIndex& metadata : metadata_) {
    std::string content;
    append(content, metadata.offset);
    append(content, metadata.length);
    append_string(content, metadata.name);
    append_record(records, Opcode::kMetadataIndex, content);
  }
  group(Opcode::kMetadataIndex, records);
  return summary;
}

void Writer::close() {
  if (closed_) return;
  closed_ = true;
  write_chunk();
  std::string data_end_content;
  append(data_end_content, data_crc_);
  write_data(record_bytes(Opcode::kDataEnd, data_end_content));

  const uint64_t summary_start = offset_;
  std::string offsets;
  std::string tail = summary_section(summary_start, offsets);
  const uint64_t summary_offset_start = summary_start + tail.size();
  tail += offsets;
  // The Footer's summary_crc covers the summary and summary offset sections and the Footer up to it.
  std::string footer;
  footer.push_back(static_cast<char>(Opcode::kFooter));
  append(footer, uint64_t{20});
  append(footer, summary_start);
  append(footer, summary_offset_start);
  append(footer, crc32(footer, crc32(tail)));
  tail += footer;
  tail += kMagic;
  write_data(tail);
  out_.close();
  if (!out_) throw McapError(path_ + ": closing failed");
}

// ---------------------------------------------------------------------------------------- reading

namespace {

// A bounded view of the file's bytes: every read is checked against `end`, and an error names the
// file and the absolute byte offset where the read began.
class Cursor {
 public:
  Cursor(const std::string& path, std::string_view bytes, uint64_t begin, uint64_t end)
      : path_(path), bytes_(bytes), pos_(begin), end_(end) {}

  uint64_t position() const { return pos_; }
  uint64_t remaining() const { return end_ - pos_; }
  bool at_end() const { return pos_ == end_; }

  [[noreturn]] void fail(uint64_t at, const std::string& what) const {
    throw McapError(path_ + ": byte " + std::to_string(at) + ": " + what);
  }

  std::string_view take(uint64_t size, const char* what) {
    if (size > remaining())
      fail(pos_, std::string(what) + " of " + std::to_string(size) + " bytes overruns its record (" +
                     std::to_string(remaining()) + " bytes left)");
    const std::string_view piece = bytes_.substr(pos_, size);
    pos_ += size;
    return piece;
  }

  template <typename Unsigned>
  Unsigned number(const char* what) {
    const std::string_view raw = take(sizeof(Unsigned), what);
    Unsigned value = 0;
    for (std::size_t i = 0; i < sizeof(Unsigned); ++i)
      value |= static_cast<Unsigned>(static_cast<Unsigned>(static_cast<unsigned char>(raw[i])) << (8 * i));
    return value;
  }

  std::string text(const char* what) { return std::string(take(number<uint32_t>(what), what)); }

  KeyValues key_values(const char* what) {
    const uint32_t size = number<uint32_t>(what);
    const uint64_t start = pos_;
    take(size, what);
    Cursor map(path_, bytes_, start, pos_);
    KeyValues values;
    while (!map.at_end()) {
      std::string key = map.text(what);
      values[key] = map.text(what);
    }
    return values;
  }

  // The next record: its opcode and a cursor over its content.
  std::pair<Opcode, Cursor> record() {
    const uint64_t start = pos_;
    if (remaining() < 9) fail(start, "a record header needs 9 bytes, " + std::to_string(remaining()) + " left");
    const auto opcode = static_cast<Opcode>(number<uint8_t>("opcode"));
    const uint64_t length = number<uint64_t>("record length");
    if (length > remaining())
      fail(start, "record (opcode 0x" + hex(static_cast<uint8_t>(opcode)) + ") of " + std::to_string(length) +
                      " bytes overruns the " + std::to_string(remaining()) + " bytes that hold it");
    Cursor content(path_, bytes_, pos_, pos_ + length);
    pos_ += length;
    return {opcode, content};
  }

  static std::string hex(uint8_t value) {
    constexpr char kDigits[] = "0123456789abcdef";
    return {kDigits[value >> 4], kDigits[value & 0xF]};
  }

 private:
  const std::string& path_;
  std::string_view bytes_;
  uint64_t pos_, end_;
};

void check_crc(const Cursor& at, uint64_t offset, uint32_t stored, std::string_view bytes, const char* what) {
  if (stored != 0 && crc32(bytes) != stored)
    at.fail(offset, std::string(what) + " CRC mismatch: stored " + std::to_string(stored) + ", computed " +
                        std::to_string(crc32(bytes)));
}

class FileReader {
 public:
  FileReader(const std::string& path, std::string_view bytes) : path_(path), bytes_(bytes) {}

  File read() {
    Cursor file(path_, bytes_, 0, bytes_.size());
    if (bytes_.size() < 2 * kMagic.size() || bytes_.substr(0, kMagic.size()) != kMagic)
      file.fail(0, "not an MCAP file (no MCAP magic at its start)");
    if (bytes_.substr(bytes_.size() - kMagic.size()) != kMagic)
      file.fail(bytes_.size() - kMagic.size(), "no MCAP magic at its end (a truncated file?)");
    file.take(kMagic.size(), "magic");
    Cursor body(path_, bytes_, kMagic.size(), bytes_.size() - kMagic.size());
    auto [opcode, header] = body.record();
    if (opcode != Opcode::kHeader) body.fail(kMagic.size(), "the first record is not a Header");
    file_.profile = header.text("profile");
    file_.library = header.text("library");

    // The data section, up to Data End.
    for (;;) {
      if (body.at_end()) body.fail(body.position(), "the file ends before its Data End record");
      const uint64_t start = body.position();
      auto [op, content] = body.record();
      if (op == Opcode::kDataEnd) {
        check_crc(content, start, content.number<uint32_t>("data_section_crc"), bytes_.substr(0, start), "data section");
        break;
      }
      if (op == Opcode::kFooter) body.fail(start, "a Footer before the Data End record");
      data_record(op, content, start);
    }
    // The summary and summary offset sections (not needed: checked by the footer's CRC), then the Footer.
    const uint64_t footer_at = bytes_.size() - kMagic.size() - 29;
    if (body.position() > footer_at) body.fail(body.position(), "no room for the Footer after the Data End");
    Cursor tail(path_, bytes_, footer_at, bytes_.size() - kMagic.size());
    auto [op, footer] = tail.record();
    if (op != Opcode::kFooter) tail.fail(footer_at, "the last record is not a Footer");
    const uint64_t summary_start = footer.number<uint64_t>("summary_start");
    footer.number<uint64_t>("summary_offset_start");
    const uint32_t summary_crc = footer.number<uint32_t>("summary_crc");
    if (summary_start != 0 && (summary_start < body.position() || summary_start > footer_at))
      tail.fail(footer_at, "summary_start " + std::to_string(summary_start) + " is outside the summary's bytes");
    const uint64_t crc_from = summary_start != 0 ? summary_start : body.position();
    check_crc(tail, footer_at, summary_crc, bytes_.substr(crc_from, footer_at + 25 - crc_from), "summary");
    return std::move(file_);
  }

 private:
  void data_record(Opcode op, Cursor& content, uint64_t start) {
    switch (op) {
      case Opcode::kSchema: {
        Schema schema;
        schema.id = content.number<uint16_t>("schema id");
        schema.name = content.text("schema name");
        schema.encoding = content.text("schema encoding");
        schema.data = content.text("schema data");
        if (schema.id != 0 && !has_schema(schema.id)) file_.schemas.push_back(std::move(schema));
        return;
      }
      case Opcode::kChannel: {
        Channel channel;
        channel.id = content.number<uint16_t>("channel id");
        channel.schema_id = content.number<uint16_t>("schema id");
        channel.topic = content.text("topic");
        channel.message_encoding = content.text("message encoding");
        channel.metadata = content.key_values("channel metadata");
        if (channel.schema_id != 0 && !has_schema(channel.schema_id))
          content.fail(start, "channel " + std::to_string(channel.id) + " names schema " +
                                  std::to_string(channel.schema_id) + ", which no earlier Schema record defines");
        if (!has_channel(channel.id)) file_.channels.push_back(std::move(channel));
        return;
      }
      case Opcode::kMessage: {
        Message message;
        message.channel_id = content.number<uint16_t>("channel id");
        message.sequence = content.number<uint32_t>("sequence");
        message.log_time = content.number<uint64_t>("log_time");
        message.publish_time = content.number<uint64_t>("publish_time");
        message.data = std::string(content.take(content.remaining(), "message data"));
        if (!has_channel(message.channel_id))
          content.fail(start, "a message on channel " + std::to_string(message.channel_id) +
                                  ", which no earlier Channel record defines");
        file_.messages.push_back(std::move(message));
        return;
      }
      case Opcode::kChunk: {
        content.number<uint64_t>("message_start_time");
        content.number<uint64_t>("message_end_time");
        const uint64_t uncompressed_size = content.number<uint64_t>("uncompressed_size");
        const uint32_t crc = content.number<uint32_t>("uncompressed_crc");
        const std::string compression = content.text("compression");
        const uint64_t records_size = content.number<uint64_t>("records length");
        const uint64_t records_at = content.position();
        const std::string_view records = content.take(records_size, "chunk records");
        if (!compression.empty())
          content.fail(start, "the chunk is compressed with `" + compression +
                                  "`; CSP reads uncompressed MCAP only (write it again with compression none, "
                                  "e.g. `mcap convert --compression none`)");
        if (uncompressed_size != records_size)
          content.fail(start, "the chunk's uncompressed_size " + std::to_string(uncompressed_size) +
                                  " differs from its records' length " + std::to_string(records_size));
        check_crc(content, start, crc, records, "chunk");
        Cursor inner(path_, bytes_, records_at, records_at + records.size());
        while (!inner.at_end()) {
          const uint64_t inner_start = inner.position();
          auto [inner_op, inner_content] = inner.record();
          if (inner_op == Opcode::kSchema || inner_op == Opcode::kChannel || inner_op == Opcode::kMessage)
            data_record(inner_op, inner_content, inner_start);
        }
        return;
      }
      case Opcode::kMetadata: {
        Metadata metadata;
        metadata.name = content.text("metadata name");
        metadata.entries = content.key_values("metadata");
        file_.metadata.push_back(std::move(metadata));
        return;
      }
      case Opcode::kHeader:
        content.fail(start, "a second Header record");
      default:
        return;   // message indexes, attachments, records of later versions or of applications
    }
  }

  bool has_schema(uint16_t id) const {
    return std::any_of(file_.schemas.begin(), file_.schemas.end(), [&](const Schema& s) { return s.id == id; });
  }
  bool has_channel(uint16_t id) const {
    return std::any_of(file_.channels.begin(), file_.channels.end(), [&](const Channel& c) { return c.id == id; });
  }

  const std::string& path_;
  std::string_view bytes_;
  File file_;
};

std::string file_bytes(const std::string& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) throw McapError(path + ": no such file (or not a regular file)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw McapError(path + ": cannot be opened");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw McapError(path + ": cannot be read");
  return bytes;
}

}  // namespace

const Channel* File::channel(const std::string& topic) const {
  const auto found = std::find_if(channels.begin(), channels.end(), [&](const Channel& c) { return c.topic == topic; });
  return found == channels.end() ? nullptr : &*found;
}

File read_file(const std::string& path) {
  const std::string bytes = file_bytes(path);
  return FileReader(path, bytes).read();
}

bool is_mcap_file(const std::string& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) return false;   // a FIFO is never waited on
  std::ifstream in(path, std::ios::binary);
  std::string start(kMagic.size(), '\0');
  return in.read(start.data(), static_cast<std::streamsize>(start.size())) && start == kMagic;
}

}  // namespace csp::mcap
