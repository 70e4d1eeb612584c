// The heap allocations of the test program so far (tests/support/alloc_counter.cpp counts every one:
// malloc and its relatives as well as operator new, also those of shared libraries). A
// no-allocation test reads it before and after the code under test.
#pragma once

#include <atomic>

extern std::atomic<long> g_allocations;

// Keeps the optimizer from removing a computation (or an allocation) whose result the test does
// not otherwise use: p escapes to an empty asm statement that may read and write memory.
template <class T>
void escape(T* p) {
  asm volatile("" : : "g"(p) : "memory");
}
