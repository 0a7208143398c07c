// Accuracy of a method layer against the reference layer of the same name: the numbers report.json holds.
#pragma once

#include <optional>
#include <string>

#include "core/layers.hpp"

namespace hfbake {

// Metrics over every texel of the compared region and every channel of the layer (pooled), with
// diff = method - reference:
//   mae = mean |diff|, rmse = sqrt(mean diff^2), bias = mean diff, max = max |diff|,
//   p99 = the 99th percentile of |diff| (nearest rank), rel_mae = mae / mean |reference| (absent when
//   the reference is zero everywhere), psnr = 10 log10(peak^2 / mean diff^2) with peak = max |reference|
//   (absent when the images are identical or the reference is zero),
//   noise_rmse = sqrt(mean stderr^2) of the reference's Monte Carlo estimate (0 without a stderr layer),
//   excess_rmse = sqrt(max(rmse^2 - noise_rmse^2, 0)): the part of the error that is the method's. When
//   the reference is unbiased with independent per-texel noise of variance stderr^2,
//   E[rmse^2] = (method - truth)_rms^2 + noise_rmse^2, so excess_rmse estimates the method's rms error
//   against the exact answer.
struct LayerMetrics {
  double mae = 0, rmse = 0, bias = 0, max = 0, p99 = 0;
  std::optional<double> rel_mae, psnr;
  double noise_rmse = 0, excess_rmse = 0;
  double reference_mean = 0;
  std::size_t values = 0;  // texels x channels compared
  // Direction layers (bent_normal): the angle in degrees between the method's and the reference's vectors,
  // over the texels where both are non-zero; elevation layers (horizon): the elevation error in degrees of
  // every channel: mean, 99th percentile (nearest rank) and max.
  std::optional<double> angle_mean_deg, angle_p99_deg, angle_max_deg;
};

// The region compared: texels [crop, width - crop) x [crop, height - crop).
struct CompareRegion {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  std::size_t texels() const { return std::size_t(x1 - x0) * std::size_t(y1 - y0); }
};
// The region left after cropping `crop` texels at each border; empty (x1 <= x0) if nothing is left.
CompareRegion crop_region(int width, int height, int crop);

// Compares `method` against `reference` (same channel count; data of width x height texels). `stderr_layer`
// (may be null) holds the reference's per-texel standard error with the same channels (or one channel,
// shared by all). Throws std::invalid_argument on mismatched channel counts or sizes, or an empty region.
// The layer table (core/layers.hpp) says what else is measured: the angle between unit vectors (a
// direction layer), or each channel's elevation error in degrees (sines of elevations) in the angle
// metrics. Values that are infinite on either side (horizon_distance where no caster was found) are left
// out of every metric.
LayerMetrics compare_layer(const Layer& method, const Layer& reference, const Layer* stderr_layer, int width,
                           int height, const CompareRegion& region);

// Metric names in the order report.json lists them, and lookup by name (nullopt: absent / unknown).
const char* const* metric_names(int& count);
std::optional<double> metric_value(const LayerMetrics& m, const std::string& name);
// Larger-is-better metrics (psnr): a threshold on them is a minimum; every other threshold is a maximum.
bool metric_is_higher_better(const std::string& name);

}  // namespace hfbake
