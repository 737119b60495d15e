// The replaced global allocation functions behind heap_count.hpp. malloc-based, so ASan still sees
// every block. Eigen's dynamic matrices and OpenCV's cv::fastMalloc call malloc directly and are not
// counted: code that claims "no allocation" must also avoid those (fixed-size Eigen types, no cv::Mat
// created per frame).
#include "heap_count.hpp"

#include <atomic>
#include <cstdlib>
#include <new>

namespace {
std::atomic<long> g_allocations{0};

void* counted(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}

void* counted_aligned(std::size_t n, std::align_val_t a) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  const auto al = static_cast<std::size_t>(a);
  if (void* p = std::aligned_alloc(al, (n + al - 1) / al * al)) return p;
  throw std::bad_alloc();
}
}  // namespace

long naneye::test::heap_allocations() {
  return g_allocations.load(std::memory_order_relaxed);
}

// Out of line: inlined into a delete expression, GCC would see free() on a pointer from new
// (-Wmismatched-new-delete under -O1 and the sanitizers).
[[gnu::noinline]] void* operator new(std::size_t n) {
  return counted(n);
}
[[gnu::noinline]] void* operator new[](std::size_t n) {
  return counted(n);
}
[[gnu::noinline]] void* operator new(std::size_t n, std::align_val_t a) {
  return counted_aligned(n, a);
}
[[gnu::noinline]] void* operator new[](std::size_t n, std::align_val_t a) {
  return counted_aligned(n, a);
}
[[gnu::noinline]] void operator delete(void* p) noexcept {
  std::free(p);
}
[[gnu::noinline]] void operator delete[](void* p) noexcept {
  std::free(p);
}
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
[[gnu::noinline]] void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
[[gnu::noinline]] void operator delete(void* p, std::align_val_t) noexcept {
  std::free(p);
}
[[gnu::noinline]] void operator delete[](void* p, std::align_val_t) noexcept {
  std::free(p);
}
[[gnu::noinline]] void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}
[[gnu::noinline]] void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}
