#pragma once
// Private (src/formats only): the ROS1 serialization (little endian, no padding,
// uint32 length before strings and variable arrays, fixed arrays bare),
// read and written without the ROS message classes, so that a message is
// parsed in place from the bytes the bag library returns.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace rvlio::bag_detail {

inline bool BigEndianHost() {
  const uint16_t one = 1;
  uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  return first == 0;
}

// Sequential reader over one message's bytes; every read checks the bounds
// and returns false when the bytes run out.
class Ros1WireReader {
 public:
  Ros1WireReader(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  template <typename T>
  bool Read(T* value) {
    if (size_ - pos_ < sizeof(T)) return false;
    uint8_t bytes[sizeof(T)];
    std::memcpy(bytes, data_ + pos_, sizeof(T));
    if (BigEndianHost()) std::reverse(bytes, bytes + sizeof(T));
    std::memcpy(value, bytes, sizeof(T));
    pos_ += sizeof(T);
    return true;
  }
  bool ReadString(std::string* s) {
    const uint8_t* bytes = nullptr;
    size_t n = 0;
    if (!ReadBytes(&bytes, &n)) return false;
    s->assign(reinterpret_cast<const char*>(bytes), n);
    return true;
  }
  // A uint8[] (or string) as a view into the message bytes.
  bool ReadBytes(const uint8_t** bytes, size_t* n) {
    uint32_t count = 0;
    if (!Read(&count) || size_ - pos_ < count) return false;
    *bytes = data_ + pos_;
    *n = count;
    pos_ += count;
    return true;
  }
  // std_msgs/Header: seq, stamp (sec, nsec), frame_id.
  bool ReadHeader(int64_t* stamp_ns, std::string* frame_id) {
    uint32_t seq = 0, sec = 0, nsec = 0;
    if (!Read(&seq) || !Read(&sec) || !Read(&nsec) || !ReadString(frame_id)) return false;
    *stamp_ns = static_cast<int64_t>(sec) * 1000000000 + nsec;
    return true;
  }
  size_t remaining() const { return size_ - pos_; }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

class Ros1WireWriter {
 public:
  template <typename T>
  void Write(T value) {
    uint8_t bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    if (BigEndianHost()) std::reverse(bytes, bytes + sizeof(T));
    out_.insert(out_.end(), bytes, bytes + sizeof(T));
  }
  void WriteString(const std::string& s) {
    Write(static_cast<uint32_t>(s.size()));
    out_.insert(out_.end(), s.begin(), s.end());
  }
  std::vector<uint8_t> Take() { return std::move(out_); }
  void Reserve(size_t n) { out_.reserve(n); }

 private:
  std::vector<uint8_t> out_;
};

}  // namespace rvlio::bag_detail
