// Reproduces every value of test/data/evo/reference.json (statistics printed
// by evo 1.36.5 for two TUM RGB-D trajectory pairs) from the files, through
// the TUM reader and the whole evaluation pipeline.
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "rvlio/eval/evaluate.h"
#include "rvlio/formats/trajectory_io.h"

namespace rvlio {
namespace {

const std::string kEvoDir = std::string(RVLIO_TEST_DATA) + "/evo/";
// reference.json prints 6 decimals (rounding error <= 5e-7); the scale 10.
constexpr double kTol = 1e-6;
constexpr double kScaleTol = 1e-8;

nlohmann::json LoadReference() {
  std::ifstream in(kEvoDir + "reference.json");
  EXPECT_TRUE(in.good());
  return nlohmann::json::parse(in);
}

// Numbers in a JSON tree (everything the reference asserts).
int CountNumbers(const nlohmann::json& j) {
  if (j.is_number()) return 1;
  int n = 0;
  if (j.is_structured())
    for (const auto& item : j) n += CountNumbers(item);
  return n;
}

class EvoReference : public ::testing::Test {
 protected:
  EvalResult Run(const nlohmann::json& c, const std::string& align, double rpe_delta = 1.0) {
    StatusOr<Trajectory> ref = ReadTum(kEvoDir + c["ref"].get<std::string>());
    StatusOr<Trajectory> est = ReadTum(kEvoDir + c["est"].get<std::string>());
    EXPECT_TRUE(ref.ok()) << ref.status().message();
    EXPECT_TRUE(est.ok()) << est.status().message();
    EvalOptions o;
    o.align = align;
    o.rpe_delta = rpe_delta;
    StatusOr<EvalResult> r = Evaluate(*ref, *est, o);
    EXPECT_TRUE(r.ok()) << r.status().message();
    EXPECT_TRUE(r->warnings.empty());
    EXPECT_EQ(AlignModeName(r->align), align);
    return *r;
  }

  void Expect(const nlohmann::json& expected, double actual, double tol, const std::string& what) {
    EXPECT_NEAR(actual, expected.get<double>(), tol) << what;
    ++compared_;
  }

  // Compares the statistics the reference lists (rmse, mean, median, std, max).
  void ExpectStats(const nlohmann::json& expected, const ErrorStats& s, const std::string& what) {
    for (const auto& [key, value] : expected.items()) {
      if (key == "rmse")
        Expect(value, s.rmse, kTol, what + ".rmse");
      else if (key == "mean")
        Expect(value, s.mean, kTol, what + ".mean");
      else if (key == "median")
        Expect(value, s.median, kTol, what + ".median");
      else if (key == "std")
        Expect(value, s.std, kTol, what + ".std");
      else if (key == "min")
        Expect(value, s.min, kTol, what + ".min");
      else if (key == "max")
        Expect(value, s.max, kTol, what + ".max");
    }
  }

  int compared_ = 0;
};

TEST_F(EvoReference, ReproducesEveryValue) {
  const nlohmann::json reference = LoadReference();
  ASSERT_EQ(reference["cases"].size(), 2u);
  for (const nlohmann::json& c : reference["cases"]) {
    const std::string name = c["est"].get<std::string>();
    const EvalResult se3 = Run(c, "se3");
    Expect(c["matched"], static_cast<double>(se3.matched), 0.0, name + " matched");
    ExpectStats(c["ape_se3"], se3.ape_m, name + " ape_se3");
    const nlohmann::json& rpe = c["rpe_trans_delta1_frames"];
    Expect(rpe["pairs"], static_cast<double>(se3.rpe.pairs), 0.0, name + " rpe pairs");
    ExpectStats(rpe, se3.rpe.trans_m, name + " rpe delta 1");
    if (c.contains("ape_se3_angle_deg_rmse"))
      Expect(c["ape_se3_angle_deg_rmse"], se3.ape_rot_deg.rmse, kTol, name + " ape angle");
    if (c.contains("rpe_angle_deg_delta1_rmse"))
      Expect(c["rpe_angle_deg_delta1_rmse"], se3.rpe.rot_deg.rmse, kTol, name + " rpe angle");

    const EvalResult sim3 = Run(c, "sim3");
    ExpectStats(c["ape_sim3"], sim3.ape_m, name + " ape_sim3");
    Expect(c["ape_sim3"]["scale"], sim3.T_ref_est.scale, kScaleTol, name + " sim3 scale");
    if (c.contains("ape_none"))
      ExpectStats(c["ape_none"], Run(c, "none").ape_m, name + " ape_none");
    if (c.contains("rpe_trans_delta10_frames_rmse"))
      Expect(c["rpe_trans_delta10_frames_rmse"], Run(c, "se3", 10.0).rpe.trans_m.rmse, kTol,
             name + " rpe delta 10");
  }
  // Every number of the reference file was compared.
  EXPECT_EQ(compared_, CountNumbers(reference["cases"]));
}

TEST_F(EvoReference, OtherAlignmentsDoNotChangeRpeOrMatching) {
  const nlohmann::json c = LoadReference()["cases"][0];
  const EvalResult se3 = Run(c, "se3");
  const EvalResult origin = Run(c, "origin");
  EXPECT_EQ(origin.matched, se3.matched);
  EXPECT_NEAR(origin.rpe.trans_m.rmse, se3.rpe.trans_m.rmse, 1e-12);
  // Umeyama minimizes the squared APE; anchoring at the first pose cannot beat it.
  EXPECT_GT(origin.ape_m.rmse, se3.ape_m.rmse);
  EXPECT_EQ(origin.T_ref_est.scale, 1.0);
}

}  // namespace
}  // namespace rvlio
