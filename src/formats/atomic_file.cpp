#include "rvlio/formats/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <utility>

namespace rvlio {
namespace {

constexpr size_t kFlushBytes = 1 << 20;  // write in blocks of 1 MiB
constexpr int kMaxLinkHops = 40;         // as the kernel's own limit (ELOOP)

std::string ErrnoText(int err) { return std::strerror(err); }

// Writes all of [data, data + size) to fd, retrying on EINTR and short writes.
// Returns 0 or the errno of the failure.
int WriteAll(int fd, const char* data, size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    if (n == 0) return EIO;
    data += n;
    size -= static_cast<size_t>(n);
  }
  return 0;
}

std::string ParentDirectory(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

// Makes the rename durable. Best effort: some file systems refuse fsync on a
// directory, which does not make the file itself incomplete.
void SyncDirectory(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  (void)::fsync(fd);
  ::close(fd);
}

const char* KindOf(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISLNK(mode)) return "a symbolic link";
  return "not a regular file";
}

Status Refuse(const std::string& path, const std::string& target, const std::string& why) {
  const std::string via = target == path ? "" : " (through the link to '" + target + "')";
  return Status::InvalidInput("cannot write '" + path + "'" + via + ": " + why +
                              "; an output must be a regular file or a new path");
}

}  // namespace

std::string SpecialFileKind(const std::string& path) {
  struct stat st;
  if (::lstat(path.c_str(), &st) != 0 || S_ISREG(st.st_mode)) return "";
  return KindOf(st.st_mode);
}

StatusOr<std::string> ResolveOutputFile(const std::string& path) {
  std::string target = path;
  for (int hops = 0;; ++hops) {
    struct stat st;
    if (::lstat(target.c_str(), &st) != 0) {
      if (errno == ENOENT) return target;  // a new file; open() reports a missing folder
      return Refuse(path, target, ErrnoText(errno));
    }
    if (S_ISREG(st.st_mode)) return target;
    if (!S_ISLNK(st.st_mode)) return Refuse(path, target, std::string("it is ") + KindOf(st.st_mode));
    if (hops == kMaxLinkHops) return Refuse(path, target, "too many levels of symbolic links");
    char link[PATH_MAX];
    const ssize_t n = ::readlink(target.c_str(), link, sizeof(link));
    if (n < 0 || static_cast<size_t>(n) >= sizeof(link))
      return Refuse(path, target, n < 0 ? ErrnoText(errno) : "link target too long");
    const std::string next(link, static_cast<size_t>(n));
    const bool here = next[0] == '/' || target.find('/') == std::string::npos;
    target = here ? next : ParentDirectory(target) + "/" + next;
  }
}

std::string AtomicTempPath(const std::string& path) {
  StatusOr<std::string> target = ResolveOutputFile(path);
  return (target.ok() ? *target : path) + ".tmp." + std::to_string(::getpid());
}

Status WriteFileAtomically(const std::string& path, const std::string& content) {
  AtomicFileWriter writer;
  Status s = writer.Open(path);
  if (s.ok()) s = writer.Append(content);
  if (s.ok()) s = writer.Commit();
  return s;
}

AtomicFileWriter::~AtomicFileWriter() { Discard(); }

AtomicFileWriter::AtomicFileWriter(AtomicFileWriter&& other) noexcept { *this = std::move(other); }

AtomicFileWriter& AtomicFileWriter::operator=(AtomicFileWriter&& other) noexcept {
  if (this != &other) {
    Discard();
    fd_ = std::exchange(other.fd_, -1);
    path_ = std::move(other.path_);
    target_ = std::move(other.target_);
    temp_path_ = std::move(other.temp_path_);
    buffer_ = std::move(other.buffer_);
    size_ = std::exchange(other.size_, 0);
    error_ = std::move(other.error_);
  }
  return *this;
}

Status AtomicFileWriter::Open(const std::string& path) {
  Discard();
  error_ = Status::Ok();
  size_ = 0;
  path_ = path;
  StatusOr<std::string> target = ResolveOutputFile(path);
  if (!target.ok()) return target.status();
  target_ = *target;
  temp_path_ = target_ + ".tmp." + std::to_string(::getpid());
  fd_ = ::open(temp_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    const int err = errno;
    temp_path_.clear();  // nothing was created
    return Status::IoError("cannot write '" + path + "': " + ErrnoText(err));
  }
  return Status::Ok();
}

Status AtomicFileWriter::Append(std::string_view data) {
  if (!error_.ok()) return error_;
  RVLIO_CHECK_MSG(is_open(), "AtomicFileWriter::Append before Open");
  buffer_.append(data.data(), data.size());
  size_ += data.size();
  if (buffer_.size() >= kFlushBytes) return Flush();
  return Status::Ok();
}

Status AtomicFileWriter::WriteAt(uint64_t offset, std::string_view data) {
  if (!error_.ok()) return error_;
  RVLIO_CHECK_MSG(is_open(), "AtomicFileWriter::WriteAt before Open");
  RVLIO_CHECK_MSG(offset + data.size() <= size_, "AtomicFileWriter::WriteAt past the end");
  if (Status s = Flush(); !s.ok()) return s;
  while (!data.empty()) {
    const ssize_t n = ::pwrite(fd_, data.data(), data.size(), static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return FailAndDiscard("cannot write", n < 0 ? errno : EIO);
    data.remove_prefix(static_cast<size_t>(n));
    offset += static_cast<uint64_t>(n);
  }
  return Status::Ok();
}

Status AtomicFileWriter::Flush() {
  const int err = WriteAll(fd_, buffer_.data(), buffer_.size());
  buffer_.clear();
  if (err != 0) return FailAndDiscard("cannot write", err);
  return Status::Ok();
}

Status AtomicFileWriter::Commit() {
  if (!error_.ok()) return error_;
  RVLIO_CHECK_MSG(is_open(), "AtomicFileWriter::Commit before Open");
  if (Status s = Flush(); !s.ok()) return s;
  if (::fsync(fd_) != 0) return FailAndDiscard("cannot sync", errno);
  const int fd = std::exchange(fd_, -1);
  if (::close(fd) != 0) return FailAndDiscard("cannot close", errno);
  if (::rename(temp_path_.c_str(), target_.c_str()) != 0)
    return FailAndDiscard("cannot rename", errno);
  temp_path_.clear();
  SyncDirectory(ParentDirectory(target_));
  return Status::Ok();
}

Status AtomicFileWriter::FailAndDiscard(const std::string& what, int err) {
  Discard();
  error_ = Status::IoError(what + " '" + path_ + "': " + ErrnoText(err));
  return error_;
}

void AtomicFileWriter::Discard() {
  if (fd_ >= 0) ::close(std::exchange(fd_, -1));
  if (!temp_path_.empty()) ::unlink(temp_path_.c_str());
  temp_path_.clear();
  buffer_.clear();
}

}  // namespace rvlio
