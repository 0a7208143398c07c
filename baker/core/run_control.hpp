// What a long-running bake needs from its caller: cancellation and progress (no globals).
#pragma once

#include <atomic>
#include <functional>

#include "core/error.hpp"

namespace hfbake {

struct RunControl {
  const std::atomic<bool>* cancel = nullptr;      // set by the SIGINT handler; may be null
  std::function<void(double fraction)> progress;  // 0..1 for the current method; may be empty; thread-safe

  bool cancelled() const { return cancel && cancel->load(std::memory_order_relaxed); }
  // Call between work items (a line, a tile); throws Cancelled so no output is written.
  void check() const {
    if (cancelled()) throw Cancelled();
  }
  void report(double fraction) const {
    if (progress) progress(fraction);
  }
};

}  // namespace hfbake
