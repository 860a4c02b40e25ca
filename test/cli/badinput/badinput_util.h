#pragma once
// Helpers for the bad-input, disk-full and determinism tests: a short
// simulated tunnel read back into memory so that each test can write a
// manipulated copy, and ways to run the tool in another folder, with other
// environment variables or under a file-size limit (a disk-full stand-in that
// works for root too).
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli/cli_util.h"
#include "rvlio/formats/sensor_bag.h"

namespace rvlio::badinput {

using testing_cli::ReadFile;
using testing_cli::ToolRun;

inline const std::string kLidarTopic = "/os_cloud_node/points";
inline const std::string kImuTopic = "/imu/data";

// Runs `sh -c "cd CWD && ENV rvlio ARGS"` with stdout/stderr captured. When
// fsize_limit_bytes > 0 the child runs under RLIMIT_FSIZE (inherited through
// exec), so every write past that size fails like on a full disk.
inline ToolRun RunToolWith(const std::string& args, const std::string& scratch,
                           const std::string& cwd = "", const std::string& env = "",
                           rlim_t fsize_limit_bytes = 0) {
  const std::string out = scratch + "/stdout.txt", err = scratch + "/stderr.txt";
  std::string cmd = (cwd.empty() ? "" : "cd '" + cwd + "' && ") + env + " " +
                    std::string(RVLIO_BIN) + " " + args + " >" + out + " 2>" + err;
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (fsize_limit_bytes > 0) {
      const rlimit limit{fsize_limit_bytes, fsize_limit_bytes};
      if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) ::_exit(99);
    }
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(98);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  ToolRun r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = ReadFile(out);
  r.err = ReadFile(err);
  return r;
}

inline int Lines(const std::string& text) {
  return static_cast<int>(std::count(text.begin(), text.end(), '\n'));
}

// Names of the entries of a folder, sorted ("" entries for none).
inline std::vector<std::string> Entries(const std::string& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec))
    names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

inline const std::vector<std::string>& OutputNames() {
  static const std::vector<std::string> kNames = {"map.pcd", "scans.csv", "summary.json",
                                                  "trajectory.tum"};
  return kNames;
}

// Number of poses (non-comment lines) of a TUM file.
inline int TumPoses(const std::string& path) {
  const std::string text = ReadFile(path);
  int n = 0;
  size_t start = 0;
  while (start < text.size()) {
    const size_t end = text.find('\n', start);
    if (text[start] != '#') ++n;
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return n;
}

// One message of the simulated bag, in record order.
struct Message {
  bool is_imu = false;
  ImuSample imu;
  Scan scan;
};

// A 4 s simulated tunnel (seed 3, 512 columns: 40 scans, 801 IMU samples,
// the first second at rest), its clean run, and its messages in memory.
class SimulatedSuite : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing_cli::MakeTempDir("rvlio_badinput");
    ASSERT_FALSE(dir_.empty());
    const ToolRun sim = testing_cli::CachedSimulate(
        "--preset tunnel --seed 3 --duration 4 --set lidar.columns=512", dir_ + "/data", dir_);
    ASSERT_EQ(sim.exit_code, 0) << sim.err;
    const ToolRun clean = Run(Bag(), dir_ + "/clean");
    ASSERT_EQ(clean.exit_code, 0) << clean.err;
    LidarOptions lidar;
    lidar.topic = kLidarTopic;
    ImuOptions imu;
    imu.topic = kImuTopic;
    auto reader = SensorBagReader::Open(Bag(), lidar, imu);
    ASSERT_TRUE(reader.ok()) << reader.status().message();
    messages_ = new std::vector<Message>();
    for (;;) {
      Message m;
      StatusOr<SensorMessage> got = (*reader)->Next(&m.imu, &m.scan);
      ASSERT_TRUE(got.ok()) << got.status().message();
      if (*got == SensorMessage::kEnd) break;
      m.is_imu = *got == SensorMessage::kImu;
      messages_->push_back(std::move(m));
    }
  }
  static void TearDownTestSuite() {
    delete messages_;
    messages_ = nullptr;
    std::filesystem::remove_all(dir_);
  }

  static std::string Bag() { return dir_ + "/data/tunnel.bag"; }
  static std::string Sensors() { return dir_ + "/data/tunnel.yaml"; }
  static std::string Clean(const std::string& name) { return dir_ + "/clean/" + name; }
  static ToolRun Run(const std::string& bag, const std::string& out, const std::string& extra = "") {
    return RunToolWith("run --bag " + bag + " --config " + Sensors() + " --out " + out + " " + extra,
                       dir_);
  }
  static nlohmann::json Summary(const std::string& out) {
    return nlohmann::json::parse(ReadFile(out + "/summary.json"), nullptr, false);
  }

  // Writes the simulated messages to `path` through SensorBagWriter (a ROS1
  // bag, or by the extension a ROS 2 .mcap or .db3 file).
  // `edit_scan` may change a scan; `keep_imu` may drop an IMU sample; the
  // topics can be renamed or left out ("" drops the whole topic).
  static void WriteCopy(const std::string& path,
                        const std::function<void(int index, Scan*)>& edit_scan = nullptr,
                        const std::function<bool(const ImuSample&)>& keep_imu = nullptr,
                        const std::string& lidar_topic = kLidarTopic,
                        const std::string& imu_topic = kImuTopic) {
    BagWriterOptions format;
    const std::string ext = std::filesystem::path(path).extension().string();
    if (ext == ".mcap" || ext == ".db3") format.format = ext.substr(1);
    auto writer = SensorBagWriter::Create(path, format);
    ASSERT_TRUE(writer.ok()) << writer.status().message();
    int scan_index = 0;
    for (const Message& m : *messages_) {
      if (m.is_imu) {
        if (imu_topic.empty() || (keep_imu && !keep_imu(m.imu))) continue;
        ASSERT_TRUE((*writer)->WriteImu(imu_topic, "imu", m.imu).ok());
      } else {
        Scan scan = m.scan;
        if (edit_scan) edit_scan(scan_index, &scan);
        ++scan_index;
        if (lidar_topic.empty()) continue;
        ASSERT_TRUE((*writer)->WriteOusterScan(lidar_topic, "os_lidar", scan, 0, 0).ok());
      }
    }
    ASSERT_TRUE((*writer)->Close().ok());
  }

  static int ScanCount() {
    return static_cast<int>(std::count_if(messages_->begin(), messages_->end(),
                                          [](const Message& m) { return !m.is_imu; }));
  }

  static inline std::string dir_;
  static inline std::vector<Message>* messages_ = nullptr;
};

}  // namespace rvlio::badinput
