#pragma once
// Helpers shared by the config tests: a per-test temp folder, file writing,
// error-message checks and a small Options struct of its own (the loader must
// work on any struct with a Visit member, e.g. the simulator's SimOptions).
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "rvlio/common/options.h"
#include "rvlio/common/status.h"

namespace rvlio::test {

// A fresh folder under the gtest temp dir, removed at the end of the test.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::path(::testing::TempDir()) /
            ("rvlio_config_" + std::string(info->test_suite_name()) + "_" + info->name());
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  // Writes `text` to <dir>/<name> and returns the full path.
  std::string Write(const std::string& name, const std::string& text) const {
    const std::string p = (path_ / name).string();
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }
  std::string Path(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

// An error of the exit-2 class, on one line, containing every substring.
inline ::testing::AssertionResult IsConfigError(const Status& s,
                                                const std::vector<std::string>& parts) {
  if (s.ok()) return ::testing::AssertionFailure() << "expected an error, got ok";
  if (s.code() != StatusCode::kInvalidInput)
    return ::testing::AssertionFailure() << "not an InvalidInput error: " << s.message();
  if (s.message().find('\n') != std::string::npos)
    return ::testing::AssertionFailure() << "message is not one line: " << s.message();
  for (const auto& p : parts)
    if (s.message().find(p) == std::string::npos)
      return ::testing::AssertionFailure() << "'" << p << "' not in: " << s.message();
  return ::testing::AssertionSuccess() << s.message();
}

// A struct unrelated to OdometryOptions: int64, float arrays of another size,
// three levels of nesting, a cross-field rule.
struct ToyDeep {
  bool flag = false;
  int count = 3;
  template <class V>
  void Visit(V& v) {
    v.Field("flag", flag, Spec().Help("a switch"));
    v.Field("count", count, Spec().Range(0, 10));
  }
};
struct ToyInner {
  int64_t seed = 7;
  std::array<double, 2> xy = {1.0, 2.0};
  std::string mode = "a";
  ToyDeep deep;
  template <class V>
  void Visit(V& v) {
    v.Field("seed", seed, Spec().Min(0).Help("random seed"));
    v.Field("xy", xy, Spec().Unit("m").Range(-100.0, 100.0));
    v.Field("mode", mode, Spec().Choices({"a", "b"}));
    v.Section("deep", deep);
  }
};
struct ToyOptions {
  double rate = 1.5;
  std::string name = "toy";
  ToyInner inner;
  template <class V>
  void Visit(V& v) {
    v.Field("rate", rate, Spec().Unit("Hz").Positive().Help("sample rate"));
    v.Field("name", name, Spec());
    v.Section("inner", inner);
  }
  Status Validate() {
    Status s = ValidateFields(*this);
    if (s.ok() && !(inner.xy[0] < inner.xy[1]))
      return Status::InvalidInput("inner.xy must be increasing");
    return s;
  }
};

}  // namespace rvlio::test
