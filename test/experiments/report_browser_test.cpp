// report.html in a real browser: Debian's chromium, headless, started and
// stopped here (its own process group, killed as a group when done or after
// a timeout). A short simulated tunnel is run, `rvlio report` writes its page,
// and chromium (1) dumps the DOM after the scripts ran: the page finished
// drawing and the metrics table holds the run's figures (those of
// summary.json and `rvlio eval --json`); (2) logs the console to stderr: no
// error; (3) takes a screenshot: the WebGL map is not blank (pixels differ
// from its background inside the map's box). Skipped when chromium is not
// installed (scripts/install_deps.sh --with-test-tools installs it).
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli/cli_util.h"

extern char** environ;

namespace rvlio {
namespace {

namespace fs = std::filesystem;
using testing_cli::ReadFile;
using testing_cli::RunTool;
using testing_cli::ToolRun;

constexpr const char* kChromium = "/usr/bin/chromium";
constexpr int kBrowserTimeoutS = 120;
// The screenshot's viewport holds the whole page (report.css lays it out).
constexpr const char* kWindowSize = "--window-size=1300,2600";

struct BrowserRun {
  int exit_code = -1;
  bool timed_out = false;
  std::string out, err;
};

// Runs chromium headless with the flags of docs/report.md in its own process
// group; the group is killed at the end (browser helpers included).
BrowserRun RunChromium(const std::vector<std::string>& extra, const std::string& scratch,
                       const std::string& tag) {
  const std::string profile = scratch + "/profile_" + tag;
  fs::create_directories(profile);
  std::vector<std::string> args = {kChromium, "--headless", "--no-sandbox", "--disable-gpu",
                                   "--disable-quic", "--no-first-run",
                                   "--disable-background-networking", "--disable-component-update",
                                   "--disable-sync", "--user-data-dir=" + profile,
                                   "--enable-logging=stderr", "--v=0",
                                   // WebGL without a GPU: software rendering (SwiftShader)
                                   "--enable-unsafe-swiftshader", kWindowSize};
  args.insert(args.end(), extra.begin(), extra.end());
  const std::string out = scratch + "/" + tag + ".out", err = scratch + "/" + tag + ".err";
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
  posix_spawnattr_setpgroup(&attr, 0);  // a new group led by chromium
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = -1;
  BrowserRun run;
  const int rc = posix_spawn(&pid, kChromium, &actions, &attr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  if (rc != 0) return run;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(kBrowserTimeoutS);
  int status = 0;
  for (;;) {
    const pid_t done = waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    if (std::chrono::steady_clock::now() > deadline) {
      run.timed_out = true;
      kill(-pid, SIGKILL);
      waitpid(pid, &status, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  kill(-pid, SIGKILL);  // helpers of the browser left in its group, if any
  run.exit_code = !run.timed_out && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.out = ReadFile(out);
  run.err = ReadFile(err);
  return run;
}

// An 8-bit RGB or RGBA PNG (what chromium's --screenshot writes), as RGB.
struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;
  const uint8_t* At(int x, int y) const { return &rgb[3 * (static_cast<size_t>(y) * width + x)]; }
};

uint32_t BigEndian32(const std::string& s, size_t at) {
  return static_cast<uint32_t>(static_cast<uint8_t>(s[at])) << 24 |
         static_cast<uint32_t>(static_cast<uint8_t>(s[at + 1])) << 16 |
         static_cast<uint32_t>(static_cast<uint8_t>(s[at + 2])) << 8 |
         static_cast<uint32_t>(static_cast<uint8_t>(s[at + 3]));
}

bool DecodePng(const std::string& png, Image* image) {
  if (png.size() < 8 || png.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0) return false;
  std::string idat;
  int depth = 0, color = 0;
  for (size_t at = 8; at + 8 <= png.size();) {
    const uint32_t length = BigEndian32(png, at);
    const std::string type = png.substr(at + 4, 4);
    if (at + 12 + length > png.size()) return false;
    if (type == "IHDR") {
      image->width = static_cast<int>(BigEndian32(png, at + 8));
      image->height = static_cast<int>(BigEndian32(png, at + 12));
      depth = static_cast<uint8_t>(png[at + 16]);
      color = static_cast<uint8_t>(png[at + 17]);
    }
    if (type == "IDAT") idat += png.substr(at + 8, length);
    at += 12 + length;
  }
  const int channels = color == 6 ? 4 : color == 2 ? 3 : 0;
  if (depth != 8 || channels == 0 || image->width <= 0 || image->height <= 0) return false;
  const size_t row = 1 + static_cast<size_t>(image->width) * channels;
  std::vector<uint8_t> raw(row * image->height);
  uLongf raw_size = raw.size();
  if (uncompress(raw.data(), &raw_size, reinterpret_cast<const Bytef*>(idat.data()), idat.size()) !=
          Z_OK ||
      raw_size != raw.size())
    return false;
  std::vector<uint8_t> pixels(row - 1), previous(row - 1, 0);
  image->rgb.clear();
  for (int y = 0; y < image->height; ++y) {
    const uint8_t filter = raw[y * row];
    const uint8_t* in = &raw[y * row + 1];
    for (size_t i = 0; i < row - 1; ++i) {
      const int a = i >= static_cast<size_t>(channels) ? pixels[i - channels] : 0;
      const int b = previous[i];
      const int c = i >= static_cast<size_t>(channels) ? previous[i - channels] : 0;
      int predictor = 0;
      if (filter == 1) predictor = a;
      if (filter == 2) predictor = b;
      if (filter == 3) predictor = (a + b) / 2;
      if (filter == 4) {
        const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
        predictor = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      }
      pixels[i] = static_cast<uint8_t>(in[i] + predictor);
    }
    for (int x = 0; x < image->width; ++x)
      image->rgb.insert(image->rgb.end(), &pixels[x * channels], &pixels[x * channels] + 3);
    previous = pixels;
  }
  return true;
}

// The quoted text that follows the first `prefix` in a DOM dump, or "".
// (Plain string search, not <regex>: gcc 12's std::regex trips
// -Werror=maybe-uninitialized in the sanitizer build.)
std::string QuotedAfter(const std::string& dom, const std::string& prefix) {
  const size_t at = dom.find(prefix + "\"");
  if (at == std::string::npos) return "";
  const size_t begin = at + prefix.size() + 1, end = dom.find('"', begin);
  return end == std::string::npos ? "" : dom.substr(begin, end - begin);
}

// The value of `attribute` on the first element carrying it in a DOM dump.
std::string Attribute(const std::string& dom, const std::string& attribute) {
  return QuotedAfter(dom, attribute + "=");
}

// data-value of the metrics table cell of `column`, or NaN.
double TableValue(const std::string& dom, const std::string& column) {
  const std::string value =
      QuotedAfter(dom, "<td data-column=\"" + column + "\" data-value=");
  return value.empty() ? std::nan("") : std::strtod(value.c_str(), nullptr);
}

TEST(ReportBrowserTest, PageLoadsWithoutConsoleErrorsDrawsTheMapAndHoldsTheRunsFigures) {
  if (access(kChromium, X_OK) != 0)
    GTEST_SKIP() << kChromium << " not installed (scripts/install_deps.sh --with-test-tools)";
  const std::string dir = testing_cli::MakeTempDir("rvlio_report_browser");
  ASSERT_FALSE(dir.empty());
  const ToolRun sim = testing_cli::SimulateTunnel(dir + "/data", 4, 6, dir);
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const std::string gt = dir + "/data/tunnel_gt.tum";
  const ToolRun run = RunTool("run --bag " + dir + "/data/tunnel.bag --config " + dir +
                                  "/data/tunnel.yaml --out " + dir + "/run",
                              dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const ToolRun report = RunTool("report " + dir + "/run --gt " + gt, dir);
  ASSERT_EQ(report.exit_code, 0) << report.err;
  const std::string page = dir + "/run/report.html";
  ASSERT_TRUE(fs::is_regular_file(page)) << report.out;

  // (1) the DOM after the scripts ran
  const BrowserRun dom_run = RunChromium({"--dump-dom", "file://" + page}, dir, "dom");
  ASSERT_FALSE(dom_run.timed_out);
  ASSERT_EQ(dom_run.exit_code, 0) << dom_run.err;
  const std::string& dom = dom_run.out;
  EXPECT_EQ(Attribute(dom, "data-rvlio-ready"), "1") << "the page's script did not finish";
  // The simulated map has an intensity: offered in the colouring list.
  EXPECT_NE(dom.find(">intensity (the sensor's"), std::string::npos) << "no intensity colouring";
  const nlohmann::json eval = testing_cli::EvalJson(gt, dir + "/run/trajectory.tum", dir);
  const nlohmann::json summary = nlohmann::json::parse(ReadFile(dir + "/run/summary.json"));
  ASSERT_TRUE(eval.is_object());
  EXPECT_NEAR(TableValue(dom, "ate_rmse_m"), eval["ape"]["rmse"].get<double>(), 1e-9);
  EXPECT_NEAR(TableValue(dom, "rpe_rmse_m"), eval["rpe"]["rmse"].get<double>(), 1e-9);
  EXPECT_EQ(TableValue(dom, "scan_count"), summary["scan_count"].get<double>());
  EXPECT_NEAR(TableValue(dom, "real_time_factor"), summary["real_time_factor"].get<double>(), 1e-9);

  // (2) no console error, (3) the map drawn: pixels unlike its background.
  const std::string shot = dir + "/shot.png";
  const BrowserRun shot_run =
      RunChromium({"--screenshot=" + shot, "file://" + page}, dir, "shot");
  ASSERT_FALSE(shot_run.timed_out);
  ASSERT_EQ(shot_run.exit_code, 0) << shot_run.err;
  // chromium logs every console message (log, warning, error, an uncaught
  // exception) as an INFO:CONSOLE line; the page writes none. The one line
  // allowed is the software GL driver's note on reading pixels back.
  for (const BrowserRun* r : {&dom_run, &shot_run}) {
    std::istringstream lines(r->err);
    for (std::string line; std::getline(lines, line);) {
      if (line.find(":CONSOLE") != std::string::npos) {
        EXPECT_NE(line.find("GL Driver Message"), std::string::npos) << line;
      }
    }
  }
  const std::string rect = Attribute(dom, "data-rect");  // x,y,width,height of the map's canvas
  int x0 = 0, y0 = 0, w = 0, h = 0;
  ASSERT_EQ(std::sscanf(rect.c_str(), "%d,%d,%d,%d", &x0, &y0, &w, &h), 4) << rect;
  Image image;
  ASSERT_TRUE(DecodePng(ReadFile(shot), &image));
  ASSERT_GE(image.width, x0 + w);
  ASSERT_GE(image.height, y0 + h);
  size_t drawn = 0;
  for (int y = y0 + 2; y < y0 + h - 2; ++y)
    for (int x = x0 + 2; x < x0 + w - 2; ++x) {
      const uint8_t* p = image.At(x, y);
      drawn += std::abs(p[0] - 0x11) + std::abs(p[1] - 0x11) + std::abs(p[2] - 0x11) > 24 ? 1 : 0;
    }
  const double fraction = static_cast<double>(drawn) / (static_cast<double>(w) * h);
  EXPECT_GT(fraction, 0.005) << drawn << " coloured pixels in the map's " << w << "x" << h;
  if (const char* keep = std::getenv("RVLIO_REPORT_SCREENSHOT"); keep != nullptr && *keep != '\0')
    fs::copy_file(shot, keep, fs::copy_options::overwrite_existing);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rvlio
