// Large scratch buffers that the kernel backs with 2 MiB pages where it can (Linux transparent huge pages
// in "madvise" mode, Debian's default): a sweep's line storage is allocated afresh for every direction
// block, and first-touching it 4 KiB at a time cost p1 about 4 % of its CPU in page faults (on this VM each
// fault is a hypervisor round trip). Contents start uninitialised, as with new float[n]. Memory only: no
// result depends on it.
#pragma once

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

// A zeroed std::vector of n elements whose whole 2 MiB pages are advised for huge pages before the zeros
// first touch them: a large layer (p1's horizon stack) is faulted in 2 MiB at a time, and its strided
// writes miss the TLB less. Only a vector at least 4 MiB large is advised.
template <class T>
std::vector<T> make_page_vector(std::size_t n) {
  constexpr std::size_t kHuge = std::size_t(2) << 20;
  std::vector<T> v;
  v.reserve(n);
  const std::size_t bytes = n * sizeof(T);
  if (bytes >= 2 * kHuge) {
    const std::uintptr_t a = reinterpret_cast<std::uintptr_t>(v.data());
    const std::uintptr_t lo = (a + kHuge - 1) / kHuge * kHuge, hi = (a + bytes) / kHuge * kHuge;
    if (hi > lo) madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);
  }
  v.resize(n);
  return v;
}

}  // namespace hfbake
