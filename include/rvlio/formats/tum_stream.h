#pragma once
// A TUM trajectory written pose by pose while a run goes on
// (`trajectory.partial.tum`), so that a killed process or a power cut loses at
// most the last second of poses. Each line (FormatTumLine) goes to the file
// with one write(2), so the file always holds whole lines: what a killed run
// leaves is a valid TUM file, the prefix of the trajectory the complete run
// writes (WriteTum, which starts with the same column comment line). The data
// is synced to disk (fdatasync) when at least `sync_period_s` passed since
// the last sync, checked in Append() and in SyncIfDue(); no sync per pose.
#include <chrono>
#include <string>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"

namespace rvlio {

class TumStream {
 public:
  TumStream() = default;
  ~TumStream();  // closes the file and keeps it
  TumStream(const TumStream&) = delete;
  TumStream& operator=(const TumStream&) = delete;

  // Creates (truncates) `path`, or the final target of a link
  // (ResolveOutputFile; a FIFO, device or folder is refused). InvalidInput
  // naming the path if that fails.
  Status Open(const std::string& path, double sync_period_s = 1.0);
  // Appends one pose line. On a write error the stream closes and every
  // later call is a no-op returning that error.
  Status Append(const StampedPose& pose);
  // Syncs the appended lines if the sync period has passed since the last sync.
  Status SyncIfDue();
  // Closes and deletes the file (the complete outputs replace it).
  void Remove();

  bool is_open() const { return fd_ >= 0; }
  const std::string& path() const { return path_; }

 private:
  Status Fail(const std::string& what, int err);
  Status WriteLine(const std::string& line);  // one write(2)

  using Clock = std::chrono::steady_clock;
  int fd_ = -1;
  std::string path_;
  double sync_period_s_ = 1.0;
  bool dirty_ = false;
  Clock::time_point last_sync_;
  Status error_;
};

}  // namespace rvlio
