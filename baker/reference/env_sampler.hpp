// Importance sampling of a lat-long environment by luminance: a piecewise-constant distribution over the
// level-0 texels (weight = the |luminance| the bilinear lookup spreads over the texel, from it and its eight
// neighbours, x solid angle), and inside a texel uniform in solid angle. The pdf is
// exact for this procedure, so any radiance lookup (bilinear, band-limited) stays unbiased under MIS.
#pragma once

#include <vector>

#include "env/environment.hpp"
#include "reference/sampling.hpp"

namespace hfbake::reference {

class EnvSampler {
 public:
  EnvSampler() = default;
  explicit EnvSampler(const Environment& env);

  bool valid() const { return width_ > 0 && total_ > 0; }
  // A direction and its pdf (per steradian).
  Vec3 sample(Point2 p, double& pdf) const;
  double pdf(Vec3 dir) const;

 private:
  int width_ = 0, height_ = 0;
  double total_ = 0;
  std::vector<double> row_cdf_;    // height + 1 entries, normalised
  std::vector<double> col_cdf_;    // height x (width + 1), each row normalised
  std::vector<double> row_mass_;   // probability of each row
  std::vector<double> texel_pdf_;  // pdf per steradian in each texel (width x height)
};

// The |luminance| weight used for the distribution (also right for band-limited, signed radiance).
inline double sampling_weight(Rgb c) {
  return 0.2126 * std::abs(c.r) + 0.7152 * std::abs(c.g) + 0.0722 * std::abs(c.b);
}

}  // namespace hfbake::reference
