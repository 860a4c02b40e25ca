#pragma once
// Atomic file output (docs/design.md "The command-line contract": "outputs are written
// atomically"). Content goes to `<path>.tmp.<pid>`, is fsync'ed and then renamed over
// `<path>`, so a reader sees either the old file or the complete new one, never
// a half-written file. On any failure the temporary file is removed and an
// InvalidInput status names the path and the system error text.
#include <cstdint>
#include <string>
#include <string_view>

#include "rvlio/common/status.h"

namespace rvlio {

// The temporary file of `path` while this process writes it (for a signal
// handler that removes it on an abort).
std::string AtomicTempPath(const std::string& path);

// Writes `content` to `path` atomically.
Status WriteFileAtomically(const std::string& path, const std::string& content);

// Streaming variant for large outputs:
//
//   AtomicFileWriter w;
//   Status s = w.Open(path);
//   ... s = w.Append(chunk); ...
//   s = w.Commit();            // fsync + rename; the file appears now
//
// Destroying an opened writer without a successful Commit() discards the
// temporary file (the target is left untouched). After a failed Append() the
// writer is discarded and every further call returns that failure.
class AtomicFileWriter {
 public:
  AtomicFileWriter() = default;
  ~AtomicFileWriter();
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
  AtomicFileWriter(AtomicFileWriter&& other) noexcept;
  AtomicFileWriter& operator=(AtomicFileWriter&& other) noexcept;

  Status Open(const std::string& path);
  Status Append(std::string_view data);
  // Replaces bytes already appended, from `offset` on (a header whose counts
  // are known only at the end: formats/las_writer.h). offset + size must not
  // pass the bytes appended so far.
  Status WriteAt(uint64_t offset, std::string_view data);
  Status Commit();
  // Removes the temporary file; the target is untouched. Safe to call twice.
  void Discard();

  bool is_open() const { return fd_ >= 0; }
  const std::string& path() const { return path_; }
  const std::string& temp_path() const { return temp_path_; }

 private:
  Status Flush();
  Status FailAndDiscard(const std::string& what, int err);

  int fd_ = -1;
  std::string path_;
  std::string temp_path_;
  std::string buffer_;  // pending bytes, flushed in large blocks
  uint64_t size_ = 0;   // bytes appended (written and pending)
  Status error_;        // sticky failure after Append()
};

}  // namespace rvlio
