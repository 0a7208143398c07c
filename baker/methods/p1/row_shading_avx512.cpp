// The row-run lighting (row_shading_kernel.inc) compiled for AVX-512F, 16 floats a register: this file
// alone is compiled with -mavx512f -ffp-contract=off (no fused multiply-add), so its bits are the SSE2
// kernel's; shade_row_kernel returns it only where the processor runs AVX-512F.
#include <cstddef>

#include "methods/p1/fast_math.hpp"
#include "methods/p1/row_shading.hpp"

namespace hfbake::p1 {

namespace {
#include "methods/p1/row_shading_kernel.inc"
}  // namespace

void shade_row_avx512(const ShadeRowTarget& t, const ShadeRowRun& run) {
  shade_row_body(t, run);
}

}  // namespace hfbake::p1
