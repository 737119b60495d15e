// Heap allocations of the whole test process, counted by the replaced global operator new in
// heap_count.cpp (linked into the test binaries that check "no allocation per frame"). Tests take
// the difference around the code under test.
#pragma once

namespace naneye::test {

// Every operator new (plain, array, aligned) since the process started, all threads.
long heap_allocations();

}  // namespace naneye::test
