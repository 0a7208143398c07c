#include "methods/ao/slice_integral.hpp"

#include <algorithm>
#include <cmath>

#include "core/vec.hpp"

namespace hfbake {
namespace {

// 8-point Gauss-Legendre on [-1, 1].
constexpr double kNodes[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
constexpr double kWeights[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                                0.1012285362903763};

// Integral of g over [a, b], split into pieces of at most pi/8 with 8 nodes each.
template <class G>
double gauss(const G& g, double a, double b) {
  if (!(b > a)) return 0.0;
  const int pieces = std::max(1, int(std::ceil((b - a) / (kPi / 8))));
  const double len = (b - a) / pieces;
  double sum = 0;
  for (int p = 0; p < pieces; ++p) {
    const double mid = a + (p + 0.5) * len, half = 0.5 * len;
    double s = 0;
    for (int q = 0; q < 4; ++q) s += kWeights[q] * (g(mid - half * kNodes[q]) + g(mid + half * kNodes[q]));
    sum += s * half;
  }
  return sum;
}

// Antiderivatives of the cosine weight w(e) = (nt cos e + nz sin e) cos e divided by cos^k e.
double cos_p0(const SliceFrame& s, double e) {
  const double sn = std::sin(e);
  return s.nt * (e / 2 + std::sin(2 * e) / 4) + s.nz * sn * sn / 2;
}
double cos_p1(const SliceFrame& s, double e) {
  return s.nt * std::sin(e) - s.nz * std::cos(e);
}
double cos_p2(const SliceFrame& s, double e) {
  return s.nt * e - s.nz * std::log(std::cos(e));
}
// Uniform weight cos e divided by cos^k e.
double uni_p0(double e) {
  return std::sin(e);
}
double uni_p1(double e) {
  return e;
}
double uni_p2(double e) {
  return std::log((1 + std::sin(e)) / std::cos(e));
}

}  // namespace

SliceFrame slice_frame(double nt, double nz) {
  SliceFrame s;
  s.nt = nt;
  s.nz = nz;
  s.tangent = std::atan2(-nt, nz);
  return s;
}

double band_occlusion(const Falloff& f, Weighting w, const SliceFrame& s, double a, double b, double x) {
  double lo = std::max(a, s.tangent), hi = std::min(b, kHalfPi);
  if (!(hi > lo)) return 0.0;
  const bool cosine = w == Weighting::cosine;
  switch (f.kind) {
    case FalloffKind::none:
      return cosine ? cos_p0(s, hi) - cos_p0(s, lo) : uni_p0(hi) - uni_p0(lo);
    case FalloffKind::step:
    case FalloffKind::linear:
    case FalloffKind::smooth: {
      // rho(x / cos e) > 0 only where cos e > x / R.
      if (x >= f.radius) return 0.0;
      const double q = x / f.radius, ec = std::acos(q);
      lo = std::max(lo, -ec), hi = std::min(hi, ec);
      if (!(hi > lo)) return 0.0;
      auto p0 = [&](double e) { return cosine ? cos_p0(s, e) : uni_p0(e); };
      auto p1 = [&](double e) { return cosine ? cos_p1(s, e) : uni_p1(e); };
      auto p2 = [&](double e) { return cosine ? cos_p2(s, e) : uni_p2(e); };
      const double i0 = p0(hi) - p0(lo);
      if (f.kind == FalloffKind::step) return i0;
      const double i1 = p1(hi) - p1(lo);
      if (f.kind == FalloffKind::linear) return i0 - q * i1;  // (1 - q / cos e)
      return i0 - 2 * q * i1 + q * q * (p2(hi) - p2(lo));     // (1 - q / cos e)^2
    }
    case FalloffKind::exponential:
    case FalloffKind::rational:
      break;
  }
  return gauss(
      [&](double e) {
        const double c = std::cos(e);
        const double wt = cosine ? std::max(0.0, s.nt * c + s.nz * std::sin(e)) * c : c;
        return c > 0 ? f(x / c) * wt : 0.0;
      },
      lo, hi);
}

SliceVec open_direction(const SliceFrame& s, double a, double b) {
  const double lo = std::max(a, s.tangent), hi = std::min(b, kHalfPi);
  if (!(hi > lo)) return {};
  auto ph = [&](double e) {  // integral of (nt c + nz s) c^2
    const double sn = std::sin(e), c = std::cos(e);
    return s.nt * (sn - sn * sn * sn / 3) - s.nz * c * c * c / 3;
  };
  auto pv = [&](double e) {  // integral of (nt c + nz s) c s
    const double sn = std::sin(e), c = std::cos(e);
    return -s.nt * c * c * c / 3 + s.nz * sn * sn * sn / 3;
  };
  return {ph(hi) - ph(lo), pv(hi) - pv(lo)};
}

SliceVec band_direction(const Falloff& f, const SliceFrame& s, double a, double b, double x) {
  double lo = std::max(a, s.tangent), hi = std::min(b, kHalfPi);
  if (!(hi > lo)) return {};
  if (f.kind == FalloffKind::none) return open_direction(s, lo, hi);
  if (f.kind == FalloffKind::step || f.kind == FalloffKind::linear || f.kind == FalloffKind::smooth) {
    if (x >= f.radius) return {};
    const double ec = std::acos(x / f.radius);
    lo = std::max(lo, -ec), hi = std::min(hi, ec);
    if (!(hi > lo)) return {};
    if (f.kind == FalloffKind::step) return open_direction(s, lo, hi);
  }
  auto weight = [&](double e) {
    const double c = std::cos(e);
    return c > 0 ? f(x / c) * std::max(0.0, s.nt * c + s.nz * std::sin(e)) * c : 0.0;
  };
  return {gauss([&](double e) { return weight(e) * std::cos(e); }, lo, hi),
          gauss([&](double e) { return weight(e) * std::sin(e); }, lo, hi)};
}

int slab_degree(const Falloff& f) {
  switch (f.kind) {
    case FalloffKind::none:
    case FalloffKind::step:
      return 0;
    case FalloffKind::linear:
      return 1;
    case FalloffKind::smooth:
      return 2;
    default:
      return -1;
  }
}

void slab_coefficients(const Falloff& f, double x, double coef[3]) {
  const double q = f.kind == FalloffKind::none ? 0.0 : x / f.radius;
  coef[0] = 1;
  coef[1] = f.kind == FalloffKind::linear ? -q : f.kind == FalloffKind::smooth ? -2 * q : 0.0;
  coef[2] = f.kind == FalloffKind::smooth ? q * q : 0.0;
}

SlabPrimitives slab_primitives(const SliceFrame& s, Weighting w, double e, double sn, double c, int degree,
                               bool direction) {
  SlabPrimitives p;
  const double nt = s.nt, nz = s.nz, sc = sn * c;
  // Cosine weight (nt cos e + nz sin e) cos e: sec^0, sec^1, sec^2.
  const double cos0 = nt * (0.5 * e + 0.5 * sc) + nz * 0.5 * sn * sn;
  const double cos1 = nt * sn - nz * c;
  const double log_c = degree >= 2 ? std::log(c) : 0.0;
  // log(sec e + tan e): the uniform measure's and the direction's sec^2 terms.
  const double log_sec_tan =
      degree >= 2 && (direction || w == Weighting::uniform) ? std::log1p(sn) - log_c : 0.0;
  if (w == Weighting::cosine) {
    p.occ[0] = cos0;
    p.occ[1] = cos1;
    p.occ[2] = nt * e - nz * log_c;
  } else {
    p.occ[0] = sn;
    p.occ[1] = e;
    p.occ[2] = log_sec_tan;
  }
  if (direction) {
    const double c3 = c * c * c, s3 = sn * sn * sn;
    p.h[0] = nt * (sn - s3 / 3) - nz * c3 / 3;
    p.h[1] = cos0;
    p.h[2] = cos1;
    p.v[0] = -nt * c3 / 3 + nz * s3 / 3;
    p.v[1] = nt * 0.5 * sn * sn + nz * (0.5 * e - 0.5 * sc);
    p.v[2] = -nt * c + nz * (log_sec_tan - sn);
  }
  return p;
}

namespace {

// The elevations of [a, b] (clipped to the tangent and the zenith) whose rays can meet the segment within
// the falloff's radius (step, linear, smooth: the segment's part inside the circle of radius R is one
// interval of u, and the elevation of A + u (B - A) is monotone in u); false when none can.
bool segment_support(const Falloff& f, const SliceFrame& s, double& lo, double& hi, SliceVec A, SliceVec B) {
  lo = std::max(lo, s.tangent), hi = std::min(hi, kHalfPi);
  if (!(hi > lo)) return false;
  if (f.kind != FalloffKind::step && f.kind != FalloffKind::linear && f.kind != FalloffKind::smooth)
    return true;
  const double R = f.radius, dh = B.h - A.h, dv = B.v - A.v;
  const double dd = dh * dh + dv * dv, ad = A.h * dh + A.v * dv, aa = A.h * A.h + A.v * A.v;
  const double disc = ad * ad - dd * (aa - R * R);
  if (!(disc > 0) || !(dd > 0)) return false;
  const double root = std::sqrt(disc), u1 = (-ad - root) / dd, u2 = (-ad + root) / dd;
  if (!(u2 > 0) || !(u1 < 1)) return false;
  if (u1 > 0) lo = std::max(lo, std::atan2(A.v + u1 * dv, A.h + u1 * dh));
  if (u2 < 1) hi = std::min(hi, std::atan2(A.v + u2 * dv, A.h + u2 * dh));
  return hi > lo;
}

// Distance from the receiver along elevation e to the segment's line.
double segment_distance(SliceVec A, SliceVec B, double e) {
  const double dh = B.h - A.h, dv = B.v - A.v;
  const double den = std::cos(e) * dv - std::sin(e) * dh;
  const double num = A.h * dv - A.v * dh;
  return den != 0 ? std::max(0.0, num / den) : 0.0;
}

}  // namespace

double segment_band_occlusion(const Falloff& f, Weighting w, const SliceFrame& s, double a, double b,
                              SliceVec A, SliceVec B) {
  double lo = a, hi = b;
  if (!segment_support(f, s, lo, hi, A, B)) return 0.0;
  const bool cosine = w == Weighting::cosine;
  if (f.kind == FalloffKind::none || f.kind == FalloffKind::step)
    return cosine ? cos_p0(s, hi) - cos_p0(s, lo) : uni_p0(hi) - uni_p0(lo);
  return gauss(
      [&](double e) {
        const double c = std::cos(e);
        const double wt = cosine ? std::max(0.0, s.nt * c + s.nz * std::sin(e)) * c : c;
        return f(segment_distance(A, B, e)) * wt;
      },
      lo, hi);
}

SliceVec segment_band_direction(const Falloff& f, const SliceFrame& s, double a, double b, SliceVec A,
                                SliceVec B) {
  double lo = a, hi = b;
  if (!segment_support(f, s, lo, hi, A, B)) return {};
  if (f.kind == FalloffKind::none || f.kind == FalloffKind::step) return open_direction(s, lo, hi);
  auto weight = [&](double e) {
    const double c = std::cos(e);
    return f(segment_distance(A, B, e)) * std::max(0.0, s.nt * c + s.nz * std::sin(e)) * c;
  };
  return {gauss([&](double e) { return weight(e) * std::cos(e); }, lo, hi),
          gauss([&](double e) { return weight(e) * std::sin(e); }, lo, hi)};
}

}  // namespace hfbake
