// base::upper_median: the element at index n / 2 of the ordered values, for odd and even counts,
// ties and an empty input; it reorders only its own span.
#include <gtest/gtest.h>

#include <span>
#include <vector>

#include "naneye/base/median.hpp"

namespace naneye::median_test {
namespace {

TEST(UpperMedian, IsTheOrderedElementAtHalfTheCount) {
  std::vector<double> odd{5, 1, 4, 2, 3};
  EXPECT_EQ(base::upper_median(odd), 3.0);
  std::vector<float> even{4, 1, 3, 2};
  EXPECT_EQ(base::upper_median(even), 3.0f);  // the larger of the middle two
  std::vector<int> ties{7, 7, 1, 7};
  EXPECT_EQ(base::upper_median(ties), 7);
  std::vector<double> one{-2.5};
  EXPECT_EQ(base::upper_median(one), -2.5);
}

TEST(UpperMedian, AnEmptySpanGivesZeroAndASubspanLeavesTheRest) {
  std::vector<double> none;
  EXPECT_EQ(base::upper_median(none), 0.0);
  std::vector<int> v{9, 8, 7, 3, 2, 1};
  EXPECT_EQ(base::upper_median(std::span<int>(v).first(3)), 8);
  EXPECT_EQ((std::vector<int>{v.begin() + 3, v.end()}), (std::vector<int>{3, 2, 1}));
}

}  // namespace
}  // namespace naneye::median_test
