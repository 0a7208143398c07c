#include "reference/env_sampler.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace hfbake::reference {
namespace {

// Index i with cdf[i] <= u < cdf[i + 1] (cdf ascending, cdf.front() = 0, cdf.back() = 1); skips empty bins.
int find_interval(const double* cdf, int n, double u) {
  const double* it = std::upper_bound(cdf, cdf + n + 1, u);
  int i = int(it - cdf) - 1;
  i = std::clamp(i, 0, n - 1);
  while (i > 0 && cdf[i + 1] <= cdf[i]) --i;  // never land in a zero-width bin
  while (i < n - 1 && cdf[i + 1] <= cdf[i]) ++i;
  return i;
}

}  // namespace

EnvSampler::EnvSampler(const Environment& env) {
  if (env.levels.empty()) return;
  const Environment::Level& l0 = env.levels[0];
  width_ = l0.width;
  height_ = l0.height;
  col_cdf_.assign(std::size_t(height_) * (width_ + 1), 0.0);
  row_cdf_.assign(height_ + 1, 0.0);
  row_mass_.assign(height_, 0.0);
  texel_pdf_.assign(std::size_t(width_) * height_, 0.0);
  // A texel's weight is the mass the radiance lookup gives it: the lookup is bilinear between texel centres,
  // so a texel's own luminance spreads 3/4 of the way across it and 1/8 into each neighbour (per axis;
  // columns wrap, rows clamp). Weighting texels by their own luminance alone, a small bright source (a sun
  // in one texel) reached its neighbours through the lookup while the distribution seldom sampled them, and
  // the estimate's noise exceeded its mean.
  constexpr double kTap[3] = {0.125, 0.75, 0.125};
  std::vector<double> weight(std::size_t(width_) * height_, 0.0);
  for (int r = 0; r < height_; ++r)
    for (int c = 0; c < width_; ++c) {
      double w = 0;
      for (int dr = -1; dr <= 1; ++dr) {
        const int rr = std::clamp(r + dr, 0, height_ - 1);
        for (int dc = -1; dc <= 1; ++dc) {
          const int cc = (c + dc + width_) % width_;
          w += kTap[dr + 1] * kTap[dc + 1] * sampling_weight(l0.texels[std::size_t(rr) * width_ + cc]);
        }
      }
      weight[std::size_t(r) * width_ + c] = w;
    }
  std::vector<double> row_sum(height_, 0.0);
  for (int r = 0; r < height_; ++r) {
    const double omega = env.texel_solid_angle(r);
    double* cdf = &col_cdf_[std::size_t(r) * (width_ + 1)];
    for (int c = 0; c < width_; ++c) cdf[c + 1] = cdf[c] + weight[std::size_t(r) * width_ + c] * omega;
    row_sum[r] = cdf[width_];
    if (row_sum[r] > 0)
      for (int c = 1; c <= width_; ++c) cdf[c] /= row_sum[r];
    row_cdf_[r + 1] = row_cdf_[r] + row_sum[r];
  }
  total_ = row_cdf_[height_];
  if (total_ <= 0) return;
  for (int r = 0; r <= height_; ++r) row_cdf_[r] /= total_;
  for (int r = 0; r < height_; ++r) {
    row_mass_[r] = row_sum[r] / total_;
    const double omega = env.texel_solid_angle(r);
    for (int c = 0; c < width_; ++c)
      texel_pdf_[std::size_t(r) * width_ + c] = weight[std::size_t(r) * width_ + c] * omega / total_ / omega;
  }
}

Vec3 EnvSampler::sample(Point2 p, double& pdf) const {
  const int r = find_interval(row_cdf_.data(), height_, p.u);
  const double du = row_mass_[r] > 0 ? (p.u - row_cdf_[r]) / row_mass_[r] : 0.5;
  const double* cdf = &col_cdf_[std::size_t(r) * (width_ + 1)];
  const int c = find_interval(cdf, width_, p.v);
  const double w = cdf[c + 1] - cdf[c];
  const double dv = w > 0 ? (p.v - cdf[c]) / w : 0.5;
  // Uniform in solid angle inside the texel: cos(theta) and phi uniform over its extent.
  const double z0 = std::cos(kPi * r / height_), z1 = std::cos(kPi * (r + 1) / height_);
  const double z = z0 + std::clamp(du, 0.0, 1.0) * (z1 - z0);
  const double phi = 2 * kPi * (c + std::clamp(dv, 0.0, 1.0)) / width_;
  const double s = std::sqrt(std::max(0.0, 1 - z * z));
  pdf = texel_pdf_[std::size_t(r) * width_ + c];
  return {s * std::cos(phi), s * std::sin(phi), z};
}

double EnvSampler::pdf(Vec3 d) const {
  double phi = std::atan2(d.y, d.x);
  if (phi < 0) phi += 2 * kPi;
  const double theta = std::acos(std::clamp(d.z, -1.0, 1.0));
  const int c = std::clamp(int(phi / (2 * kPi) * width_), 0, width_ - 1);
  const int r = std::clamp(int(theta / kPi * height_), 0, height_ - 1);
  return texel_pdf_[std::size_t(r) * width_ + c];
}

}  // namespace hfbake::reference
