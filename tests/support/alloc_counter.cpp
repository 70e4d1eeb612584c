// Counts every heap allocation of the test program in g_allocations (alloc_counter.hpp): the C
// allocation functions (malloc, calloc, realloc, aligned_alloc, posix_memalign, memalign) as
// well as operator new, because Eigen allocates with std::malloc, not operator new, and CHOLMOD
// (a shared library) with malloc. One source of the one test program, ricochet_tests.
//
// Two ways, chosen at compile time:
// - Normal builds: all replaceable global operator new / delete overloads are replaced, and the
//   C functions are interposed the way glibc documents ("Replacing malloc"), forwarding to its
//   __libc_* entry points, so every block still comes from and returns to the one glibc heap.
// - AddressSanitizer builds (RICOCHET_SANITIZE, ci/sanitize): nothing is replaced. ASan
//   intercepts malloc and operator new itself, and blocks from glibc's heap would not be ASan's
//   (free would report them, or start-up crashes). Instead a hook is installed in ASan's
//   allocator (__sanitizer_install_malloc_and_free_hooks), which calls it for every block it
//   hands out, whichever entry point asked: malloc, calloc, realloc, the aligned forms, every
//   operator new, from this executable or a shared library. Counting stays complete, and a
//   no-allocation test still fails when something allocates (docs/reliability.md, "Sanitizers").
#include "tests/support/alloc_counter.hpp"

#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdlib>
#include <new>

#if defined(__SANITIZE_ADDRESS__)  // g++
#define RICOCHET_ALLOC_COUNTER_ASAN 1
#elif defined(__has_feature)  // clang
#if __has_feature(address_sanitizer)
#define RICOCHET_ALLOC_COUNTER_ASAN 1
#endif
#endif

#ifdef RICOCHET_ALLOC_COUNTER_ASAN

// Declared here because g++ 12 ships no <sanitizer/allocator_interface.h> (clang does; this is
// the same declaration). The function is exported by libasan; it returns 1 once installed.
extern "C" int __sanitizer_install_malloc_and_free_hooks(
    void (*malloc_hook)(const volatile void*, std::size_t),
    void (*free_hook)(const volatile void*));

std::atomic<long> g_allocations{0};

namespace {

void count_allocation(const volatile void*, std::size_t) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
}
void ignore_free(const volatile void*) {}

// Installed before main (the tests count only inside main); 1 when ASan took the hooks.
[[maybe_unused]] const int g_allocation_hooks_installed =
    __sanitizer_install_malloc_and_free_hooks(count_allocation, ignore_free);

}  // namespace

#else  // not ASan: interpose

extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* ptr, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
void __libc_free(void* ptr);
}

std::atomic<long> g_allocations{0};

namespace {

void* counted_alloc(std::size_t size, std::size_t alignment) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (size == 0) size = 1;
  return alignment <= alignof(std::max_align_t) ? __libc_malloc(size)
                                                : __libc_memalign(alignment, size);
}

void* new_or_throw(std::size_t size, std::size_t alignment) {
  void* p = counted_alloc(size, alignment);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}

}  // namespace

extern "C" {
void* malloc(std::size_t size) { return counted_alloc(size, 0); }
void* calloc(std::size_t count, std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_calloc(count, size);
}
void* realloc(void* ptr, std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_realloc(ptr, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_memalign(alignment, size);
}
void* memalign(std::size_t alignment, std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  void* p = __libc_memalign(alignment, size);
  if (p == nullptr) return ENOMEM;
  *out = p;
  return 0;
}
void free(void* ptr) { __libc_free(ptr); }
}

void* operator new(std::size_t size) { return new_or_throw(size, 0); }
void* operator new[](std::size_t size) { return new_or_throw(size, 0); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  return counted_alloc(size, 0);
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  return counted_alloc(size, 0);
}
void* operator new(std::size_t size, std::align_val_t al) {
  return new_or_throw(size, static_cast<std::size_t>(al));
}
void* operator new[](std::size_t size, std::align_val_t al) {
  return new_or_throw(size, static_cast<std::size_t>(al));
}
void* operator new(std::size_t size, std::align_val_t al, const std::nothrow_t&) noexcept {
  return counted_alloc(size, static_cast<std::size_t>(al));
}
void* operator new[](std::size_t size, std::align_val_t al, const std::nothrow_t&) noexcept {
  return counted_alloc(size, static_cast<std::size_t>(al));
}
void operator delete(void* p) noexcept { __libc_free(p); }
void operator delete[](void* p) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { __libc_free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { __libc_free(p); }
void operator delete(void* p, std::align_val_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { __libc_free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  __libc_free(p);
}
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  __libc_free(p);
}

#endif  // RICOCHET_ALLOC_COUNTER_ASAN
