// Heap allocations of the whole test process, counted by the replaced global operator new and C
// allocator in heap_count.cpp (linked into the test binaries that check "no allocation per
// frame"). Tests take the difference around the code under test.
#pragma once

namespace naneye::test {

// Every operator new (plain, array, aligned) and, when heap_counts_malloc(), every malloc, calloc,
// realloc, memalign, aligned_alloc and posix_memalign since the process started, all threads.
long heap_allocations();
// False in the sanitizer builds, where the C allocator belongs to the sanitizer (operator new only).
bool heap_counts_malloc();
// OpenCV on the calling thread (cv::setNumThreads(1)), as the processor runs it (app/src/processor.cpp).
// Call it before a test renders anything: the count is the whole process's, and a render's
// cv::GaussianBlur wakes OpenCV's pool, whose workers' late bookkeeping once landed between the
// counts (SparseAllocations under ctest -j2, 2026-12-07, never seen with the test alone).
void keep_opencv_on_this_thread();

}  // namespace naneye::test
