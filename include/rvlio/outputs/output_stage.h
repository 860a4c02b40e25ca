#pragma once
// How run and refine write their output folder: all outputs or none.
#include <string>
#include <utility>
#include <vector>

#include "rvlio/common/status.h"

namespace rvlio {

// Creates `dir` if needed and proves it writable (InvalidInput naming it if
// not, or if it exists as something else than a folder or a link to one).
Status PrepareOutputDir(const std::string& dir);

// The output folder of every command that writes one (run, refine, merge,
// simulate, compare, ablate, calibrate-time): Prepare() creates it at once
// (an unwritable folder fails before the work), and the destructor removes
// again, unless Keep() was called, the folders Prepare() created (the output
// folder and its missing parents) that are still empty, so that a command
// that failed (bad input, disk full, file-size limit) leaves no new folder
// behind. A folder that existed before is never removed; one that holds
// anything is kept.
class OutputFolder {
 public:
  explicit OutputFolder(std::string dir) : dir_(std::move(dir)) {}
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  Status Prepare();
  void Keep() { keep_ = true; }
  const std::string& dir() const { return dir_; }

 private:
  void RemoveCreated();

  std::string dir_;
  std::vector<std::string> created_;  // innermost first
  bool keep_ = false;
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
  // Renames every staged file into the output folder, once every one of
  // them is known to be allowed there (ResolveOutputFile: a link to a regular
  // file is followed, a FIFO, device, socket or folder refuses them all).
  Status Commit();
  // A writer's error names the staged file; this one names the output.
  Status Explain(const Status& s) const;

 private:
  std::string out_dir_, stage_dir_;
  std::vector<std::string> names_;
};

}  // namespace rvlio
