#include "io/half_planes.hpp"

#include <Imath/half.h>
#include <cpuid.h>

#include "core/instruction_set.hpp"

namespace hfbake {

void to_half_planes_portable(const float* src, std::size_t channels, std::size_t count, std::uint16_t* dst,
                             std::size_t plane_stride) {
  for (std::size_t i = 0; i < count; ++i)
    for (std::size_t c = 0; c < channels; ++c) dst[c * plane_stride + i] = half(src[i * channels + c]).bits();
}

bool half_planes_f16c_available() {
  // AVX with the operating system's support of its registers (the builtin checks both), and F16C (CPUID
  // leaf 1, ECX bit 29: read directly, as not every compiler's builtin knows the name).
  static const bool f16c = [] {
    unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
    return __builtin_cpu_supports("avx") && __get_cpuid(1, &eax, &ebx, &ecx, &edx) && (ecx & bit_F16C) != 0;
  }();
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
