// The row-run lighting (row_shading_kernel.inc) compiled for AVX2, 8 floats a register: this file alone
// is compiled with -mavx2 -mno-fma -ffp-contract=off (no fused multiply-add), so its bits are the SSE2
// kernel's; shade_row_kernel returns it only where the processor runs AVX2.
#include <cstddef>

#include "methods/p1/fast_math.hpp"
#include "methods/p1/row_shading.hpp"

namespace hfbake::p1 {

namespace {
#include "methods/p1/row_shading_kernel.inc"
}  // namespace

void shade_row_avx2(const ShadeRowTarget& t, const ShadeRowRun& run) {
  shade_row_body(t, run);
}

}  // namespace hfbake::p1
