#include "io/half_planes.hpp"

#include <Imath/half.h>

#include "core/instruction_set.hpp"

namespace hfbake {

void to_half_planes_portable(const float* src, std::size_t channels, std::size_t count, std::uint16_t* dst,
                             std::size_t plane_stride) {
  for (std::size_t i = 0; i < count; ++i)
    for (std::size_t c = 0; c < channels; ++c) dst[c * plane_stride + i] = half(src[i * channels + c]).bits();
}

bool half_planes_f16c_available() {
  static const bool f16c = __builtin_cpu_supports("avx") && __builtin_cpu_supports("f16c");
  return f16c;
}

void to_half_planes(const float* src, std::size_t channels, std::size_t count, std::uint16_t* dst,
                    std::size_t plane_stride) {
  static const bool f16c = instruction_set_cap() >= InstructionSet::avx2 && half_planes_f16c_available();
  if (f16c)
    to_half_planes_f16c(src, channels, count, dst, plane_stride);
  else
    to_half_planes_portable(src, channels, count, dst, plane_stride);
}

}  // namespace hfbake
