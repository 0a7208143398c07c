#include "reference/horizon_reference.hpp"

#include <embree3/rtcore.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "core/azimuth.hpp"
#include "reference/embree_field.hpp"

namespace hfbake {
namespace {

RTCRayHit ray_from(const Vec3& o, double c, double s, double e) {
  RTCRayHit h;
  h.ray.org_x = float(o.x), h.ray.org_y = float(o.y), h.ray.org_z = float(o.z);
  h.ray.dir_x = float(std::cos(e) * c), h.ray.dir_y = float(std::cos(e) * s),
  h.ray.dir_z = float(std::sin(e));
  h.ray.tnear = 0.0f;
  h.ray.tfar = std::numeric_limits<float>::infinity();
  h.ray.time = 0.0f;
  h.ray.mask = 0xffffffffu;
  h.ray.id = 0;
  h.ray.flags = 0;
  h.hit.geomID = h.hit.primID = h.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return h;
}

// The first hit of the chain of chords of the parabola o + (d c, d s, d tan e + k d^2), d in [0, end]
// (horizontal): the straight distance from o to the hit, or a negative value when nothing is hit.
double curved_hit(const reference::EmbreeField& geometry, const Vec3& o, double c, double s, double e,
                  double end, const CurvedRays& curved) {
  const double k = curved.curvature, slope = std::tan(e);
  auto at = [&](double d) { return Vec3{o.x + d * c, o.y + d * s, o.z + d * slope + k * d * d}; };
  RTCIntersectContext context;
  Vec3 a = o;
  for (double d0 = 0; d0 < end;) {
    const double d1 = std::min(end, d0 + curved.step);
    const Vec3 b = at(d1);
    const Vec3 v = b - a;
    const double length = std::sqrt(dot(v, v));
    RTCRayHit h = ray_from(a, 1, 0, 0);
    h.ray.dir_x = float(v.x / length), h.ray.dir_y = float(v.y / length), h.ray.dir_z = float(v.z / length);
    h.ray.tfar = float(length);
    rtcInitIntersectContext(&context);
    rtcIntersect1(geometry.scene(), &context, &h);
    if (h.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
      const Vec3 p = a + v * (double(h.ray.tfar) / length);
      const Vec3 r = p - o;
      return std::sqrt(dot(r, r));
    }
    // Above every height and rising: nothing further is hit.
    if (b.z > curved.z_top && slope + 2 * k * d1 >= 0) return -1;
    a = b, d0 = d1;
  }
  return -1;
}

}  // namespace

CurvedRays curved_rays(const HeightField& f, double curvature) {
  CurvedRays r;
  if (curvature == 0) return r;
  r.curvature = curvature;
  r.sagitta = 1e-4 * std::min(f.dx(), f.dy());
  r.step = 2 * std::sqrt(r.sagitta / std::abs(curvature));
  // The traced block: the field, or (repeat) the 3 x 3 tiles around it (EmbreeField's repeat_tiles 1).
  const double tiles = f.wrap == Wrap::repeat ? 3 : 1;
  r.reach = tiles * std::hypot(f.width * f.dx(), f.height * f.dy());
  r.z_top = *std::max_element(f.z.begin(), f.z.end());
  return r;
}

TexelHorizon bisect_horizon(const reference::EmbreeField& geometry, const Vec3& o, double c, double s,
                            int iterations, double max_horizontal, const CurvedRays& curved) {
  // lo: an occluded elevation (straight down always is), hi: a free one (straight up).
  double lo = -kPi / 2, hi = kPi / 2, lo_distance = 0;
  const bool limited = max_horizontal < std::numeric_limits<double>::infinity();
  RTCIntersectContext context;
  for (int it = 0; it < iterations; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (curved.curvature != 0) {
      const double d = curved_hit(geometry, o, c, s, mid, std::min(max_horizontal, curved.reach), curved);
      if (d >= 0) {
        lo = mid;
        lo_distance = d;
      } else {
        hi = mid;
      }
      continue;
    }
    RTCRayHit h = ray_from(o, c, s, mid);
    if (limited)  // the ray's length at which it is max_horizontal away horizontally
      h.ray.tfar = float(std::min(max_horizontal / std::max(std::cos(mid), 1e-30), 3.0e38));
    rtcInitIntersectContext(&context);
    rtcIntersect1(geometry.scene(), &context, &h);
    if (h.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
      lo = mid;
      lo_distance = h.ray.tfar;
    } else {
      hi = mid;
    }
  }
  return {lo, lo_distance};
}

double horizon_receiver_lift(const HeightField& f, const reference::EmbreeField& geometry) {
  return std::max(1e-5 * std::min(f.dx(), f.dy()), geometry.float_floor());
}

TexelHorizon texel_horizon(const HeightField& f, const reference::EmbreeField& geometry, int i, int j,
                           double lift, double c, double s, int iterations, const CurvedRays& curved,
                           double max_horizontal) {
  const Vec3 o = f.position(i, j) + Vec3{0, 0, lift};
  int di = 0, dj = 0;  // the step along the border, or none
  if (f.wrap == Wrap::clamp) {
    if (std::abs(s) < 1e-12 && (j == 0 || j == f.height - 1)) di = c > 0 ? 1 : -1;
    if (std::abs(c) < 1e-12 && (i == 0 || i == f.width - 1)) dj = s > 0 ? 1 : -1;
  }
  if (di == 0 && dj == 0) return bisect_horizon(geometry, o, c, s, iterations, max_horizontal, curved);
  const double step = di ? f.dx() : f.dy();
  double best_rise = 0, best_run = 0;  // the steepest point's (runs are positive)
  const auto consider = [&](double run, double height) {
    const double rise = height - o.z - curved.curvature * run * run;
    if (best_run == 0 || rise * best_run > best_rise * run) best_rise = rise, best_run = run;
  };
  for (int n = 1;; ++n) {
    const int x = i + n * di, y = j + n * dj;
    if (x < 0 || y < 0 || x >= f.width || y >= f.height) break;
    const double run = n * step;
    if (run > max_horizontal) {  // the polyline's point at max_horizontal, between the last two vertices
      const double t = (max_horizontal - (n - 1) * step) / step;
      const double before = n == 1 ? double(f.at(i, j)) : double(f.at(x - di, y - dj));
      if (t > 0) consider(max_horizontal, before + t * (double(f.at(x, y)) - before));
      break;
    }
    consider(run, double(f.at(x, y)));
  }
  // Nothing along it (a corner looking out along its border): what the rays make of it.
  if (best_run == 0) return bisect_horizon(geometry, o, c, s, iterations, max_horizontal, curved);
  return {std::atan2(best_rise, best_run), std::hypot(best_run, best_rise)};
}

ReferenceHorizons trace_reference_horizons(const HeightField& f, int K, bool distance, const RunControl& rc,
                                           int iterations, double curvature) {
  ReferenceHorizons out;
  out.K = K;
  const std::size_t N = f.texel_count();
  out.sin_elevation.assign(N * std::size_t(K), 0.0f);
  if (distance) out.distance.assign(N * std::size_t(K), 0.0f);
  const reference::EmbreeField geometry(f, reference::GeometryKind::grid, 1);
  std::vector<double> cos_phi, sin_phi;
  azimuth_table(K, cos_phi, sin_phi);
  const double lift = horizon_receiver_lift(f, geometry);
  const CurvedRays curved = curved_rays(f, curvature);
  std::atomic<int> rows{0};
  tbb::parallel_for(0, f.height, [&](int j) {
    rc.check();
    rc.report(double(rows.fetch_add(1)) / f.height);
    for (int i = 0; i < f.width; ++i) {
      const std::size_t t = f.index(i, j);
      for (int k = 0; k < K; ++k) {
        const TexelHorizon h =
            texel_horizon(f, geometry, i, j, lift, cos_phi[k], sin_phi[k], iterations, curved);
        out.sin_elevation[t * K + k] = float(std::sin(h.elevation));
        if (distance) out.distance[t * K + k] = float(h.distance);
      }
    }
  });
  return out;
}

void add_reference_horizons(const HeightField& field, const std::vector<const LayerSet*>& methods,
                            LayerSet& reference, const RunControl& rc, double curvature) {
  if (reference.find("horizon") || reference.find("horizon_distance")) return;
  const Layer *horizon = nullptr, *distance = nullptr;
  for (const LayerSet* m : methods) {
    if (!horizon) horizon = m->find("horizon");
    if (!distance) distance = m->find("horizon_distance");
  }
  if (!horizon && !distance) return;
  const Layer& shape = horizon ? *horizon : *distance;
  const int K = shape.channel_count();
  const bool same_k = !horizon || !distance || distance->channel_count() == K;
  ReferenceHorizons h =
      trace_reference_horizons(field, K, distance && same_k, rc, kHorizonBisections, curvature);
  if (horizon) reference.layers.push_back({"horizon", horizon->channels, std::move(h.sin_elevation)});
  if (distance && same_k)
    reference.layers.push_back({"horizon_distance", distance->channels, std::move(h.distance)});
}

}  // namespace hfbake
