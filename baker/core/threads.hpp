// How many threads a bake's parallel loops may run at once.
#pragma once

#include <algorithm>
#include <cstddef>

#include <tbb/global_control.h>

namespace hfbake {

// tbb::global_control's max_allowed_parallelism: hfbake's --threads where given (bake, merge, validate; the
// tasks' --cpus-per-task for slurm's --mem), else the machine's hardware threads. The memory estimates'
// per-thread terms count it: each thread holds its own scratch.
inline int worker_threads() {
  const std::size_t cap = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
  return int(std::clamp<std::size_t>(cap, 1, 1 << 16));
}

}  // namespace hfbake
