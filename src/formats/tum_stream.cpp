#include "rvlio/formats/tum_stream.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "rvlio/formats/atomic_file.h"
#include "rvlio/formats/trajectory_io.h"

namespace rvlio {

TumStream::~TumStream() {
  if (fd_ >= 0) ::close(fd_);
}

Status TumStream::Open(const std::string& path, double sync_period_s) {
  sync_period_s_ = sync_period_s;
  StatusOr<std::string> target = ResolveOutputFile(path);  // never a FIFO or a device
  if (!target.ok()) return error_ = target.status();
  path_ = *target;
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) return Fail("cannot create", errno);
  last_sync_ = Clock::now();
  return WriteLine(kTumColumnsComment);  // as WriteTum: the file is a prefix of its output
}

Status TumStream::Fail(const std::string& what, int err) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  error_ = Status::InvalidInput(what + " '" + path_ + "': " + std::strerror(err));
  return error_;
}

Status TumStream::Append(const StampedPose& pose) {
  if (fd_ < 0) return error_;
  if (Status s = WriteLine(FormatTumLine(pose)); !s.ok()) return s;
  return SyncIfDue();
}

Status TumStream::WriteLine(const std::string& line) {
  ssize_t n;
  do {
    n = ::write(fd_, line.data(), line.size());  // one call: whole lines only
  } while (n < 0 && errno == EINTR);
  if (n < 0) return Fail("cannot write", errno);
  if (static_cast<size_t>(n) != line.size()) return Fail("cannot write", ENOSPC);
  dirty_ = true;
  return Status::Ok();
}

Status TumStream::SyncIfDue() {
  if (fd_ < 0) return error_;
  if (!dirty_) return Status::Ok();
  const Clock::time_point now = Clock::now();
  if (std::chrono::duration<double>(now - last_sync_).count() < sync_period_s_)
    return Status::Ok();
  if (::fdatasync(fd_) != 0) return Fail("cannot sync", errno);
  dirty_ = false;
  last_sync_ = now;
  return Status::Ok();
}

void TumStream::Remove() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!path_.empty()) ::unlink(path_.c_str());
}

}  // namespace rvlio
