#include "reference/bake_reference.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <set>

#if defined(__SSE__) || defined(__x86_64__)
#include <xmmintrin.h>
#define HFBAKE_HAVE_MXCSR 1
#endif

#include "core/azimuth.hpp"
#include "core/error.hpp"
#include "field/triangulation.hpp"
#include "job/params.hpp"
#include "methods/method_table.hpp"
#include "reference/env_sampler.hpp"
#include "reference/horizon_reference.hpp"
#include "reference/sampling.hpp"
#include "reference/sh_environment.hpp"
#include "reference/sh_irradiance_reference.hpp"

namespace hfbake {
namespace {

using reference::EmbreeField;
using reference::EnvSampler;
using reference::Point2;
using reference::Sequence2;

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr int kChunk = 64;  // rays per stream call (per texel, per replicate)
// sh_irradiance: the azimuths of its environment term's horizons and their bisection steps (pi / 2^20:
// 3e-6 rad).
constexpr int kShAzimuths = 128;
constexpr int kShIterations = 20;

// Flush-to-zero / denormals-are-zero while tracing (Embree's advice), restored afterwards so other work
// sharing the worker threads is unaffected.
struct FlushDenormals {
#if HFBAKE_HAVE_MXCSR
  unsigned csr = _mm_getcsr();
  FlushDenormals() {
    _mm_setcsr(csr | 0x8040u);
  }
  ~FlushDenormals() {
    _mm_setcsr(csr);
  }
#endif
};

// --- channels ------------------------------------------------------------------------------------

struct Channels {
  int ao = 0, vsky = 1, obscurance = 2, direct = 3, indirect = 6;
  int bounce0 = 9;  // indirect_b1 at bounce0, b2 at bounce0 + 3, ...
  int total = 0;
  int count = 0;
  int bent = 0;  // the sum of the unoccluded cosine-sampled directions (x, y, z)
  int sh = 0;    // sh_irradiance's Monte Carlo terms: L_in Y_i, i < 9, RGB ([sh + i * 3 + c])
  explicit Channels(int bounces) {
    total = bounce0 + 3 * bounces;
    bent = total + 3;
    sh = bent + 3;
    count = sh + reference::kShIrradianceSums;
  }
  int bounce(int k) const { return bounce0 + 3 * (k - 1); }  // k = 1..bounces

  // The channels of reference layer `layer` (reference_layer_names): the first and how many (1 or 3).
  struct Slot {
    int first = 0, channels = 1;
  };
  Slot slot(const std::string& layer) const {
    if (layer == "ao") return {ao, 1};
    if (layer == "vsky") return {vsky, 1};
    if (layer == "obscurance") return {obscurance, 1};
    if (layer == "direct") return {direct, 3};
    if (layer == "indirect") return {indirect, 3};
    if (layer == "total") return {total, 3};
    if (layer == "bent_normal") return {bent, 3};
    if (layer == "sh_irradiance") return {sh, reference::kShIrradianceSums};  // written as 48 (band 3 zero)
    return {bounce(std::stoi(layer.substr(10))), 3};                          // indirect_b<k>
  }
};

struct Needs {
  bool ao = false, vsky = false, obscurance = false, direct = false, indirect = false, bent_normal = false;
  bool sh_irradiance = false;
};

void add_rgb(double* a, Rgb c) {
  a[0] += c.r, a[1] += c.g, a[2] += c.b;
}

Vec3 vec(const float* p) {
  return {p[0], p[1], p[2]};
}

RTCRay make_ray(Vec3 org, Vec3 dir, float tfar = kInf) {
  RTCRay r;
  r.org_x = float(org.x), r.org_y = float(org.y), r.org_z = float(org.z);
  r.tnear = 0.0f;
  r.dir_x = float(dir.x), r.dir_y = float(dir.y), r.dir_z = float(dir.z);
  r.time = 0.0f;
  r.tfar = tfar;
  r.mask = 0xffffffffu;
  r.id = 0;
  r.flags = 0;
  return r;
}

RTCRayHit make_rayhit(Vec3 org, Vec3 dir, float tfar = kInf) {
  RTCRayHit rh;
  rh.ray = make_ray(org, dir, tfar);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

// A shadow ray and what it contributes when unoccluded.
struct ShadowSample {
  Rgb value;
};

// Everything the per-texel estimators read.
struct Context {
  const Scene& scene;
  const HeightField& field;
  const Environment& env;
  const EnvSampler& env_sampler;
  const EmbreeField& geometry;
  const ReferenceOptions& options;
  Channels ch;
  Needs needs;
  int bounces = 0;
  int lights = 0;
  // Dimension pairs: primary (ao / obscurance / first path direction), vsky, the receiver's
  // next-event estimation, then per path vertex: next-event estimation and the continuation direction.
  // sh_irradiance's come after every one of those (so tracing it changes no other layer's bits): its
  // hemisphere direction, a point on each light's disk, then its paths' vertices (same stride).
  int pair_primary = 0, pair_vsky = 1, pair_direct = 2, nee_pairs = 0, pair_path = 0, path_stride = 0;
  int pair_sh = 0, pair_sh_path = 0;
  float obscurance_tfar = kInf;

  Context(const Scene& s, const Environment& e, const EnvSampler& es, const EmbreeField& g,
          const ReferenceOptions& o, int b)
      : scene(s), field(s.field), env(e), env_sampler(es), geometry(g), options(o), ch(b), bounces(b) {
    lights = int(s.lights.size());
    nee_pairs = 2 + lights;
    pair_path = pair_direct + nee_pairs;
    path_stride = nee_pairs + 1;
    pair_sh = pair_path + (bounces + 1) * path_stride;
    pair_sh_path = pair_sh + 1 + lights;
  }

  Sequence2 sequence(std::uint64_t texel_seed, int replicate, int pair) const {
    return Sequence2::make(
        reference::hash_combine(texel_seed, (std::uint64_t(replicate) << 32) | unsigned(pair)));
  }

  // Next-event estimation of E_direct / pi at (origin, n): appends shadow rays (origin already offset)
  // and their contributions. Returns the number appended.
  int nee(Vec3 origin, Vec3 n, std::uint64_t texel_seed, int replicate, int pair0, std::uint32_t s,
          RTCRay* rays, ShadowSample* out) const {
    int k = 0;
    const Point2 pc = sequence(texel_seed, replicate, pair0 + 1)(s);
    const Vec3 wc = reference::cosine_hemisphere(n, pc);
    if (env.uniform || !env_sampler.valid()) {
      // f / p = L V (n.w / pi) / (n.w / pi) = L V: cosine sampling is optimal for a uniform sky.
      const Rgb L = env.radiance(wc);
      if (L.r != 0 || L.g != 0 || L.b != 0) {
        rays[k] = make_ray(origin, wc);
        out[k++].value = L;
      }
    } else {
      double pe = 0;
      const Vec3 we = env_sampler.sample(sequence(texel_seed, replicate, pair0)(s), pe);
      const double ce = dot(n, we);
      if (ce > 0 && pe > 0) {
        const double w = (ce / kPi) / (pe + ce / kPi);
        rays[k] = make_ray(origin, we);
        out[k++].value = env.radiance(we) * float(w);
      }
      const double cc = dot(n, wc);
      if (cc > 0) {
        const double w = (cc / kPi) / (env_sampler.pdf(wc) + cc / kPi);
        rays[k] = make_ray(origin, wc);
        out[k++].value = env.radiance(wc) * float(w);
      }
    }
    for (int l = 0; l < lights; ++l) {
      const DirectionalLight& light = scene.lights[l];
      const double alpha = 0.5 * light.angular_diameter;
      Vec3 w = light.direction;
      double scale = 0;  // E_light * max(n.w, 0) / pi, averaged over the disk
      if (alpha > 0) {
        const double s2 = std::sin(alpha / 2);
        const double one_minus_cos = 2 * s2 * s2;
        w = reference::uniform_cone(light.direction, one_minus_cos,
                                    sequence(texel_seed, replicate, pair0 + 2 + l)(s));
        // Radiance E / (pi sin^2 alpha), times the cone's solid angle 2 pi (1 - cos alpha), times cos / pi.
        const double sin2 = one_minus_cos * (2 - one_minus_cos);
        scale = 2 * one_minus_cos / sin2 * std::max(0.0, dot(n, w)) / kPi;
      } else {
        scale = std::max(0.0, dot(n, w)) / kPi;
      }
      if (scale > 0) {
        rays[k] = make_ray(origin, w);
        out[k++].value = light.irradiance * float(scale);
      }
    }
    return k;
  }

  void occluded(RTCRay* rays, int n) const {
    if (n <= 0) return;
    RTCIntersectContext c;
    rtcInitIntersectContext(&c);
    if (options.ray_streams && n > 1) {
      rtcOccluded1M(geometry.scene(), &c, rays, unsigned(n), sizeof(RTCRay));
    } else {
      for (int i = 0; i < n; ++i) rtcOccluded1(geometry.scene(), &c, &rays[i]);
    }
  }
  void intersect(RTCRayHit* rays, int n) const {
    if (n <= 0) return;
    RTCIntersectContext c;
    rtcInitIntersectContext(&c);
    if (options.ray_streams && n > 1) {
      rtcIntersect1M(geometry.scene(), &c, rays, unsigned(n), sizeof(RTCRayHit));
    } else {
      for (int i = 0; i < n; ++i) rtcIntersect1(geometry.scene(), &c, &rays[i]);
    }
  }

  // Albedo and emission at a world point on the surface: barycentric weights of the texel triangle the
  // point lies over (field/triangulation.hpp, the split of the geometry); outside the field (the skirt) the
  // nearest texel.
  void surface_at(Vec3 p, Rgb& albedo, Rgb& emission) const {
    const double x = p.x / field.dx(), y = p.y / field.dy();
    double fi = std::floor(x), fj = std::floor(y);
    double fx = x - fi, fy = y - fj;
    int i = int(fi), j = int(fj);
    if (field.wrap == Wrap::clamp) {
      if (i < 0) i = 0, fx = 0;
      if (j < 0) j = 0, fy = 0;
      if (i > field.width - 2) i = field.width - 2, fx = 1;
      if (j > field.height - 2) j = field.height - 2, fy = 1;
      if (field.width < 2) i = 0, fx = 0;
      if (field.height < 2) j = 0, fy = 0;
    }
    fx = std::clamp(fx, 0.0, 1.0), fy = std::clamp(fy, 0.0, 1.0);
    const FacetWeights fw = facet_weights(fx, fy);
    auto idx = [&](int c) { return field.index(field.wrap_i(i + fw.di[c]), field.wrap_j(j + fw.dj[c])); };
    const std::size_t a = idx(0), b = idx(1), c = idx(2);
    const float wa = float(fw.w[0]), wb = float(fw.w[1]), wc = float(fw.w[2]);
    const auto& al = scene.surface.albedo;
    albedo = al[a] * wa + al[b] * wb + al[c] * wc;
    const auto& em = scene.surface.emission;
    emission = em.empty() ? Rgb{} : em[a] * wa + em[b] * wb + em[c] * wc;
  }
};

// Scratch for one texel's batches (allocated once per tile).
struct Scratch {
  std::vector<RTCRay> rays;
  std::vector<RTCRayHit> hits;
  std::vector<ShadowSample> shadow;
  std::vector<int> shadow_sample;  // which sample each shadow ray belongs to
  std::vector<Vec3> dirs;
  explicit Scratch(int lights) {
    const std::size_t per_sample = std::size_t(2 + lights);
    rays.resize(kChunk * per_sample);
    hits.resize(kChunk);
    shadow.resize(kChunk * per_sample);
    shadow_sample.resize(kChunk * per_sample);
    dirs.resize(kChunk);
  }
};

// One texel's samples [c0, c0 + m) of replicate r: where its rays start and which sequences they read.
struct TexelBatch {
  const Context& cx;
  reference::Frame frame;  // about the receiver's normal
  Vec3 n, origin;
  std::uint64_t texel_seed = 0;
  int r = 0;
  std::uint32_t c0 = 0;
  int m = 0;
  double* sums = nullptr;  // ch.count doubles of replicate r
};

// Adds the direction of every unoccluded ray to the bent-normal channels.
void add_unoccluded(double* bent, Vec3 dir) {
  bent[0] += dir.x, bent[1] += dir.y, bent[2] += dir.z;
}

// Primary cosine rays: ao, the bent normal, obscurance, and (in sc.hits, sc.dirs) the first segment of the
// paths.
void trace_primary(const TexelBatch& b, Scratch& sc) {
  const Context& cx = b.cx;
  const Channels& ch = cx.ch;
  const bool primary_hit = cx.needs.obscurance || (cx.needs.indirect && cx.bounces > 0);
  const Sequence2 seq = cx.sequence(b.texel_seed, b.r, cx.pair_primary);
  for (int k = 0; k < b.m; ++k) sc.dirs[k] = reference::cosine_hemisphere(b.frame, seq(b.c0 + k));
  if (primary_hit) {
    // ao and the path need the whole ray; obscurance alone only reaches the falloff's support. Each
    // quantity reads the hit its own way: ao any hit, obscurance a hit within the support only, so
    // neither depends on which other layers the job traces.
    const bool whole_ray = cx.needs.ao || cx.needs.bent_normal || (cx.needs.indirect && cx.bounces > 0);
    const float tfar = whole_ray ? kInf : cx.obscurance_tfar;
    for (int k = 0; k < b.m; ++k) sc.hits[k] = make_rayhit(b.origin, sc.dirs[k], tfar);
    cx.intersect(sc.hits.data(), b.m);
    for (int k = 0; k < b.m; ++k) {
      const RTCRayHit& h = sc.hits[k];
      const bool hit = h.hit.geomID != RTC_INVALID_GEOMETRY_ID;
      if (cx.needs.ao) b.sums[ch.ao] += hit ? 0.0 : 1.0;
      if (cx.needs.bent_normal && !hit) add_unoccluded(&b.sums[ch.bent], sc.dirs[k]);
      if (cx.needs.obscurance) {
        const bool within = hit && h.ray.tfar <= cx.obscurance_tfar;
        b.sums[ch.obscurance] += 1.0 - (within ? cx.options.falloff(h.ray.tfar) : 0.0);
      }
    }
  } else {
    for (int k = 0; k < b.m; ++k) sc.rays[k] = make_ray(b.origin, sc.dirs[k]);
    cx.occluded(sc.rays.data(), b.m);
    for (int k = 0; k < b.m; ++k) {
      const bool free = sc.rays[k].tfar >= 0;
      b.sums[ch.ao] += free ? 1.0 : 0.0;
      if (cx.needs.bent_normal && free) add_unoccluded(&b.sums[ch.bent], sc.dirs[k]);
    }
  }
}

// Sky view: uniform over the upper hemisphere.
void trace_vsky(const TexelBatch& b, Scratch& sc) {
  const Context& cx = b.cx;
  const Sequence2 seq = cx.sequence(b.texel_seed, b.r, cx.pair_vsky);
  for (int k = 0; k < b.m; ++k)
    sc.rays[k] = make_ray(b.origin, reference::uniform_upper_hemisphere(seq(b.c0 + k)));
  cx.occluded(sc.rays.data(), b.m);
  for (int k = 0; k < b.m; ++k) b.sums[cx.ch.vsky] += sc.rays[k].tfar >= 0 ? 1.0 : 0.0;
}

// Direct light at the receiver: next-event estimation, all the batch's shadow rays in one stream.
void trace_direct(const TexelBatch& b, Scratch& sc) {
  const Context& cx = b.cx;
  int count = 0;
  for (int k = 0; k < b.m; ++k) {
    const int added = cx.nee(b.origin, b.n, b.texel_seed, b.r, cx.pair_direct, b.c0 + k, &sc.rays[count],
                             &sc.shadow[count]);
    for (int q = 0; q < added; ++q) sc.shadow_sample[count + q] = k;
    count += added;
  }
  cx.occluded(sc.rays.data(), count);
  for (int q = 0; q < count; ++q)
    if (sc.rays[q].tfar >= 0) {
      add_rgb(&b.sums[cx.ch.direct], sc.shadow[q].value);
      add_rgb(&b.sums[cx.ch.total], sc.shadow[q].value);
    }
}

// The shadow rays of next-event estimation at one path vertex (2 + lights of them).
struct NeeBuffers {
  RTCRay fixed_rays[64];
  ShadowSample fixed_values[64];
  std::vector<RTCRay> big_rays;
  std::vector<ShadowSample> big_values;
  RTCRay* rays = fixed_rays;
  ShadowSample* values = fixed_values;
  explicit NeeBuffers(int lights) {
    const int max_nee = 2 + lights;
    if (max_nee > 64) {
      big_rays.resize(max_nee);
      big_values.resize(max_nee);
      rays = big_rays.data();
      values = big_values.data();
    }
  }
  NeeBuffers(const NeeBuffers&) = delete;
  NeeBuffers& operator=(const NeeBuffers&) = delete;
};

// Where a path vertex's next rays (its next-event and continuation rays) start, for a hit at pos with
// geometric normal ng (facing the arriving ray, which came along dir from tfar away): eps off the hit
// along ng, which is in the air above the hit's own facet when the hit lies more than eps (horizontally)
// from the facet's edges (field/triangulation.hpp facet_edge_distance). Nearer an edge that point can fall
// under a neighbouring facet that folds up beside it: a receiver at the bottom of a pit finds its hits
// within a few eps of the pit's vertex, and light read under the opposite wall is dark (7 % low at a 2-unit
// pit, whatever eps). There the rays start on the arriving ray's own segment, which is free, eps (at most
// half of it) short of the hit.
Vec3 path_origin(const HeightField& f, Vec3 pos, Vec3 ng, Vec3 dir, double tfar, double eps) {
  const double u = pos.x / f.dx(), v = pos.y / f.dy();
  if (facet_edge_distance(u - std::floor(u), v - std::floor(v), f.dx(), f.dy()) > 2 * eps)
    return pos + ng * eps;
  return pos - dir * std::min(eps, 0.5 * tfar);
}

// The Lambertian path from the surface hit h of the ray along `dir` (sample s of replicate b.r): at each
// vertex v = 1..bounces, add(v, throughput * (emission + albedo * direct)), with next-event estimation on
// the pairs pair_base + (v - 1) * path_stride and the continuation direction on the next pair. The sum of
// what it adds estimates the radiance arriving along -dir at the ray's origin from the surface.
template <class Add>
void follow_path(const TexelBatch& b, RTCRayHit h, Vec3 dir, std::uint32_t s, int pair_base, NeeBuffers& nb,
                 Add&& add) {
  const Context& cx = b.cx;
  const double eps = cx.geometry.epsilon();
  RTCRay* nr = nb.rays;
  ShadowSample* nv = nb.values;
  Rgb throughput{1, 1, 1};
  Vec3 pos = vec(&h.ray.org_x) + dir * double(h.ray.tfar);
  for (int v = 1; v <= cx.bounces; ++v) {
    Vec3 ng = normalize(Vec3{h.hit.Ng_x, h.hit.Ng_y, h.hit.Ng_z});
    if (dot(ng, dir) > 0) ng = -ng;
    Rgb albedo, emission;
    cx.surface_at(pos, albedo, emission);
    const Vec3 o = path_origin(cx.field, pos, ng, dir, double(h.ray.tfar), eps);
    const int pair0 = pair_base + (v - 1) * cx.path_stride;
    const int count = cx.nee(o, ng, b.texel_seed, b.r, pair0, s, nr, nv);
    cx.occluded(nr, count);
    Rgb direct{};
    for (int q = 0; q < count; ++q)
      if (nr[q].tfar >= 0) direct += nv[q].value;
    add(v, throughput * (emission + albedo * direct));
    if (v == cx.bounces) break;
    throughput = throughput * albedo;
    if (throughput.r <= 0 && throughput.g <= 0 && throughput.b <= 0) break;
    dir = reference::cosine_hemisphere(ng, cx.sequence(b.texel_seed, b.r, pair0 + cx.nee_pairs)(s));
    h = make_rayhit(o, dir);
    cx.intersect(&h, 1);
    if (h.hit.geomID == RTC_INVALID_GEOMETRY_ID) break;
    pos = o + dir * double(h.ray.tfar);
  }
}

// Indirect: one path per primary ray that hit the surface (sc.hits, sc.dirs from trace_primary), with
// next-event estimation at every vertex.
void trace_paths(const TexelBatch& b, Scratch& sc) {
  const Context& cx = b.cx;
  const Channels& ch = cx.ch;
  NeeBuffers nb(cx.lights);
  for (int k = 0; k < b.m; ++k) {
    const RTCRayHit& h = sc.hits[k];
    if (h.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
    follow_path(b, h, sc.dirs[k], b.c0 + k, cx.pair_path, nb, [&](int v, Rgb contribution) {
      add_rgb(&b.sums[ch.bounce(v)], contribution);
      add_rgb(&b.sums[ch.indirect], contribution);
      add_rgb(&b.sums[ch.total], contribution);
    });
  }
}

// sh_irradiance's Monte Carlo terms (reference/sh_irradiance_reference.hpp): the terrain's radiance over the
// upper hemisphere of the normal (uniform directions, pdf 1 / (2 pi), each hit continued as the indirect
// layer's paths) and each light's disk (a uniform point of the disk, radiance E / (pi sin^2 alpha) times
// the disk's solid angle), times Y_i, i < 9. Reads and overwrites sc.hits and sc.dirs.
void trace_sh_irradiance(const TexelBatch& b, Scratch& sc) {
  const Context& cx = b.cx;
  double* sums = &b.sums[cx.ch.sh];
  auto add = [&](Vec3 w, Rgb value) {
    const auto y = reference::sh_basis(w);
    for (int i = 0; i < 9; ++i) {
      sums[i * 3] += value.r * y[i];
      sums[i * 3 + 1] += value.g * y[i];
      sums[i * 3 + 2] += value.b * y[i];
    }
  };
  if (cx.bounces > 0) {
    const Sequence2 seq = cx.sequence(b.texel_seed, b.r, cx.pair_sh);
    for (int k = 0; k < b.m; ++k) {
      sc.dirs[k] = reference::uniform_hemisphere(b.frame, seq(b.c0 + k));
      sc.hits[k] = make_rayhit(b.origin, sc.dirs[k]);
    }
    cx.intersect(sc.hits.data(), b.m);
    NeeBuffers nb(cx.lights);
    for (int k = 0; k < b.m; ++k) {
      const RTCRayHit& h = sc.hits[k];
      if (h.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
      Rgb radiance{};
      follow_path(b, h, sc.dirs[k], b.c0 + k, cx.pair_sh_path, nb,
                  [&](int, Rgb contribution) { radiance += contribution; });
      add(sc.dirs[k], radiance * float(2 * kPi));
    }
  }
  for (int l = 0; l < cx.lights; ++l) {
    const DirectionalLight& light = cx.scene.lights[l];
    const double alpha = 0.5 * light.angular_diameter;
    const Sequence2 seq = cx.sequence(b.texel_seed, b.r, cx.pair_sh + 1 + l);
    double scale = 1;  // E / (pi sin^2 alpha) x 2 pi (1 - cos alpha), per unit of E
    double one_minus_cos = 0;
    if (alpha > 0) {
      const double s2 = std::sin(alpha / 2);
      one_minus_cos = 2 * s2 * s2;
      scale = 2 * one_minus_cos / (one_minus_cos * (2 - one_minus_cos));
    }
    for (int k = 0; k < b.m; ++k) {
      sc.dirs[k] = alpha > 0 ? reference::uniform_cone(light.direction, one_minus_cos, seq(b.c0 + k))
                             : light.direction;
      sc.rays[k] = make_ray(b.origin, sc.dirs[k]);
    }
    cx.occluded(sc.rays.data(), b.m);
    for (int k = 0; k < b.m; ++k)
      if (sc.rays[k].tfar >= 0) add(sc.dirs[k], light.irradiance * float(scale));
  }
}

// Adds samples [s0, s1) of replicate r of texel (i, j) to sums (ch.count doubles), kChunk at a time.
void run_samples(const Context& cx, int i, int j, std::uint64_t texel_seed, int r, std::uint32_t s0,
                 std::uint32_t s1, double* sums, Scratch& sc) {
  const HeightField& f = cx.field;
  const Vec3 n = cx.scene.normals[f.index(i, j)].d();
  const Vec3 origin = f.position(i, j) + Vec3{0, 0, cx.geometry.epsilon()};
  TexelBatch b{cx, reference::Frame(n), n, origin, texel_seed, r, 0, 0, sums};
  const bool paths = cx.needs.indirect && cx.bounces > 0;
  const bool primary_hit = cx.needs.obscurance || paths;
  for (std::uint32_t c0 = s0; c0 < s1; c0 += kChunk) {
    b.c0 = c0;
    b.m = int(std::min<std::uint32_t>(kChunk, s1 - c0));
    if (cx.needs.ao || cx.needs.bent_normal || primary_hit) trace_primary(b, sc);
    if (cx.needs.vsky) trace_vsky(b, sc);
    if (cx.needs.direct) trace_direct(b, sc);
    if (paths) trace_paths(b, sc);
    if (cx.needs.sh_irradiance) trace_sh_irradiance(b, sc);
  }
}

// A texel's estimate from B independent replicates: sums per replicate ([r * C + c]), then the mean of
// the replicate means and its standard error per channel.
struct ReplicateEstimate {
  int B = 0, C = 0;
  std::vector<double> sums, mean, se;
  ReplicateEstimate(int replicates, int channels)
      : B(replicates), C(channels), sums(std::size_t(B) * C), mean(C), se(C) {}

  // Runs n samples in each of replicates [r0, r0 + B) of texel (i, j).
  void run(const Context& cx, int i, int j, std::uint64_t texel_seed, int r0, int n, Scratch& scratch) {
    std::fill(sums.begin(), sums.end(), 0.0);
    for (int r = 0; r < B; ++r)
      run_samples(cx, i, j, texel_seed, r0 + r, 0, std::uint32_t(n), &sums[std::size_t(r) * C], scratch);
    for (int c = 0; c < C; ++c) {
      double m = 0;
      for (int r = 0; r < B; ++r) m += sums[std::size_t(r) * C + c];
      m /= double(B) * n;
      double var = 0;
      for (int r = 0; r < B; ++r) {
        const double d = sums[std::size_t(r) * C + c] / n - m;
        var += d * d;
      }
      mean[c] = m;
      se[c] = std::sqrt(var / (double(B) * (B - 1)));
    }
  }
};

// Which quantities the reference traces: the layers it writes need them.
Needs needs_of(const ReferenceOptions& options, int bounces) {
  auto wants = [&](const std::string& l) {
    return std::find(options.layers.begin(), options.layers.end(), l) != options.layers.end();
  };
  Needs needs;
  needs.ao = wants("ao");
  needs.vsky = wants("vsky");
  needs.obscurance = wants("obscurance");
  bool any_bounce = false;
  for (int b = 1; b <= bounces; ++b) any_bounce |= wants("indirect_b" + std::to_string(b));
  needs.indirect = wants("indirect") || wants("total") || any_bounce;
  needs.direct = wants("direct") || wants("total");
  needs.bent_normal = wants("bent_normal");
  needs.sh_irradiance = wants("sh_irradiance");
  return needs;
}

// What the reference records about how it was computed (hfbake:reference_setup).
nlohmann::json reference_setup(const HeightField& f, const ReferenceOptions& options,
                               const EmbreeField& geometry, int replicates, int per_replicate_cap,
                               bool adaptive, int bounces) {
  nlohmann::json setup = {{"geometry", reference::geometry_name(options.geometry)},
                          {"epsilon", geometry.epsilon()},
                          {"replicates", replicates},
                          {"samples_per_texel", adaptive ? nlohmann::json("adaptive")
                                                         : nlohmann::json(replicates * per_replicate_cap)},
                          {"bounces", bounces},
                          {"environment", options.sh_environment ? "sh4" : "full"},
                          {"falloff", falloff_kind_name(options.falloff.kind)},
                          {"radius", options.falloff.radius}};
  if (std::find(options.layers.begin(), options.layers.end(), "sh_irradiance") != options.layers.end())
    setup["sh_irradiance_horizons"] = {{"azimuths", kShAzimuths}, {"bisections", kShIterations}};
  if (f.wrap == Wrap::repeat) {
    setup["repeat_tiles"] = options.repeat_tiles;
    setup["repeat_distance_bound"] = options.repeat_tiles * std::min(f.width * f.dx(), f.height * f.dy());
  }
  return setup;
}

}  // namespace

std::vector<std::string> reference_layer_names(int bounces) {
  std::vector<std::string> names;
  for (const LayerKind& k : layer_kinds())
    if (k.trace == LayerTrace::path_traced) {
      if (!k.numbered) names.emplace_back(k.name);
      for (int b = 1; k.numbered && b <= bounces; ++b)
        names.push_back(std::string(k.name) + std::to_string(b));
    }
  return names;
}

int reference_falloff_entry(const nlohmann::json& reference,
                            const std::vector<const MethodConfig*>& entries) {
  if (reference.is_object() && (reference.contains("falloff") || reference.contains("radius"))) return -1;
  for (std::size_t b = 0; b < entries.size(); ++b)
    if (entries[b]->obscurance) return int(b);
  return -1;
}

ReferenceOptions read_reference_options(const nlohmann::json& reference,
                                        const std::vector<const MethodConfig*>& entries,
                                        const MethodContext& context, const std::string& file) {
  ReferenceOptions o;
  const nlohmann::json ref = reference.is_object() ? reference : nlohmann::json::object();
  Params in(ref, file, "/reference");
  o.samples = in.integer("samples", 256, 1, 1 << 24);
  o.replicates = in.integer("replicates", 8, 2, 64);
  o.repeat_tiles = in.integer("repeat_tiles", 1, 1, 16);
  if (in.has("seed")) {
    if (!in.raw("seed").is_number_integer() || in.raw("seed").get<long long>() < 0)
      in.fail("seed", "must be a non-negative integer");
    o.seed = in.raw("seed").get<std::uint64_t>();
  }
  in.resolve("seed", o.seed);
  o.target_stderr = in.number("target_stderr", 0, 0, 1e9);
  if (in.has("target_stderr") && !(o.target_stderr > 0))
    in.fail("target_stderr", "must be a positive number");
  // Quads trace about 1.5x faster than the grid but hold 108 bytes a texel against 54 (the bits are the
  // same): the default up to 4096² texels, the grid beyond (a 16384² field's quads alone would take 27 GiB).
  const double texels = double(context.field.width) * context.field.height;
  o.geometry = reference::geometry_kind(
      in.choice("geometry", texels <= 4096.0 * 4096.0 ? "quads" : "grid", {"quads", "grid", "triangles"}));
  o.sh_environment = in.choice("environment", "full", {"full", "sh4"}) == "sh4";

  // Falloff: the reference's own, else the first obscurance-family bake entry's (the same rule).
  bool have_falloff = false;
  if (in.has("falloff") || in.has("radius")) {
    o.falloff = read_falloff(in);
    have_falloff = true;
  } else if (const int b = reference_falloff_entry(ref, entries); b >= 0) {
    o.falloff = *entries[std::size_t(b)]->obscurance;
    have_falloff = true;
  }

  const std::vector<std::string> known = reference_layer_names(context.bounces);
  if (in.has("layers")) {
    o.layers = in.layers(known, {});
  } else if (!entries.empty()) {
    // Only what some method of the job is scored against: the reference layers its layers name.
    std::set<std::string> scored;
    for (const MethodConfig* e : entries) scored.insert(e->layers.begin(), e->layers.end());
    // A layer scored against the reference's falloff needs one.
    for (const std::string& l : known)
      if (scored.count(l) && (find_layer_kind(l)->reach != LayerReach::falloff || have_falloff))
        o.layers.push_back(l);
    if (o.layers.empty()) o.layers = {"ao"};  // nothing comparable: the cheapest layer, for the report's page
    in.resolve("layers", o.layers);
  } else {
    o.layers = {"ao", "vsky"};
    if (have_falloff) o.layers.push_back("obscurance");
    for (const char* l : {"direct", "indirect", "total"}) o.layers.push_back(l);
    in.resolve("layers", o.layers);
  }
  o.resolved = in.resolved();
  return o;
}

ReferenceOptions read_reference_options(const nlohmann::json& job_doc, const MethodContext& context,
                                        const std::string& file) {
  std::vector<MethodConfig> configs;
  if (job_doc.contains("bake") && job_doc["bake"].is_array())
    for (std::size_t b = 0; b < job_doc["bake"].size(); ++b)
      configs.push_back(resolve_method(job_doc["bake"][b], context, file, "/bake/" + std::to_string(b)));
  std::vector<const MethodConfig*> entries;
  for (const MethodConfig& c : configs) entries.push_back(&c);
  return read_reference_options(job_doc.value("reference", nlohmann::json::object()), entries, context, file);
}

ReferenceOptions parse_reference_options(const Scene& scene, const nlohmann::json& job_doc) {
  return read_reference_options(job_doc, scene_method_context(scene), "");
}

LayerSet bake_reference(const Scene& scene, const nlohmann::json& job_doc, const RunControl& rc) {
  return bake_reference(scene, parse_reference_options(scene, job_doc), rc);
}

int reference_band_count(const ReferenceOptions& options, int rows) {
  const int ts = std::max(1, options.tile_size);
  return (std::max(0, rows) + ts - 1) / ts;
}

LayerSet bake_reference(const Scene& scene, const ReferenceOptions& options, const RunControl& rc,
                        ReferenceResume* resume) {
  const HeightField& f = scene.field;
  if (scene.normals.size() != f.texel_count() || scene.surface.albedo.size() != f.texel_count())
    throw std::invalid_argument("bake_reference: the scene's normals and albedo must cover the field");
  const int bounces = std::max(0, scene.bounces);
  const std::vector<std::string> known = reference_layer_names(bounces);
  for (const std::string& l : options.layers)
    if (std::find(known.begin(), known.end(), l) == known.end())
      throw InputError("", "/reference/layers", "unknown reference layer \"" + l + "\"");
  const Environment env =
      options.sh_environment ? reference::band_limited_environment(scene.environment) : scene.environment;
  const EnvSampler sampler = env.uniform ? EnvSampler() : EnvSampler(env);
  const EmbreeField geometry(f, options.geometry, options.repeat_tiles);

  Context cx(scene, env, sampler, geometry, options, bounces);
  cx.needs = needs_of(options, bounces);
  const reference::ShEnvironmentTable sh_table = cx.needs.sh_irradiance
                                                     ? reference::make_sh_environment_table(env, kShAzimuths)
                                                     : reference::ShEnvironmentTable{};
  const double sh_lift = horizon_receiver_lift(f, geometry);
  if (options.falloff.kind != FalloffKind::none)
    cx.obscurance_tfar = float(std::min<double>(options.falloff.support(1e-6), 3.0e38));

  const int B = std::max(2, options.replicates);
  const int per_replicate_cap = std::max(1, (options.samples + B - 1) / B);
  const bool adaptive = options.target_stderr > 0;
  const int pilot = std::max(1, 64 / B);  // per replicate, target_stderr only

  // Output channels, in the order of options.layers.
  struct Out {
    std::string name;
    int first = 0, channels = 1;
  };
  std::vector<Out> outs;
  for (const std::string& l : options.layers) {
    const Channels::Slot c = cx.ch.slot(l);
    outs.push_back({l, c.first, c.channels});
  }

  const int row0 = std::clamp(options.row_begin, 0, f.height);
  const int row1 = options.row_end < 0 ? f.height : std::clamp(options.row_end, row0, f.height);
  LayerSet result;
  result.width = f.width;
  result.height = row1 - row0;
  std::vector<float*> value_data, stderr_data;
  auto channel_names = [](const Out& o) {
    if (o.name == "sh_irradiance") return reference::sh_irradiance_channels();  // 48: band 3 written as 0
    return o.channels == 1 ? mono_channels() : is_direction_layer(o.name) ? xyz_channels() : rgb_channels();
  };
  for (const Out& o : outs) value_data.push_back(result.add(o.name, channel_names(o)).data.data());
  for (const Out& o : outs)
    stderr_data.push_back(result.add(o.name + "_stderr", channel_names(o)).data.data());
  float* samples_data = adaptive ? result.add("samples", mono_channels()).data.data() : nullptr;
  // LayerSet::add may reallocate: take the pointers again now that every layer exists.
  for (std::size_t k = 0; k < outs.size(); ++k) {
    value_data[k] = result.find(outs[k].name)->data.data();
    stderr_data[k] = result.find(outs[k].name + "_stderr")->data.data();
  }
  if (adaptive) samples_data = result.find("samples")->data.data();

  const int ts = std::max(1, options.tile_size);
  const int tiles_x = (f.width + ts - 1) / ts, tiles_y = reference_band_count(options, row1 - row0);
  const int tiles = tiles_x * tiles_y;
  const int C = cx.ch.count;

  // A band (a row of tiles): its floats in every layer, for resuming (ReferenceResume).
  auto band_floats = [&](int band) {
    const std::size_t rows = std::size_t(std::min(row1 - row0, (band + 1) * ts) - band * ts);
    std::size_t n = 0;
    for (const Layer& l : result.layers) n += rows * std::size_t(f.width) * l.channels.size();
    return n;
  };
  auto band_copy = [&](int band, float* to, const float* from) {  // to or from is the band's floats
    const std::size_t first = std::size_t(band) * ts * std::size_t(f.width);
    const std::size_t texels =
        std::size_t(std::min(row1 - row0, (band + 1) * ts) - band * ts) * std::size_t(f.width);
    std::size_t at = 0;
    for (Layer& l : result.layers) {
      const std::size_t nc = l.channels.size();
      float* layer = l.data.data() + first * nc;
      if (to)
        std::copy(layer, layer + texels * nc, to + at);
      else
        std::copy(from + at, from + at + texels * nc, layer);
      at += texels * nc;
    }
  };
  std::vector<char> band_done(std::size_t(tiles_y), 0);
  if (resume && resume->load) {
    std::vector<float> buffer;
    for (int band = 0; band < tiles_y; ++band) {
      buffer.assign(band_floats(band), 0.0f);
      if (!resume->load(band, buffer)) continue;
      band_copy(band, nullptr, buffer.data());
      band_done[std::size_t(band)] = 1;
      ++resume->bands_resumed;
    }
  }
  // The tiles left to trace, and how many of each band's are still running.
  std::vector<int> todo;
  std::vector<std::atomic<int>> band_left(static_cast<std::size_t>(tiles_y));
  for (int tile = 0; tile < tiles; ++tile)
    if (!band_done[std::size_t(tile / tiles_x)]) {
      todo.push_back(tile);
      band_left[std::size_t(tile / tiles_x)].fetch_add(1);
    }
  std::atomic<int> done{tiles - int(todo.size())};
  std::atomic<int> bands_traced{0};

  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, todo.size(), 1), [&](const auto& range) {
    FlushDenormals ftz;
    Scratch scratch(cx.lights);
    ReplicateEstimate est(B, C);
    std::vector<double> sh_elevation(cx.needs.sh_irradiance ? kShAzimuths : 0);
    double sh_environment[reference::kShIrradianceSums] = {};
    const std::vector<double>& mean = est.mean;
    const std::vector<double>& se = est.se;
    for (std::size_t next = range.begin(); next != range.end(); ++next) {
      rc.check();
      const int tile = todo[next];
      const int tx = tile % tiles_x, ty = tile / tiles_x;
      for (int j = row0 + ty * ts; j < std::min(row1, row0 + (ty + 1) * ts); ++j) {
        for (int i = tx * ts; i < std::min(f.width, (tx + 1) * ts); ++i) {
          rc.check();  // per texel: a texel of a many-sample reference can take seconds
          const std::uint64_t texel_seed =
              reference::hash_combine(reference::mix64(options.seed), std::uint64_t(f.index(i, j)));
          auto estimate = [&](int r0, int n) { est.run(cx, i, j, texel_seed, r0, n, scratch); };
          int n = per_replicate_cap;
          if (adaptive) {
            // Pilot on independent replicates (ids B..2B-1): predicts the count that reaches the target at
            // the Monte Carlo rate (QMC usually does better), with a floor of |value| / N for samples that
            // all agreed (zero spread proves nothing), rounded up to a power of two. The reported estimate
            // comes from fresh samples only, so stopping early does not bias it or its stderr.
            estimate(B, pilot);
            const double n_pilot = double(B) * pilot;
            double ratio = 0;
            for (const Out& o : outs)
              for (int c = 0; c < o.channels; ++c) {
                const double floor = std::max(1.0, std::abs(mean[o.first + c])) / n_pilot;
                ratio = std::max(ratio, std::max(se[o.first + c], floor) / options.target_stderr);
              }
            const double need = n_pilot * ratio * ratio / B;
            n = 1;
            while (n < need && n < per_replicate_cap) n *= 2;  // powers of two keep the sequences' nets
            n = std::min(n, per_replicate_cap);
          }
          estimate(0, n);
          const std::size_t t = f.index(i, j - row0);
          if (cx.needs.sh_irradiance) {
            // Its environment term: no noise, from the texel's horizons.
            std::fill(sh_environment, sh_environment + reference::kShIrradianceSums, 0.0);
            for (int k = 0; k < kShAzimuths; ++k)
              sh_elevation[std::size_t(k)] = texel_horizon(f, geometry, i, j, sh_lift, sh_table.cos_phi[k],
                                                           sh_table.sin_phi[k], kShIterations)
                                                 .elevation;
            reference::add_sh_environment_above(sh_table, sh_elevation.data(), sh_environment);
          }
          for (std::size_t k = 0; k < outs.size(); ++k) {
            if (outs[k].first == cx.ch.sh && outs[k].name == "sh_irradiance") {
              // c_lm = (A_l / pi) L_lm for bands 0..2 (environment term + Monte Carlo terms), band 3 zero.
              float* v = value_data[k] + t * 48;
              float* e = stderr_data[k] + t * 48;
              std::fill(v, v + 48, 0.0f);
              std::fill(e, e + 48, 0.0f);
              for (int q = 0; q < reference::kShIrradianceSums; ++q) {
                const double a = reference::kShIrradianceScale[std::size_t(q / 3)];
                v[q] = float(a * (mean[cx.ch.sh + q] + sh_environment[q]));
                e[q] = float(a * se[cx.ch.sh + q]);
              }
              continue;
            }
            // The bent normal is the unit mean of the unoccluded directions (zero where every ray was
            // blocked); its stderr is the components' divided by that mean's length.
            double scale = 1;
            if (outs[k].first == cx.ch.bent) {
              const double* m = &mean[outs[k].first];
              const double len = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
              scale = len > 0 ? 1 / len : 0.0;
            }
            for (int c = 0; c < outs[k].channels; ++c) {
              value_data[k][t * outs[k].channels + c] = float(mean[outs[k].first + c] * scale);
              stderr_data[k][t * outs[k].channels + c] = float(se[outs[k].first + c] * scale);
            }
          }
          if (samples_data) samples_data[t] = float(n * B);
        }
      }
      if (band_left[std::size_t(ty)].fetch_sub(1) == 1) {  // the band's last tile: the band is final
        bands_traced.fetch_add(1);
        if (resume && resume->store) {
          std::vector<float> values(band_floats(ty));
          band_copy(ty, values.data(), nullptr);
          resume->store(ty, values);
        }
      }
      rc.report(double(done.fetch_add(1) + 1) / tiles);
    }
  });
  if (resume) resume->bands_traced = bands_traced.load();

  const nlohmann::json setup = reference_setup(f, options, geometry, B, per_replicate_cap, adaptive, bounces);
  result.attributes.emplace_back("hfbake:reference_setup", setup.dump());
  return result;
}

}  // namespace hfbake
