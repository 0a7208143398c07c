// to_half_planes (io/half_planes.hpp): each path's bits against Imath's half(float) (compiled here for the
// baseline, its portable rounding), on every sign, exponent and leading ten mantissa bits of a float, each
// with the low bits that decide a rounding: exactly representable, just below, at and just above half an
// ulp of half, and just below a whole one.
#include <Imath/half.h>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "io/half_planes.hpp"

namespace hfbake {
namespace {

std::vector<float> rounding_cases() {
  std::vector<float> v;
  const std::uint32_t low[] = {0x0000, 0x0001, 0x0fff, 0x1000, 0x1001, 0x1fff, 0x0800, 0x17ff};
  for (std::uint32_t sign = 0; sign < 2; ++sign)
    for (std::uint32_t e = 0; e < 256; ++e)
      for (std::uint32_t m = 0; m < 1024; ++m)
        for (std::uint32_t l : low) {
          const std::uint32_t mant = (m << 13) | l;
          if (e == 255 && mant != 0) continue;  // NaN: tested apart (its payload is not kept)
          v.push_back(std::bit_cast<float>((sign << 31) | (e << 23) | mant));
        }
  return v;
}

using Path = void (*)(const float*, std::size_t, std::size_t, std::uint16_t*, std::size_t);

void expect_imath_bits(Path path, const char* name) {
  const std::vector<float> values = rounding_cases();
  for (const std::size_t channels : {1, 3, 8, 9, 16, 64}) {
    const std::size_t count = values.size() / channels;  // texels; the values interleaved as they come
    const std::size_t stride = count + 13;               // planes apart by more than a plane
    std::vector<std::uint16_t> planes(stride * channels, 0xdead);
    path(values.data(), channels, count, planes.data(), stride);
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < count; ++i)
      for (std::size_t c = 0; c < channels; ++c) {
        const float f = values[i * channels + c];
        const std::uint16_t got = planes[c * stride + i], want = half(f).bits();
        if (got != want && ++wrong <= 5)
          ADD_FAILURE() << name << ", " << channels << " channels: " << f << " (0x" << std::hex
                        << std::bit_cast<std::uint32_t>(f) << ") gave 0x" << got << ", Imath 0x" << want;
      }
    EXPECT_EQ(wrong, 0u) << name << ", " << channels << " channels";
    for (std::size_t c = 0; c < channels; ++c)  // nothing written beyond a plane's texels
      for (std::size_t i = count; i < stride; ++i) ASSERT_EQ(planes[c * stride + i], 0xdead);
  }
}

TEST(HalfPlanes, PortablePathIsImathsRounding) {
  expect_imath_bits(to_half_planes_portable, "portable");
}

TEST(HalfPlanes, F16cPathIsImathsRounding) {
  if (!half_planes_f16c_available()) GTEST_SKIP() << "this processor has no F16C";
  expect_imath_bits(to_half_planes_f16c, "F16C");
}

TEST(HalfPlanes, DispatchedPathIsImathsRounding) {
  expect_imath_bits(to_half_planes, "dispatched");
}

TEST(HalfPlanes, ANanStaysANan) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> v(64 * 9, 0.5f);
  v[0] = v[70] = v[64 * 9 - 1] = nan;
  for (Path path : {Path(to_half_planes_portable), Path(to_half_planes)}) {
    std::vector<std::uint16_t> planes(64 * 9);
    path(v.data(), 64, 9, planes.data(), 9);
    for (std::size_t i = 0; i < 9; ++i)
      for (std::size_t c = 0; c < 64; ++c) {
        EXPECT_EQ(std::isnan(float(half(half::FromBits, planes[c * 9 + i]))), std::isnan(v[i * 64 + c]));
      }
  }
}

}  // namespace
}  // namespace hfbake
