#include "methods/p2/bake_p2.hpp"

#include "sweep/sweep_lines.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <string>

#include "core/error.hpp"
#include "job/params.hpp"
#include "methods/p1/p1.hpp"

namespace hfbake {
namespace {

// A RunControl reporting progress into [a, a + span) of the caller's.
RunControl sub_range(const RunControl& rc, double a, double span) {
  RunControl s;
  s.cancel = rc.cancel;
  if (rc.progress) s.progress = [&rc, a, span](double f) { rc.report(a + span * f); };
  return s;
}

}  // namespace

P2Params read_p2_params(Params& in, int job_bounces) {
  P2Params p;
  p.directions = in.integer("directions", 64, 1, 4096);
  p.bounces = in.integer("bounces", -1, 0, 64);
  p.wrap_periods = in.integer("wrap_periods", 1, 1, 16);
  p.supersampling = in.integer("supersampling", 1, 1, 16);
  p.visibility =
      in.choice("visibility", "tree", {"tree", "naive"}) == "tree" ? P2Visibility::tree : P2Visibility::naive;
  p.near_radius = in.number("near_radius", p.near_radius, 0, 16);
  if (p.near_radius != 0 && p.near_radius < 1)
    in.fail("near_radius", "must be 0 (off) or a number in [1, 16]");
  p.facet_senders = in.choice("senders", "facets", {"facets", "texels"}) == "facets";
  const int B = p.bounces >= 0 ? p.bounces : std::max(0, job_bounces);
  std::vector<std::string> known = {"indirect", "total", "direct"};
  for (int b = 1; b <= B; ++b) known.push_back("indirect_b" + std::to_string(b));
  p.layers = in.layers(known, {"indirect", "total", "direct"});
  in.resolve("bounces", B);
  return p;
}

P2Params parse_p2_params(const nlohmann::json& e, int job_bounces) {
  Params in(e);
  return read_p2_params(in, job_bounces);
}

P1Params p2_direct_params(const P2Params& params) {
  P1Params p1;
  p1.directions = params.directions;
  p1.wrap_periods = params.wrap_periods;
  p1.ao = p1.vsky = false;
  p1.direct = true;
  p1.horizon = true;  // the lobe split uses P1's own horizons (K floats per texel while P2 runs)
  p1.facet_direct = params.facet_senders;
  // P1's exact near field reaches at least as far as the texels' own near-field gather.
  if (params.facet_senders) p1.near_radius = std::max(p1.near_radius, params.near_radius);
  p1.horizon_by_direction = true;
  return p1;
}

double p2_working_bytes(const FieldShape& shape, const P2Params& p) {
  const double N = double(shape.width) * double(shape.height);
  const int B = std::max(0, p.bounces);
  const double horizons = 4.0 * p.directions * N;
  // The layers the estimate counts separately, allocated only at the end (from direct and indirect).
  const double layers = 12.0 * double(p.layers.size()) * N;
  const bool keep = std::any_of(p.layers.begin(), p.layers.end(),
                                [](const std::string& l) { return l.rfind("indirect_b", 0) == 0; });
  // P1: its horizons and direct (and the facets' light) plus its own working memory.
  const double p1_phase = horizons + 12 * N + p1_working_bytes(shape, p2_direct_params(p));
  // A bounce: P1's horizons, direct, the exit radiance, the facets' (24), the sweep's double sums (24) and
  // its result (12), the indirect sum from the second bounce on; before the last bounce the facets' double
  // sums (48) and their result (24); the bounces kept for indirect_b layers (12 each); the line buffers.
  IndirectSweepSpec is;
  is.directions = p.directions;
  is.wrap_periods = p.wrap_periods;
  HeightField field;  // the sweep's plan needs only the shape
  static_cast<FieldShape&>(field) = shape;
  const double line_buffers = double(sweep_buffer_bytes(field, indirect_sweep_spec(is)));
  double bounce_phase = 0;
  for (int b = 1; b <= B; ++b) {
    double t =
        12 + 12 + (p.facet_senders ? 24 : 0) + 24 + 12 + (b > 1 ? 12 : 0) + (keep ? 12.0 * (b - 1) : 0);
    if (p.facet_senders && b < B) t += 48 + 24;
    bounce_phase = std::max(bounce_phase, horizons + t * N + line_buffers);
  }
  // Writing the layers: direct and indirect (and the kept bounces) beside them.
  const double output = (24 + (keep ? 12.0 * B : 0)) * N;
  return std::max(output, std::max(p1_phase, bounce_phase) - layers);
}

P2Result compute_p2(const Scene& scene, const P2Params& params, const RunControl& rc) {
  const HeightField& f = scene.field;
  const int B = params.bounces >= 0 ? params.bounces : std::max(0, scene.bounces);
  const std::size_t N = f.texel_count();
  const double phase = 1.0 / (1 + B);
  P2Result r;
  r.width = f.width;
  r.height = f.height;

  // Direct light: P1 on the same driver (its horizons, its lighting tables, its sun shadows).
  const P1Params p1 = p2_direct_params(params);
  P1Result direct = compute_p1(scene, p1, sub_range(rc, 0, phase));
  r.direct.resize(N);
  for (std::size_t i = 0; i < N; ++i) r.direct[i] = direct.direct_at(i);
  std::vector<float>().swap(direct.direct);
  const std::vector<float> p1_sin_horizon = std::move(direct.horizon);
  rc.check();

  // Exit radiance of bounce 0: reflected direct light plus emission.
  std::vector<Rgb> exit(N);
  const bool emits = scene.surface.emission.size() == N;
  for (std::size_t i = 0; i < N; ++i)
    exit[i] = scene.surface.albedo[i] * r.direct[i] + (emits ? scene.surface.emission[i] : Rgb{});
  // Facet senders: each texel's two facets (P1Result::direct_facets), lit with their own normals, with
  // the mean albedo and emission of their three corners (the reference interpolates them over the facet).
  // Their exit radiance replaces P1's facet light in place; albedos and normals are recomputed where needed.
  const auto facet_albedo = [&](int i, int j, int q) {
    const int d = q == 0 ? 1 : -1;  // the corners (i, j), (i + d, j), (i, j + d)
    const std::size_t t = f.index(i, j), a = f.index(f.wrap_i(i + d), j), b = f.index(i, f.wrap_j(j + d));
    const auto& al = scene.surface.albedo;
    return (al[t] + al[a] + al[b]) * (1.0f / 3);
  };
  std::vector<Rgb> facet_exit;
  if (params.facet_senders) {
    facet_exit = std::move(direct.direct_facets);
    tbb::parallel_for(0, f.height, [&](int j) {
      for (int i = 0; i < f.width; ++i) {
        const std::size_t t = f.index(i, j);
        for (int q = 0; q < 2; ++q) {
          const int d = q == 0 ? 1 : -1;
          const std::size_t a = f.index(f.wrap_i(i + d), j), b = f.index(i, f.wrap_j(j + d));
          Rgb em{};
          if (emits)
            em = (scene.surface.emission[t] + scene.surface.emission[a] + scene.surface.emission[b]) *
                 (1.0f / 3);
          facet_exit[2 * t + q] = facet_albedo(i, j, q) * facet_exit[2 * t + q] + em;
        }
      }
    });
  }
  std::vector<Rgb>().swap(direct.direct_facets);

  IndirectSweepSpec spec;
  spec.directions = params.directions;
  spec.visibility = params.visibility;
  spec.wrap_periods = params.wrap_periods;
  spec.supersampling = params.supersampling;
  spec.p1_sin_horizon = &p1_sin_horizon;
  if (params.facet_senders) {
    spec.exit_facets = &facet_exit;
    spec.near_radius = params.near_radius;
  }
  std::vector<Rgb> facet_e;
  for (int b = 1; b <= B; ++b) {
    P2SweepStats st;
    std::vector<Rgb> e = sweep_indirect(f, scene.normals, exit, spec, sub_range(rc, b * phase, phase), &st,
                                        params.facet_senders && b < B ? &facet_e : nullptr);
    if (params.facet_senders && b < B)
      tbb::parallel_for(0, f.height, [&](int j) {
        for (int i = 0; i < f.width; ++i)
          for (int q = 0; q < 2; ++q) {
            const std::size_t fq = 2 * f.index(i, j) + q;
            facet_exit[fq] = facet_albedo(i, j, q) * facet_e[fq];
          }
      });
    r.stats.receivers += st.receivers;
    r.stats.iterations += st.iterations;
    r.stats.naive_iterations += st.naive_iterations;
    r.stats.horizons += st.horizons;
    r.stats.run_starts += st.run_starts;
    r.stats.pushed += st.pushed;
    r.stats.horizons_pushed += st.horizons_pushed;
    if (b < B)
      for (std::size_t i = 0; i < N; ++i) exit[i] = scene.surface.albedo[i] * e[i];
    else
      std::vector<Rgb>().swap(exit);
    if (b == 1) {  // 0 + e: the same values (the sums never hold -0)
      if (params.keep_bounces)
        r.indirect = e;
      else
        r.indirect = std::move(e);
    } else {
      for (std::size_t i = 0; i < N; ++i) r.indirect[i] += e[i];
    }
    if (params.keep_bounces) r.indirect_b.push_back(std::move(e));
  }
  if (B == 0) r.indirect.assign(N, Rgb{});
  rc.report(1.0);
  return r;
}

LayerSet bake_p2(const Scene& scene, const nlohmann::json& params, const RunControl& rc) {
  P2Params p = parse_p2_params(params, scene.bounces);
  p.keep_bounces = std::any_of(p.layers.begin(), p.layers.end(),
                               [](const std::string& l) { return l.rfind("indirect_b", 0) == 0; });
  const int B = p.bounces >= 0 ? p.bounces : std::max(0, scene.bounces);
  const P2Result r = compute_p2(scene, p, rc);
  const std::size_t N = std::size_t(r.width) * std::size_t(r.height);
  LayerSet out;
  out.width = r.width;
  out.height = r.height;
  auto put = [&](const std::string& name, auto value) {
    Layer& l = out.add(name, rgb_channels());
    for (std::size_t i = 0; i < N; ++i) {
      const Rgb v = value(i);
      l.data[3 * i] = v.r, l.data[3 * i + 1] = v.g, l.data[3 * i + 2] = v.b;
    }
  };
  for (const std::string& name : p.layers) {
    if (name == "indirect")
      put(name, [&](std::size_t i) { return r.indirect[i]; });
    else if (name == "total")
      put(name, [&](std::size_t i) { return r.direct[i] + r.indirect[i]; });
    else if (name == "direct")
      put(name, [&](std::size_t i) { return r.direct[i]; });
    else
      put(name, [&, b = std::stoi(name.substr(10))](std::size_t i) { return r.indirect_b[b - 1][i]; });
  }
  out.attributes.emplace_back("hfbake:p2:bounces", std::to_string(B));
  if (r.stats.receivers > 0) {
    const double pts = double(r.stats.receivers);
    out.attributes.emplace_back("hfbake:p2:horizons_per_point_direction",
                                std::to_string(r.stats.horizons / pts));
    out.attributes.emplace_back("hfbake:p2:iterations_per_point_direction",
                                std::to_string(r.stats.iterations / pts));
  }
  return out;
}

MethodInfo p2_method() {
  MethodInfo m;
  m.name = "p2";
  m.summary =
      "direct light from p1, then indirect bounces gathered over the exactly visible terrain (hull tree)";
  m.read = [](Params& in, const MethodContext& c) { read_p2_params(in, c.bounces); };
  m.bake = bake_p2;
  m.memory_knob = "its directions (p1's horizons: 4 bytes a texel per direction) and the indirect_b layers";
  m.working_bytes = [](const nlohmann::json& r, const MethodContext& c) {
    return p2_working_bytes(c.field, parse_p2_params(r, c.bounces));
  };
  m.division = WorkDivision::bounce_stages;
  m.division_note =
      "by direction sets within a bounce; each bounce is a stage that needs the previous bounce's radiance "
      "of the whole field";
  return m;
}

}  // namespace hfbake
