// The shared helpers of common/median.h and common/text.h.
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/common/median.h"
#include "rvlio/common/text.h"

namespace rvlio {
namespace {

TEST(MedianTest, MedianAveragesTheMiddlePairUpperMedianTakesTheUpper) {
  EXPECT_EQ(Median({3.0, 1.0, 2.0}), 2.0);
  EXPECT_EQ(Median({4.0, 1.0, 3.0, 2.0}), 2.5);  // numpy.median
  EXPECT_EQ(UpperMedian(std::vector<double>{4.0, 1.0, 3.0, 2.0}), 3.0);
  EXPECT_EQ(UpperMedian(std::vector<int64_t>{30, 10, 20}), 20);
  EXPECT_TRUE(std::isnan(Median({})));
  EXPECT_EQ(UpperMedian(std::vector<double>{}), 0.0);
}

TEST(TextTest, NumbersAndLists) {
  EXPECT_EQ(FormatG(0.1), "0.1");
  EXPECT_EQ(FormatG(2e-05), "2e-05");
  EXPECT_EQ(FormatG(1.0 / 3.0, 3), "0.333");
  EXPECT_EQ(FormatFinite(1.0 / 3.0, 10), "0.3333333333");
  EXPECT_EQ(FormatFinite(std::numeric_limits<double>::quiet_NaN(), 6), "");
  EXPECT_EQ(FormatFinite(std::numeric_limits<double>::infinity(), 6), "");
  EXPECT_EQ(FormatFixed(2.0 / 3.0, 3), "0.667");
  EXPECT_EQ(FormatFixed(-1e300, 0).size(), 302u);  // no truncation
  EXPECT_EQ(Join({}, ", "), "");
  EXPECT_EQ(Join({"a", "b", "c"}, ", "), "a, b, c");
}

}  // namespace
}  // namespace rvlio
