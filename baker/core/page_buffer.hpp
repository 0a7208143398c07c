// Large scratch buffers that the kernel backs with 2 MiB pages where it can (Linux transparent huge pages
// in "madvise" mode, Debian's default): a sweep's line storage is allocated afresh for every direction
// block, and first-touching it 4 KiB at a time cost p1 about 4 % of its CPU in page faults (on this VM each
// fault is a hypervisor round trip). Contents start uninitialised, as with new float[n]. Memory only: no
// result depends on it. For scratch that is written many times: a buffer written once is cheaper on 4 KiB
// pages on such a VM (methods/p1/p1.cpp, compute_p1's horizon layers).
#pragma once

#include <malloc.h>
#include <sys/mman.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <vector>

namespace hfbake {

struct PageBufferFree {
  void operator()(void* p) const noexcept { std::free(p); }
};

template <class T>
using PageBuffer = std::unique_ptr<T[], PageBufferFree>;

// n elements of T (trivially constructible), 2 MiB aligned and advised for huge pages when at least 2 MiB.
template <class T>
PageBuffer<T> make_page_buffer(std::size_t n) {
  constexpr std::size_t kHuge = std::size_t(2) << 20;
  const std::size_t bytes = n * sizeof(T);
  if (bytes < kHuge) {
    void* p = std::malloc(bytes > 0 ? bytes : 1);
    if (!p) throw std::bad_alloc();
    return PageBuffer<T>(static_cast<T*>(p));
  }
  const std::size_t rounded =
      (bytes + kHuge - 1) / kHuge * kHuge;  // aligned_alloc: a multiple of the alignment
  void* p = std::aligned_alloc(kHuge, rounded);
  if (!p) throw std::bad_alloc();
  madvise(p, rounded, MADV_HUGEPAGE);  // advice only: where it is refused, the usual 4 KiB pages
  return PageBuffer<T>(static_cast<T*>(p));
}

// n zeros, their pages faulted in by one call (MADV_POPULATE_WRITE, Linux 5.14) before they are zeroed:
// for a large buffer written once, such as a layer, where faulting 4 KiB pages one at a time costs a
// hypervisor round trip each on a virtual machine (a 256 MiB horizon layer: 0.7 s of first touches against
// 0.4 s populated). A kernel without the advice faults them in as they are zeroed.
template <class T>
std::vector<T> populated_zeros(std::size_t n) {
  std::vector<T> v;
  v.reserve(n);
  constexpr std::uintptr_t kPage = 4096;
  const auto first = (reinterpret_cast<std::uintptr_t>(v.data()) + kPage - 1) & ~(kPage - 1);
  const auto end = reinterpret_cast<std::uintptr_t>(v.data() + n) & ~(kPage - 1);
#ifdef MADV_POPULATE_WRITE
  if (end > first) madvise(reinterpret_cast<void*>(first), end - first, MADV_POPULATE_WRITE);
#endif
  v.resize(n);
  return v;
}

// Hands the memory freed inside the heap back to the kernel (glibc's malloc_trim): buffers a phase of a bake
// freed (1 to 32 MiB each, below glibc's mmap threshold once it has grown) otherwise stay resident, and
// fragmented, beside the next phase's. The memory estimates take a bake's phases as not coinciding
// (docs/large-fields.md): a method calls this between phases whose largest buffers are freed (p2 after its
// direct light and after each direction block of a bounce). Memory only: no result depends on it.
inline void release_freed_memory() {
  malloc_trim(0);
}

}  // namespace hfbake
