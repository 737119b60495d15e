// The replaced global allocation functions behind heap_count.hpp: operator new (all forms) and,
// outside the sanitizer builds, the C allocator itself (malloc, calloc, realloc, posix_memalign,
// aligned_alloc, memalign), which Eigen's dynamic matrices and OpenCV's cv::fastMalloc call
// directly: counting operator new alone, the "allocates nothing" tests could not see a cv::Mat.
// The C functions forward to glibc's own entry points (__libc_malloc...). Under ASan/TSan they are
// not replaced: the sanitizer's interceptors must see every block, and operator new still counts.
#include "heap_count.hpp"

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <new>
#include <opencv2/core/utility.hpp>

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define NANEYE_COUNT_MALLOC 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define NANEYE_COUNT_MALLOC 0
#endif
#endif
#ifndef NANEYE_COUNT_MALLOC
#define NANEYE_COUNT_MALLOC 1
#endif

namespace {
std::atomic<long> g_allocations{0};

void* counted(std::size_t n) {
  // Counted once here: with the C allocator replaced, std::malloc would count it a second time.
  if (void* p = std::malloc(n ? n : 1)) {
    if (!NANEYE_COUNT_MALLOC) g_allocations.fetch_add(1, std::memory_order_relaxed);
    return p;
  }
  throw std::bad_alloc();
}

void* counted_aligned(std::size_t n, std::align_val_t a) {
  const auto al = static_cast<std::size_t>(a);
  if (void* p = std::aligned_alloc(al, (n + al - 1) / al * al)) {
    if (!NANEYE_COUNT_MALLOC) g_allocations.fetch_add(1, std::memory_order_relaxed);
    return p;
  }
  throw std::bad_alloc();
}
}  // namespace

long naneye::test::heap_allocations() {
  return g_allocations.load(std::memory_order_relaxed);
}

bool naneye::test::heap_counts_malloc() {
  return NANEYE_COUNT_MALLOC != 0;
}

void naneye::test::keep_opencv_on_this_thread() {
  cv::setNumThreads(1);
}

#if NANEYE_COUNT_MALLOC
// glibc's allocator under its internal names (exported since GLIBC_2.2.5).
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void __libc_free(void*);

void* malloc(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t n) {
  // A realloc may move the block: a new allocation as far as "allocates nothing" is concerned.
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_realloc(p, n);
}
void free(void* p) {
  __libc_free(p);
}
void* memalign(std::size_t alignment, std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_memalign(alignment, n);
}
void* aligned_alloc(std::size_t alignment, std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_memalign(alignment, n);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t n) {
  if (alignment < sizeof(void*) || (alignment & (alignment - 1)) != 0) return EINVAL;
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  void* p = __libc_memalign(alignment, n);
  if (!p) return ENOMEM;
  *out = p;
  return 0;
}
}
#endif

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
