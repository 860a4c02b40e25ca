#pragma once
// Atomic file output (docs/design.md "The command-line contract": "outputs are written
// atomically"). Content goes to `<target>.tmp.<pid>`, is fsync'ed and then renamed over
// `<target>` (the path, or the final target of a link: ResolveOutputFile), so a reader sees either the old file or the complete new one, never
// a half-written file. On any failure the temporary file is removed and an
// InvalidInput status names the path and the system error text.
#include <cstdint>
#include <string>
#include <string_view>

#include "rvlio/common/status.h"

namespace rvlio {

// What an output path may name (docs/outputs.md "What an output path may
// be"), for every file any command writes: a new path in an existing folder,
// or a regular file, which is replaced. A symbolic link is followed (a chain
// of links too) and its final target is written in the target's own folder;
// the link itself stays. A dangling link makes its target a new file.
// Anything else is refused before a byte is written: a folder, a character or
// block device, a FIFO, a socket, a link loop (InvalidInput, one line naming
// `path` and what it is). Returns the path to write: `path` itself or the
// link's final target.
StatusOr<std::string> ResolveOutputFile(const std::string& path);

// "a FIFO", "a folder", ... : what the file at `path` is, "" when it does not
// exist or is a regular file (lstat: a link is "a symbolic link").
std::string SpecialFileKind(const std::string& path);

// The temporary file of `path` (of its link's final target) while this
// process writes it (for a signal handler that removes it on an abort).
std::string AtomicTempPath(const std::string& path);

// Writes `content` to `path` atomically.
Status WriteFileAtomically(const std::string& path, const std::string& content);

// Streaming variant for large outputs (its target: ResolveOutputFile(path)):
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
  const std::string& path() const { return path_; }        // as the caller named it
  const std::string& target() const { return target_; }    // the file replaced
  const std::string& temp_path() const { return temp_path_; }

 private:
  Status Flush();
  Status FailAndDiscard(const std::string& what, int err);

  int fd_ = -1;
  std::string path_;
  std::string target_;
  std::string temp_path_;
  std::string buffer_;  // pending bytes, flushed in large blocks
  uint64_t size_ = 0;   // bytes appended (written and pending)
  Status error_;        // sticky failure after Append()
};

}  // namespace rvlio
