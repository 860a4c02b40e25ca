#pragma once
// MCAP record layout shared by mcap_reader.cpp and mcap_writer.cpp (written
// from the public specification, https://mcap.dev/spec, format version 0):
// opcodes, the magic, CRC-32 and little-endian field encoding/decoding.
//
// A record is opcode (uint8) + content length (uint64) + content. Content
// fields are little-endian integers; String = uint32 byte length + bytes;
// Bytes = uint32 (or uint64 for chunk records / attachment data) length +
// bytes; Map and Array = uint32 byte length + entries.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <string_view>

#include <libdeflate.h>

namespace rvlio::mcap::detail {

inline constexpr char kMagic[8] = {'\x89', 'M', 'C', 'A', 'P', '0', '\r', '\n'};
inline constexpr size_t kMagicSize = sizeof(kMagic);
inline constexpr size_t kRecordHeaderSize = 9;  // opcode + uint64 length
inline constexpr size_t kFooterContentSize = 20;
inline constexpr size_t kFooterRecordSize = kRecordHeaderSize + kFooterContentSize;

enum Opcode : uint8_t {
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

// Message content bytes before the payload: channel_id, sequence, log_time,
// publish_time.
inline constexpr size_t kMessagePrefixSize = 2 + 4 + 8 + 8;

// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320, the zlib CRC), as
// the specification requires. Crc32Update(0, ...) starts a new CRC; feeding
// a buffer in pieces gives the same value as feeding it at once. Computed by
// libdeflate (Debian libdeflate-dev), which uses carry-less multiplication
// (PCLMUL/VPCLMUL) where the CPU has it: 32 MiB in 3-4.5 ms here, against
// 9 ms for zlib's crc32 and about 30 ms for a slicing-by-8 table
// (bench_decode BM_Crc32; docs/input_formats.md "Reading cost").
inline uint32_t Crc32Update(uint32_t crc, const void* data, size_t size) {
  return libdeflate_crc32(crc, data, size);
}
inline uint32_t Crc32(std::string_view bytes) { return Crc32Update(0, bytes.data(), bytes.size()); }

// Appends little-endian fields to a byte string.
class FieldWriter {
 public:
  explicit FieldWriter(std::string* out) : out_(out) {}
  void U8(uint8_t v) { out_->push_back(static_cast<char>(v)); }
  void U16(uint16_t v) { Le(v, 2); }
  void U32(uint32_t v) { Le(v, 4); }
  void U64(uint64_t v) { Le(v, 8); }
  void String(std::string_view s) {
    U32(static_cast<uint32_t>(s.size()));
    out_->append(s.data(), s.size());
  }
  void Raw(std::string_view s) { out_->append(s.data(), s.size()); }
  void StringMap(const std::map<std::string, std::string>& m) {
    std::string body;
    FieldWriter w(&body);
    for (const auto& [key, value] : m) {
      w.String(key);
      w.String(value);
    }
    String(body);
  }

 private:
  void Le(uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) out_->push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
  }
  std::string* out_;
};

// Appends a whole record (opcode, length, content) to `out`.
inline void AppendRecord(std::string* out, Opcode opcode, std::string_view content) {
  FieldWriter w(out);
  w.U8(opcode);
  w.U64(content.size());
  w.Raw(content);
}

// Reads little-endian fields from a byte range. Every read checks the
// remaining bytes first; after a failed read ok() is false and every later
// read fails too (values read as zero / empty), so a parser may read all its
// fields and check ok() once.
class FieldReader {
 public:
  FieldReader(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  explicit FieldReader(std::string_view s)
      : data_(reinterpret_cast<const uint8_t*>(s.data())), size_(s.size()) {}

  bool ok() const { return ok_; }
  size_t remaining() const { return ok_ ? size_ - pos_ : 0; }
  size_t position() const { return pos_; }

  uint8_t U8() { return static_cast<uint8_t>(Le(1)); }
  uint16_t U16() { return static_cast<uint16_t>(Le(2)); }
  uint32_t U32() { return static_cast<uint32_t>(Le(4)); }
  uint64_t U64() { return Le(8); }
  // `size` raw bytes (a view into the input).
  std::string_view Bytes(uint64_t size) {
    if (!Need(size)) return {};
    std::string_view v(reinterpret_cast<const char*>(data_ + pos_), static_cast<size_t>(size));
    pos_ += static_cast<size_t>(size);
    return v;
  }
  std::string_view String() { return Bytes(U32()); }
  std::string_view Rest() { return Bytes(remaining()); }
  // The byte range of a uint32-length-prefixed Map or Array.
  FieldReader Sub() {
    const std::string_view body = String();
    FieldReader sub(reinterpret_cast<const uint8_t*>(body.data()), body.size());
    sub.ok_ = ok_;
    return sub;
  }
  bool StringMap(std::map<std::string, std::string>* out) {
    FieldReader sub = Sub();
    while (sub.ok() && sub.remaining() > 0) {
      const std::string_view key = sub.String();
      const std::string_view value = sub.String();
      if (sub.ok()) (*out)[std::string(key)] = std::string(value);
    }
    return ok_ && sub.ok();
  }

 private:
  bool Need(uint64_t n) {
    if (!ok_ || n > size_ - pos_) ok_ = false;
    return ok_;
  }
  uint64_t Le(int bytes) {
    if (!Need(static_cast<uint64_t>(bytes))) return 0;
    uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v |= static_cast<uint64_t>(data_[pos_ + i]) << (8 * i);
    pos_ += static_cast<size_t>(bytes);
    return v;
  }

  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  bool ok_ = true;
};

}  // namespace rvlio::mcap::detail
