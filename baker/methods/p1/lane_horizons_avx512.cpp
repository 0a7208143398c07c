// The lane search's kernel (lane_kernel.inc) on AVX-512F (16 lanes a register, paired up to kLanes): this
// file alone is compiled with -mavx512f and -ffp-contract=off (no fused multiply-add is formed, so the bits
// are the SSE2 kernel's); lane_search calls it only where the processor and the operating system have
// AVX-512F.
#include <immintrin.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <type_traits>

#include "methods/p1/lane_horizons.hpp"

namespace hfbake::p1 {

namespace {

struct Avx512 {
  static constexpr int kWidth = 16;
  using F = __m512;
  using I = __m512i;
  using M = __mmask16;
  static F load(const float* p) { return _mm512_loadu_ps(p); }
  static void store(float* p, F a) { _mm512_storeu_ps(p, a); }
  static void storei(std::int32_t* p, I a) { _mm512_storeu_si512(p, a); }
  static F set1(float x) { return _mm512_set1_ps(x); }
  static I seti(std::int32_t x) { return _mm512_set1_epi32(x); }
  static F add(F a, F b) { return _mm512_add_ps(a, b); }
  static F sub(F a, F b) { return _mm512_sub_ps(a, b); }
  static F mul(F a, F b) { return _mm512_mul_ps(a, b); }
  // _mm512_max_ps's own header draws a false -Wmaybe-uninitialized from GCC 12; the masked form with every
  // lane set is the same instruction.
  static F max(F a, F b) { return _mm512_mask_max_ps(a, __mmask16(0xFFFF), a, b); }
  static M gt(F a, F b) { return _mm512_cmp_ps_mask(a, b, _CMP_GT_OQ); }
  static F sel(M m, F a, F b) { return _mm512_mask_blend_ps(m, b, a); }
  static I seli(M m, I a, I b) { return _mm512_mask_blend_epi32(m, b, a); }
  static bool any(M m) { return m != 0; }
  static M or_(M a, M b) { return M(a | b); }
};

#include "methods/p1/lane_kernel.inc"

}  // namespace

void lane_search_avx512(const LaneLayout& layout, const LaneDirection& d, int s0, int s1, float tolerance,
                        LaneScratch& scratch, float* slope, std::int32_t* which, LaneStats* stats) {
  lane_search_any<Avx512>(layout, d, s0, s1, tolerance, scratch, slope, which, stats);
}

}  // namespace hfbake::p1
