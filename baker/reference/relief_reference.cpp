#include "reference/relief_reference.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "methods/relief/relief.hpp"
#include "reference/embree_field.hpp"
#include "reference/horizon_reference.hpp"

namespace hfbake {
namespace {

constexpr double kDegPerRad = 180.0 / kPi;

// The highest elevation within the radius along every direction, from every texel centre of f.
void trace_up(const HeightField& f, const ReliefReferenceSettings& s, const RunControl& rc, int iterations,
              double curvature, std::vector<double>& out) {
  const int K = s.directions;
  out.assign(f.texel_count() * std::size_t(K), 0.0);
  const reference::EmbreeField geometry(f, reference::GeometryKind::grid, 1);
  std::vector<double> dx(static_cast<std::size_t>(K)), dy(static_cast<std::size_t>(K));
  for (int k = 0; k < K; ++k)
    relief_direction(k, K, s.compass, s.axes, dx[std::size_t(k)], dy[std::size_t(k)]);
  const double lift = horizon_receiver_lift(f, geometry);
  const CurvedRays curved = curved_rays(f, curvature);
  tbb::parallel_for(0, f.height, [&](int j) {
    rc.check();
    for (int i = 0; i < f.width; ++i) {
      for (int k = 0; k < K; ++k) {
        const double x = dx[std::size_t(k)], y = dy[std::size_t(k)];
        // A clamp border texel looking out of the field: no surface along the ray at all (the skirt is not
        // surface), 0 as relief.
        if (f.wrap == Wrap::clamp && ((i == 0 && x < -1e-9) || (i == f.width - 1 && x > 1e-9) ||
                                      (j == 0 && y < -1e-9) || (j == f.height - 1 && y > 1e-9))) {
          out[f.index(i, j) * K + k] = 0.0;
          continue;
        }
        out[f.index(i, j) * K + k] =
            texel_horizon(f, geometry, i, j, lift, x, y, iterations, curved, s.search_radius).elevation;
      }
    }
  });
}

}  // namespace

ReliefHorizons trace_relief_horizons(const HeightField& field, const ReliefReferenceSettings& s, bool down,
                                     const RunControl& rc, int iterations, double curvature) {
  ReliefHorizons h;
  trace_up(field, s, rc, iterations, curvature, h.up);
  if (down) {
    // Upside down the casters are raised by c d^2: the curvature changes sign.
    HeightField inverted = field;
    for (float& z : inverted.z) z = -z;
    trace_up(inverted, s, rc, iterations, -curvature, h.down);
    for (double& d : h.down) d = -d;
  }
  return h;
}

nlohmann::json relief_reference_record(const ReliefReferenceSettings& s) {
  return {{"directions", s.directions},
          {"search_radius", s.search_radius},
          {"azimuth_convention", s.compass ? "compass" : "hfbake"}};
}

void add_reference_relief(const HeightField& field, const ReliefSettings& settings,
                          const LayerSet& relief_layers, LayerSet& reference, const RunControl& rc,
                          double curvature, GridAxes axes) {
  // relief's layers: those the layer table says this step computes.
  std::vector<std::string> names;
  for (const LayerKind& k : layer_kinds())
    if (k.trace == LayerTrace::relief) names.emplace_back(k.name);
  for (const std::string& l : names)
    if (reference.find(l)) return;
  const LayerSet* relief = &relief_layers;
  ReliefReferenceSettings s;
  s.directions = settings.directions;
  s.search_radius = settings.search_radius;
  s.compass = settings.compass;
  s.axes = axes;
  const int K = s.directions;
  const ReliefHorizons h =
      trace_relief_horizons(field, s, relief->find("openness_negative") != nullptr, rc, 30, curvature);
  const std::size_t N = field.texel_count();
  for (const std::string& name : names) {
    const Layer* ml = relief->find(name);
    if (!ml) continue;
    std::vector<float> data(N * std::size_t(ml->channel_count()));
    for (std::size_t t = 0; t < N; ++t) {
      double sum_sin = 0, sum_up = 0, sum_down = 0;
      for (int k = 0; k < K; ++k) {
        const double up = h.up[t * K + k];
        sum_sin += std::sin(std::max(up, 0.0));
        sum_up += up;
        if (!h.down.empty()) sum_down += h.down[t * K + k];
      }
      const std::string& n = name;
      if (n == "svf") data[t] = float(1 - sum_sin / K);
      if (n == "openness_positive") data[t] = float(90 - sum_up / K * kDegPerRad);
      if (n == "openness_negative") data[t] = float(90 + sum_down / K * kDegPerRad);
      if (n == "horizon_deg" && ml->channel_count() == K)
        for (int k = 0; k < K; ++k) data[t * K + k] = float(h.up[t * K + k] * kDegPerRad);
    }
    reference.layers.push_back({name, ml->channels, std::move(data)});
  }
  reference.attributes.emplace_back(kReliefReferenceAttribute, relief_reference_record(s).dump());
}

}  // namespace hfbake
