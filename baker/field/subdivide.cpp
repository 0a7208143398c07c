#include "field/subdivide.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>

namespace hfbake {

FieldShape subdivided_shape(const FieldShape& coarse, int s) {
  FieldShape f = coarse;
  const bool repeat = coarse.wrap == Wrap::repeat;
  f.width = repeat ? coarse.width * s : (coarse.width - 1) * s + 1;
  f.height = repeat ? coarse.height * s : (coarse.height - 1) * s + 1;
  f.texel_size = coarse.texel_size / s;
  if (coarse.texel_size_y > 0) f.texel_size_y = coarse.texel_size_y / s;
  return f;
}

namespace {
// The coarse quad along one axis holding fine texel f and the fraction across it. On a clamp field the last
// fine texel lies at fraction 1 of the last quad (a field one texel wide has none: quad 0, fraction 0).
void quad_of(int f, int s, int n, Wrap wrap, int& q, double& t) {
  q = f / s;
  if (wrap == Wrap::clamp) q = std::max(0, std::min(q, n - 2));
  t = n < 2 && wrap == Wrap::clamp ? 0.0 : double(f - q * s) / s;
}
}  // namespace

FineTexelWeights fine_texel_weights(const FieldShape& coarse, int s, int fi, int fj) {
  FineTexelWeights r;
  double fx = 0, fy = 0;
  quad_of(fi, s, coarse.width, coarse.wrap, r.i, fx);
  quad_of(fj, s, coarse.height, coarse.wrap, r.j, fy);
  r.w = facet_weights(fx, fy);
  return r;
}

namespace {
// The weights in W: double for heights, float for colours (as surface_at weighs them).
template <class T, class W, class Value>
std::vector<T> interpolate(const HeightField& coarse, int s, Value value) {
  const FieldShape fine = subdivided_shape(coarse, s);
  std::vector<T> out(std::size_t(fine.width) * std::size_t(fine.height));
  tbb::parallel_for(0, fine.height, [&](int fj) {
    for (int fi = 0; fi < fine.width; ++fi) {
      const FineTexelWeights t = fine_texel_weights(coarse, s, fi, fj);
      T sum{};
      for (int c = 0; c < 3; ++c) {
        const std::size_t at = coarse.index(coarse.wrap_i(t.i + t.w.di[c]), coarse.wrap_j(t.j + t.w.dj[c]));
        sum = sum + value(at) * W(t.w.w[c]);
      }
      out[std::size_t(fj) * std::size_t(fine.width) + std::size_t(fi)] = sum;
    }
  });
  return out;
}
}  // namespace

HeightField subdivided_field(const HeightField& coarse, int s) {
  HeightField f;
  static_cast<FieldShape&>(f) = subdivided_shape(coarse, s);
  const std::vector<double> z =
      interpolate<double, double>(coarse, s, [&](std::size_t t) { return double(coarse.z[t]); });
  f.z.assign(z.begin(), z.end());
  return f;
}

std::vector<Rgb> subdivided_values(const HeightField& coarse, int s, const std::vector<Rgb>& values) {
  return interpolate<Rgb, float>(coarse, s, [&](std::size_t t) { return values[t]; });
}

}  // namespace hfbake
