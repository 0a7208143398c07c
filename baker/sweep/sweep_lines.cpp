#include "sweep/sweep_lines.hpp"

#include "core/azimuth.hpp"

namespace hfbake {
namespace {

int wrap_index(int a, int n) {
  a %= n;
  return a < 0 ? a + n : a;
}
int clamp_index(int a, int n) {
  return a < 0 ? 0 : (a >= n ? n - 1 : a);
}

}  // namespace

SweepDirection plan_direction(const HeightField& field, const SweepSpec& spec, int k) {
  SweepDirection d;
  d.k = k;
  bool on_octant;
  int octant = -1;
  if (spec.azimuths.empty()) {
    const int K = spec.directions;
    d.phi = azimuth(k, K);
    // Exact axes and diagonals (8k/K integral): no rounding noise in the slope or the major axis choice.
    const long long e8 = 8LL * k;
    on_octant = e8 % K == 0;
    if (on_octant) octant = int((e8 / K) % 8);
  } else {
    d.phi = spec.azimuths[k];
    const double o = d.phi / (kPi / 4), r = std::round(o);
    on_octant = std::fabs(o - r) < 1e-12;
    if (on_octant) octant = int(((long long)r % 8 + 8) % 8);
  }
  d.dx = std::cos(d.phi);
  d.dy = std::sin(d.phi);
  if (on_octant && octant % 2 == 0) {
    static const int ax[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
    d.dx = ax[octant / 2][0];
    d.dy = ax[octant / 2][1];
  }
  d.x_major = on_octant && octant % 2 == 1 ? true : std::fabs(d.dx) >= std::fabs(d.dy);
  const double dmaj = d.x_major ? d.dx : d.dy, dmin = d.x_major ? d.dy : d.dx;
  d.su = dmaj > 0 ? -1 : 1;
  d.slope = dmin / dmaj;
  if (on_octant) d.slope = std::round(d.slope);  // 0 or +-1 exactly
  d.n_major = d.x_major ? field.width : field.height;
  d.n_minor = d.x_major ? field.height : field.width;
  d.repeat = field.wrap == Wrap::repeat;
  d.texel_size = field.texel_size;
  d.step = field.texel_size * std::sqrt(1 + d.slope * d.slope);
  if (d.repeat) {
    const int P = std::max(1, spec.wrap_periods);
    d.line_begin = 0;
    d.line_end = d.n_minor;
    d.count = (P + 1) * d.n_major;
    d.first_receiver = P * d.n_major;
    d.u_start = d.su > 0 ? -P * d.n_major : d.n_major - 1 + P * d.n_major;
  } else {
    // Every texel (u, v0) blends lines floor(v0 - u * slope) and the next: cover the extremes.
    const double far = 0.0 - double(d.n_major - 1) * d.slope;
    const double lo = std::min(0.0, far), hi = std::max(double(d.n_minor - 1), double(d.n_minor - 1) + far);
    d.line_begin = int(std::floor(lo));
    d.line_end = int(std::floor(hi)) + 2;
    d.count = d.n_major;
    d.first_receiver = 0;
    d.u_start = d.su > 0 ? 0 : d.n_major - 1;
  }
  return d;
}

void sample_line(const HeightField& f, const SweepDirection& d, int line, float* z, int* inside_begin,
                 int* inside_end, const float* transposed) {
  const int nmin = d.n_minor, nmaj = d.n_major;
  const bool use_t = !d.x_major && transposed;
  const float* data = use_t ? transposed : f.z.data();
  // x-major: z[v * width + u]; y-major: z[u * width + v], or transposed[v * height + u].
  const std::ptrdiff_t major_stride = d.x_major ? 1 : (use_t ? 1 : f.width);
  const std::ptrdiff_t minor_stride = d.x_major ? f.width : (use_t ? f.height : 1);
  int ib = -1, ie = -1;
  // repeat: wrapped indices followed incrementally (u moves by one, floor(v) by at most one per step).
  int um_w = wrap_index(d.u_start, nmaj), j0_prev = 0, a_prev = 0;
  bool have_prev = false;
  for (int n = 0; n < d.count; ++n) {
    const int u = d.u_start + n * d.su;
    const double v = line + double(u) * d.slope;
    const double fv = double(floor_int(v));
    const int j0 = int(fv);
    const float t = float(v - fv);
    int um, a, b;
    if (d.repeat) {
      if (n > 0) {
        um_w += d.su;
        if (um_w == nmaj) um_w = 0;
        if (um_w < 0) um_w = nmaj - 1;
      }
      um = um_w;
      if (have_prev && j0 == j0_prev) {
        a = a_prev;
      } else if (have_prev && j0 == j0_prev + 1) {
        a = a_prev + 1 == nmin ? 0 : a_prev + 1;
      } else if (have_prev && j0 == j0_prev - 1) {
        a = a_prev == 0 ? nmin - 1 : a_prev - 1;
      } else {
        a = wrap_index(j0, nmin);
      }
      j0_prev = j0, a_prev = a, have_prev = true;
      b = a + 1 == nmin ? 0 : a + 1;
    } else {
      um = u;
      a = clamp_index(j0, nmin);
      b = clamp_index(j0 + 1, nmin);
      if (v >= 0 && v <= nmin - 1) {
        if (ib < 0) ib = n;
        ie = n + 1;
      }
    }
    const float za = data[um * major_stride + a * minor_stride],
                zb = data[um * major_stride + b * minor_stride];
    z[n] = za * (1 - t) + zb * t;
  }
  if (d.repeat) {
    *inside_begin = 0;
    *inside_end = d.count;
  } else {
    *inside_begin = ib < 0 ? 0 : ib;
    *inside_end = ib < 0 ? 0 : ie;
  }
}

TexelPair SweepLine::height_taps(int n, const HeightField& f) const {
  const SweepDirection& d = *dir;
  const int u = d.u(n);
  const double v = d.v(line, n), fv = double(floor_int(v));
  const int j0 = int(fv);
  const float t = float(v - fv);
  int um, a, b;
  if (d.repeat) {
    um = wrap_index(u, d.n_major), a = wrap_index(j0, d.n_minor), b = wrap_index(j0 + 1, d.n_minor);
  } else {
    um = u, a = clamp_index(j0, d.n_minor), b = clamp_index(j0 + 1, d.n_minor);
  }
  TexelPair p;
  p.texel[0] = std::ptrdiff_t(d.x_major ? f.index(um, a) : f.index(a, um));
  p.texel[1] = std::ptrdiff_t(d.x_major ? f.index(um, b) : f.index(b, um));
  p.weight[0] = 1 - t;
  p.weight[1] = t;
  return p;
}

TexelPair SweepLine::receiver_texels(int n, const HeightField& f) const {
  const SweepDirection& d = *dir;
  const int u = d.repeat ? wrap_index(d.u(n), d.n_major) : d.u(n);
  const double v = d.v(line, n), fv = double(floor_int(v));
  const int j0 = int(fv);
  const float t = float(v - fv);
  TexelPair p;
  if (!d.repeat && (v < 0 || v > d.n_minor - 1)) return p;  // off the field: no receiver
  for (int e = 0; e < 2; ++e) {
    int a = j0 + e;
    if (d.repeat)
      a = wrap_index(a, d.n_minor);
    else if (a < 0 || a >= d.n_minor)
      continue;
    p.texel[e] = std::ptrdiff_t(d.x_major ? f.index(u, a) : f.index(a, u));
    p.weight[e] = e == 0 ? 1 - t : t;
    // A border texel whose other line runs off the field takes this sample alone (see texel_taps).
    if (lone_border_tap(d, a, t)) p.weight[e] = 1;
  }
  return p;
}

}  // namespace hfbake
