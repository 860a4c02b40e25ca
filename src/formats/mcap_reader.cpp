// MCAP reader (include/rvlio/formats/mcap.h), written from the public
// specification. Plan of a read:
//   1. magic + Header record at the start;
//   2. Footer + magic at the end: the summary section gives schemas,
//      channels, statistics and chunk indexes (summary CRC checked);
//   3. without chunk indexes (no summary, a file cut short, an unchunked
//      file) a linear scan of the data section finds the same: it
//      decompresses every chunk once (CRCs checked) and stops at the first
//      incomplete record;
//   4. Next() merges "segments" (chunks, runs of loose messages in log-time
//      order) by log time: a segment is opened only when its start time is
//      reached, so memory holds the chunks that overlap in time, never the
//      whole file.
#include <fcntl.h>
#include <lz4frame.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <functional>
#include <queue>
#include <set>
#include <utility>

#include "mcap_records.h"
#include "rvlio/formats/mcap.h"

namespace rvlio::mcap {
namespace {

using detail::FieldReader;
using detail::kFooterRecordSize;
using detail::kMagic;
using detail::kMagicSize;
using detail::kRecordHeaderSize;

// ---------------------------------------------------------------------------
// Random access to the bytes of a file or a buffer.
class ByteSource {
 public:
  virtual ~ByteSource() = default;
  virtual uint64_t size() const = 0;
  // Reads [offset, offset + n) (the caller checked the range); false on an
  // I/O error.
  virtual bool Read(uint64_t offset, size_t n, std::string* out) = 0;
};

class FileSource : public ByteSource {
 public:
  ~FileSource() override {
    if (fd_ >= 0) ::close(fd_);
  }
  Status Open(const std::string& path) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    struct stat st {};
    if (fd_ < 0 || ::fstat(fd_, &st) != 0)
      return Status::InvalidInput("cannot open '" + path + "': " + std::strerror(errno));
    if (!S_ISREG(st.st_mode))
      return Status::InvalidInput("cannot open '" + path + "': not a regular file");
    size_ = static_cast<uint64_t>(st.st_size);
    return Status::Ok();
  }
  uint64_t size() const override { return size_; }
  bool Read(uint64_t offset, size_t n, std::string* out) override {
    out->resize(n);
    size_t done = 0;
    while (done < n) {
      const ssize_t r = ::pread(fd_, &(*out)[done], n - done, static_cast<off_t>(offset + done));
      if (r < 0 && errno == EINTR) continue;
      if (r <= 0) return false;
      done += static_cast<size_t>(r);
    }
    return true;
  }

 private:
  int fd_ = -1;
  uint64_t size_ = 0;
};

class BufferSource : public ByteSource {
 public:
  explicit BufferSource(std::string bytes) : bytes_(std::move(bytes)) {}
  uint64_t size() const override { return bytes_.size(); }
  bool Read(uint64_t offset, size_t n, std::string* out) override {
    out->assign(bytes_, static_cast<size_t>(offset), n);
    return true;
  }

 private:
  std::string bytes_;
};

std::string Hex32(uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "0x%08" PRIx32, v);
  return buf;
}

// A name read from the file, safe for a one-line message: control and
// non-ASCII bytes as \xNN, at most 64 bytes shown.
std::string Printable(const std::string& text) {
  std::string out;
  for (size_t i = 0; i < text.size() && i < 64; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7F && c != '\\') {
      out.push_back(static_cast<char>(c));
    } else {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "\\x%02x", c);
      out += buf;
    }
  }
  if (text.size() > 64) out += "...";
  return out;
}

// ---------------------------------------------------------------------------
// Chunk decompression. The output grows with what the decoder produces (never
// more than uncompressed_size + 1 bytes), so a corrupt size field cannot make
// a huge allocation.
constexpr size_t kMinOutput = 64 << 10;

size_t InitialOutput(uint64_t uncompressed_size, size_t compressed_size) {
  const uint64_t guess = std::max<uint64_t>(kMinOutput, uint64_t{16} * compressed_size);
  return static_cast<size_t>(std::min(uncompressed_size + 1, guess));
}

// Grows *out (currently fully used) towards `limit`; false when at the limit.
bool GrowOutput(std::string* out, size_t limit) {
  if (out->size() >= limit) return false;
  out->resize(std::min(limit, std::max(kMinOutput, out->size() * 2)));
  return true;
}

// Returns "" or what went wrong.
std::string DecompressZstd(std::string_view in_bytes, uint64_t uncompressed_size,
                           std::string* out) {
  std::unique_ptr<ZSTD_DCtx, size_t (*)(ZSTD_DCtx*)> dctx(ZSTD_createDCtx(), ZSTD_freeDCtx);
  if (!dctx) return "zstd: out of memory";
  const size_t limit = static_cast<size_t>(uncompressed_size + 1);
  out->resize(InitialOutput(uncompressed_size, in_bytes.size()));
  ZSTD_inBuffer in{in_bytes.data(), in_bytes.size(), 0};
  size_t produced = 0;
  for (;;) {
    if (produced == out->size() && !GrowOutput(out, limit)) break;
    ZSTD_outBuffer ob{&(*out)[0], out->size(), produced};
    const size_t before_in = in.pos;
    const size_t r = ZSTD_decompressStream(dctx.get(), &ob, &in);
    if (ZSTD_isError(r)) return std::string("zstd: ") + ZSTD_getErrorName(r);
    const bool progress = in.pos != before_in || ob.pos != produced;
    produced = ob.pos;
    if (r == 0 && in.pos == in.size) break;
    if (!progress) return "zstd: compressed data ends early";
  }
  out->resize(produced);
  return "";
}

std::string DecompressLz4(std::string_view in_bytes, uint64_t uncompressed_size,
                          std::string* out) {
  LZ4F_dctx* raw = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION))) return "lz4: no context";
  std::unique_ptr<LZ4F_dctx, LZ4F_errorCode_t (*)(LZ4F_dctx*)> dctx(
      raw, LZ4F_freeDecompressionContext);
  const size_t limit = static_cast<size_t>(uncompressed_size + 1);
  out->resize(InitialOutput(uncompressed_size, in_bytes.size()));
  size_t consumed = 0, produced = 0;
  for (;;) {
    if (produced == out->size() && !GrowOutput(out, limit)) break;
    size_t dst_size = out->size() - produced;
    size_t src_size = in_bytes.size() - consumed;
    const size_t r = LZ4F_decompress(dctx.get(), &(*out)[produced], &dst_size,
                                     in_bytes.data() + consumed, &src_size, nullptr);
    if (LZ4F_isError(r)) return std::string("lz4: ") + LZ4F_getErrorName(r);
    consumed += src_size;
    produced += dst_size;
    if (r == 0 && consumed == in_bytes.size()) break;
    if (src_size == 0 && dst_size == 0) return "lz4: compressed data ends early";
  }
  out->resize(produced);
  return "";
}

// ---------------------------------------------------------------------------
// Parsed records.
struct ChunkHeader {
  uint64_t start_time = 0, end_time = 0, uncompressed_size = 0;
  uint32_t uncompressed_crc = 0;
  std::string compression;
  std::string_view records;  // compressed bytes (a view into the record content)
};

struct ChunkIndex {
  uint64_t start_time = 0, end_time = 0, offset = 0, length = 0;
  std::vector<uint16_t> channels;  // from message_index_offsets (empty: unknown)
  std::string compression;
};

struct MessageView {
  uint16_t channel_id = 0;
  uint32_t sequence = 0;
  uint64_t log_time = 0, publish_time = 0;
  std::string_view data;
};

bool ParseMessage(std::string_view content, MessageView* m) {
  FieldReader r(content);
  m->channel_id = r.U16();
  m->sequence = r.U32();
  m->log_time = r.U64();
  m->publish_time = r.U64();
  m->data = r.Rest();
  return r.ok();
}

bool ParseSchema(std::string_view content, Schema* s) {
  FieldReader r(content);
  s->id = r.U16();
  s->name = std::string(r.String());
  s->encoding = std::string(r.String());
  s->data = std::string(r.String());
  return r.ok();
}

bool ParseChannel(std::string_view content, Channel* c) {
  FieldReader r(content);
  c->id = r.U16();
  c->schema_id = r.U16();
  c->topic = std::string(r.String());
  c->message_encoding = std::string(r.String());
  return r.StringMap(&c->metadata) && r.ok();
}

bool ParseChunkHeader(std::string_view content, ChunkHeader* c) {
  FieldReader r(content);
  c->start_time = r.U64();
  c->end_time = r.U64();
  c->uncompressed_size = r.U64();
  c->uncompressed_crc = r.U32();
  c->compression = std::string(r.String());
  c->records = r.Bytes(r.U64());
  return r.ok();
}

bool ParseChunkIndex(std::string_view content, ChunkIndex* c) {
  FieldReader r(content);
  c->start_time = r.U64();
  c->end_time = r.U64();
  c->offset = r.U64();
  c->length = r.U64();
  FieldReader offsets = r.Sub();
  while (offsets.ok() && offsets.remaining() > 0) {
    const uint16_t channel = offsets.U16();
    offsets.U64();
    if (offsets.ok()) c->channels.push_back(channel);
  }
  r.U64();  // message_index_length
  c->compression = std::string(r.String());
  return r.ok() && offsets.ok();
}

bool ParseStatistics(std::string_view content, FileSummary* s) {
  FieldReader r(content);
  s->message_count = r.U64();
  r.U16();  // schema_count
  r.U32();  // channel_count
  r.U32();  // attachment_count
  r.U32();  // metadata_count
  s->chunk_count = r.U32();
  s->message_start_time_ns = r.U64();
  s->message_end_time_ns = r.U64();
  FieldReader counts = r.Sub();
  while (counts.ok() && counts.remaining() > 0) {
    const uint16_t channel = counts.U16();
    const uint64_t count = counts.U64();
    if (counts.ok()) s->channel_message_counts[channel] = count;
  }
  return r.ok() && counts.ok();
}

// Calls visit(opcode, content, offset_in_records) for every record of a
// chunk's decompressed records; false when a record runs past the end.
bool ForEachRecord(std::string_view records,
                   const std::function<bool(uint8_t, std::string_view, size_t)>& visit) {
  FieldReader r(records);
  while (r.remaining() > 0) {
    const size_t at = r.position();
    const uint8_t opcode = r.U8();
    const std::string_view content = r.Bytes(r.U64());
    if (!r.ok()) return false;
    if (!visit(opcode, content, at)) return false;
  }
  return true;
}

// ---------------------------------------------------------------------------
// A stretch of the data section Next() reads as one sorted stream: a chunk,
// or a run of loose (unchunked) messages with non-decreasing log times.
struct Segment {
  bool is_chunk = false;
  uint64_t offset = 0;  // chunk record start / first record of the run
  uint64_t end = 0;     // one past the last byte
  uint64_t start_time = 0, end_time = 0;
  std::vector<uint16_t> channels;  // sorted; empty: unknown
};

// An opened segment: its messages one at a time. Cursors of finished
// segments are kept and reused, so the decompressed records and the message
// buffer keep their capacity from chunk to chunk (no fresh multi-megabyte
// allocation and page faults per chunk or per message).
struct Cursor {
  size_t segment = 0;   // index in file order (ties go to the lower one)
  Message current;
  // Chunk: decompressed records and the wanted messages sorted by log time.
  std::string records;
  std::vector<std::pair<uint64_t, size_t>> entries;  // (log_time, record offset)
  size_t next_entry = 0;
  // Loose run: the file position of the next record.
  uint64_t position = 0;

  // Ready for segment `index` at file offset `offset`; buffers keep their
  // capacity (records keeps its size too: Decompress overwrites it).
  void Reset(size_t index, uint64_t offset) {
    segment = index;
    entries.clear();
    next_entry = 0;
    position = offset;
  }
};

struct CursorAfter {
  bool operator()(const Cursor* a, const Cursor* b) const {
    if (a->current.log_time_ns != b->current.log_time_ns)
      return a->current.log_time_ns > b->current.log_time_ns;
    return a->segment > b->segment;
  }
};

class McapReader : public Reader {
 public:
  McapReader(std::string path, std::unique_ptr<ByteSource> source)
      : path_(std::move(path)), source_(std::move(source)) {}

  Status Init();

  const FileSummary& summary() const override { return summary_; }
  const std::map<uint16_t, Schema>& schemas() const override { return schemas_; }
  const std::map<uint16_t, Channel>& channels() const override { return channels_; }
  void SetChannelFilter(const std::vector<uint16_t>& channel_ids) override {
    filter_ = std::set<uint16_t>(channel_ids.begin(), channel_ids.end());
    filtering_ = true;
  }
  void SetTimeRange(uint64_t first_ns, uint64_t last_ns) override {
    time_first_ns_ = first_ns;
    time_last_ns_ = last_ns;
  }
  StatusOr<bool> Next(Message* out) override;
  std::vector<std::string> warnings() const override { return warnings_; }
  uint64_t chunks_loaded() const override { return chunks_loaded_; }

 private:
  Status Error(const std::string& what) const {
    return Status::InvalidInput("'" + path_ + "': " + what);
  }
  Status AtOffset(const char* record, uint64_t offset, const std::string& what) const {
    return Error(std::string(record) + " at offset " + std::to_string(offset) + ": " + what);
  }
  Status ReadBytes(uint64_t offset, uint64_t n, std::string* out);
  Status ReadHeader();
  // Footer + summary; sets *use_index when the chunk indexes can drive Next().
  Status ReadSummary(bool* use_index);
  Status ReadSummarySection(uint64_t start, uint64_t end, std::vector<ChunkIndex>* indexes);
  Status UseChunkIndexes(const std::vector<ChunkIndex>& indexes, uint64_t data_end);
  // State of the linear scan: counts, the running data-section CRC (from the
  // first byte of the file) and the open run of loose messages.
  struct ScanState {
    FileSummary counts;
    uint32_t crc = 0;
    Segment run;
    bool run_open = false;
    std::set<uint16_t> run_channels;
  };
  Status Scan(uint64_t data_end, bool fill_summary);
  Status ScanRecord(uint8_t opcode, uint64_t pos, uint64_t end, ScanState* state);
  void CloseRun(ScanState* state);
  void StopScan(const std::string& where);
  Status CheckDataEnd(uint64_t pos, uint64_t length, uint32_t computed);
  Status ScanChunk(uint64_t offset, std::string_view content, Segment* segment,
                   FileSummary* counts);
  void CountMessage(const MessageView& m, FileSummary* counts);
  Status Decompress(uint64_t offset, const ChunkHeader& chunk, std::string* records);

  bool Wanted(uint16_t channel) const { return !filtering_ || filter_.count(channel) > 0; }
  bool InTimeRange(uint64_t log_time_ns) const {
    return log_time_ns >= time_first_ns_ && log_time_ns <= time_last_ns_;
  }
  bool Wanted(uint16_t channel, uint64_t log_time_ns) const {
    return Wanted(channel) && InTimeRange(log_time_ns);
  }
  bool WantSegment(const Segment& s) const;
  Status OpenSegment(size_t index, std::unique_ptr<Cursor>* cursor);
  // Ends a finished cursor; keeps it for reuse.
  void Retire(Cursor* cursor);
  Status Advance(Cursor* cursor, bool* has_message);

  std::string path_;
  std::unique_ptr<ByteSource> source_;
  FileSummary summary_;
  std::map<uint16_t, Schema> schemas_;
  std::map<uint16_t, Channel> channels_;
  std::vector<std::string> warnings_;
  uint64_t data_start_ = 0;  // first record after the Header

  std::vector<Segment> segments_;    // file order
  std::vector<size_t> open_order_;   // by (start_time, file order)
  size_t next_to_open_ = 0;
  std::vector<std::unique_ptr<Cursor>> cursors_;  // owners of the heap entries
  std::vector<std::unique_ptr<Cursor>> spare_cursors_;  // finished, for reuse
  std::string chunk_bytes_;  // the chunk record being opened (reused)
  std::priority_queue<Cursor*, std::vector<Cursor*>, CursorAfter> heap_;
  std::set<uint16_t> filter_;
  bool filtering_ = false;
  uint64_t time_first_ns_ = 0, time_last_ns_ = UINT64_MAX;  // SetTimeRange
  uint64_t chunks_loaded_ = 0;
  Status error_;
};

Status McapReader::ReadBytes(uint64_t offset, uint64_t n, std::string* out) {
  if (offset > source_->size() || n > source_->size() - offset)
    return Error("read past the end of the file at offset " + std::to_string(offset));
  if (!source_->Read(offset, static_cast<size_t>(n), out))
    return Error("read error at offset " + std::to_string(offset) + ": " + std::strerror(errno));
  return Status::Ok();
}

Status McapReader::ReadHeader() {
  const uint64_t size = source_->size();
  std::string bytes;
  if (size < kMagicSize + kRecordHeaderSize)
    return Error("not an MCAP file (" + std::to_string(size) + " bytes, too short)");
  if (Status s = ReadBytes(0, kMagicSize + kRecordHeaderSize, &bytes); !s.ok()) return s;
  if (bytes.compare(0, kMagicSize, kMagic, kMagicSize) != 0)
    return Error("not an MCAP file (bad magic)");
  FieldReader r(std::string_view(bytes).substr(kMagicSize));
  const uint8_t opcode = r.U8();
  const uint64_t length = r.U64();
  if (opcode != detail::kHeader)
    return AtOffset("record", kMagicSize, "expected the Header record, found opcode " +
                                              std::to_string(opcode));
  const uint64_t content_at = kMagicSize + kRecordHeaderSize;
  if (length > size - content_at)
    return AtOffset("Header", kMagicSize, "record extends past the end of the file");
  std::string content;
  if (Status s = ReadBytes(content_at, length, &content); !s.ok()) return s;
  FieldReader h(content);
  summary_.profile = std::string(h.String());
  summary_.library = std::string(h.String());
  if (!h.ok()) return AtOffset("Header", kMagicSize, "malformed record");
  data_start_ = content_at + length;
  return Status::Ok();
}

Status McapReader::Init() {
  if (Status s = ReadHeader(); !s.ok()) return s;
  bool use_index = false;
  if (Status s = ReadSummary(&use_index); !s.ok()) return s;
  open_order_.resize(segments_.size());
  for (size_t i = 0; i < open_order_.size(); ++i) open_order_[i] = i;
  std::stable_sort(open_order_.begin(), open_order_.end(), [&](size_t a, size_t b) {
    return segments_[a].start_time < segments_[b].start_time;
  });
  return Status::Ok();
}

Status McapReader::ReadSummary(bool* use_index) {
  const uint64_t size = source_->size();
  const uint64_t tail = kFooterRecordSize + kMagicSize;
  bool has_footer = false;
  uint64_t summary_start = 0, summary_offset_start = 0, footer_at = 0;
  uint32_t summary_crc = 0;
  if (size >= data_start_ + tail) {
    std::string bytes;
    footer_at = size - tail;
    if (Status s = ReadBytes(footer_at, tail, &bytes); !s.ok()) return s;
    FieldReader r(bytes);
    const uint8_t opcode = r.U8();
    const uint64_t length = r.U64();
    summary_start = r.U64();
    summary_offset_start = r.U64();
    summary_crc = r.U32();
    has_footer = opcode == detail::kFooter && length == detail::kFooterContentSize &&
                 bytes.compare(kFooterRecordSize, kMagicSize, kMagic, kMagicSize) == 0;
  }
  if (!has_footer) {
    summary_.truncated = true;
    warnings_.push_back("'" + path_ +
                        "': no footer at the end: the file was cut short; read by a linear "
                        "scan of the data section");
    return Scan(size, true);
  }
  if (summary_start == 0) {
    warnings_.push_back("'" + path_ + "': no summary section: read by a linear scan");
    return Scan(footer_at, true);
  }
  if (summary_start < data_start_ || summary_start > footer_at ||
      (summary_offset_start != 0 &&
       (summary_offset_start < summary_start || summary_offset_start > footer_at)))
    return AtOffset("Footer", footer_at, "summary offsets outside the file");
  if (summary_crc != 0) {
    std::string bytes;
    // From the summary start up to and including Footer.summary_offset_start.
    if (Status s = ReadBytes(summary_start, footer_at + kRecordHeaderSize + 16 - summary_start,
                             &bytes);
        !s.ok())
      return s;
    const uint32_t computed = detail::Crc32(bytes);
    if (computed != summary_crc)
      return AtOffset("summary section", summary_start,
                      "CRC mismatch (stored " + Hex32(summary_crc) + ", computed " +
                          Hex32(computed) + ")");
  }
  std::vector<ChunkIndex> indexes;
  const uint64_t summary_end = summary_offset_start != 0 ? summary_offset_start : footer_at;
  if (Status s = ReadSummarySection(summary_start, summary_end, &indexes); !s.ok()) return s;
  summary_.has_summary = true;
  *use_index = !indexes.empty() && !channels_.empty();
  if (*use_index) return UseChunkIndexes(indexes, summary_start);
  // An unchunked file (or a summary without what Next() needs): scan the
  // data section, keeping the summary's statistics when it has them.
  return Scan(summary_start, false);
}

Status McapReader::ReadSummarySection(uint64_t start, uint64_t end,
                                      std::vector<ChunkIndex>* indexes) {
  std::string bytes;
  if (Status s = ReadBytes(start, end - start, &bytes); !s.ok()) return s;
  FieldReader r(bytes);
  bool have_statistics = false;
  while (r.remaining() > 0) {
    const uint64_t at = start + r.position();
    const uint8_t opcode = r.U8();
    const std::string_view content = r.Bytes(r.U64());
    if (!r.ok()) return AtOffset("summary record", at, "extends past the summary section");
    bool ok = true;
    if (opcode == detail::kSchema) {
      Schema schema;
      ok = ParseSchema(content, &schema);
      schemas_[schema.id] = std::move(schema);
    } else if (opcode == detail::kChannel) {
      Channel channel;
      ok = ParseChannel(content, &channel);
      channels_[channel.id] = std::move(channel);
    } else if (opcode == detail::kStatistics) {
      ok = ParseStatistics(content, &summary_);
      have_statistics = true;
    } else if (opcode == detail::kChunkIndex) {
      ChunkIndex index;
      ok = ParseChunkIndex(content, &index);
      indexes->push_back(std::move(index));
    }
    if (!ok) return AtOffset("summary record", at, "malformed (opcode " + std::to_string(opcode) + ")");
  }
  if (!have_statistics) summary_.chunk_count = indexes->size();
  return Status::Ok();
}

Status McapReader::UseChunkIndexes(const std::vector<ChunkIndex>& indexes, uint64_t data_end) {
  std::set<std::string> compressions;
  for (const ChunkIndex& index : indexes) {
    if (index.offset < data_start_ || index.offset > data_end ||
        index.length > data_end - index.offset || index.length < kRecordHeaderSize)
      return AtOffset("chunk index for the chunk", index.offset,
                      "chunk outside the data section");
    Segment segment;
    segment.is_chunk = true;
    segment.offset = index.offset;
    segment.end = index.offset + index.length;
    segment.start_time = index.start_time;
    segment.end_time = index.end_time;
    segment.channels = index.channels;
    std::sort(segment.channels.begin(), segment.channels.end());
    segments_.push_back(std::move(segment));
    compressions.insert(index.compression);
  }
  std::sort(segments_.begin(), segments_.end(),
            [](const Segment& a, const Segment& b) { return a.offset < b.offset; });
  summary_.compressions.assign(compressions.begin(), compressions.end());
  return Status::Ok();
}

void McapReader::CountMessage(const MessageView& m, FileSummary* counts) {
  if (counts->message_count == 0 || m.log_time < counts->message_start_time_ns)
    counts->message_start_time_ns = m.log_time;
  if (counts->message_count == 0 || m.log_time > counts->message_end_time_ns)
    counts->message_end_time_ns = m.log_time;
  ++counts->message_count;
  ++counts->channel_message_counts[m.channel_id];
}

Status McapReader::Decompress(uint64_t offset, const ChunkHeader& chunk, std::string* records) {
  std::string problem;
  if (chunk.compression.empty()) {
    if (chunk.records.size() != chunk.uncompressed_size)
      problem = "uncompressed chunk of " + std::to_string(chunk.records.size()) +
                " bytes, header says " + std::to_string(chunk.uncompressed_size);
    else
      records->assign(chunk.records.data(), chunk.records.size());
  } else if (chunk.compression == "zstd") {
    problem = DecompressZstd(chunk.records, chunk.uncompressed_size, records);
  } else if (chunk.compression == "lz4") {
    problem = DecompressLz4(chunk.records, chunk.uncompressed_size, records);
  } else {
    return Error("chunk at offset " + std::to_string(offset) + " uses unknown compression '" +
                 Printable(chunk.compression) + "'");
  }
  if (problem.empty() && records->size() != chunk.uncompressed_size)
    problem = "decompressed size differs from the uncompressed_size " +
              std::to_string(chunk.uncompressed_size) + " of the record";
  if (!problem.empty()) return AtOffset("chunk", offset, problem);
  if (chunk.uncompressed_crc != 0) {
    const uint32_t computed = detail::Crc32(*records);
    if (computed != chunk.uncompressed_crc)
      return AtOffset("chunk", offset,
                      "CRC mismatch (stored " + Hex32(chunk.uncompressed_crc) + ", computed " +
                          Hex32(computed) + ")");
  }
  return Status::Ok();
}

// One chunk met by the linear scan: decompressed and checked once, its
// schemas/channels taken, its messages counted.
Status McapReader::ScanChunk(uint64_t offset, std::string_view content, Segment* segment,
                             FileSummary* counts) {
  ChunkHeader chunk;
  if (!ParseChunkHeader(content, &chunk)) return AtOffset("chunk", offset, "malformed record");
  std::string records;
  if (Status s = Decompress(offset, chunk, &records); !s.ok()) return s;
  std::set<uint16_t> channels;
  bool any = false, malformed = false;
  const bool complete = ForEachRecord(records, [&](uint8_t opcode, std::string_view c, size_t) {
    if (opcode == detail::kMessage) {
      MessageView m;
      if (!ParseMessage(c, &m)) return !(malformed = true);
      CountMessage(m, counts);
      channels.insert(m.channel_id);
      segment->start_time = any ? std::min(segment->start_time, m.log_time) : m.log_time;
      segment->end_time = any ? std::max(segment->end_time, m.log_time) : m.log_time;
      any = true;
    } else if (opcode == detail::kSchema) {
      Schema schema;
      if (!ParseSchema(c, &schema)) return !(malformed = true);
      schemas_.emplace(schema.id, std::move(schema));
    } else if (opcode == detail::kChannel) {
      Channel channel;
      if (!ParseChannel(c, &channel)) return !(malformed = true);
      channels_.emplace(channel.id, std::move(channel));
    }
    return true;
  });
  if (!complete || malformed) return AtOffset("chunk", offset, "malformed record inside");
  segment->channels.assign(channels.begin(), channels.end());  // empty: no messages
  if (std::find(summary_.compressions.begin(), summary_.compressions.end(), chunk.compression) ==
      summary_.compressions.end())
    summary_.compressions.push_back(chunk.compression);
  ++counts->chunk_count;
  return Status::Ok();
}

constexpr uint64_t kCrcBlock = 1 << 20;

// Reads the data section record by record from data_start_ up to data_end
// (exclusive), stopping early at DataEnd or at a record that does not fit.
Status McapReader::Scan(uint64_t data_end, bool fill_summary) {
  ScanState state;
  std::string record;
  if (Status s = ReadBytes(0, data_start_, &record); !s.ok()) return s;
  state.crc = detail::Crc32(record);
  uint64_t pos = data_start_;
  while (pos < data_end) {
    if (data_end - pos < kRecordHeaderSize) {
      StopScan("incomplete record header at offset " + std::to_string(pos));
      break;
    }
    if (Status s = ReadBytes(pos, kRecordHeaderSize, &record); !s.ok()) return s;
    FieldReader h(record);
    const uint8_t opcode = h.U8();
    const uint64_t length = h.U64();
    if (length > data_end - pos - kRecordHeaderSize) {
      StopScan("record at offset " + std::to_string(pos) + " (opcode " + std::to_string(opcode) +
               ") extends past the end of the data");
      break;
    }
    if (opcode == detail::kDataEnd) {
      if (Status s = CheckDataEnd(pos, length, state.crc); !s.ok()) return s;
      break;
    }
    if (opcode == detail::kFooter) break;
    if (Status s = ScanRecord(opcode, pos, pos + kRecordHeaderSize + length, &state); !s.ok())
      return s;
    pos += kRecordHeaderSize + length;
  }
  CloseRun(&state);
  if (fill_summary || summary_.message_count == 0) {
    const FileSummary& counts = state.counts;
    summary_.message_count = counts.message_count;
    summary_.message_start_time_ns = counts.message_start_time_ns;
    summary_.message_end_time_ns = counts.message_end_time_ns;
    summary_.channel_message_counts = counts.channel_message_counts;
    summary_.chunk_count = counts.chunk_count;
  }
  return Status::Ok();
}

void McapReader::StopScan(const std::string& where) {
  summary_.truncated = true;
  warnings_.push_back("'" + path_ + "': " + where + ": the rest of the file is ignored");
}

Status McapReader::CheckDataEnd(uint64_t pos, uint64_t length, uint32_t computed) {
  std::string content;
  if (Status s = ReadBytes(pos + kRecordHeaderSize, length, &content); !s.ok()) return s;
  FieldReader r(content);
  const uint32_t stored = r.U32();
  if (r.ok() && stored != 0 && stored != computed)
    return AtOffset("DataEnd", pos,
                    "data section CRC mismatch (stored " + Hex32(stored) + ", computed " +
                        Hex32(computed) + ")");
  return Status::Ok();
}

void McapReader::CloseRun(ScanState* state) {
  if (!state->run_open) return;
  state->run.channels.assign(state->run_channels.begin(), state->run_channels.end());
  segments_.push_back(state->run);
  state->run_open = false;
  state->run_channels.clear();
}

// One complete record [pos, end) of the data section met by the scan.
Status McapReader::ScanRecord(uint8_t opcode, uint64_t pos, uint64_t end, ScanState* state) {
  std::string bytes;
  const bool needed = opcode == detail::kMessage || opcode == detail::kChunk ||
                      opcode == detail::kSchema || opcode == detail::kChannel;
  if (!needed) {  // attachments, indexes, ...: only their CRC, in blocks
    for (uint64_t at = pos; at < end; at += kCrcBlock) {
      if (Status s = ReadBytes(at, std::min<uint64_t>(kCrcBlock, end - at), &bytes); !s.ok())
        return s;
      state->crc = detail::Crc32Update(state->crc, bytes.data(), bytes.size());
    }
    return Status::Ok();
  }
  if (Status s = ReadBytes(pos, end - pos, &bytes); !s.ok()) return s;
  state->crc = detail::Crc32Update(state->crc, bytes.data(), bytes.size());
  const std::string_view content = std::string_view(bytes).substr(kRecordHeaderSize);
  if (opcode == detail::kMessage) {
    MessageView m;
    if (!ParseMessage(content, &m)) return AtOffset("message", pos, "malformed record");
    CountMessage(m, &state->counts);
    if (state->run_open && m.log_time < state->run.end_time) CloseRun(state);
    if (!state->run_open) {
      state->run = Segment();
      state->run.offset = pos;
      state->run.start_time = m.log_time;
      state->run_open = true;
    }
    state->run.end = end;
    state->run.end_time = m.log_time;
    state->run_channels.insert(m.channel_id);
  } else if (opcode == detail::kChunk) {
    CloseRun(state);
    Segment segment;
    segment.is_chunk = true;
    segment.offset = pos;
    segment.end = end;
    if (Status s = ScanChunk(pos, content, &segment, &state->counts); !s.ok()) return s;
    if (!segment.channels.empty()) segments_.push_back(std::move(segment));  // has messages
  } else if (opcode == detail::kSchema) {
    Schema schema;
    if (!ParseSchema(content, &schema)) return AtOffset("schema", pos, "malformed record");
    schemas_.emplace(schema.id, std::move(schema));
  } else {
    Channel channel;
    if (!ParseChannel(content, &channel)) return AtOffset("channel", pos, "malformed record");
    channels_.emplace(channel.id, std::move(channel));
  }
  return Status::Ok();
}

bool McapReader::WantSegment(const Segment& s) const {
  // A segment's span is its messages' log times (start <= end when it holds any).
  if (s.start_time <= s.end_time && (s.end_time < time_first_ns_ || s.start_time > time_last_ns_))
    return false;
  if (!filtering_ || s.channels.empty()) return true;
  for (uint16_t channel : s.channels)
    if (filter_.count(channel) > 0) return true;
  return false;
}

Status McapReader::OpenSegment(size_t index, std::unique_ptr<Cursor>* cursor) {
  const Segment& segment = segments_[index];
  if (spare_cursors_.empty()) {
    *cursor = std::make_unique<Cursor>();
  } else {
    *cursor = std::move(spare_cursors_.back());
    spare_cursors_.pop_back();
  }
  Cursor& c = **cursor;
  c.Reset(index, segment.offset);
  if (!segment.is_chunk) return Status::Ok();
  if (Status s = ReadBytes(segment.offset, segment.end - segment.offset, &chunk_bytes_); !s.ok())
    return s;
  FieldReader h(chunk_bytes_);
  const uint8_t opcode = h.U8();
  const std::string_view content = h.Bytes(h.U64());
  if (!h.ok() || opcode != detail::kChunk)
    return AtOffset("chunk", segment.offset, "no chunk record where the chunk index points");
  ChunkHeader chunk;
  if (!ParseChunkHeader(content, &chunk))
    return AtOffset("chunk", segment.offset, "malformed record");
  if (Status s = Decompress(segment.offset, chunk, &c.records); !s.ok()) return s;
  ++chunks_loaded_;
  bool malformed = false;
  const bool complete = ForEachRecord(c.records, [&](uint8_t op, std::string_view rc, size_t at) {
    if (op != detail::kMessage) return true;
    MessageView m;
    if (!ParseMessage(rc, &m)) return !(malformed = true);
    if (Wanted(m.channel_id, m.log_time)) c.entries.emplace_back(m.log_time, at);
    return true;
  });
  if (!complete || malformed)
    return AtOffset("chunk", segment.offset, "malformed record inside");
  std::stable_sort(c.entries.begin(), c.entries.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  return Status::Ok();
}

void CopyMessage(const MessageView& m, Message* out) {
  out->channel_id = m.channel_id;
  out->sequence = m.sequence;
  out->log_time_ns = m.log_time;
  out->publish_time_ns = m.publish_time;
  out->data.assign(m.data.begin(), m.data.end());
}

Status McapReader::Advance(Cursor* c, bool* has_message) {
  *has_message = false;
  const Segment& segment = segments_[c->segment];
  if (segment.is_chunk) {
    if (c->next_entry >= c->entries.size()) return Status::Ok();
    FieldReader r(std::string_view(c->records).substr(c->entries[c->next_entry++].second));
    r.U8();
    MessageView m;
    ParseMessage(r.Bytes(r.U64()), &m);  // parsed before, when the chunk was opened
    CopyMessage(m, &c->current);
    *has_message = true;
    return Status::Ok();
  }
  std::string bytes;
  while (c->position < segment.end) {
    if (Status s = ReadBytes(c->position, kRecordHeaderSize, &bytes); !s.ok()) return s;
    FieldReader h(bytes);
    const uint8_t opcode = h.U8();
    const uint64_t length = h.U64();
    const uint64_t at = c->position;
    c->position += kRecordHeaderSize + length;  // the scan checked the bounds
    if (opcode != detail::kMessage) continue;
    if (Status s = ReadBytes(at + kRecordHeaderSize, length, &bytes); !s.ok()) return s;
    MessageView m;
    if (!ParseMessage(bytes, &m)) return AtOffset("message", at, "malformed record");
    if (!Wanted(m.channel_id, m.log_time)) continue;
    CopyMessage(m, &c->current);
    *has_message = true;
    return Status::Ok();
  }
  return Status::Ok();
}

void McapReader::Retire(Cursor* cursor) {
  const auto it = std::find_if(cursors_.begin(), cursors_.end(),
                               [&](const auto& p) { return p.get() == cursor; });
  spare_cursors_.push_back(std::move(*it));
  cursors_.erase(it);
}

StatusOr<bool> McapReader::Next(Message* out) {
  if (!error_.ok()) return error_;
  for (;;) {
    // Open every segment that may hold a message before the earliest open one.
    while (next_to_open_ < open_order_.size()) {
      const size_t index = open_order_[next_to_open_];
      if (!heap_.empty() && segments_[index].start_time > heap_.top()->current.log_time_ns) break;
      ++next_to_open_;
      if (!WantSegment(segments_[index])) continue;
      std::unique_ptr<Cursor> cursor;
      bool has_message = false;
      error_ = OpenSegment(index, &cursor);
      if (error_.ok()) error_ = Advance(cursor.get(), &has_message);
      if (!error_.ok()) return error_;
      if (!has_message) {
        spare_cursors_.push_back(std::move(cursor));
        continue;
      }
      heap_.push(cursor.get());
      cursors_.push_back(std::move(cursor));
    }
    if (heap_.empty()) return false;
    Cursor* top = heap_.top();
    heap_.pop();
    const bool wanted = Wanted(top->current.channel_id, top->current.log_time_ns);
    // Swapped, not moved: the cursor gets the caller's previous buffer to
    // copy its next message into.
    if (wanted) std::swap(*out, top->current);
    bool has_message = false;
    error_ = Advance(top, &has_message);
    if (!error_.ok()) return error_;
    if (has_message) {
      heap_.push(top);
    } else {
      Retire(top);
    }
    if (wanted) return true;
  }
}

StatusOr<std::unique_ptr<Reader>> OpenSource(const std::string& name,
                                             std::unique_ptr<ByteSource> source) {
  auto reader = std::make_unique<McapReader>(name, std::move(source));
  if (Status s = reader->Init(); !s.ok()) return s;
  return std::unique_ptr<Reader>(std::move(reader));
}

}  // namespace

StatusOr<std::unique_ptr<Reader>> Reader::Open(const std::string& path) {
  auto source = std::make_unique<FileSource>();
  if (Status s = source->Open(path); !s.ok()) return s;
  return OpenSource(path, std::move(source));
}

StatusOr<std::unique_ptr<Reader>> Reader::OpenBuffer(std::string bytes, const std::string& name) {
  return OpenSource(name, std::make_unique<BufferSource>(std::move(bytes)));
}

}  // namespace rvlio::mcap
