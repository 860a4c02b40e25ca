#pragma once
// Helpers of the LAS tests: a scratch folder, a PCD writer of any field types
// (the maps `rvlio export` reads), and little-endian reads of the bytes of a
// LAS file written from the specification's tables, not from the writer.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli/cli_util.h"

namespace rvlio::las_test {

// 6 s of the tunnel (seed 3, 512 columns) with a band of reflectivity 250
// on the left wall from x = 16 to 19 m (the walls' 80 elsewhere;
// docs/simulator.md "A painted band"): tunnel.bag, tunnel.yaml,
// tunnel_gt.tum in `out`. Simulated once per build (CachedSimulate) for
// every test of test_las.
inline testing_cli::ToolRun SimulateBandFlight(const std::string& out, const std::string& scratch) {
  return testing_cli::SimulateTunnel(
      out, 3, 6, scratch,
      "--set world.band.reflectivity=250 --set world.band.x_min=16 --set world.band.x_max=19");
}

class ScratchDir {
 public:
  ScratchDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           ("rvlio_las_" + std::string(info->test_suite_name()) + "_" + info->name() + "_" +
            std::to_string(::getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  ~ScratchDir() { std::filesystem::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  const std::filesystem::path& dir() const { return dir_; }
  // The names of the files in the folder (to see that nothing was left).
  std::vector<std::string> Files() const {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(dir_))
      names.push_back(e.path().filename().string());
    return names;
  }

 private:
  std::filesystem::path dir_;
};

inline std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

template <typename T>
T At(const std::string& bytes, size_t offset) {
  T v{};
  EXPECT_LE(offset + sizeof(T), bytes.size());
  if (offset + sizeof(T) <= bytes.size()) std::memcpy(&v, bytes.data() + offset, sizeof(T));
  return v;
}

inline std::string Text(const std::string& bytes, size_t offset, size_t width) {
  const std::string s = bytes.substr(offset, width);
  return s.substr(0, s.find('\0'));
}

struct PcdField {
  std::string name;
  char type = 'F';
  int size = 4;
};

// A PCD (v0.7) of `rows` (one value per field, x y z among the fields) in
// DATA ascii or binary.
inline void WritePcd(const std::string& path, const std::vector<PcdField>& fields,
                     const std::vector<std::vector<double>>& rows, bool binary) {
  std::ostringstream h;
  h << "# .PCD v0.7\nVERSION 0.7\nFIELDS";
  for (const auto& f : fields) h << ' ' << f.name;
  h << "\nSIZE";
  for (const auto& f : fields) h << ' ' << f.size;
  h << "\nTYPE";
  for (const auto& f : fields) h << ' ' << f.type;
  h << "\nCOUNT";
  for (size_t i = 0; i < fields.size(); ++i) h << " 1";
  h << "\nWIDTH " << rows.size() << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << rows.size()
    << "\nDATA " << (binary ? "binary" : "ascii") << "\n";
  std::ofstream out(path, std::ios::binary);
  out << h.str();
  for (const auto& row : rows) {
    for (size_t k = 0; k < fields.size(); ++k) {
      const double v = row[k];
      const PcdField& f = fields[k];
      if (!binary) {
        std::ostringstream s;
        s.precision(17);
        s << v;
        out << (k == 0 ? "" : " ") << s.str();
        continue;
      }
      char b[8];
      if (f.type == 'F' && f.size == 4) { const float x = static_cast<float>(v); std::memcpy(b, &x, 4); }
      else if (f.type == 'F') std::memcpy(b, &v, 8);
      else if (f.type == 'U' && f.size == 1) b[0] = static_cast<char>(static_cast<uint8_t>(v));
      else if (f.type == 'U' && f.size == 2) { const uint16_t x = static_cast<uint16_t>(v); std::memcpy(b, &x, 2); }
      else if (f.type == 'U' && f.size == 4) { const uint32_t x = static_cast<uint32_t>(v); std::memcpy(b, &x, 4); }
      else if (f.type == 'I' && f.size == 2) { const int16_t x = static_cast<int16_t>(v); std::memcpy(b, &x, 2); }
      else if (f.type == 'I' && f.size == 4) { const int32_t x = static_cast<int32_t>(v); std::memcpy(b, &x, 4); }
      else ADD_FAILURE() << "WritePcd: type " << f.type << f.size;
      out.write(b, f.size);
    }
    if (!binary) out << "\n";
  }
}

// The peak resident memory (VmHWM, kB) of this process.
inline long PeakRssKb() {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("VmHWM:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}
// Resets VmHWM to the current resident memory (Linux: clear_refs 5); false
// when the kernel does not allow it.
inline bool ResetPeakRss() {
  std::ofstream out("/proc/self/clear_refs");
  out << "5";
  out.flush();
  return static_cast<bool>(out);
}

}  // namespace rvlio::las_test
