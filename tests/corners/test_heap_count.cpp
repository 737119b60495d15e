// The allocation counter behind the "allocates nothing" tests must see the allocations the code
// under test can make: OpenCV's cv::fastMalloc and Eigen's dynamic matrices call the C allocator,
// not operator new (it counted operator new only, so these went unseen).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "../support/heap_count.hpp"

namespace {

TEST(HeapCount, SeesOpenCvAndEigenAllocationsThatBypassOperatorNew) {
  if (!naneye::test::heap_counts_malloc())
    GTEST_SKIP() << "sanitizer build: the C allocator is the sanitizer's";
  long before = naneye::test::heap_allocations();
  void* p = cv::fastMalloc(4096);  // posix_memalign (or malloc) inside OpenCV, no operator new
  const long fast = naneye::test::heap_allocations() - before;
  cv::fastFree(p);
  EXPECT_GE(fast, 1) << "cv::fastMalloc was not counted";

  before = naneye::test::heap_allocations();
  {
    cv::Mat m(250, 250, CV_16UC1);  // a frame's worth: its header (new) and its data (fastMalloc)
    m.setTo(0);
  }
  EXPECT_GE(naneye::test::heap_allocations() - before, 2) << "a cv::Mat's data was not counted";

  before = naneye::test::heap_allocations();
  {
    Eigen::MatrixXd a = Eigen::MatrixXd::Ones(40, 40);  // Eigen's aligned_malloc -> malloc
    EXPECT_EQ(a.sum(), 1600.0);
  }
  EXPECT_GE(naneye::test::heap_allocations() - before, 1) << "an Eigen dynamic matrix was not counted";

  // Fixed-size Eigen types and stack buffers stay invisible, as they should.
  before = naneye::test::heap_allocations();
  Eigen::Matrix<double, 6, 6> fixed = Eigen::Matrix<double, 6, 6>::Identity();
  EXPECT_EQ(fixed.trace(), 6.0);
  EXPECT_EQ(naneye::test::heap_allocations() - before, 0);
}

}  // namespace
