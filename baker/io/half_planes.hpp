// Interleaved floats into planes of OpenEXR halves: how the EXR writer converts a band of a layer's rows.
#pragma once

#include <cstddef>
#include <cstdint>

namespace hfbake {

// Texels [0, count) of `channels` interleaved floats (src[i * channels + c]) as half bits in planes
// dst[c * plane_stride + i]: each value rounded to the nearest half, ties to even, as Imath's half(float)
// (beyond 65504 an infinity; a NaN stays a NaN). Uses F16C where the processor has it and
// instruction_set_cap() allows AVX2 (core/instruction_set.hpp); every path gives the same bits for every
// value but a NaN's payload.
void to_half_planes(const float* src, std::size_t channels, std::size_t count, std::uint16_t* dst,
                    std::size_t plane_stride);

// The paths, for tests: Imath's conversion, and F16C (only where half_planes_f16c_available()).
void to_half_planes_portable(const float* src, std::size_t channels, std::size_t count, std::uint16_t* dst,
                             std::size_t plane_stride);
void to_half_planes_f16c(const float* src, std::size_t channels, std::size_t count, std::uint16_t* dst,
                         std::size_t plane_stride);
bool half_planes_f16c_available();

}  // namespace hfbake
