#pragma once
// How run and refine write their output folder: all outputs or none.
#include <string>
#include <utility>
#include <vector>

#include "rvlio/common/status.h"

namespace rvlio {

// Creates `dir` if needed and proves it writable (InvalidInput naming it if not).
Status PrepareOutputDir(const std::string& dir);

// The output folder of a command that can still fail before it writes
// anything: Prepare() creates it at once (an unwritable folder fails before
// the work), and the destructor removes it again, unless Keep() was called,
// when Prepare() created it and it is still empty, so that a rejected
// command leaves no new folder behind.
class OutputFolder {
 public:
  explicit OutputFolder(std::string dir) : dir_(std::move(dir)) {}
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  Status Prepare();
  void Keep() { keep_ = true; }

 private:
  std::string dir_;
  bool created_ = false, keep_ = false;
};

// A command's outputs are written (each atomically) into a private folder
// inside the output folder and moved into place only when every one of them
// is complete, so a failed write (disk full, file-size limit) leaves the
// output folder exactly as it was: no half file, no mix of old and new.
class OutputStage {
 public:
  explicit OutputStage(std::string out_dir) : out_dir_(std::move(out_dir)) {}
  ~OutputStage();  // removes the staging folder with whatever is left in it
  OutputStage(const OutputStage&) = delete;
  OutputStage& operator=(const OutputStage&) = delete;

  // Creates OUT/.rvlio_stage.<pid>.<random> (mkdtemp: unique per run) and
  // removes staging folders that processes no longer running left behind.
  Status Open();
  // Where to write output `name` (a plain file name); Commit() moves it.
  std::string Path(const std::string& name);
  // Renames every staged file into the output folder.
  Status Commit();
  // A writer's error names the staged file; this one names the output.
  Status Explain(const Status& s) const;

 private:
  std::string out_dir_, stage_dir_;
  std::vector<std::string> names_;
};

}  // namespace rvlio
