// MCAP writer (include/rvlio/formats/mcap.h), written from the public
// specification. Layout of a written file:
//   magic, Header,
//   data section: Schema/Channel records where they are added (inside the
//     current chunk when chunked), Messages (in Chunks, each followed by one
//     MessageIndex record per channel), DataEnd (CRC of every byte before it),
//   summary section: Schemas, Channels, Statistics, ChunkIndexes,
//   summary offset section: one SummaryOffset per group above,
//   Footer (summary CRC), magic.
// Output goes through AtomicFileWriter: the file appears on Close() only.
#include <lz4frame.h>
#include <zstd.h>

#include <algorithm>
#include <utility>

#include "mcap_records.h"
#include "rvlio/formats/atomic_file.h"
#include "rvlio/formats/mcap.h"

namespace rvlio::mcap {
namespace {

using detail::FieldWriter;

constexpr int kZstdLevel = 1;  // fast; rosbag-sized chunks compress well already

class McapWriter : public Writer {
 public:
  McapWriter(std::string path, WriterOptions options)
      : path_(std::move(path)), options_(std::move(options)) {}

  Status Init();
  StatusOr<uint16_t> AddSchema(const std::string& name, const std::string& encoding,
                               const std::string& data) override;
  StatusOr<uint16_t> AddChannel(uint16_t schema_id, const std::string& topic,
                                const std::string& message_encoding) override;
  Status Write(const Message& message) override;
  Status Close() override;

 private:
  Status Error(const std::string& what) const {
    return Status::IoError("cannot write '" + path_ + "': " + what);
  }
  // Appends bytes to the file (sticky failure), counting offset and CRC.
  Status Emit(std::string_view bytes);
  // A Schema/Channel/Message record: into the open chunk or the file.
  Status Output(detail::Opcode opcode, std::string_view content);
  Status FlushChunk();
  Status Compress(const std::string& records, std::string* out) const;
  std::string SummarySection(uint64_t summary_start, uint64_t* summary_offset_start) const;

  std::string path_;
  WriterOptions options_;
  AtomicFileWriter file_;
  Status error_;
  bool closed_ = false;
  uint64_t offset_ = 0;
  uint32_t data_crc_ = 0;

  std::string schema_records_;   // the summary's copies
  std::string channel_records_;
  std::string chunk_index_records_;
  uint16_t schema_count_ = 0;
  std::map<uint16_t, uint16_t> channel_schema_;  // channel id -> schema id

  // Statistics.
  uint64_t message_count_ = 0, start_time_ = 0, end_time_ = 0;
  uint32_t chunk_count_ = 0;
  std::map<uint16_t, uint64_t> channel_counts_;

  // The open chunk.
  std::string chunk_records_;
  uint64_t chunk_start_time_ = 0, chunk_end_time_ = 0;
  bool chunk_has_messages_ = false;
  std::map<uint16_t, std::string> chunk_message_index_;  // channel -> (time, offset) pairs
};

Status McapWriter::Init() {
  const std::string& c = options_.compression;
  if (c != "" && c != "zstd" && c != "lz4")
    return Error("unknown MCAP compression '" + c + "' (use \"\", \"zstd\" or \"lz4\")");
  if (Status s = file_.Open(path_); !s.ok()) return s;
  std::string head(detail::kMagic, detail::kMagicSize);
  std::string header;
  FieldWriter w(&header);
  w.String(options_.profile);
  w.String(options_.library);
  detail::AppendRecord(&head, detail::kHeader, header);
  return Emit(head);
}

Status McapWriter::Emit(std::string_view bytes) {
  if (!error_.ok()) return error_;
  data_crc_ = detail::Crc32Update(data_crc_, bytes.data(), bytes.size());
  offset_ += bytes.size();
  error_ = file_.Append(bytes);
  return error_;
}

Status McapWriter::Output(detail::Opcode opcode, std::string_view content) {
  if (options_.chunked) {
    detail::AppendRecord(&chunk_records_, opcode, content);
    return error_;
  }
  std::string record;
  detail::AppendRecord(&record, opcode, content);
  return Emit(record);
}

StatusOr<uint16_t> McapWriter::AddSchema(const std::string& name, const std::string& encoding,
                                         const std::string& data) {
  if (closed_) return Error("AddSchema after Close");
  if (schema_count_ == UINT16_MAX) return Error("more than 65535 schemas");
  const uint16_t id = ++schema_count_;  // 0 means "no schema"
  std::string content;
  FieldWriter w(&content);
  w.U16(id);
  w.String(name);
  w.String(encoding);
  w.String(data);
  detail::AppendRecord(&schema_records_, detail::kSchema, content);
  if (Status s = Output(detail::kSchema, content); !s.ok()) return s;
  return id;
}

StatusOr<uint16_t> McapWriter::AddChannel(uint16_t schema_id, const std::string& topic,
                                          const std::string& message_encoding) {
  if (closed_) return Error("AddChannel after Close");
  if (schema_id > schema_count_) return Error("channel '" + topic + "' names unknown schema " +
                                              std::to_string(schema_id));
  if (channel_schema_.size() > UINT16_MAX) return Error("more than 65536 channels");
  const uint16_t id = static_cast<uint16_t>(channel_schema_.size());
  channel_schema_[id] = schema_id;
  std::string content;
  FieldWriter w(&content);
  w.U16(id);
  w.U16(schema_id);
  w.String(topic);
  w.String(message_encoding);
  w.StringMap({});
  detail::AppendRecord(&channel_records_, detail::kChannel, content);
  if (Status s = Output(detail::kChannel, content); !s.ok()) return s;
  return id;
}

Status McapWriter::Write(const Message& message) {
  if (closed_) return Error("Write after Close");
  if (channel_schema_.count(message.channel_id) == 0)
    return Error("message on unknown channel " + std::to_string(message.channel_id));
  const uint64_t t = message.log_time_ns;
  std::string content;
  content.reserve(detail::kMessagePrefixSize + message.data.size());
  FieldWriter w(&content);
  w.U16(message.channel_id);
  w.U32(message.sequence);
  w.U64(t);
  w.U64(message.publish_time_ns);
  w.Raw(std::string_view(reinterpret_cast<const char*>(message.data.data()), message.data.size()));

  start_time_ = message_count_ == 0 ? t : std::min(start_time_, t);
  end_time_ = message_count_ == 0 ? t : std::max(end_time_, t);
  ++message_count_;
  ++channel_counts_[message.channel_id];
  if (!options_.chunked) return Output(detail::kMessage, content);

  FieldWriter index(&chunk_message_index_[message.channel_id]);
  index.U64(t);
  index.U64(chunk_records_.size());
  chunk_start_time_ = chunk_has_messages_ ? std::min(chunk_start_time_, t) : t;
  chunk_end_time_ = chunk_has_messages_ ? std::max(chunk_end_time_, t) : t;
  chunk_has_messages_ = true;
  if (Status s = Output(detail::kMessage, content); !s.ok()) return s;
  if (chunk_records_.size() >= options_.chunk_size) return FlushChunk();
  return Status::Ok();
}

Status McapWriter::Compress(const std::string& records, std::string* out) const {
  if (options_.compression.empty()) {
    *out = records;
  } else if (options_.compression == "zstd") {
    out->resize(ZSTD_compressBound(records.size()));
    const size_t n = ZSTD_compress(&(*out)[0], out->size(), records.data(), records.size(),
                                   kZstdLevel);
    if (ZSTD_isError(n)) return Error(std::string("zstd: ") + ZSTD_getErrorName(n));
    out->resize(n);
  } else {
    out->resize(LZ4F_compressFrameBound(records.size(), nullptr));
    const size_t n =
        LZ4F_compressFrame(&(*out)[0], out->size(), records.data(), records.size(), nullptr);
    if (LZ4F_isError(n)) return Error(std::string("lz4: ") + LZ4F_getErrorName(n));
    out->resize(n);
  }
  return Status::Ok();
}

// Writes the open chunk, then its message indexes; keeps its ChunkIndex.
Status McapWriter::FlushChunk() {
  if (chunk_records_.empty()) return error_;
  std::string compressed;
  if (Status s = Compress(chunk_records_, &compressed); !s.ok()) return s;
  std::string content;
  FieldWriter w(&content);
  w.U64(chunk_start_time_);
  w.U64(chunk_end_time_);
  w.U64(chunk_records_.size());
  w.U32(detail::Crc32(chunk_records_));
  w.String(options_.compression);
  w.U64(compressed.size());
  w.Raw(compressed);
  std::string record;
  detail::AppendRecord(&record, detail::kChunk, content);
  const uint64_t chunk_start = offset_;
  if (Status s = Emit(record); !s.ok()) return s;
  const uint64_t chunk_length = offset_ - chunk_start;

  std::string offsets;  // Map<uint16 channel, uint64 offset of its MessageIndex>
  FieldWriter o(&offsets);
  const uint64_t indexes_start = offset_;
  for (const auto& [channel, entries] : chunk_message_index_) {
    std::string index;
    FieldWriter iw(&index);
    iw.U16(channel);
    iw.String(entries);  // Array<Tuple<timestamp, offset>>: uint32 byte length + entries
    o.U16(channel);
    o.U64(offset_);
    record.clear();
    detail::AppendRecord(&record, detail::kMessageIndex, index);
    if (Status s = Emit(record); !s.ok()) return s;
  }
  std::string chunk_index;
  FieldWriter ci(&chunk_index);
  ci.U64(chunk_start_time_);
  ci.U64(chunk_end_time_);
  ci.U64(chunk_start);
  ci.U64(chunk_length);
  ci.String(offsets);
  ci.U64(offset_ - indexes_start);
  ci.String(options_.compression);
  ci.U64(compressed.size());
  ci.U64(chunk_records_.size());
  detail::AppendRecord(&chunk_index_records_, detail::kChunkIndex, chunk_index);
  ++chunk_count_;
  chunk_records_.clear();
  chunk_message_index_.clear();
  chunk_has_messages_ = false;
  chunk_start_time_ = chunk_end_time_ = 0;
  return Status::Ok();
}

// Summary + summary offset sections, starting at file offset summary_start.
std::string McapWriter::SummarySection(uint64_t summary_start,
                                       uint64_t* summary_offset_start) const {
  std::string statistics;
  FieldWriter s(&statistics);
  s.U64(message_count_);
  s.U16(schema_count_);
  s.U32(static_cast<uint32_t>(channel_schema_.size()));
  s.U32(0);  // attachments
  s.U32(0);  // metadata
  s.U32(chunk_count_);
  s.U64(start_time_);
  s.U64(end_time_);
  std::string counts;
  FieldWriter c(&counts);
  for (const auto& [channel, count] : channel_counts_) {
    c.U16(channel);
    c.U64(count);
  }
  s.String(counts);
  std::string statistics_record;
  detail::AppendRecord(&statistics_record, detail::kStatistics, statistics);

  std::string summary, offsets;
  const std::pair<detail::Opcode, const std::string*> groups[] = {
      {detail::kSchema, &schema_records_},
      {detail::kChannel, &channel_records_},
      {detail::kStatistics, &statistics_record},
      {detail::kChunkIndex, &chunk_index_records_}};
  for (const auto& [opcode, records] : groups) {
    if (records->empty()) continue;
    std::string offset;
    FieldWriter w(&offset);
    w.U8(opcode);
    w.U64(summary_start + summary.size());
    w.U64(records->size());
    detail::AppendRecord(&offsets, detail::kSummaryOffset, offset);
    summary += *records;
  }
  *summary_offset_start = summary_start + summary.size();
  return summary + offsets;
}

Status McapWriter::Close() {
  if (closed_) return Error("Close called twice");
  closed_ = true;
  if (options_.chunked) {
    if (Status s = FlushChunk(); !s.ok()) return s;
  }
  std::string tail, data_end;
  FieldWriter(&data_end).U32(data_crc_);
  detail::AppendRecord(&tail, detail::kDataEnd, data_end);
  const uint64_t summary_start = offset_ + tail.size();
  uint64_t summary_offset_start = 0;
  const std::string summary = SummarySection(summary_start, &summary_offset_start);
  std::string footer;
  FieldWriter f(&footer);
  f.U8(detail::kFooter);
  f.U64(detail::kFooterContentSize);
  f.U64(summary_start);
  f.U64(summary_offset_start);
  // The summary CRC covers the summary start up to Footer.summary_offset_start.
  const uint32_t summary_crc =
      detail::Crc32Update(detail::Crc32(summary), footer.data(), footer.size());
  f.U32(summary_crc);
  footer.append(detail::kMagic, detail::kMagicSize);
  tail += summary;
  tail += footer;
  if (Status s = Emit(tail); !s.ok()) return s;
  error_ = file_.Commit();
  return error_;
}

}  // namespace

StatusOr<std::unique_ptr<Writer>> Writer::Create(const std::string& path,
                                                 const WriterOptions& options) {
  auto writer = std::make_unique<McapWriter>(path, options);
  if (Status s = writer->Init(); !s.ok()) return s;
  return std::unique_ptr<Writer>(std::move(writer));
}

}  // namespace rvlio::mcap
