#include "rvlio/outputs/output_stage.h"

#include <signal.h>
#include <stdlib.h>
#include <sys/stat.h>
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
  // A link to a folder is followed; anything else that is not a folder is refused.
  if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec)) {
    const std::string kind = SpecialFileKind(dir);
    return Status::InvalidInput("output folder " + dir + " is " +
                                (kind.empty() ? "a regular file" : kind) + ", not a folder");
  }
  std::filesystem::create_directories(dir, ec);
  if (ec) return Status::IoError("cannot create output folder " + dir + ": " + ec.message());
  const std::string probe = (std::filesystem::path(dir) / ".rvlio_write_test").string();
  if (Status s = WriteFileAtomically(probe, "ok\n"); !s.ok())
    return Status::IoError("output folder " + dir + " is not writable: " + s.message());
  std::filesystem::remove(probe, ec);
  return Status::Ok();
}

// The folders create_directories(dir) will create, innermost first: dir and
// each missing parent (a dangling link is not a missing folder: nothing of it
// is created here, so it is not listed).
static std::vector<std::string> MissingFolders(const std::string& dir) {
  std::vector<std::string> missing;
  std::error_code ec;
  for (std::filesystem::path p = std::filesystem::path(dir).lexically_normal();
       !p.empty() && p.has_relative_path(); p = p.parent_path()) {
    if (p.filename().empty()) continue;  // "a/b/" normalizes to "a/b/": its last element is ""
    if (std::filesystem::symlink_status(p, ec).type() != std::filesystem::file_type::not_found)
      break;
    missing.push_back(p.string());
  }
  return missing;
}

Status OutputFolder::Prepare() {
  created_ = MissingFolders(dir_);
  Status s = PrepareOutputDir(dir_);
  if (!s.ok()) RemoveCreated();
  return s;
}

void OutputFolder::RemoveCreated() {
  std::error_code ec;
  for (const std::string& folder : created_)
    if (!std::filesystem::remove(folder, ec)) break;  // only when empty
  created_.clear();
}

OutputFolder::~OutputFolder() {
  if (!keep_) RemoveCreated();
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

// The file each staged output replaces (ResolveOutputFile of OUT/name), all
// checked before the first is moved so that a refused one moves none. A link
// is followed only within the stage's file system (a rename cannot cross it).
static Status StageTargets(const std::string& stage_dir, const std::string& out_dir,
                           const std::vector<std::string>& names, std::vector<std::string>* targets) {
  struct stat stage;
  if (::stat(stage_dir.c_str(), &stage) != 0)
    return Status::IoError("cannot write to output folder " + out_dir + ": " + std::strerror(errno));
  for (const std::string& name : names) {
    const std::string path = (std::filesystem::path(out_dir) / name).string();
    StatusOr<std::string> target = ResolveOutputFile(path);
    if (!target.ok()) return target.status();
    const std::string folder = std::filesystem::path(*target).parent_path().string();
    struct stat st;
    if (*target != path && (::stat(folder.empty() ? "." : folder.c_str(), &st) != 0 ||
                            st.st_dev != stage.st_dev))
      return Status::InvalidInput("cannot write '" + path + "': it links to '" + *target +
                                  "', which is not on the output folder's file system");
    targets->push_back(*target);
  }
  return Status::Ok();
}

Status OutputStage::Commit() {
  std::vector<std::string> targets;
  if (Status s = StageTargets(stage_dir_, out_dir_, names_, &targets); !s.ok()) return s;
  for (size_t i = 0; i < names_.size(); ++i) {
    const std::string from = (std::filesystem::path(stage_dir_) / names_[i]).string();
    if (std::rename(from.c_str(), targets[i].c_str()) != 0)
      return Status::IoError("cannot move " + names_[i] + " into " + out_dir_ + ": " +
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
