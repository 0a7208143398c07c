// to_half_planes' F16C path (io/half_planes.hpp), compiled with -mavx -mf16c: intrinsics only, so that no
// inline function of another header is emitted here with those instructions.
#include <immintrin.h>

#include "io/half_planes.hpp"

namespace hfbake {

namespace {

// Round to nearest, ties to even, whatever MXCSR says; no precision exception (Imath's immediate).
constexpr int kRound = _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC;

std::uint16_t one(float v) {
  return std::uint16_t(_cvtss_sh(v, kRound));
}

}  // namespace

void to_half_planes_f16c(const float* src, std::size_t channels, std::size_t count, std::uint16_t* dst,
                         std::size_t plane_stride) {
  const std::size_t c8 = channels / 8 * 8;
  std::size_t i = 0;
  for (; i + 8 <= count; i += 8) {
    // Blocks of 8 texels x 8 channels: each texel's 8 halves converted at once, the 8 x 8 block of halves
    // transposed, each channel's 8 texels stored at once.
    for (std::size_t c = 0; c < c8; c += 8) {
      __m128i r[8];
      for (int k = 0; k < 8; ++k)
        r[k] = _mm256_cvtps_ph(_mm256_loadu_ps(src + (i + std::size_t(k)) * channels + c), kRound);
      const __m128i a0 = _mm_unpacklo_epi16(r[0], r[1]), a1 = _mm_unpackhi_epi16(r[0], r[1]);
      const __m128i a2 = _mm_unpacklo_epi16(r[2], r[3]), a3 = _mm_unpackhi_epi16(r[2], r[3]);
      const __m128i a4 = _mm_unpacklo_epi16(r[4], r[5]), a5 = _mm_unpackhi_epi16(r[4], r[5]);
      const __m128i a6 = _mm_unpacklo_epi16(r[6], r[7]), a7 = _mm_unpackhi_epi16(r[6], r[7]);
      const __m128i b0 = _mm_unpacklo_epi32(a0, a2), b1 = _mm_unpackhi_epi32(a0, a2);
      const __m128i b2 = _mm_unpacklo_epi32(a1, a3), b3 = _mm_unpackhi_epi32(a1, a3);
      const __m128i b4 = _mm_unpacklo_epi32(a4, a6), b5 = _mm_unpackhi_epi32(a4, a6);
      const __m128i b6 = _mm_unpacklo_epi32(a5, a7), b7 = _mm_unpackhi_epi32(a5, a7);
      const __m128i t[8] = {_mm_unpacklo_epi64(b0, b4), _mm_unpackhi_epi64(b0, b4),
                            _mm_unpacklo_epi64(b1, b5), _mm_unpackhi_epi64(b1, b5),
                            _mm_unpacklo_epi64(b2, b6), _mm_unpackhi_epi64(b2, b6),
                            _mm_unpacklo_epi64(b3, b7), _mm_unpackhi_epi64(b3, b7)};
      for (int k = 0; k < 8; ++k)
        _mm_storeu_si128(reinterpret_cast<__m128i*>(dst + (c + std::size_t(k)) * plane_stride + i), t[k]);
    }
    for (std::size_t c = c8; c < channels; ++c)
      for (std::size_t k = 0; k < 8; ++k) dst[c * plane_stride + i + k] = one(src[(i + k) * channels + c]);
  }
  for (; i < count; ++i)
    for (std::size_t c = 0; c < channels; ++c) dst[c * plane_stride + i] = one(src[i * channels + c]);
}

}  // namespace hfbake
