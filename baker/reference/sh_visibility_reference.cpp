#include "reference/sh_visibility_reference.hpp"

#include <tbb/parallel_for.h>

#include <cmath>

#include "core/azimuth.hpp"
#include "methods/nlp/quadrature.hpp"
#include "reference/embree_field.hpp"
#include "reference/horizon_reference.hpp"
#include "reference/sh_environment.hpp"

namespace hfbake {
namespace {

constexpr int kNodes = 10;  // Gauss-Legendre in elevation: exact for the basis times cos e (degree <= 4)

}  // namespace

namespace {

// The projection from horizons at the azimuths of the tables (cos_phi, sin_phi: azimuth_table of K).
std::array<double, 16> project_horizons(const std::vector<double>& elevation,
                                        const std::vector<double>& cos_phi,
                                        const std::vector<double>& sin_phi) {
  static const QuadratureRule gl = gauss_legendre(kNodes);
  const int K = int(elevation.size());
  std::array<double, 16> c{};
  const double dphi = 2 * kPi / K;
  for (int k = 0; k < K; ++k) {
    const double a = elevation[k], b = kPi / 2, half = 0.5 * (b - a), mid = 0.5 * (a + b);
    for (int n = 0; n < kNodes; ++n) {
      const double e = mid + half * gl.x[n], ce = std::cos(e);
      const auto y = reference::sh_basis(Vec3{ce * cos_phi[k], ce * sin_phi[k], std::sin(e)});
      const double wgt = dphi * half * gl.w[n] * ce;
      for (int i = 0; i < 16; ++i) c[i] += wgt * y[i];
    }
  }
  return c;
}

}  // namespace

std::array<double, 16> sh_visibility_of_horizons(const std::vector<double>& elevation) {
  std::vector<double> cos_phi, sin_phi;
  azimuth_table(int(elevation.size()), cos_phi, sin_phi);
  return project_horizons(elevation, cos_phi, sin_phi);
}

std::vector<float> trace_reference_sh_visibility(const HeightField& f, int azimuths, const RunControl& rc,
                                                 int iterations) {
  std::vector<float> out(f.texel_count() * 16);
  const reference::EmbreeField geometry(f, reference::GeometryKind::grid, 1);
  std::vector<double> cos_phi, sin_phi;
  azimuth_table(azimuths, cos_phi, sin_phi);
  const double lift = horizon_receiver_lift(f, geometry);
  tbb::parallel_for(0, f.height, [&](int j) {
    rc.check();
    std::vector<double> elevation(azimuths);
    for (int i = 0; i < f.width; ++i) {
      for (int k = 0; k < azimuths; ++k)
        elevation[k] = texel_horizon(f, geometry, i, j, lift, cos_phi[k], sin_phi[k], iterations).elevation;
      const std::array<double, 16> c = project_horizons(elevation, cos_phi, sin_phi);  // no allocation
      float* dst = out.data() + f.index(i, j) * 16;
      for (int n = 0; n < 16; ++n) dst[n] = float(c[n]);
    }
  });
  return out;
}

void add_reference_sh_visibility(const HeightField& field, const std::vector<const LayerSet*>& methods,
                                 LayerSet& reference, const RunControl& rc, int azimuths) {
  if (reference.find("sh_visibility")) return;
  const Layer* sh = nullptr;
  for (const LayerSet* m : methods)
    if (!sh) sh = m->find("sh_visibility");
  if (!sh || sh->channel_count() != 16) return;
  reference.layers.push_back(
      {"sh_visibility", sh->channels, trace_reference_sh_visibility(field, azimuths, rc)});
}

}  // namespace hfbake
