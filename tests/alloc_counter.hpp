// The heap allocations of the test program so far (tests/alloc_counter.cpp counts every one:
// malloc and its relatives as well as operator new, also those of shared libraries). A
// no-allocation test reads it before and after the code under test.
#pragma once

#include <atomic>

extern std::atomic<long> g_allocations;
