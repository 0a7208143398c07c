#include "report/compare.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "core/vec.hpp"

namespace hfbake {

CompareRegion crop_region(int width, int height, int crop) {
  crop = std::max(crop, 0);
  return {crop, crop, std::max(crop, width - crop), std::max(crop, height - crop)};
}

namespace {

// Angles between the method's and the reference's direction vectors, in degrees, in a fixed order.
void set_angle_metrics(std::vector<double>& angles, double sum, LayerMetrics& out) {
  if (angles.empty()) return;
  out.angle_mean_deg = sum / double(angles.size());
  const std::size_t rank = std::size_t(std::ceil(0.99 * double(angles.size())));
  const std::size_t k = std::min(angles.size() - 1, rank > 0 ? rank - 1 : 0);
  std::nth_element(angles.begin(), angles.begin() + std::ptrdiff_t(k), angles.end());
  out.angle_p99_deg = angles[k];
  out.angle_max_deg = *std::max_element(angles.begin(), angles.end());
}

// Elevation layers (horizon: sin of the elevation per channel): |asin(method) - asin(reference)| in degrees.
void add_elevation_metrics(const Layer& method, const Layer& reference, int width,
                           const CompareRegion& region, LayerMetrics& out) {
  const int channels = method.channel_count();
  std::vector<double> angles;
  angles.reserve(region.texels() * std::size_t(channels));  // no growth's copy beside it
  double sum = 0;
  for (int y = region.y0; y < region.y1; ++y)
    for (int x = region.x0; x < region.x1; ++x)
      for (int c = 0; c < channels; ++c) {
        const std::size_t t = (std::size_t(y) * width + x) * channels + c;
        const double a = std::asin(std::clamp(double(method.data[t]), -1.0, 1.0));
        const double b = std::asin(std::clamp(double(reference.data[t]), -1.0, 1.0));
        const double deg = std::abs(a - b) * 180.0 / kPi;
        angles.push_back(deg);
        sum += deg;
      }
  set_angle_metrics(angles, sum, out);
}

void add_angle_metrics(const Layer& method, const Layer& reference, int width, const CompareRegion& region,
                       LayerMetrics& out) {
  std::vector<double> angles;
  angles.reserve(region.texels());
  double sum = 0;
  for (int y = region.y0; y < region.y1; ++y)
    for (int x = region.x0; x < region.x1; ++x) {
      const std::size_t t = (std::size_t(y) * width + x) * 3;
      const double a[3] = {method.data[t], method.data[t + 1], method.data[t + 2]};
      const double b[3] = {reference.data[t], reference.data[t + 1], reference.data[t + 2]};
      const double la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
      const double lb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
      if (!(la > 0) || !(lb > 0)) continue;
      const double c = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (la * lb);
      const double deg = std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / kPi;
      angles.push_back(deg);
      sum += deg;
    }
  set_angle_metrics(angles, sum, out);
}

}  // namespace

LayerMetrics compare_layer(const Layer& method, const Layer& reference, const Layer* stderr_layer, int width,
                           int height, const CompareRegion& region) {
  const int channels = method.channel_count();
  const std::size_t texels = std::size_t(width) * std::size_t(height);
  if (channels == 0 || reference.channel_count() != channels)
    throw std::invalid_argument("layer " + method.name + ": the method has " + std::to_string(channels) +
                                " channels, the reference " + std::to_string(reference.channel_count()));
  if (method.data.size() != texels * channels || reference.data.size() != texels * channels)
    throw std::invalid_argument("layer " + method.name + ": method and reference differ in size");
  int se_channels = 0;
  if (stderr_layer) {
    se_channels = stderr_layer->channel_count();
    if ((se_channels != channels && se_channels != 1) || stderr_layer->data.size() != texels * se_channels)
      throw std::invalid_argument("layer " + method.name + ": the stderr layer does not match");
  }
  if (region.x1 <= region.x0 || region.y1 <= region.y0 || region.x0 < 0 || region.y0 < 0 ||
      region.x1 > width || region.y1 > height)
    throw std::invalid_argument("the compared region is empty: the crop leaves no texel");

  // Sums in double, in a fixed order (row by row): the same bits whatever the caller's threading.
  double sum_abs = 0, sum_sq = 0, sum_diff = 0, sum_ref_abs = 0, sum_se_sq = 0, max_abs = 0, peak = 0;
  std::vector<float> abs_diff;
  abs_diff.reserve(region.texels() * channels);
  for (int y = region.y0; y < region.y1; ++y) {
    for (int x = region.x0; x < region.x1; ++x) {
      const std::size_t t = std::size_t(y) * width + x;
      for (int c = 0; c < channels; ++c) {
        const double m = method.data[t * channels + c], r = reference.data[t * channels + c];
        if (std::isinf(m) || std::isinf(r)) continue;  // a horizon distance without a caster
        const double d = m - r, a = std::abs(d);
        sum_abs += a;
        sum_sq += d * d;
        sum_diff += d;
        sum_ref_abs += std::abs(r);
        max_abs = std::max(max_abs, a);
        peak = std::max(peak, std::abs(r));
        abs_diff.push_back(float(a));
        if (stderr_layer) {
          const double se = stderr_layer->data[t * se_channels + (se_channels == 1 ? 0 : c)];
          sum_se_sq += se * se;
        }
      }
    }
  }
  const double n = double(abs_diff.size());
  LayerMetrics out;
  if (abs_diff.empty()) return out;  // nothing finite on both sides
  out.values = abs_diff.size();
  out.mae = sum_abs / n;
  out.rmse = std::sqrt(sum_sq / n);
  out.bias = sum_diff / n;
  out.max = max_abs;
  out.reference_mean = sum_ref_abs / n;
  // Nearest-rank percentile: the smallest value with at least 99 % of the values at or below it.
  const std::size_t rank = std::size_t(std::ceil(0.99 * n));
  const std::size_t k = std::min(abs_diff.size() - 1, rank > 0 ? rank - 1 : 0);
  std::nth_element(abs_diff.begin(), abs_diff.begin() + std::ptrdiff_t(k), abs_diff.end());
  out.p99 = abs_diff[k];
  if (out.reference_mean > 0) out.rel_mae = out.mae / out.reference_mean;
  if (sum_sq > 0 && peak > 0) out.psnr = 10.0 * std::log10(peak * peak / (sum_sq / n));
  out.noise_rmse = std::sqrt(sum_se_sq / n);
  out.excess_rmse = std::sqrt(std::max(out.rmse * out.rmse - out.noise_rmse * out.noise_rmse, 0.0));
  abs_diff = std::vector<float>();  // freed before the angles' doubles (a horizon layer's: 8 bytes a value)
  const LayerKind* kind = find_layer_kind(method.name);
  if (channels == 3 && kind && kind->score == LayerScore::directions)
    add_angle_metrics(method, reference, width, region, out);
  if (kind && kind->score == LayerScore::elevations)
    add_elevation_metrics(method, reference, width, region, out);
  return out;
}

const char* const* metric_names(int& count) {
  static const char* const names[] = {"mae",         "rmse",           "rel_mae",       "max",
                                      "p99",         "psnr",           "bias",          "noise_rmse",
                                      "excess_rmse", "angle_mean_deg", "angle_p99_deg", "angle_max_deg"};
  count = int(sizeof names / sizeof names[0]);
  return names;
}

std::optional<double> metric_value(const LayerMetrics& m, const std::string& name) {
  if (name == "mae") return m.mae;
  if (name == "rmse") return m.rmse;
  if (name == "rel_mae") return m.rel_mae;
  if (name == "max") return m.max;
  if (name == "p99") return m.p99;
  if (name == "psnr") return m.psnr;
  if (name == "bias") return m.bias;
  if (name == "noise_rmse") return m.noise_rmse;
  if (name == "excess_rmse") return m.excess_rmse;
  if (name == "angle_mean_deg") return m.angle_mean_deg;
  if (name == "angle_p99_deg") return m.angle_p99_deg;
  if (name == "angle_max_deg") return m.angle_max_deg;
  return std::nullopt;
}

bool metric_is_higher_better(const std::string& name) {
  return name == "psnr";
}

}  // namespace hfbake
