#include "methods/ao/farfield_slab_table.hpp"

#include <algorithm>
#include <cmath>
#include <functional>

#include "core/vec.hpp"

namespace hfbake {
namespace {

double prim_a(double e) {  // integral of cos^2
  return 0.5 * e + 0.25 * std::sin(2.0 * e);
}
double prim_b(double e) {  // integral of sin cos
  const double s = std::sin(e);
  return 0.5 * s * s;
}

// rho at the distance along a ray of elevation e to a slab at horizontal distance x > 0.
double rho_on_slab(const Falloff& rho, double x, double e) {
  const double c = std::cos(e);
  if (c <= 0.0) return 0.0;
  return rho(x / c);
}

}  // namespace

SlabTable::SlabTable(const Falloff& rho, int elevation_nodes, int distance_nodes) : rho_(rho) {
  if (rho.kind == FalloffKind::none || rho.kind == FalloffKind::step) return;  // closed forms
  ne_ = std::max(elevation_nodes, 3);
  nu_ = std::max(distance_nodes, 3);
  compact_ = rho.kind == FalloffKind::linear || rho.kind == FalloffKind::smooth;
  a_.assign(std::size_t(ne_) * nu_, 0.0);
  b_.assign(std::size_t(ne_) * nu_, 0.0);
  const double de = kPi / (ne_ - 1);
  constexpr int kSub = 8;  // Simpson sub-intervals per table cell (even)
  for (int iu = 0; iu < nu_; ++iu) {
    const double u = double(iu) / (nu_ - 1);
    double* ca = &a_[std::size_t(iu) * ne_];
    double* cb = &b_[std::size_t(iu) * ne_];
    if (iu == 0) {  // x = 0: rho = 1 on every ray
      for (int ie = 0; ie < ne_; ++ie) {
        const double e = -kHalfPi + ie * de;
        ca[ie] = prim_a(e) - prim_a(-kHalfPi);
        cb[ie] = prim_b(e) - prim_b(-kHalfPi);
      }
      continue;
    }
    if (iu == nu_ - 1) continue;  // x >= R (compact) or x = infinity: rho = 0
    const double x = compact_ ? u * rho.radius : rho.radius * u / (1.0 - u);
    double sa = 0, sb = 0;
    ca[0] = cb[0] = 0;
    for (int ie = 0; ie + 1 < ne_; ++ie) {
      const double e0 = -kHalfPi + ie * de, h = de / kSub;
      double ia = 0, ib = 0;
      for (int s = 0; s <= kSub; ++s) {
        const double e = e0 + s * h;
        const double w = (s == 0 || s == kSub) ? 1.0 : (s % 2 ? 4.0 : 2.0);
        const double r = rho_on_slab(rho, x, e), c = std::cos(e);
        ia += w * r * c * c;
        ib += w * r * std::sin(e) * c;
      }
      sa += ia * h / 3.0;
      sb += ib * h / 3.0;
      ca[ie + 1] = sa;
      cb[ie + 1] = sb;
    }
  }
}

double SlabTable::to_u(double x) const {
  if (compact_) return std::min(x / rho_.radius, 1.0);
  return x / (x + rho_.radius);
}

void SlabTable::integrals(double e, double x, double* a, double* b) const {
  e = std::clamp(e, -kHalfPi, kHalfPi);
  switch (rho_.kind) {
    case FalloffKind::none:
      *a = prim_a(e) - prim_a(-kHalfPi);
      *b = prim_b(e) - prim_b(-kHalfPi);
      return;
    case FalloffKind::step: {
      if (x >= rho_.radius) {
        *a = *b = 0;
        return;
      }
      const double al = std::acos(std::max(x, 0.0) / rho_.radius);  // rays with |e| < al end before R
      const double hi = std::clamp(e, -al, al);
      *a = prim_a(hi) - prim_a(-al);
      *b = prim_b(hi) - prim_b(-al);
      return;
    }
    default:
      break;
  }
  const double fe = (e + kHalfPi) / kPi * (ne_ - 1);
  const double fu = to_u(std::max(x, 0.0)) * (nu_ - 1);
  const int ie = std::min(int(fe), ne_ - 2), iu = std::min(int(fu), nu_ - 2);
  const double te = fe - ie, tu = fu - iu;
  const std::size_t i00 = std::size_t(iu) * ne_ + ie, i10 = i00 + 1, i01 = i00 + ne_, i11 = i01 + 1;
  *a = (a_[i00] * (1 - te) + a_[i10] * te) * (1 - tu) + (a_[i01] * (1 - te) + a_[i11] * te) * tu;
  *b = (b_[i00] * (1 - te) + b_[i10] * te) * (1 - tu) + (b_[i01] * (1 - te) + b_[i11] * te) * tu;
}

double SlabTable::band(double a, double b, double x, double nt, double nz, double t) const {
  if (b <= t || b <= a) return 0.0;
  a = std::max(a, t);
  double a0, b0, a1, b1;
  integrals(a, x, &a0, &b0);
  integrals(b, x, &a1, &b1);
  return std::max(0.0, nt * (a1 - a0) + nz * (b1 - b0));
}

double slab_band_reference(const Falloff& rho, double a, double b, double x, double nt, double nz) {
  const std::function<double(double)> f = [&](double e) {
    const double c = std::cos(e);
    const double r = x > 0 ? rho_on_slab(rho, x, e) : 1.0;
    return r * std::max(0.0, nt * c + nz * std::sin(e)) * c;
  };
  // Adaptive Simpson on [a, b].
  const std::function<double(double, double, double, double, double, double, int)> rec =
      [&](double l, double r, double fl, double fm, double fr, double whole, int depth) {
        const double m = 0.5 * (l + r), lm = 0.5 * (l + m), rm = 0.5 * (m + r);
        const double flm = f(lm), frm = f(rm);
        const double left = (m - l) / 6 * (fl + 4 * flm + fm), right = (r - m) / 6 * (fm + 4 * frm + fr);
        if (depth <= 0 || std::fabs(left + right - whole) < 1e-12) return left + right;
        return rec(l, m, fl, flm, fm, left, depth - 1) + rec(m, r, fm, frm, fr, right, depth - 1);
      };
  if (b <= a) return 0.0;
  const int pieces = 64;
  double sum = 0;
  for (int p = 0; p < pieces; ++p) {
    const double l = a + (b - a) * p / pieces, r = a + (b - a) * (p + 1) / pieces, m = 0.5 * (l + r);
    const double fl = f(l), fm = f(m), fr = f(r);
    sum += rec(l, r, fl, fm, fr, (r - l) / 6 * (fl + 4 * fm + fr), 30);
  }
  return sum;
}

}  // namespace hfbake
