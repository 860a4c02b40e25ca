#include "rvlio/outputs/output_stage.h"

#include <signal.h>
#include <stdlib.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "rvlio/formats/atomic_file.h"

namespace rvlio {

Status PrepareOutputDir(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return Status::IoError("cannot create output folder " + dir + ": " + ec.message());
  const std::string probe = (std::filesystem::path(dir) / ".rvlio_write_test").string();
  if (Status s = WriteFileAtomically(probe, "ok\n"); !s.ok())
    return Status::IoError("output folder " + dir + " is not writable: " + s.message());
  std::filesystem::remove(probe, ec);
  return Status::Ok();
}

Status OutputFolder::Prepare() {
  std::error_code ec;
  created_ = !std::filesystem::exists(dir_, ec);
  return PrepareOutputDir(dir_);
}

OutputFolder::~OutputFolder() {
  if (!created_ || keep_) return;
  std::error_code ec;
  std::filesystem::remove(dir_, ec);  // only when empty
}

OutputStage::~OutputStage() {
  if (stage_dir_.empty()) return;
  std::error_code ec;
  std::filesystem::remove_all(stage_dir_, ec);
}

// Staging folders of processes that no longer exist (killed, or aborted by a
// second signal while writing) are removed when the next run stages there.
static void RemoveStaleStages(const std::string& out_dir) {
  const std::string prefix = ".rvlio_stage.";
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(out_dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    const long pid = std::strtol(name.c_str() + prefix.size(), nullptr, 10);
    if (pid <= 0 || (::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH)) {
      std::error_code ignored;
      std::filesystem::remove_all(e.path(), ignored);
    }
  }
}

Status OutputStage::Open() {
  RemoveStaleStages(out_dir_);
  // Unique per run, not per process: compare runs several variants in one
  // process, and two runs of one process may share an output folder.
  std::string name = (std::filesystem::path(out_dir_) /
                      (".rvlio_stage." + std::to_string(::getpid()) + ".XXXXXX"))
                         .string();
  if (::mkdtemp(name.data()) == nullptr) {
    const std::string why = std::strerror(errno);
    return Status::IoError("cannot write to output folder " + out_dir_ + ": " + why);
  }
  stage_dir_ = name;
  return Status::Ok();
}

std::string OutputStage::Path(const std::string& name) {
  names_.push_back(name);
  return (std::filesystem::path(stage_dir_) / name).string();
}

Status OutputStage::Commit() {
  for (const std::string& name : names_) {
    const std::string from = (std::filesystem::path(stage_dir_) / name).string();
    const std::string to = (std::filesystem::path(out_dir_) / name).string();
    if (std::rename(from.c_str(), to.c_str()) != 0)
      return Status::IoError("cannot move " + name + " into " + out_dir_ + ": " +
                             std::strerror(errno));
  }
  return Status::Ok();
}

Status OutputStage::Explain(const Status& s) const {
  std::string message = s.message();
  const std::string staged = stage_dir_ + "/";
  const std::string final_dir = (std::filesystem::path(out_dir_) / "").string();
  for (size_t at = message.find(staged); at != std::string::npos; at = message.find(staged, at))
    message.replace(at, staged.size(), final_dir);
  return s.WithMessage(message);
}

}  // namespace rvlio
