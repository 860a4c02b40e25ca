#pragma once
// A fresh folder per test case of test_mapio (under the temp directory,
// named after the suite, the case and gtest's seed), removed afterwards.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

namespace rvlio {

class MapioTestDir : public ::testing::Test {
 protected:
  void SetUp() override {
    const ::testing::UnitTest& unit = *::testing::UnitTest::GetInstance();
    dir_ = std::filesystem::temp_directory_path() /
           ("rvlio_" + std::string(unit.current_test_info()->test_suite_name()) + "_" +
            std::to_string(unit.random_seed()) + "_" + unit.current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::filesystem::path dir_;
};

}  // namespace rvlio
