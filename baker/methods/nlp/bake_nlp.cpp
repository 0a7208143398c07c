#include "methods/nlp/bake_nlp.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "core/azimuth.hpp"
#include "core/error.hpp"
#include "field/triangulation.hpp"
#include "job/params.hpp"
#include "methods/nlp/horizon_march.hpp"
#include "methods/nlp/nlp_basis.hpp"
#include "methods/nlp/pyramid.hpp"
#include "methods/nlp/sh.hpp"
#include "methods/nlp/sh_lighting.hpp"

namespace hfbake {

const char* sh_convention_text() {
  return "real spherical harmonics, order 4 (bands l = 0..3), 16 coefficients per channel; index i = "
         "l*(l+1)+m "
         "(m = -l..l): 000 = (0,0), 001..003 = (1,-1),(1,0),(1,1), 004..008 = (2,-2)..(2,2), 009..015 = "
         "(3,-3)..(3,3); orthonormal on the sphere (integral of Y_i Y_j = delta_ij); no Condon-Shortley "
         "phase "
         "(m > 0: cos(m phi), m < 0: sin(|m| phi)); world frame, +z up, direction (sin t cos p, sin t sin p, "
         "cos t), "
         "phi from +x towards +y. Y000 = 0.282095; Y001..003 = 0.488603 (y, z, x); Y004 = 1.092548 xy, "
         "Y005 = 1.092548 yz, Y006 = 0.315392 (3z^2-1), Y007 = 1.092548 xz, Y008 = 0.546274 (x^2-y^2); "
         "Y009 = 0.590044 y(3x^2-y^2), Y010 = 2.890611 xyz, Y011 = 0.457046 y(5z^2-1), Y012 = 0.373176 "
         "z(5z^2-3), Y013 = 0.457046 x(5z^2-1), Y014 = 1.445306 z(x^2-y^2), Y015 = 0.590044 x(x^2-3y^2). "
         "sh_visibility: SH of the binary visibility V(w) over the whole sphere (1 = the ray escapes). "
         "sh_irradiance: SH of E(n)/pi as a function of the normal n (channels <coefficient>.R/G/B): "
         "sum_i c_i Y_i(n) is the diffuse total (direct + indirect) / pi for a surface of normal n at that "
         "texel; band 3 is zero (the clamped cosine has no l = 3 part). Incident radiance L_in = c_i / A_l "
         "with A_l = {1, 2/3, 1/4} for l = 0, 1, 2.";
}

const std::vector<std::string>& nlp_layer_names() {
  static const std::vector<std::string> names = {"direct", "indirect", "total", "sh_visibility",
                                                 "sh_irradiance"};
  return names;
}

NlpOptions read_nlp_options(Params& in) {
  NlpOptions o;
  o.directions = in.integer("directions", o.directions, 3, 1024);
  o.levels_per_octave = in.integer("levels_per_octave", o.levels_per_octave, 1, 16);
  o.level_offset = in.integer("level_offset", o.level_offset, 0, 16);
  o.radiance_level_offset = in.integer("radiance_level_offset", o.radiance_level_offset, 0, 16);
  o.light_directions = in.integer("light_directions", o.light_directions, 1, 64);
  o.light_level_offset = in.integer("light_level_offset", o.light_level_offset, 0, 16);
  o.light_horizon_knots = in.choice("light_horizon", "knots", {"bspline", "knots"}) == "knots";
  o.visibility_horizon_knots = in.choice("visibility_horizon", "knots", {"bspline", "knots"}) == "knots";
  o.subsample = in.integer("subsample", o.subsample, 1, 2);
  o.exact_indirect_cosine = in.choice("indirect_cosine", "exact", {"sh", "exact"}) == "exact";
  o.exact_direct_cosine = in.choice("direct_cosine", "exact", {"sh", "exact"}) == "exact";
  o.near_spacing = in.number("near_spacing", o.near_spacing, 0, 64);
  o.facet_senders = in.choice("senders", "facets", {"facets", "texels"}) == "facets";
  nlp::parse_azimuth_interpolation(in.choice("azimuth_interpolation", "linear", {"linear", "bspline"}),
                                   o.interpolation);
  o.layers = in.layers(nlp_layer_names(), o.layers);
  return o;
}

namespace {

constexpr int kSh = sh::kCount;

// Receivers along an axis of n texels: every texel, or with subsample sub > 1 every sub-th and the last.
int receivers_along(int n, int sub) {
  return (n + sub - 1) / sub + (sub > 1 && (n - 1) % sub ? 1 : 0);
}
// sh_irradiance: 16 coefficients x RGB a texel, held as the layer itself (bands l < 3 filled: 27 floats).
constexpr std::size_t kIrrChannels = 3 * kSh;
constexpr float kInvPi = float(1 / kPi);
constexpr float kInf = std::numeric_limits<float>::infinity();
// Clamped-cosine convolution per coefficient (l <= 2; band 3 is zero).
constexpr float kConv[9] = {3.14159265f, 2.09439510f, 2.09439510f, 2.09439510f, 0.78539816f,
                            0.78539816f, 0.78539816f, 0.78539816f, 0.78539816f};

struct LightSetup {
  Vec3 dir;
  Rgb irradiance;
  float elevation = 0, radius = 0;
  std::vector<float> cx, cy;  // sub-azimuths across the disk
  float sh[9];                // a_l Y_k(dir) / pi: the light's contribution to sh_irradiance per unit
};

// The radiance kernel's per-receiver state along one azimuth (RowMarch order: receiver t of the row).
struct RadianceRow {
  std::vector<float> run, prevF, nh, cur, prev, u;  // prev: 4 a receiver, u: 3 x 4
  std::vector<float> lim;                           // 2 n - 1: the receiver's curve points
  std::vector<float> hit;                           // 1: this point is in the receiver's casting set
  std::vector<int> hits;                            // the receivers with hit 1, increasing
  std::vector<float> rad;                           // 3 a hit: the radiance its stretch sends
  std::vector<unsigned char> any;
  explicit RadianceRow(int width)
      : run(std::size_t(width)),
        prevF(std::size_t(width)),
        nh(std::size_t(width)),
        cur(std::size_t(width)),
        prev(4 * std::size_t(width)),
        u(12 * std::size_t(width)),
        lim(std::size_t(width)),
        hit(std::size_t(width)),
        hits(std::size_t(width)),
        rad(3 * std::size_t(width)),
        any(std::size_t(width)) {}
};

// Curve point p (knots k-1..k+2 of every receiver in w0..w3; even p: knot k, odd: between k and k + 1) for
// a row of receivers: cur[t] = its value, and where it is one of the receiver's curve points (p < lim[t])
// above the running maximum run[t], run[t] = it and hit[t] = 1 (else 0). Returns whether any receiver hit.
int curve_point(int cnt, int p, const float* __restrict w0, const float* __restrict w1,
                const float* __restrict w2, const float* __restrict w3, const float* __restrict lim,
                float* __restrict cur, float* __restrict run, float* __restrict hit) {
  const float fp = float(p);
  int hits = 0;
  if (p & 1) {
    for (int t = 0; t < cnt; ++t) {
      const float c = (w0[t] + 23 * w1[t] + 23 * w2[t] + w3[t]) * (1.0f / 48), r = run[t];
      const bool h = (fp < lim[t]) & (c > r);
      run[t] = h ? c : r;
      cur[t] = c;
      hit[t] = h ? 1.0f : 0.0f;
      hits |= int(h);
    }
  } else {
    for (int t = 0; t < cnt; ++t) {
      const float c = (w0[t] + 4 * w1[t] + w2[t]) * (1.0f / 6), r = run[t];
      const bool h = (fp < lim[t]) & (c > r);
      run[t] = h ? c : r;
      cur[t] = c;
      hit[t] = h ? 1.0f : 0.0f;
      hits |= int(h);
    }
  }
  return hits;
}

// The receivers whose hit is 1, increasing, into out; returns their count. Branch-free: every receiver is
// stored and the count moves past the kept ones (which receivers hit is hard to predict).
int hit_list(int cnt, const float* __restrict hit, int* __restrict out) {
  int n = 0;
  for (int t = 0; t < cnt; ++t) {
    out[n] = t;
    n += hit[t] != 0 ? 1 : 0;
  }
  return n;
}

// Per-thread buffers: one row of receivers (heights per level, per-receiver outputs) and one march.
struct Scratch {
  std::vector<float> recv;  // [l * width + t]: receiver t's height in level l
  std::vector<float> omega, dist, curve, row, wmax;
  std::vector<Vec3f> nrm;  // the row's receivers' normals (normal_at)
  nlp::RowMarch rm;        // one azimuth's march of the row
  RadianceRow rad;
  explicit Scratch(int levels, int steps, int width, int row_floats)
      : recv(std::size_t(levels) * width),
        omega(steps + 1),
        dist(steps + 1),
        curve(2 * steps + 2),
        row(std::size_t(row_floats) * width),
        wmax(std::size_t(width)),
        nrm(std::size_t(width)),
        rm(steps, width),
        rad(width) {}
};

nlp::MarchSetup with_near_spacing(nlp::MarchSetup s, double spacing) {
  s.near_spacing = float(spacing);
  return s;
}

bool wants(const NlpOptions& o, const char* name) {
  return std::find(o.layers.begin(), o.layers.end(), name) != o.layers.end();
}

// One bake, in phases: the inputs (normals, pyramids, azimuths, the environment's SH products, the lights),
// pass 1 (visibility V and direct light, Eq. 11), one pass per bounce (indirect radiance U, Eq. 12) and the
// output layers. The kernels (visibility, radiance) work on a row of receivers at a time, azimuth-major,
// so neighbouring receivers march the same direction through the same cache lines.
class NlpBake {
 public:
  NlpBake(const Scene& scene, const NlpOptions& o, const RunControl& rc);
  void direct_pass();
  void bounce_passes();
  LayerSet layers();

 private:
  // --- inputs ---
  static std::vector<LightSetup> setup_lights(const Scene& scene, const NlpOptions& o);
  void setup_environment();
  void setup_environment_wedges();
  void env_above(int a, float e, float nh, float nz, float* out) const;

  // --- kernels ---
  void receivers(Scratch& s, const int* xs, int cnt, int j) const;
  void horizons(Scratch& s, const int* xs, int cnt, int j, float cx, float cy, bool light) const;
  void light_visibility(Scratch& s, const int* xs, int cnt, int j, float* out, int stride) const;
  void visibility(Scratch& s, const int* xs, int cnt, int j, float* out, int stride, bool exact_env) const;
  void facet_radiance(float x, float y, float* out) const;
  void radiance(const nlp::Pyramid& rp, Scratch& s, const int* xs, int cnt_row, int j, float* Uout,
                float* Eout) const;

  // --- shading ---
  void shade_direct(int i, int j, const float* V, const float* frac, const float* E);
  void direct_facets(int i, int j, const float (&lin)[3][9], const float* frac);
  // add: this_bounce[idx] += the texel's indirect light (the last bounce adds straight into `indirect`);
  // else this_bounce[idx] = it.
  void shade_indirect(std::vector<Rgb>& this_bounce, bool add, int i, int j, const float* U, const float* E);
  void upsample(const std::vector<float>& buf, int cnt, int i, int j, float* out) const;
  int coarse_i(int ci) const { return std::min(ci * sub, W - 1); }
  int coarse_j(int cj) const { return std::min(cj * sub, H - 1); }
  void report_rows(int rows) { rc.report(std::min(1.0, (rows_done += rows) / units)); }

  const Scene& scene;
  const NlpOptions& o;
  const RunControl& rc;
  const HeightField& f;
  const int W, H, m;
  const std::size_t N;
  const nlp::MarchSetup ms;
  // Directional lights march with their own (sharper) level offset; the pyramid has enough levels.
  const nlp::MarchSetup ms_light;
  const nlp::Pyramid hp;
  const std::vector<std::array<float, 64>> A;
  std::vector<float> cphi, sphi;
  // Environment in SH and its product matrices (rows k < 9 suffice: the cosine has no band 3).
  float T[3][9][kSh];
  // direct_cosine exact: per azimuth a, the environment's mean radiance over the wedge of a, per lat-long
  // row r (env_rad[(a * env_rows + r) * 3 + c]), and its integrals from the zenith down to row r's upper
  // edge, of L cos^2 e (env_cum[(a * (env_rows + 1) + r) * 6 + c]) and of L sin e cos e (+ 3 + c); env_edge:
  // the row edges' F(e) = ((e + sin e cos e) / 2, sin^2 e / 2).
  int env_rows = 0;
  std::vector<float> env_rad, env_cum, env_edge;
  const std::vector<LightSetup> lights;
  const std::size_t nl;
  const bool want_vis, want_irr;
  const int lv, steps;
  // Receivers of V and U: every texel, or (subsample 2) every other texel in x and y, whose V, U and light
  // visibility are bilinearly interpolated to the texels in between and shaded with their own normals.
  const int sub, cw, ch;
  std::vector<int> xs_full, xs_coarse;
  // Distance of B-spline curve point p for knots inside the field: d_k at p = 2k, sqrt(d_k d_(k+1)) at
  // p = 2k + 1 (the border knot's points are computed per receiver).
  std::vector<float> point_dist;
  tbb::enumerable_thread_specific<Scratch> scratch;
  const double units;
  std::atomic<int> rows_done{0};

  // --- results ---
  std::vector<Rgb> direct, indirect;
  // Facet senders: the exit radiance of every texel's two facets ([2 * texel + q], facet_normals' order)
  // for the bounce being gathered; empty with texel senders or without bounces.
  std::vector<Rgb> facet_exit;
  std::vector<float> vis, irr;
  int lu = 0;  // radiance levels (the bounces' pyramids)
};

NlpBake::NlpBake(const Scene& scene_, const NlpOptions& o_, const RunControl& rc_)
    : scene(scene_),
      o(o_),
      rc(rc_),
      f(scene.field),
      W(f.width),
      H(f.height),
      m(o.directions),
      N(f.texel_count()),
      ms(with_near_spacing(nlp::make_march_setup(W, H, f.texel_size, f.wrap, o.levels_per_octave,
                                                 o.level_offset, o.radiance_level_offset),
                           o.near_spacing)),
      ms_light(with_near_spacing(
          nlp::make_march_setup(W, H, f.texel_size, f.wrap, o.levels_per_octave,
                                std::max(o.level_offset, o.light_level_offset), o.radiance_level_offset),
          o.near_spacing)),
      hp(nlp::build_pyramid(f.z.data(), 1, W, H, f.wrap, o.levels_per_octave, nlp::height_levels(ms))),
      A(nlp::sample_matrices(o.interpolation, m)),
      lights(setup_lights(scene, o)),
      nl(lights.size()),
      want_vis(wants(o, "sh_visibility")),
      want_irr(wants(o, "sh_irradiance")),
      lv(nlp::height_levels(ms)),
      steps(ms.steps),
      sub(o.subsample),
      cw(receivers_along(W, sub)),
      ch(receivers_along(H, sub)),
      // Row buffers: V and the lights' visibility (kSh + lights), or U and the exact-cosine E (3 kSh + 3).
      scratch([lv = lv, steps = steps, W = W,
               row_floats = std::max(kSh + int(scene.lights.size()) + 3, 3 * kSh + 3)] {
        return Scratch(lv, steps, W, row_floats);
      }),
      units(double(H) * (1 + std::max(0, scene.bounces))),
      direct(N),
      vis(want_vis ? N * kSh : 0),
      irr(want_irr ? N * kIrrChannels : 0) {
  azimuth_table(m, cphi, sphi);
  setup_environment();
  if (o.exact_direct_cosine) setup_environment_wedges();
  xs_full.resize(W);
  xs_coarse.resize(cw);
  for (int i = 0; i < W; ++i) xs_full[i] = i;
  for (int ci = 0; ci < cw; ++ci) xs_coarse[ci] = coarse_i(ci);
  for (int k = 0; k < steps; ++k) {
    point_dist.push_back(ms.dist[k]);
    if (k + 1 < steps) point_dist.push_back(std::sqrt(ms.dist[k] * ms.dist[k + 1]));
  }
  if (o.facet_senders && scene.bounces > 0) facet_exit.resize(2 * N);
}

void NlpBake::setup_environment() {
  const std::array<sh::Coeffs, 3> env = nlp::project_environment(scene.environment);
  for (int c = 0; c < 3; ++c) {
    const auto pm = sh::product_matrix(env[c]);
    for (int k = 0; k < 9; ++k)
      for (int j = 0; j < kSh; ++j) T[c][k][j] = float(pm[k][j]);
  }
}

void NlpBake::setup_environment_wedges() {
  const Environment& env = scene.environment;
  std::vector<std::vector<Rgb>> prof(static_cast<std::size_t>(m));
  for (int a = 0; a < m; ++a) {
    const double phi = azimuth(a, m);
    prof[std::size_t(a)] = azimuth_wedge_profile(env, phi - kPi / m, phi + kPi / m);
    if (prof[std::size_t(a)].empty()) prof[std::size_t(a)].assign(1, env.uniform_radiance);
  }
  env_rows = int(prof[0].size());
  const int h = env_rows;
  std::vector<double> F1(std::size_t(h) + 1), F2(std::size_t(h) + 1);
  env_edge.resize(2 * (std::size_t(h) + 1));
  for (int r = 0; r <= h; ++r) {
    const double e = kPi / 2 - kPi * r / h, se = std::sin(e), ce = std::cos(e);
    F1[r] = 0.5 * (e + se * ce), F2[r] = 0.5 * se * se;
    env_edge[2 * r] = float(F1[r]), env_edge[2 * r + 1] = float(F2[r]);
  }
  env_rad.resize(std::size_t(m) * h * 3);
  env_cum.resize(std::size_t(m) * (h + 1) * 6);
  for (int a = 0; a < m; ++a) {
    double c1[3] = {}, c2[3] = {};
    for (int r = 0; r <= h; ++r) {
      float* C = &env_cum[(std::size_t(a) * (h + 1) + r) * 6];
      for (int c = 0; c < 3; ++c) C[c] = float(c1[c]), C[3 + c] = float(c2[c]);
      if (r == h) break;
      const Rgb L = prof[std::size_t(a)][std::size_t(r)];
      const double l[3] = {L.r, L.g, L.b};
      for (int c = 0; c < 3; ++c) {
        env_rad[(std::size_t(a) * h + r) * 3 + c] = float(l[c]);
        c1[c] += l[c] * (F1[r] - F1[r + 1]);
        c2[c] += l[c] * (F2[r] - F2[r + 1]);
      }
    }
  }
}

// direct_cosine exact: adds to out (RGB) the integral over azimuth a's elevations above e of the wedge's
// radiance times (nh cos e + nz sin e) cos e, nh = n . azimuth, nz = n_z (e at or above omega_min).
void NlpBake::env_above(int a, float e, float nh, float nz, float* out) const {
  const int h = env_rows;
  int r = int((0.5f - e * float(1 / kPi)) * float(h));
  r = r < 0 ? 0 : (r > h - 1 ? h - 1 : r);
  const float se = std::sin(e), ce = std::cos(e);
  const float d1 = env_edge[2 * r] - 0.5f * (e + se * ce), d2 = env_edge[2 * r + 1] - 0.5f * se * se;
  const float* C = &env_cum[(std::size_t(a) * (h + 1) + r) * 6];
  const float* L = &env_rad[(std::size_t(a) * h + r) * 3];
  for (int c = 0; c < 3; ++c) out[c] += nh * (C[c] + L[c] * d1) + nz * (C[3 + c] + L[c] * d2);
}

std::vector<LightSetup> NlpBake::setup_lights(const Scene& scene, const NlpOptions& o) {
  std::vector<LightSetup> lights;
  for (const DirectionalLight& dl : scene.lights) {
    LightSetup L;
    L.dir = normalize(dl.direction);
    L.irradiance = dl.irradiance;
    L.elevation = float(std::asin(std::clamp(L.dir.z, -1.0, 1.0)));
    L.radius = float(dl.angular_diameter / 2);
    const double az = std::atan2(L.dir.y, L.dir.x);
    const int q = L.radius > 0 ? o.light_directions : 1;
    const double half = L.radius / std::max(std::cos(double(L.elevation)), 1e-3);
    for (int s = 0; s < q; ++s) {
      const double phi = az + (q == 1 ? 0.0 : half * ((2.0 * s + 1) / q - 1));
      L.cx.push_back(float(std::cos(phi)));
      L.cy.push_back(float(std::sin(phi)));
    }
    const sh::Coeffs y = sh::eval(L.dir);
    for (int k = 0; k < 9; ++k) L.sh[k] = kConv[k] * float(y[k]) * kInvPi;
    lights.push_back(std::move(L));
  }
  return lights;
}

// Receiver heights in every height level (Eq. 15's f_i(x, y)) for a row of receivers (xs[t], j), and their
// normals (recomputed from the heights: normal_at, the values compute_normals gives).
void NlpBake::receivers(Scratch& s, const int* xs, int cnt, int j) const {
  for (int t = 0; t < cnt; ++t) s.nrm[std::size_t(t)] = normal_at(f, xs[t], j);
  for (int l = 0; l < lv; ++l) {
    const nlp::PyramidLevel& L = hp.levels[l];
    float* out = s.recv.data() + std::size_t(l) * W;
    if (L.w == W && L.h == H && L.inv_sx == 1 && L.inv_sy == 1) {
      // A level on the field's grid read at a texel centre: its node, exactly what the bilinear read gives.
      const float* row = L.data.data() + std::size_t(j) * W;
      for (int t = 0; t < cnt; ++t) out[t] = row[xs[t]];
    } else {
      for (int t = 0; t < cnt; ++t) out[t] = nlp::sample_level1(hp, L, float(xs[t]), float(j));
    }
  }
}

// The horizon omega_max of every receiver of the row along (cx, cy) into s.wmax (lights: their march
// setup and horizon rule): the knots' or the B-spline curve's maximum, omega_min where the ray leaves the
// field at once.
void NlpBake::horizons(Scratch& s, const int* xs, int cnt, int j, float cx, float cy, bool light) const {
  nlp::RowMarch& rm = s.rm;
  nlp::march_row(light ? ms_light : ms, hp, xs, cnt, xs == xs_full.data(), j, cx, cy, s.recv.data(), W, rm);
  if (light ? o.light_horizon_knots : o.visibility_horizon_knots) {
    nlp::row_knot_max(rm, cnt, s.wmax.data());
  } else {
    nlp::row_angles(rm, cnt);
    for (int t = 0; t < cnt; ++t) {
      const int n = rm.n[t];
      for (int k = 0; k < n; ++k) s.omega[k] = rm.omega[std::size_t(k) * rm.stride + t];
      s.wmax[t] = n > 0 ? nlp::bspline_max(s.omega.data(), n) : 0.0f;
    }
  }
  for (int t = 0; t < cnt; ++t)
    if (rm.n[t] == 0) {
      const Vec3f& n = s.nrm[std::size_t(t)];
      s.wmax[t] = nlp::omega_min(n.x, n.y, n.z, cx, cy);
    }
}

// The restricted-extent visibility of each light at the row's receivers (NS09 §6): out[t * stride + q].
void NlpBake::light_visibility(Scratch& s, const int* xs, int cnt, int j, float* out, int stride) const {
  for (std::size_t q = 0; q < nl; ++q) {
    const LightSetup& L = lights[q];
    for (int t = 0; t < cnt; ++t) out[std::size_t(t) * stride + q] = 0;
    for (std::size_t k = 0; k < L.cx.size(); ++k) {
      horizons(s, xs, cnt, j, L.cx[k], L.cy[k], true);
      for (int t = 0; t < cnt; ++t) {
        const float wmax = s.wmax[t];
        float& fr = out[std::size_t(t) * stride + q];
        if (L.radius > 0) {
          const float lo = std::max(L.elevation - L.radius, -1.5707963f);
          const float hi = std::min(L.elevation + L.radius, 1.5707963f);
          const float slo = std::sin(std::max(wmax, lo)), shi = std::sin(hi);
          fr += std::clamp((shi - slo) / (shi - std::sin(lo)), 0.0f, 1.0f);
        } else {
          fr += wmax < L.elevation ? 1.0f : 0.0f;
        }
      }
    }
    for (int t = 0; t < cnt; ++t) out[std::size_t(t) * stride + q] /= float(L.cx.size());
  }
}

// Kernel: V (Eq. 11, 20-21) and the lights' visibility for the row of receivers (xs[t], j), t < cnt:
// out[t * stride] = V (kSh floats), then the lights' fractions (then, exact_env, the environment light).
// Azimuth-major over the row (one row march per azimuth); each receiver still sums its azimuths in order, so
// the bits do not depend on the loop order or the thread.
void NlpBake::visibility(Scratch& s, const int* xs, int cnt, int j, float* out, int stride,
                         bool exact_env) const {
  receivers(s, xs, cnt, j);
  const int eoff = kSh + int(nl);  // exact_env: the environment light (3 floats) after the lights' fractions
  for (int t = 0; t < cnt; ++t) {
    std::fill(out + std::size_t(t) * stride, out + std::size_t(t) * stride + kSh, 0.0f);
    if (exact_env)
      std::fill(out + std::size_t(t) * stride + eoff, out + std::size_t(t) * stride + eoff + 3, 0.0f);
  }
  for (int a = 0; a < m; ++a) {
    const float* Aj = A[a].data();
    horizons(s, xs, cnt, j, cphi[a], sphi[a], false);
    for (int t = 0; t < cnt; ++t) {
      const float wmax = s.wmax[t];
      float v[4];
      nlp::band4(std::sin(wmax), 1.0f, v);
      float* V = out + std::size_t(t) * stride;
      for (int r = 0; r < kSh; ++r)
        V[r] += Aj[r * 4] * v[0] + Aj[r * 4 + 1] * v[1] + Aj[r * 4 + 2] * v[2] + Aj[r * 4 + 3] * v[3];
      if (exact_env) {
        const Vec3f& n = s.nrm[std::size_t(t)];
        const float wmin = nlp::omega_min(n.x, n.y, n.z, cphi[a], sphi[a]);
        env_above(a, std::max(wmax, wmin), n.x * cphi[a] + n.y * sphi[a], n.z, V + eoff);
      }
    }
  }
  light_visibility(s, xs, cnt, j, out + kSh, stride);
}

// Shading of direct light at texel idx from V and the lights' visibility.
void NlpBake::shade_direct(int i, int j, const float* V, const float* frac, const float* E) {
  const std::size_t idx = f.index(i, j);
  const Vec3f n = normal_at(f, i, j);
  float y[kSh];
  sh::eval(n.x, n.y, n.z, y);
  float e[3] = {}, lin[3][9];
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 9; ++k) {
      float acc = 0;
      for (int q = 0; q < kSh; ++q) acc += T[c][k][q] * V[q];
      lin[c][k] = acc;
      e[c] += kConv[k] * y[k] * acc;
    }
  Rgb d{e[0] * kInvPi, e[1] * kInvPi, e[2] * kInvPi};
  if (E) {
    const float w = float(2 / double(m));  // (2 pi / m) / pi
    d = Rgb{E[0] * w, E[1] * w, E[2] * w};
  }
  float irr_local[27];
  for (int k = 0; k < 9; ++k)
    for (int c = 0; c < 3; ++c) irr_local[k * 3 + c] = kConv[k] * lin[c][k] * kInvPi;
  // Directional lights: exact cosine, visibility over the light's restricted extent (NS09 §6).
  for (std::size_t q = 0; q < nl; ++q) {
    const LightSetup& L = lights[q];
    const float cosn = float(n.x * L.dir.x + n.y * L.dir.y + n.z * L.dir.z);
    if (cosn <= 0 || frac[q] <= 0) continue;
    d += L.irradiance * (cosn * frac[q] * kInvPi);
    for (int k = 0; k < 9; ++k) {
      irr_local[k * 3 + 0] += L.sh[k] * frac[q] * L.irradiance.r;
      irr_local[k * 3 + 1] += L.sh[k] * frac[q] * L.irradiance.g;
      irr_local[k * 3 + 2] += L.sh[k] * frac[q] * L.irradiance.b;
    }
  }
  direct[idx] = d;
  if (!facet_exit.empty()) direct_facets(i, j, lin, frac);
  if (want_vis) std::copy(V, V + kSh, vis.begin() + idx * kSh);
  if (want_irr) std::copy(irr_local, irr_local + 27, irr.begin() + idx * kIrrChannels);
}

// Facet senders: the exit radiance (albedo x direct) of texel (i, j)'s two facets, lit with their own
// normals: the texel's environment light `lin` (its SH visibility times the environment, bands l <= 2) dotted
// with the clamped cosine about each facet normal, and the lights with the exact cosine and the texel's
// visibility of them.
void NlpBake::direct_facets(int i, int j, const float (&lin)[3][9], const float* frac) {
  const std::size_t idx = f.index(i, j);
  const Rgb albedo = scene.surface.albedo.empty() ? Rgb{} : scene.surface.albedo[idx];
  Vec3f fn[2];
  facet_normals(f, i, j, fn);
  for (int q = 0; q < 2; ++q) {
    float y[kSh];
    sh::eval(fn[q].x, fn[q].y, fn[q].z, y);
    float e[3] = {};
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 9; ++k) e[c] += kConv[k] * y[k] * lin[c][k];
    Rgb d{e[0] * kInvPi, e[1] * kInvPi, e[2] * kInvPi};
    for (std::size_t l = 0; l < nl; ++l) {
      const LightSetup& L = lights[l];
      const float cosn = float(fn[q].x * L.dir.x + fn[q].y * L.dir.y + fn[q].z * L.dir.z);
      if (cosn > 0 && frac[l] > 0) d += L.irradiance * (cosn * frac[l] * kInvPi);
    }
    Rgb b = albedo * d;
    if (!scene.surface.emission.empty()) b += scene.surface.emission[idx];
    facet_exit[2 * idx + q] = b;
  }
}

// Bilinear interpolation of per-receiver vectors (cnt floats each) from the coarse grid to texel (i, j).
void NlpBake::upsample(const std::vector<float>& buf, int cnt, int i, int j, float* out) const {
  const float u = float(i) / sub, v = float(j) / sub;
  const int i0 = std::min(int(u), cw - 1), j0 = std::min(int(v), ch - 1);
  const int i1 = std::min(i0 + 1, cw - 1), j1 = std::min(j0 + 1, ch - 1);
  // Exact positions of the coarse receivers (the last one may sit on the border, closer than sub).
  const float x0 = float(coarse_i(i0)), x1 = float(coarse_i(i1)), y0 = float(coarse_j(j0)),
              y1 = float(coarse_j(j1));
  const float fu = x1 > x0 ? (float(i) - x0) / (x1 - x0) : 0.0f,
              fv = y1 > y0 ? (float(j) - y0) / (y1 - y0) : 0.0f;
  const float* a = buf.data() + (std::size_t(j0) * cw + i0) * cnt;
  const float* b = buf.data() + (std::size_t(j0) * cw + i1) * cnt;
  const float* c = buf.data() + (std::size_t(j1) * cw + i0) * cnt;
  const float* d = buf.data() + (std::size_t(j1) * cw + i1) * cnt;
  for (int k = 0; k < cnt; ++k)
    out[k] = (a[k] * (1 - fu) + b[k] * fu) * (1 - fv) + (c[k] * (1 - fu) + d[k] * fu) * fv;
}

// Pass 1: visibility V and direct light, on every texel or on the coarse receivers then upsampled.
void NlpBake::direct_pass() {
  if (sub == 1) {
    tbb::parallel_for(0, H, [&](int j) {
      rc.check();
      Scratch& s = scratch.local();
      const bool exact = o.exact_direct_cosine;
      const int stride = kSh + int(nl) + (exact ? 3 : 0);
      visibility(s, xs_full.data(), W, j, s.row.data(), stride, exact);
      for (int i = 0; i < W; ++i) {
        const float* V = s.row.data() + std::size_t(i) * stride;
        shade_direct(i, j, V, V + kSh, exact ? V + kSh + nl : nullptr);
      }
      report_rows(1);
    });
  } else {
    const int stride = kSh + int(nl);
    std::vector<float> coarse(std::size_t(cw) * ch * stride);
    tbb::parallel_for(0, ch, [&](int cj) {
      rc.check();
      Scratch& s = scratch.local();
      visibility(s, xs_coarse.data(), cw, coarse_j(cj), coarse.data() + std::size_t(cj) * cw * stride, stride,
                 false);
      report_rows(sub);
    });
    tbb::parallel_for(0, H, [&](int j) {
      std::vector<float> buf(stride);
      for (int i = 0; i < W; ++i) {
        upsample(coarse, stride, i, j, buf.data());
        shade_direct(i, j, buf.data(), buf.data() + kSh, nullptr);
      }
    });
  }
}

// Facet senders: the exit radiance of the facet of the triangulated surface under (x, y) (texel
// coordinates; clamped to the field, wrapped on a repeating one).
void NlpBake::facet_radiance(float x, float y, float* out) const {
  if (f.wrap == Wrap::repeat) {
    x -= std::floor(x / W) * W;
    y -= std::floor(y / H) * H;
  } else {
    x = std::clamp(x, 0.0f, float(W - 1));
    y = std::clamp(y, 0.0f, float(H - 1));
  }
  const FacetRef r = facet_under(x, y);
  const int i = f.wrap == Wrap::repeat ? r.i % W : std::min(r.i, W - 1);
  const int j = f.wrap == Wrap::repeat ? r.j % H : std::min(r.j, H - 1);
  const Rgb v = facet_exit[2 * f.index(i, j) + r.q];
  out[0] = v.r, out[1] = v.g, out[2] = v.b;
}

// Kernel: U (3 x 16, colour-major) at receiver (i, j) from the radiance pyramid rp.
// E (optional, 3 floats): the irradiance / (2 pi / m) of the same casting-set segments with the exact
// cosine: segment (e0, e1] of radiance r adds r * (F(e1) - F(e0)), F(e) = n_h (e + sin e cos e) / 2 +
// n_z sin^2 e / 2, the integral of (n_h cos e + n_z sin e) cos e (n_h = n . azimuth).
// Row form as visibility: receivers (xs[t], j), U at out[t * 3 kSh], E (if exact) at Eout[t * 3]. Only U's
// bands l < 3 are computed (shading and sh_irradiance read no more; band 3 stays 0), and none when E is
// wanted and sh_irradiance is not.
// Per azimuth, the B-spline curve of the whole row's knots is evaluated point by point (knot-major, every
// receiver at once; knots past a receiver's last repeat it, which is bspline_curve's end rule), and each
// receiver's running maximum picks its casting set; only the casting-set points do per-receiver work. Each
// receiver sums its points and azimuths in order: the bits do not depend on the row or the thread.
void NlpBake::radiance(const nlp::Pyramid& rp, Scratch& s, const int* xs, int cnt_row, int j, float* Uout,
                       float* Eout) const {
  receivers(s, xs, cnt_row, j);
  const bool facets = !facet_exit.empty();
  const int nU = Eout && !want_irr ? 0 : 9;
  std::fill(Uout, Uout + std::size_t(cnt_row) * 3 * kSh, 0.0f);
  if (Eout) std::fill(Eout, Eout + std::size_t(cnt_row) * 3, 0.0f);
  nlp::RowMarch& rm = s.rm;
  RadianceRow& q = s.rad;
  const std::size_t st = std::size_t(rm.stride);
  for (int a = 0; a < m; ++a) {
    const float cx = cphi[a], cy = sphi[a];
    nlp::march_row(ms, hp, xs, cnt_row, xs == xs_full.data(), j, cx, cy, s.recv.data(), W, rm);
    nlp::row_angles(rm, cnt_row);
    const int max_n = rm.max_n;
    if (max_n == 0) continue;
    float* w = rm.omega.data();
    for (int t = 0; t < cnt_row; ++t) {  // pad: knots past a receiver's last (and row max_n) repeat it
      const int n = rm.n[t];
      if (n > 0)
        for (int k = n; k <= max_n; ++k) w[k * st + t] = w[std::size_t(n - 1) * st + t];
      const Vec3f nn = s.nrm[std::size_t(t)];
      const float wmin = nlp::omega_min(nn.x, nn.y, nn.z, cx, cy);
      q.run[t] = wmin;
      q.lim[t] = float(2 * n - 1);
      q.nh[t] = nn.x * cx + nn.y * cy;
      q.any[t] = 0;
      const float se = std::sin(wmin), ce = std::sqrt(std::max(0.0f, 1 - se * se));
      q.prevF[t] = Eout ? 0.5f * (q.nh[t] * (wmin + se * ce) + nn.z * se * se) : 0.0f;
      nlp::occlusion4(se, &q.prev[std::size_t(t) * 4]);
      std::fill(&q.u[std::size_t(t) * 12], &q.u[std::size_t(t) * 12] + 12, 0.0f);
    }
    // Distance of curve point p of receiver t (knots, and the geometric mean between two).
    auto dist_p = [&](int p, int t) {
      const int k = p >> 1;
      if ((p >> 1) + (p & 1) < rm.n[t] - 1 || !(rm.exit[t] < kInf)) return point_dist[std::size_t(p)];
      return (p & 1) ? std::sqrt(rm.dist(ms, k, t) * rm.dist(ms, k + 1, t)) : rm.dist(ms, k, t);
    };
    for (int p = 0; p < 2 * max_n - 1; ++p) {
      const int k = p >> 1;
      const float* w0 = w + std::size_t(k > 0 ? k - 1 : 0) * st;
      const float* w1 = w + std::size_t(k) * st;
      const float* w2 = w + std::size_t(k + 1) * st;
      const float* w3 = w + std::size_t(k + 2 <= max_n ? k + 2 : max_n) * st;
      const int hits =
          curve_point(cnt_row, p, w0, w1, w2, w3, q.lim.data(), q.cur.data(), q.run.data(), q.hit.data());
      const float* cur = q.cur.data();
      if (hits == 0) continue;
      const int nhit = hit_list(cnt_row, q.hit.data(), q.hits.data());
      // The radiance of every hit's stretch first (the reads, independent of each other, overlap), then
      // each hit's sums.
      const int rl = ms.rlevel[k];
      const nlp::PyramidLevel& L = rp.levels[rl];
      for (int h = 0; h < nhit; ++h) {
        const int t = q.hits[h];
        const int i = xs[t];
        const float dd = dist_p(p, t);
        float* rad = &q.rad[3 * std::size_t(h)];
        if (facets) {
          // The stretch this step reveals lies between the previous curve point and this one: it radiates
          // from its middle, the light of the facet there (level 0) or the filtered facet light.
          const float ds = 0.5f * ((p > 0 ? dist_p(p - 1, t) : 0.0f) + dd);
          if (rl == 0) {
            facet_radiance(i + ds * cx, j + ds * cy, rad);
          } else {
            nlp::sample_level(rp, L, i + ds * cx, j + ds * cy, rad);
          }
        } else {
          nlp::sample_level(rp, L, i + dd * cx, j + dd * cy, rad);
        }
      }
      for (int h = 0; h < nhit; ++h) {
        const int t = q.hits[h];
        const float run = cur[t];
        const float* rad = &q.rad[3 * std::size_t(h)];
        float nu[4];
        const float srun = std::sin(run);
        nlp::occlusion4(srun, nu);
        float* u = &q.u[std::size_t(t) * 12];
        float* prev = &q.prev[std::size_t(t) * 4];
        for (int l = 0; l < 4; ++l) {
          const float dl = nu[l] - prev[l];
          u[l] += rad[0] * dl, u[4 + l] += rad[1] * dl, u[8 + l] += rad[2] * dl;
          prev[l] = nu[l];
        }
        if (Eout) {
          float* E = Eout + std::size_t(t) * 3;
          const float ce = std::sqrt(std::max(0.0f, 1 - srun * srun));
          const float Fr = 0.5f * (q.nh[t] * (run + srun * ce) + s.nrm[std::size_t(t)].z * srun * srun);
          const float dF = Fr - q.prevF[t];
          E[0] += rad[0] * dF, E[1] += rad[1] * dF, E[2] += rad[2] * dF;
          q.prevF[t] = Fr;
        }
        q.any[t] = 1;
      }
    }
    if (nU == 0) continue;
    const float* Aj = A[a].data();
    for (int t = 0; t < cnt_row; ++t) {
      if (!q.any[t]) continue;
      float* U = Uout + std::size_t(t) * 3 * kSh;
      const float* u = &q.u[std::size_t(t) * 12];
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < nU; ++r)
          U[c * kSh + r] += Aj[r * 4] * u[c * 4] + Aj[r * 4 + 1] * u[c * 4 + 1] +
                            Aj[r * 4 + 2] * u[c * 4 + 2] + Aj[r * 4 + 3] * u[c * 4 + 3];
    }
  }
}

void NlpBake::shade_indirect(std::vector<Rgb>& this_bounce, bool add, int i, int j, const float* U,
                             const float* E) {
  const std::size_t idx = f.index(i, j);
  Rgb v;
  if (E) {
    const float w = float(2 / double(m));  // (2 pi / m) / pi
    v = Rgb{E[0] * w, E[1] * w, E[2] * w};
  } else {
    const Vec3f n = normal_at(f, i, j);
    float y[kSh];
    sh::eval(n.x, n.y, n.z, y);
    float e[3] = {};
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 9; ++k) e[c] += kConv[k] * y[k] * U[c * kSh + k];
    v = Rgb{e[0] * kInvPi, e[1] * kInvPi, e[2] * kInvPi};
  }
  if (add)
    this_bounce[idx] += v;
  else
    this_bounce[idx] = v;
  if (want_irr)
    for (int k = 0; k < 9; ++k)
      for (int c = 0; c < 3; ++c) irr[idx * kIrrChannels + k * 3 + c] += kConv[k] * U[c * kSh + k] * kInvPi;
}

// The bounces: indirect radiance U (Eq. 12, 20-21) through a radiance pyramid of the exitant light of the
// bounce before (albedo x direct plus emission for the first).
void NlpBake::bounce_passes() {
  std::vector<float> exitant;
  auto exit_from = [&](const std::vector<Rgb>& light, bool reflect_only) {
    exitant.resize(N * 3);
    for (std::size_t t = 0; t < N; ++t) {
      Rgb b = scene.surface.albedo.empty() ? Rgb{} : scene.surface.albedo[t] * light[t];
      if (!reflect_only && !scene.surface.emission.empty()) b += scene.surface.emission[t];
      exitant[t * 3] = b.r, exitant[t * 3 + 1] = b.g, exitant[t * 3 + 2] = b.b;
    }
  };
  exit_from(direct, false);
  // Facet senders: the pyramid filters the mean of each texel's two facets (level 0 is read per facet).
  auto facet_means = [&] {
    for (std::size_t t = 0; t < N; ++t) {
      const Rgb b = (facet_exit[2 * t] + facet_exit[2 * t + 1]) * 0.5f;
      exitant[t * 3] = b.r, exitant[t * 3 + 1] = b.g, exitant[t * 3 + 2] = b.b;
    }
  };
  if (!facet_exit.empty()) facet_means();
  lu = nlp::radiance_levels(ms);
  for (int bounce = 1; bounce <= scene.bounces; ++bounce) {
    // The radiance pyramid in binary16 (half its memory; the heights stay float).
    const nlp::Pyramid rp =
        nlp::build_pyramid(exitant.data(), 3, W, H, f.wrap, o.levels_per_octave, lu, /*half=*/true);
    std::vector<float>().swap(exitant);  // the pyramid's level 0 is a copy of it
    // Allocated only now, after the pyramid's build (its largest moment): it is zero until this gather.
    if (indirect.empty()) indirect.assign(N, Rgb{});
    // The last bounce adds straight into `indirect` (the same sum); the others keep their light for the
    // next bounce's exitant radiance.
    const bool last = bounce == scene.bounces;
    std::vector<Rgb> this_bounce(last ? 0 : N);
    std::vector<Rgb>& target = last ? indirect : this_bounce;
    if (sub == 1) {
      tbb::parallel_for(0, H, [&](int j) {
        rc.check();
        Scratch& s = scratch.local();
        float* U = s.row.data();
        float* E = o.exact_indirect_cosine ? U + std::size_t(W) * 3 * kSh : nullptr;
        radiance(rp, s, xs_full.data(), W, j, U, E);
        for (int i = 0; i < W; ++i)
          shade_indirect(target, last, i, j, U + std::size_t(i) * 3 * kSh,
                         E ? E + std::size_t(i) * 3 : nullptr);
        report_rows(1);
      });
    } else {
      std::vector<float> coarse(std::size_t(cw) * ch * 3 * kSh);
      tbb::parallel_for(0, ch, [&](int cj) {
        rc.check();
        Scratch& s = scratch.local();
        radiance(rp, s, xs_coarse.data(), cw, coarse_j(cj), coarse.data() + std::size_t(cj) * cw * 3 * kSh,
                 nullptr);
        report_rows(sub);
      });
      tbb::parallel_for(0, H, [&](int j) {
        float U[3 * kSh];
        for (int i = 0; i < W; ++i) {
          upsample(coarse, 3 * kSh, i, j, U);
          shade_indirect(target, last, i, j, U, nullptr);
        }
      });
    }
    if (!last) {
      for (std::size_t t = 0; t < N; ++t) indirect[t] += this_bounce[t];
      exit_from(this_bounce, true);
      // Later bounces: both facets radiate their texel's reflected indirect light.
      for (std::size_t t = 0; t < facet_exit.size() / 2; ++t) {
        const Rgb b{exitant[t * 3], exitant[t * 3 + 1], exitant[t * 3 + 2]};
        facet_exit[2 * t] = b, facet_exit[2 * t + 1] = b;
      }
    }
  }
  std::vector<Rgb>().swap(facet_exit);  // read by the gathers only; the layers are made without it
}

// The requested layers, in the order of NlpOptions::layers, and the metadata.
LayerSet NlpBake::layers() {
  LayerSet out;
  out.width = W;
  out.height = H;
  for (const std::string& name : o.layers) {
    if (name == "direct" || name == "indirect" || name == "total") {
      Layer& L = out.add(name, rgb_channels());
      for (std::size_t t = 0; t < N; ++t) {
        const Rgb ind = indirect.empty() ? Rgb{} : indirect[t];  // empty without bounces
        const Rgb v = name == "direct" ? direct[t] : (name == "indirect" ? ind : direct[t] + ind);
        // Light is never negative; the SH form of a receiver's cosine lobe (every texel with
        // indirect_cosine "sh", the texels between subsampled receivers always) rings below 0 where the
        // light comes from a narrow range of directions.
        L.data[t * 3] = std::max(v.r, 0.0f), L.data[t * 3 + 1] = std::max(v.g, 0.0f),
                   L.data[t * 3 + 2] = std::max(v.b, 0.0f);
      }
    } else if (name == "sh_visibility") {
      out.adopt(name, indexed_channels(kSh), std::move(vis));
    } else if (name == "sh_irradiance") {
      std::vector<std::string> channels;
      for (const std::string& c : indexed_channels(kSh))
        for (const char* col : {"R", "G", "B"}) channels.push_back(c + "." + col);
      out.adopt(name, channels, std::move(irr));  // 48 floats a texel, the bands l = 3 zero
    }
  }
  out.attributes.emplace_back("hfbake:sh_convention", sh_convention_text());
  out.attributes.emplace_back("hfbake:nlp_pyramid", "height levels " + std::to_string(hp.levels.size()) +
                                                        " (" + std::to_string(hp.bytes()) +
                                                        " bytes), steps " + std::to_string(ms.steps) +
                                                        ", radiance levels " + std::to_string(lu));
  return out;
}

}  // namespace

LayerSet bake_nlp(const Scene& scene, const NlpOptions& o, const RunControl& rc) {
  NlpBake bake(scene, o, rc);
  bake.direct_pass();
  bake.bounce_passes();
  return bake.layers();
}

double nlp_working_bytes(const FieldShape& field, const NlpOptions& o, int bounces) {
  const int W = field.width, H = field.height;
  const double N = double(W) * double(H);
  const nlp::MarchSetup ms = nlp::make_march_setup(W, H, field.texel_size, field.wrap, o.levels_per_octave,
                                                   o.level_offset, o.radiance_level_offset);
  const double heights =
      double(nlp::pyramid_bytes(1, W, H, field.wrap, o.levels_per_octave, nlp::height_levels(ms)));
  const double radiance =
      double(nlp::pyramid_bytes(3, W, H, field.wrap, o.levels_per_octave, nlp::radiance_levels(ms), true));
  // The layers the estimate counts that are not allocated until the end: direct, indirect, total.
  double rgb_layers = 0;
  for (const char* name : {"direct", "indirect", "total"})
    if (std::find(o.layers.begin(), o.layers.end(), name) != o.layers.end()) rgb_layers += 12 * N;
  // With subsampled receivers, their values before they are interpolated to the texels: the direct pass's
  // visibility (kSh floats a receiver; the lights' one each are left out) and each bounce's U (3 kSh).
  const double receivers =
      o.subsample > 1 ? double(receivers_along(W, o.subsample)) * receivers_along(H, o.subsample) : 0.0;
  const double coarse_direct = 4.0 * kSh * receivers, coarse_bounce = 4.0 * 3 * kSh * receivers;
  // Through the direct pass and the bounces: the height pyramid, direct (RGB floats) and, with facet
  // senders and bounces, the two facets' exit radiance (RGB floats). While a bounce's radiance pyramid is
  // built: the exitant radiance, one level in float and its horizontal pass (12 bytes a texel each), the
  // pyramid (binary16), and after the first bounce `indirect` (12). Its gather holds the pyramid, indirect
  // (12), for all but the last bounce that bounce's light (12), and the subsampled receivers' U. At the end:
  // the heights, direct and indirect beside the layers (the facets freed).
  const double held = heights + 12 * N + (o.facet_senders && bounces > 0 ? 24 * N : 0);
  const double build = 36 * N + (bounces > 1 ? 12 * N : 0);
  const double gather = (bounces > 1 ? 24 * N : 12 * N) + coarse_bounce;
  const double bounce = bounces > 0 ? radiance + std::max(build, gather) : 0;
  return std::max(heights + 24 * N, held + std::max(bounce, coarse_direct) - rgb_layers);
}

MethodInfo nlp_method() {
  MethodInfo m;
  m.name = "nlp";
  m.summary = "spherical-harmonic visibility and light over a height pyramid (Nowrouzezahrai & Snyder 2009)";
  m.read = [](Params& in, const MethodContext&) {
    const NlpOptions o = read_nlp_options(in);
    return method_config(o, o.directions);
  };
  m.bake = [](const Scene& s, const MethodConfig& c, const RunControl& rc) {
    return bake_nlp(s, c.get<NlpOptions>(), rc);
  };
  m.reads_normals = false;  // normal_at per row of receivers
  m.memory_knob = "its layers (sh_visibility and sh_irradiance: 64 and 192 bytes a texel)";
  m.working_bytes = [](const MethodConfig& config, const MethodContext& c) {
    return nlp_working_bytes(c.field, config.get<NlpOptions>(), c.bounces);
  };
  m.division = WorkDivision::texel_tiles;
  m.division_note =
      "whole, in one shard: its pyramids span the whole field, so a tile's halo would be the whole field";
  return m;
}

}  // namespace hfbake
