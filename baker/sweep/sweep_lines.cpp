#include "sweep/sweep_lines.hpp"

#include "core/azimuth.hpp"
#include "core/threads.hpp"

#include <climits>

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
    // Thin fields: lines keep the columns around their run (header: trimmed lines).
    if (spec.sampling.trim_thin && d.slope != 0) {
      const double need = std::ceil((d.n_minor + 2) / std::fabs(d.slope)) + 4;
      if (4 * need <= d.n_major) d.span = int(need);
    }
  }
  return d;
}

int line_u_start(const SweepDirection& d, int line) {
  if (d.span == 0) return d.u_start;
  // Columns where v = line + u * slope lies in [-1.5, n_minor + 0.5], widened by a column each side.
  const double ua = (-1.5 - line) / d.slope, ub = (d.n_minor + 0.5 - line) / d.slope;
  const double lo = std::floor(std::min(ua, ub)) - 1;
  const int first = int(std::clamp(lo, 0.0, double(d.n_major - d.span)));
  return d.su > 0 ? first : first + d.span - 1;
}

SweepDirection line_direction(const SweepDirection& d, int line) {
  if (d.span == 0) return d;
  SweepDirection t = d;
  t.count = d.span;
  t.u_start = line_u_start(d, line);
  return t;
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

void sweep_tile_lines(const SweepDirection& d, int i0, int i1, int j0, int j1, int* lo, int* hi) {
  const int ua = d.x_major ? i0 : j0, ub = (d.x_major ? i1 : j1) - 1;
  const int va = d.x_major ? j0 : i0, vb = (d.x_major ? j1 : i1) - 1;
  // g = v0 - u * slope as texel_taps computes it: the rounded product and difference are monotone, so the
  // smallest g is at (the u with the largest u * slope, va) and the largest at (the other u, vb).
  auto line_of = [&](int u, int v) { return floor_int(double(v) - double(u) * d.slope); };
  const int l_min = line_of(d.slope > 0 ? ub : ua, va) - d.line_begin;
  const int l_max = line_of(d.slope > 0 ? ua : ub, vb) - d.line_begin;
  if (!d.repeat) {
    *lo = std::clamp(l_min, 0, d.lines() - 2);
    *hi = std::clamp(l_max, 0, d.lines() - 2) + 1;
    return;
  }
  const int n = d.n_minor;
  if (l_max + 1 - l_min + 1 >= n) {
    *lo = 0;
    *hi = n - 1;
    return;
  }
  *lo = wrap_index(l_min, n);
  *hi = wrap_index(l_max + 1, n);
}

namespace detail {

SweepStream plan_stream(const HeightField& f, const SweepDirection& d, std::size_t budget_bytes, int channels,
                        bool with_order) {
  SweepStream s;
  const int L = d.lines();
  const int tx = (f.width + kSweepTile - 1) / kSweepTile, ty = (f.height + kSweepTile - 1) / kSweepTile;
  const std::size_t T = std::size_t(tx) * std::size_t(ty);
  std::vector<int> first_line(T), last_line(T);
  for (int tj = 0; tj < ty; ++tj)
    for (int ti = 0; ti < tx; ++ti) {
      const std::size_t t = std::size_t(tj) * tx + ti;
      int lo, hi;
      sweep_tile_lines(d, ti * kSweepTile, std::min(f.width, (ti + 1) * kSweepTile), tj * kSweepTile,
                       std::min(f.height, (tj + 1) * kSweepTile), &lo, &hi);
      if (lo > hi) {  // across the repeat seam: lines [0, hi] from the head, gathered after the last line
        s.head = std::max(s.head, hi + 1);
        hi = L - 1;
      }
      first_line[t] = lo, last_line[t] = hi;
    }
  // Tiles by last line (a counting sort: first[p] = tiles whose last line is below p).
  s.first.assign(std::size_t(L) + 1, 0);
  for (std::size_t t = 0; t < T; ++t) ++s.first[std::size_t(last_line[t]) + 1];
  for (int p = 0; p < L; ++p) s.first[p + 1] += s.first[p];
  // keep[p]: the first ring line that a tile whose last line is >= p still reads.
  std::vector<int> keep(std::size_t(L) + 1, INT_MAX);
  int span = 1;
  for (std::size_t t = 0; t < T; ++t) {
    const int a = std::max(first_line[t], s.head);
    keep[last_line[t]] = std::min(keep[last_line[t]], a);
    span = std::max(span, last_line[t] - a + 1);
  }
  for (int p = L - 1; p >= 0; --p) keep[p] = std::min(keep[p], keep[p + 1]);
  // The ring lines a chunk size needs: after computing [c0, c1) the lines [keep, c1) are live.
  auto window_for = [&](int chunk) {
    int w = 1;
    for (int c0 = 0; c0 < L; c0 += chunk) {
      const int c1 = std::min(L, c0 + chunk);
      if (c1 > s.head) w = std::max(w, c1 - std::max(s.head, std::min(keep[c0], c0)));
    }
    return w;
  };
  const std::size_t line_bytes = std::size_t(d.stride()) * std::size_t(channels) * sizeof(float);
  const std::size_t fit = budget_bytes / line_bytes;
  // Ring lines the budget leaves beside the head (at least one); no more than the lines there are.
  const int budget = fit > std::size_t(s.head) ? int(std::min(fit - std::size_t(s.head), std::size_t(L))) : 1;
  s.chunk = std::max(1, budget - span + 1);
  s.window = window_for(s.chunk);
  while (s.window > budget && s.chunk > 1) {  // the window is about chunk + span - 1: shrink by the excess
    s.chunk = std::max(1, s.chunk - (s.window - budget));
    s.window = window_for(s.chunk);
  }
  if (with_order) {
    s.order.resize(T);
    std::vector<std::uint32_t> at(s.first.begin(), s.first.end() - 1);
    for (std::size_t t = 0; t < T; ++t) s.order[at[last_line[t]]++] = std::uint32_t(t);
  }
  return s;
}

SweepPlan plan_sweep(const HeightField& f, const SweepSpec& spec, const std::vector<SweepDirection>& dirs) {
  SweepPlan plan;
  const int K = int(dirs.size());
  const std::size_t C = std::size_t(std::max(1, spec.channels));
  const std::size_t t_bytes = f.texel_count() * sizeof(float);
  bool any_y_major = false;
  for (const SweepDirection& d : dirs) any_y_major = any_y_major || !d.x_major;
  plan.transposed = spec.sampling.heights && any_y_major && t_bytes <= spec.buffers.max_bytes / 4;
  plan.buffer_budget = spec.buffers.max_bytes - (plan.transposed ? t_bytes : 0);
  auto whole = [&](int k) {
    return std::size_t(dirs[k].lines()) * std::size_t(dirs[k].stride()) * C * sizeof(float);
  };
  const int batch = std::max(1, spec.buffers.batch);
  for (int k0 = 0; k0 < K;) {
    SweepBatch b;
    b.k0 = k0;
    std::size_t bytes = whole(k0);
    if (bytes > plan.buffer_budget) {
      b.stream = true;
    } else {
      while (b.nb < batch && k0 + b.nb < K && bytes + whole(k0 + b.nb) <= plan.buffer_budget)
        bytes += whole(k0 + b.nb++);
    }
    plan.batches.push_back(b);
    k0 += b.nb;
  }
  return plan;
}

}  // namespace detail

std::size_t sweep_buffer_bytes(const HeightField& f, const SweepSpec& spec) {
  const int K = spec.azimuths.empty() ? spec.directions : int(spec.azimuths.size()), C = spec.channels;
  if (K <= 0 || C <= 0 || f.width <= 0 || f.height <= 0) return 0;
  std::vector<SweepDirection> dirs(K);
  int max_count = 0;
  for (int k = 0; k < K; ++k) {
    dirs[k] = plan_direction(f, spec, k);
    max_count = std::max(max_count, dirs[k].count);
  }
  const detail::SweepPlan plan = detail::plan_sweep(f, spec, dirs);
  const std::size_t tiles = std::size_t((f.width + detail::kSweepTile - 1) / detail::kSweepTile) *
                            std::size_t((f.height + detail::kSweepTile - 1) / detail::kSweepTile);
  std::size_t storage = 0, batch_peak = 0;
  for (const detail::SweepBatch& b : plan.batches) {
    std::size_t floats = 0, extra = 0;
    for (int k = b.k0; k < b.k0 + b.nb; ++k) {
      const SweepDirection& d = dirs[k];
      const std::size_t line_floats = std::size_t(d.stride()) * std::size_t(C);
      extra += std::size_t(d.lines()) * sizeof(float*);  // the line table
      if (b.stream) {
        const detail::SweepStream s = detail::plan_stream(f, d, plan.buffer_budget, C, false);
        floats += std::size_t(s.head + s.window) * line_floats;
        // The tile order and its index, and plan_stream's two ints per tile and per line.
        extra += tiles * (sizeof(std::uint32_t) + 2 * sizeof(int)) +
                 (std::size_t(d.lines()) + 1) * (sizeof(std::uint32_t) + sizeof(int));
      } else {
        floats += std::size_t(d.lines()) * line_floats;
      }
    }
    storage = std::max(storage, floats * sizeof(float));
    batch_peak = std::max(batch_peak, extra);
  }
  const std::size_t threads = std::size_t(worker_threads());
  const std::size_t per_thread =
      std::size_t(max_count) * sizeof(float) + std::size_t(4 * C + 3) * 32 * 32 * sizeof(float);
  return storage + batch_peak + (plan.transposed ? f.texel_count() * sizeof(float) : 0) +
         threads * per_thread;
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
