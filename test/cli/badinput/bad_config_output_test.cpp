// The rest of the bad-input matrix: configuration files with unknown keys,
// wrong types and out-of-range values, output folders that cannot be written
// (in ways that stop root too), and a full disk simulated with a file-size
// limit (RLIMIT_FSIZE, which binds root as well): a failed write exits 2 with
// one line naming the file, leaves no half or temporary file, and leaves the
// complete outputs of an earlier run in that folder untouched.
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "badinput_util.h"

namespace rvlio::badinput {
namespace {

namespace fs = std::filesystem;

class BadConfigOutputTest : public SimulatedSuite {
 protected:
  static std::string WriteConfig(const std::string& name, const std::string& text) {
    const std::string path = dir_ + "/" + name;
    std::ofstream(path) << text;
    return path;
  }
  // A copy of the clean run's outputs in a new folder: "the earlier run".
  static std::string EarlierRun(const std::string& name) {
    const std::string dir = dir_ + "/" + name;
    fs::create_directories(dir);
    for (const auto& f : OutputNames()) fs::copy_file(Clean(f), dir + "/" + f);
    return dir;
  }
  static void ExpectUntouched(const std::string& dir) {
    EXPECT_EQ(Entries(dir), OutputNames()) << "no half, temporary or staging file may stay";
    for (const auto& f : OutputNames())
      EXPECT_EQ(ReadFile(dir + "/" + f), ReadFile(Clean(f))) << f;
  }
};

TEST_F(BadConfigOutputTest, ConfigFileErrorsNameKeyAndFileAndStopBeforeOutput) {
  struct Case {
    std::string file, text, line;
  };
  const std::vector<Case> cases = {
      {"unknown.yaml", "rv:\n  epss0: 0.3\n", "rv.epss0: unknown key in FILE:2 (did you mean rv.eps0?)"},
      {"type.yaml", "lidar:\n  max_range: far\n", "lidar.max_range in FILE:2: expected a number, got 'far'"},
      {"range.yaml", "lidar:\n  min_range: -1\n", "FILE:2: lidar.min_range = -1 is out of range [0, 1000]"},
  };
  for (const Case& c : cases) {
    const std::string path = WriteConfig(c.file, c.text);
    std::string line = c.line;
    line.replace(line.find("FILE"), 4, path);
    const std::string out = dir_ + "/out_config";
    const ToolRun r = Run(Bag(), out, "--config " + path);
    EXPECT_EQ(r.exit_code, 2) << c.file << ": " << r.err;
    EXPECT_EQ(r.err, "rvlio run: error: " + line + "\n") << c.file;
    EXPECT_FALSE(fs::exists(out)) << c.file;
  }
}

TEST_F(BadConfigOutputTest, OutputFolderThatCannotBeWrittenStopsEvenForRoot) {
  // A regular file where a folder is needed: mkdir fails with ENOTDIR/EEXIST
  // whatever the user's privileges (chmod would not stop root).
  const std::string file = WriteConfig("a_file", "keep me\n");
  const ToolRun below = Run(Bag(), file + "/out");
  EXPECT_EQ(below.exit_code, 2) << below.err;
  EXPECT_EQ(below.err, "rvlio run: error: cannot create output folder " + file +
                           "/out: Not a directory\n");
  const ToolRun itself = Run(Bag(), file);
  EXPECT_EQ(itself.exit_code, 2) << itself.err;
  EXPECT_EQ(Lines(itself.err), 1) << itself.err;
  EXPECT_EQ(itself.err, "rvlio run: error: output folder " + file +
                            " is a regular file, not a folder\n");
  EXPECT_EQ(ReadFile(file), "keep me\n");
}

TEST_F(BadConfigOutputTest, DiskFullDuringMapWriteLeavesTheEarlierRunIntact) {
  ASSERT_GT(fs::file_size(Clean("map.pcd")), 60000u);
  ASSERT_LT(fs::file_size(Clean("trajectory.tum")), 40000u);
  const std::string out = EarlierRun("full_map");
  const ToolRun r = RunToolWith("run --bag " + Bag() + " --config " + Sensors() +
                                    " --set rv.enabled=false --out " + out,
                                dir_, "", "", 40000);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err, "rvlio run: error: cannot write '" + out + "/map.pcd': File too large\n");
  // trajectory.tum of the new run was complete, but it must not be mixed
  // with the earlier run's map: the folder is exactly as before.
  ExpectUntouched(out);
}

TEST_F(BadConfigOutputTest, DiskFullDuringTrajectoryWriteLeavesNoFile) {
  const std::string out = dir_ + "/full_fresh";
  const ToolRun r = RunToolWith("run --bag " + Bag() + " --config " + Sensors() + " --out " + out,
                                dir_, "", "", 1000);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err, "rvlio run: error: cannot write '" + out + "/trajectory.tum': File too large\n");
  EXPECT_FALSE(fs::exists(out)) << "the folder the failed run created is removed";
  // The same folder takes the next run that has room.
  const ToolRun ok = Run(Bag(), out);
  ASSERT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_EQ(Entries(out), OutputNames());
  EXPECT_EQ(ReadFile(out + "/trajectory.tum"), ReadFile(Clean("trajectory.tum")));
}

TEST_F(BadConfigOutputTest, DiskFullWhileSimulatingLeavesNoHalfBag) {
  const std::string out = dir_ + "/full_sim";
  for (rlim_t limit : {4000, 2000000}) {  // fails at the first chunk / in the middle
    const ToolRun r = RunToolWith("simulate --preset tunnel --duration 2 --set lidar.columns=512 "
                                  "--out " + out, dir_, "", "", limit);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(Lines(r.err), 1) << r.err;
    // Names the bag (its temporary name when creating the file already failed).
    EXPECT_EQ(r.err.rfind("rvlio simulate: error: cannot write bag '" + out + "/tunnel.bag", 0), 0u)
        << r.err;
    EXPECT_NE(r.err.find("Error writing to file"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out)) << "the folder the failed simulation created is removed";
  }
  // Into a folder that holds an earlier simulation: a failure leaves every
  // file as it was.
  const std::string earlier = dir_ + "/full_sim_earlier";
  fs::create_directories(earlier);
  for (const auto& e : fs::directory_iterator(dir_ + "/data")) fs::copy(e.path(), earlier);
  const std::vector<std::string> before = Entries(earlier);
  const ToolRun r = RunToolWith("simulate --preset tunnel --seed 3 --duration 4 --set "
                                "lidar.columns=512 --out " + earlier,
                                dir_, "", "", 2000000);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  EXPECT_EQ(r.err.rfind("rvlio simulate: error: cannot write bag '" + earlier + "/", 0), 0u)
      << r.err;
  EXPECT_EQ(Entries(earlier), before) << "no staging or half file may stay";
  for (const std::string& f : before)
    EXPECT_EQ(ReadFile(earlier + "/" + f), ReadFile(dir_ + "/data/" + f)) << f;
}

// Special files named as outputs (docs/outputs.md "What an output path may
// be"): refused with one line and left as they were; a link is followed.
TEST_F(BadConfigOutputTest, ReportOutThatIsAFifoOrALink) {
  const std::string fifo = dir_ + "/report_fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  const ToolRun refused = RunToolWith("report " + Clean("") + " --out " + fifo, dir_);
  EXPECT_EQ(refused.exit_code, 2) << refused.err;
  EXPECT_EQ(refused.err, "rvlio report: error: cannot write '" + fifo +
                             "': it is a FIFO (named pipe); an output must be a regular file "
                             "or a new path\n");
  EXPECT_TRUE(fs::is_fifo(fifo));
  std::ofstream(dir_ + "/report_target.html") << "old";
  fs::create_symlink("report_target.html", dir_ + "/report_link.html");
  const ToolRun followed =
      RunToolWith("report " + Clean("") + " --out " + dir_ + "/report_link.html", dir_);
  EXPECT_EQ(followed.exit_code, 0) << followed.err;
  EXPECT_TRUE(fs::is_symlink(dir_ + "/report_link.html"));
  EXPECT_GT(fs::file_size(dir_ + "/report_target.html"), 1000u);
}

TEST_F(BadConfigOutputTest, DiskFullDuringRefineLeavesTheEarlierRunIntact) {
  const std::string out = dir_ + "/full_refine";
  fs::create_directories(out);
  for (const char* f : {"trajectory.tum", "map.pcd", "summary.json"})
    fs::copy_file(Clean(f), out + "/" + f);
  const ToolRun r = RunToolWith("refine --bag " + Bag() + " --config " + Sensors() + " --init " +
                                    Clean("trajectory.tum") +
                                    " --set refine.rounds=1 --out " + out,
                                dir_, "", "", 20000);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.substr(r.err.find("rvlio refine: error")),
            "rvlio refine: error: cannot write '" + out + "/map.pcd': File too large\n");
  EXPECT_EQ(Entries(out), (std::vector<std::string>{"map.pcd", "summary.json", "trajectory.tum"}));
  for (const char* f : {"trajectory.tum", "map.pcd", "summary.json"})
    EXPECT_EQ(ReadFile(out + "/" + f), ReadFile(Clean(f))) << f;
}

// Found by the config fuzzer's notes: file names and --set strings need not be
// UTF-8 (Latin-1 folder names are common). summary.json must still be written
// and parse, with the bytes replaced (U+FFFD), instead of an uncaught throw.
TEST_F(BadConfigOutputTest, NonUtf8PathsStillGiveAParsableSummary) {
  const std::string latin1_dir = dir_ + "/caf\xe9";
  fs::create_directories(latin1_dir);
  fs::copy_file(Bag(), latin1_dir + "/t.bag");
  const std::string out = latin1_dir + "/out";
  const ToolRun r = Run(latin1_dir + "/t.bag", out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json summary = nlohmann::json::parse(ReadFile(out + "/summary.json"), nullptr, false);
  ASSERT_FALSE(summary.is_discarded());
  EXPECT_NE(summary.dump().find("caf\xef\xbf\xbd"), std::string::npos);
}

}  // namespace
}  // namespace rvlio::badinput
