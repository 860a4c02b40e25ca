// End to end: `rvlio eval` on the evo fixtures (values of reference.json) and
// on bad input (one error line, exit 2).
#include <stdlib.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_util.h"

namespace rvlio {
namespace {

const std::string kEvo = std::string(RVLIO_TEST_DATA) + "/evo/";
const std::string kBad = std::string(RVLIO_TEST_DATA) + "/eval/";

struct EvalRun {
  int exit_code = -1;
  std::string out, err;
};

std::string ReadAll(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

class EvalCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string tmpl = ::testing::TempDir() + "rvlio_eval_cli_XXXXXX";
    ASSERT_NE(::mkdtemp(tmpl.data()), nullptr);
    dir_ = tmpl;
    reference_ = nlohmann::json::parse(ReadAll(kEvo + "reference.json"));
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  EvalRun Eval(const std::string& args) {
    const std::string out = dir_ + "/stdout", err = dir_ + "/stderr";
    const std::string cmd = std::string(RVLIO_BIN) + " eval " + args + " >" + out + " 2>" + err;
    const int status = std::system(cmd.c_str());
    EvalRun r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = ReadAll(out);
    r.err = ReadAll(err);
    return r;
  }

  std::string Pair(int k) const {
    const nlohmann::json& c = reference_["cases"][k];
    return "--gt " + kEvo + c["ref"].get<std::string>() + " --est " + kEvo +
           c["est"].get<std::string>();
  }

  // Exit 2 and exactly one stderr line "rvlio eval: error: ..." containing `part`.
  void ExpectBadInput(const std::string& args, const std::string& part) {
    const EvalRun r = Eval(args);
    testing_cli::ExpectOneErrorLine({r.exit_code, r.out, r.err}, "eval", part);
  }

  std::string dir_;
  nlohmann::json reference_;
};

void ExpectStats(const nlohmann::json& expected, const nlohmann::json& got, const char* what) {
  for (const auto& [key, value] : expected.items()) {
    if (key == "scale") continue;
    ASSERT_TRUE(got.contains(key)) << what << "." << key;
    EXPECT_NEAR(got[key].get<double>(), value.get<double>(), 1e-6) << what << "." << key;
  }
}

TEST_F(EvalCliTest, JsonReproducesTheEvoReference) {
  for (int k = 0; k < 2; ++k) {
    const nlohmann::json& c = reference_["cases"][k];
    EvalRun r = Eval(Pair(k) + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(r.err.empty()) << r.err;
    const nlohmann::json j = nlohmann::json::parse(r.out);  // exactly one object
    EXPECT_EQ(j["matched"].get<int>(), c["matched"].get<int>());
    EXPECT_EQ(j["align"], "se3");
    EXPECT_EQ(j["scale"].get<double>(), 1.0);
    ExpectStats(c["ape_se3"], j["ape"], "ape");
    ExpectStats(c["rpe_trans_delta1_frames"], j["rpe"], "rpe");
    EXPECT_EQ(j["rpe"]["pairs"].get<int>(), c["rpe_trans_delta1_frames"]["pairs"].get<int>());
    for (const char* key : {"ape_rot_deg", "rpe_rot_deg"})
      for (const char* stat : {"rmse", "mean", "median", "std", "min", "max"})
        EXPECT_TRUE(j[key][stat].is_number()) << key << "." << stat;
    EXPECT_GT(j["end_point_error"].get<double>(), 0.0);
    EXPECT_LE(j["along_axis"]["max"].get<double>(), j["ape"]["max"].get<double>() + 1e-12);
    EXPECT_TRUE(j["warnings"].is_array() && j["warnings"].empty());
    if (c.contains("ape_se3_angle_deg_rmse")) {
      EXPECT_NEAR(j["ape_rot_deg"]["rmse"].get<double>(), c["ape_se3_angle_deg_rmse"].get<double>(),
                  1e-6);
    }

    r = Eval(Pair(k) + " --align sim3 --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json s = nlohmann::json::parse(r.out);
    EXPECT_EQ(s["align"], "sim3");
    EXPECT_NEAR(s["scale"].get<double>(), c["ape_sim3"]["scale"].get<double>(), 1e-8);
    ExpectStats(c["ape_sim3"], s["ape"], "ape sim3");
  }
}

TEST_F(EvalCliTest, RpeDeltaAndAlignNoneOptions) {
  const nlohmann::json& c = reference_["cases"][0];
  EvalRun r = Eval(Pair(0) + " --rpe-delta 10 --rpe-unit frames --max-dt 0.01 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j["rpe"]["rmse"].get<double>(), c["rpe_trans_delta10_frames_rmse"].get<double>(),
              1e-6);
  r = Eval(Pair(0) + " --align=none --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  ExpectStats(c["ape_none"], j["ape"], "ape none");
  r = Eval(Pair(0) + " --rpe-delta 0.05 --rpe-unit meters --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_GT(nlohmann::json::parse(r.out)["rpe"]["pairs"].get<int>(), 10);
}

TEST_F(EvalCliTest, HumanTable) {
  const EvalRun r = Eval(Pair(0));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("matched poses  785"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("APE [m]"), std::string::npos);
  EXPECT_NE(r.out.find("0.013470"), std::string::npos) << r.out;  // APE rmse of reference.json
  EXPECT_NE(r.out.find("784 pairs"), std::string::npos);
}

TEST_F(EvalCliTest, CollinearReferenceWarnsOnStderrAndReportsOrigin) {
  std::ofstream line(dir_ + "/line.tum");
  for (int i = 0; i < 50; ++i) line << i * 0.1 << " " << 0.5 * i << " 0 0 0 0 0 1\n";
  line.close();
  const EvalRun r = Eval("--gt " + dir_ + "/line.tum --est " + dir_ + "/line.tum --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("rvlio eval: warning: se3 alignment is ill-conditioned"), std::string::npos)
      << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["align"], "origin");
  ASSERT_EQ(j["warnings"].size(), 1u);
  EXPECT_NEAR(j["ape"]["max"].get<double>(), 0.0, 1e-9);
}

TEST_F(EvalCliTest, BadInputExitsTwoWithOneLine) {
  const std::string gt = kEvo + "freiburg1_xyz-groundtruth.txt";
  ExpectBadInput("--gt " + kBad + "nope.tum --est " + gt, "nope.tum");
  ExpectBadInput("--gt " + gt + " --est " + kBad + "empty.tum", "contains no poses");
  ExpectBadInput("--gt " + gt + " --est " + kBad + "missing_value.tum", "line 5");
  ExpectBadInput("--gt " + gt + " --est " + kBad + "decreasing_stamps.tum", "line 4");
  ExpectBadInput("--gt " + gt + " --est " + kBad + "zero_quaternion.tum", "quaternion");
  ExpectBadInput("--gt " + gt + " --est " + kBad + "not_a_number.tum", "line 4");
  ExpectBadInput("--gt " + gt + " --est " + kBad + "unknown_format.txt", "found 11");
  ExpectBadInput("--gt " + gt + " --est " + kEvo + "fr2_desk_ORB.txt", "no matching timestamps");
  ExpectBadInput("--gt " + gt + " --est " + gt + " --align affine", "--align 'affine'");
  ExpectBadInput("--gt " + gt + " --est " + gt + " --rpe-unit seconds", "--rpe-unit");
  ExpectBadInput("--gt " + gt + " --est " + gt + " --rpe-delta abc", "--rpe-delta 'abc'");
  ExpectBadInput("--gt " + gt + " --est " + gt + " --rpe-delta 2.5", "whole number");
  ExpectBadInput("--gt " + gt + " --est " + gt + " --rpe-delta 100000", "no pose pair");
  ExpectBadInput("--gt " + gt, "missing required option --est");
}

}  // namespace
}  // namespace rvlio
