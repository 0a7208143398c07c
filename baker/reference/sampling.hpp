// Sample points for the reference: Owen-scrambled Sobol (0,2)-sequences, one independent 2D sequence per
// "dimension pair" (the directions of one estimator at one path vertex), per texel and per replicate.
// Every value is a pure function of (seed, texel, replicate, pair, index), so any thread count and any
// tile order produce the same bits.
//
// Scrambling: nested uniform (Owen) scrambling of each coordinate and of the sample index, done with a
// hash that only lets lower digits influence higher ones (Laine-Karras; Burley 2020, "Practical hash-based
// Owen scrambling"). The first 2^m points of every pair then form a (0, m, 2)-net, and differently
// seeded pairs are independent random scrambles: the replicate means are i.i.d., which is what the
// reference's standard errors are computed from.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/vec.hpp"

namespace hfbake::reference {

inline std::uint64_t mix64(std::uint64_t x) {  // splitmix64 finaliser
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}
inline std::uint64_t hash_combine(std::uint64_t a, std::uint64_t b) {
  return mix64(a ^ mix64(b));
}

inline std::uint32_t reverse_bits(std::uint32_t x) {
  x = __builtin_bswap32(x);  // the bytes reversed; then the bits within each byte
  x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
  x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
  return ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
}

// A bijection on 32-bit words in which bit k of the result depends only on bits 0..k of x: applied to
// bit-reversed values it permutes digits nested from the most significant one (an Owen scramble).
inline std::uint32_t nested_permutation(std::uint32_t x, std::uint32_t seed) {
  x += seed;
  x ^= x * 0x6c50b47cu;
  x ^= x * 0xb82f1e52u;
  x ^= x * 0xc7afe638u;
  x ^= x * 0x8d22f6e6u;
  return x;
}
inline std::uint32_t owen_scramble(std::uint32_t x, std::uint32_t seed) {
  return reverse_bits(nested_permutation(reverse_bits(x), seed));
}

// The first two Sobol dimensions as 32-bit fractions: van der Corput, and the sequence with direction
// numbers v_0 = 2^31, v_k = v_{k-1} ^ (v_{k-1} >> 1): the XOR of v_k over the set bits k of the index,
// here 8 bits at a time from tables of the XORs of every byte's bits (the same bits as the bit loop, four
// loads instead of 32 data-dependent branches: it was a tenth of the reference's time).
inline std::uint32_t sobol_dim0(std::uint32_t index) {
  return reverse_bits(index);
}
struct SobolDim1Tables {
  std::uint32_t t[4][256] = {};
  constexpr SobolDim1Tables() {
    std::uint32_t v[32] = {};
    v[0] = 1u << 31;
    for (int k = 1; k < 32; ++k) v[k] = v[k - 1] ^ (v[k - 1] >> 1);
    for (int b = 0; b < 4; ++b)
      for (int x = 0; x < 256; ++x)
        for (int k = 0; k < 8; ++k)
          if (x & (1 << k)) t[b][x] ^= v[8 * b + k];
  }
};
inline constexpr SobolDim1Tables kSobolDim1{};
inline std::uint32_t sobol_dim1(std::uint32_t index) {
  return kSobolDim1.t[0][index & 0xffu] ^ kSobolDim1.t[1][(index >> 8) & 0xffu] ^
         kSobolDim1.t[2][(index >> 16) & 0xffu] ^ kSobolDim1.t[3][index >> 24];
}

inline double to_unit(std::uint32_t x) {
  return double(x) * (1.0 / 4294967296.0);  // [0, 1)
}

struct Point2 {
  double u = 0, v = 0;
};

// One scrambled 2D sequence.
struct Sequence2 {
  std::uint32_t index_seed = 0, seed_u = 0, seed_v = 0;

  static Sequence2 make(std::uint64_t stream) {
    const std::uint64_t a = mix64(stream), b = mix64(a);
    return {std::uint32_t(a), std::uint32_t(a >> 32), std::uint32_t(b)};
  }
  Point2 operator()(std::uint32_t i) const {
    const std::uint32_t s = owen_scramble(i, index_seed);  // shuffles the order, keeps 2^m prefixes nets
    // owen_scramble(sobol_dim0(s), seed_u), whose two bit reversals cancel: reverse(reverse(s)) = s.
    const std::uint32_t u = reverse_bits(nested_permutation(s, seed_u));
    return {to_unit(u), to_unit(owen_scramble(sobol_dim1(s), seed_v))};
  }
};

// --- warps from [0,1)^2 to directions -------------------------------------------------------------

// An orthonormal basis around unit n (Duff et al. 2017).
inline void basis(Vec3 n, Vec3& t, Vec3& b) {
  const double s = n.z >= 0 ? 1.0 : -1.0;
  const double a = -1.0 / (s + n.z), c = n.x * n.y * a;
  t = {1.0 + s * n.x * n.x * a, s * c, -s * n.x};
  b = {c, s + n.y * n.y * a, -n.y};
}

// The basis around unit n, made once for many directions.
struct Frame {
  Vec3 t, b, n;
  explicit Frame(Vec3 normal) : n(normal) { basis(n, t, b); }
};

// Cosine-weighted hemisphere around unit n: pdf cos(theta) / pi.
inline Vec3 cosine_hemisphere(const Frame& f, Point2 p) {
  const double r = std::sqrt(p.u), phi = 2 * kPi * p.v;
  const double z = std::sqrt(std::max(0.0, 1.0 - p.u));
  return f.t * (r * std::cos(phi)) + f.b * (r * std::sin(phi)) + f.n * z;
}
inline Vec3 cosine_hemisphere(Vec3 n, Point2 p) {
  return cosine_hemisphere(Frame(n), p);
}

// Uniform over the upper (+z) hemisphere: pdf 1 / (2 pi). z = u is uniform (Archimedes), so the fraction
// of samples escaping in an azimuth with horizon elevation h is 1 - sin h.
inline Vec3 uniform_upper_hemisphere(Point2 p) {
  const double z = p.u, r = std::sqrt(std::max(0.0, 1.0 - z * z)), phi = 2 * kPi * p.v;
  return {r * std::cos(phi), r * std::sin(phi), z};
}

// Uniform over the hemisphere around f.n: pdf 1 / (2 pi).
inline Vec3 uniform_hemisphere(const Frame& f, Point2 p) {
  const double z = p.u, r = std::sqrt(std::max(0.0, 1.0 - z * z)), phi = 2 * kPi * p.v;
  return f.t * (r * std::cos(phi)) + f.b * (r * std::sin(phi)) + f.n * z;
}

// Uniform over the cone of half-angle alpha around unit axis d; one_minus_cos = 1 - cos(alpha) (passed in
// so tiny cones keep their precision). pdf 1 / (2 pi one_minus_cos).
inline Vec3 uniform_cone(Vec3 d, double one_minus_cos, Point2 p) {
  const double one_minus_z = p.u * one_minus_cos;
  const double z = 1.0 - one_minus_z;
  const double r = std::sqrt(std::max(0.0, one_minus_z * (2.0 - one_minus_z))), phi = 2 * kPi * p.v;
  Vec3 t, b;
  basis(d, t, b);
  return t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + d * z;
}

}  // namespace hfbake::reference
