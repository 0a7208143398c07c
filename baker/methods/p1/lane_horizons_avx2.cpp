// The lane search's kernel (lane_kernel.inc) on AVX2 (eight lanes a register, paired up to kLanes): this file
// alone is compiled with -mavx2 (and no FMA); lane_search (lane_horizons.cpp) calls it only where the
// processor has AVX2.
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

struct Avx2 {
  static constexpr int kWidth = 8;
  using F = __m256;
  using I = __m256i;
  using M = F;
  static F load(const float* p) { return _mm256_loadu_ps(p); }
  static void store(float* p, F a) { _mm256_storeu_ps(p, a); }
  static void storei(std::int32_t* p, I a) { _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), a); }
  static F set1(float x) { return _mm256_set1_ps(x); }
  static I seti(std::int32_t x) { return _mm256_set1_epi32(x); }
  static F add(F a, F b) { return _mm256_add_ps(a, b); }
  static F sub(F a, F b) { return _mm256_sub_ps(a, b); }
  static F mul(F a, F b) { return _mm256_mul_ps(a, b); }
  static F max(F a, F b) { return _mm256_max_ps(a, b); }
  static F gt(F a, F b) { return _mm256_cmp_ps(a, b, _CMP_GT_OQ); }
  static F sel(F m, F a, F b) { return _mm256_blendv_ps(b, a, m); }
  static I seli(F m, I a, I b) {
    return _mm256_castps_si256(_mm256_blendv_ps(_mm256_castsi256_ps(b), _mm256_castsi256_ps(a), m));
  }
  static bool any(F m) { return _mm256_movemask_ps(m) != 0; }
  static F or_(F a, F b) { return _mm256_or_ps(a, b); }
};

#include "methods/p1/lane_kernel.inc"

}  // namespace

void lane_search_avx2(const LaneLayout& layout, const LaneDirection& d, int s0, int s1, float tolerance,
                      LaneScratch& scratch, float* slope, std::int32_t* which, LaneStats* stats) {
  lane_search_any<Avx2>(layout, d, s0, s1, tolerance, scratch, slope, which, stats);
}

}  // namespace hfbake::p1
