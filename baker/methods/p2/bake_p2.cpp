#include "methods/p2/bake_p2.hpp"

#include <algorithm>
#include <string>

#include "core/error.hpp"
#include "methods/p1/p1.hpp"

namespace hfbake {
namespace {

int int_param(const nlohmann::json& e, const char* key, int fallback, int lo, int hi) {
  if (!e.contains(key)) return fallback;
  const auto& v = e.at(key);
  if (!v.is_number_integer()) throw InputError("", key, "must be an integer");
  const long long x = v.get<long long>();
  if (x < lo || x > hi)
    throw InputError("", key, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return int(x);
}

// A RunControl reporting progress into [a, a + span) of the caller's.
RunControl sub_range(const RunControl& rc, double a, double span) {
  RunControl s;
  s.cancel = rc.cancel;
  if (rc.progress) s.progress = [&rc, a, span](double f) { rc.report(a + span * f); };
  return s;
}

bool is_bounce_layer(const std::string& name, int bounces) {
  if (name.rfind("indirect_b", 0) != 0 || name.size() == 10) return false;
  int b = 0;
  for (std::size_t i = 10; i < name.size(); ++i) {
    if (name[i] < '0' || name[i] > '9' || (i == 10 && name[i] == '0')) return false;
    b = b * 10 + (name[i] - '0');
    if (b > 1000) return false;
  }
  return b >= 1 && b <= bounces;
}

}  // namespace

P2Params parse_p2_params(const nlohmann::json& e) {
  P2Params p;
  p.directions = int_param(e, "directions", 64, 1, 4096);
  p.bounces = int_param(e, "bounces", -1, 0, 64);
  p.wrap_periods = int_param(e, "wrap_periods", 1, 1, 16);
  p.supersampling = int_param(e, "supersampling", 1, 1, 16);
  if (e.contains("visibility")) {
    const auto& v = e.at("visibility");
    if (v == "tree")
      p.visibility = P2Visibility::tree;
    else if (v == "naive")
      p.visibility = P2Visibility::naive;
    else
      throw InputError("", "visibility", "must be \"tree\" or \"naive\"");
  }
  if (e.contains("near_radius")) {
    const auto& v = e.at("near_radius");
    if (!v.is_number() || !(v.get<double>() == 0 || (v.get<double>() >= 1 && v.get<double>() <= 16)))
      throw InputError("", "near_radius", "must be 0 (off) or a number in [1, 16]");
    p.near_radius = v.get<double>();
  }
  if (e.contains("senders")) {
    const auto& v = e.at("senders");
    if (v == "facets")
      p.facet_senders = true;
    else if (v == "texels")
      p.facet_senders = false;
    else
      throw InputError("", "senders", "must be \"facets\" or \"texels\"");
  }
  if (e.contains("layers")) {
    if (!e.at("layers").is_array()) throw InputError("", "layers", "must be an array of layer names");
    for (const auto& l : e.at("layers")) {
      if (!l.is_string()) throw InputError("", "layers", "must be an array of layer names");
      p.layers.push_back(l.get<std::string>());
    }
  }
  return p;
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
  P1Params p1;
  p1.directions = params.directions;
  p1.wrap_periods = params.wrap_periods;
  p1.ao = p1.vsky = false;
  p1.direct = true;
  p1.horizon = true;  // the lobe split below uses P1's own horizons (K floats per texel while P2 runs)
  p1.facet_direct = params.facet_senders;
  // P1's exact near field reaches at least as far as the texels' own near-field gather (below).
  if (params.facet_senders) p1.near_radius = std::max(p1.near_radius, params.near_radius);
  p1.horizon_by_direction = true;
  P1Result direct = compute_p1(scene, p1, sub_range(rc, 0, phase));
  r.direct = std::move(direct.direct);
  const std::vector<float> p1_sin_horizon = std::move(direct.horizon);
  rc.check();

  // Exit radiance of bounce 0: reflected direct light plus emission.
  std::vector<Rgb> exit(N);
  const bool emits = scene.surface.emission.size() == N;
  for (std::size_t i = 0; i < N; ++i)
    exit[i] = scene.surface.albedo[i] * r.direct[i] + (emits ? scene.surface.emission[i] : Rgb{});
  // Facet senders: each texel's two facets (P1Result::direct_facets), lit with their own normals, with
  // the mean albedo and emission of their three corners (the reference interpolates them over the facet).
  std::vector<Vec3f> facet_normal;
  std::vector<Rgb> facet_albedo, facet_exit;
  if (params.facet_senders) {
    facet_normal.resize(2 * N);
    facet_albedo.resize(2 * N);
    facet_exit.resize(2 * N);
    for (int j = 0; j < f.height; ++j)
      for (int i = 0; i < f.width; ++i) {
        const std::size_t t = f.index(i, j);
        facet_normals(f, i, j, &facet_normal[2 * t]);
        for (int q = 0; q < 2; ++q) {
          const int d = q == 0 ? 1 : -1;  // the corners (i, j), (i + d, j), (i, j + d)
          const std::size_t a = f.index(f.wrap_i(i + d), j), b = f.index(i, f.wrap_j(j + d));
          const auto& al = scene.surface.albedo;
          facet_albedo[2 * t + q] = (al[t] + al[a] + al[b]) * (1.0f / 3);
          Rgb em{};
          if (emits)
            em = (scene.surface.emission[t] + scene.surface.emission[a] + scene.surface.emission[b]) *
                 (1.0f / 3);
          facet_exit[2 * t + q] = facet_albedo[2 * t + q] * direct.direct_facets[2 * t + q] + em;
        }
      }
  }

  IndirectSweepSpec spec;
  spec.directions = params.directions;
  spec.visibility = params.visibility;
  spec.wrap_periods = params.wrap_periods;
  spec.supersampling = params.supersampling;
  spec.p1_sin_horizon = &p1_sin_horizon;
  if (params.facet_senders) {
    spec.exit_facets = &facet_exit;
    spec.facet_normals = &facet_normal;
    spec.near_radius = params.near_radius;
  }
  r.indirect.assign(N, Rgb{});
  std::vector<Rgb> facet_e;
  for (int b = 1; b <= B; ++b) {
    P2SweepStats st;
    std::vector<Rgb> e = sweep_indirect(f, scene.normals, exit, spec, sub_range(rc, b * phase, phase), &st,
                                        params.facet_senders && b < B ? &facet_e : nullptr);
    if (params.facet_senders && b < B)
      for (std::size_t q = 0; q < 2 * N; ++q) facet_exit[q] = facet_albedo[q] * facet_e[q];
    r.stats.receivers += st.receivers;
    r.stats.iterations += st.iterations;
    r.stats.naive_iterations += st.naive_iterations;
    r.stats.horizons += st.horizons;
    r.stats.run_starts += st.run_starts;
    r.stats.pushed += st.pushed;
    r.stats.horizons_pushed += st.horizons_pushed;
    for (std::size_t i = 0; i < N; ++i) {
      r.indirect[i] += e[i];
      exit[i] = scene.surface.albedo[i] * e[i];
    }
    r.indirect_b.push_back(std::move(e));
  }
  rc.report(1.0);
  return r;
}

LayerSet bake_p2(const Scene& scene, const nlohmann::json& params, const RunControl& rc) {
  P2Params p = parse_p2_params(params);
  const int B = p.bounces >= 0 ? p.bounces : std::max(0, scene.bounces);
  if (p.layers.empty()) p.layers = {"indirect", "total", "direct"};
  for (const std::string& name : p.layers)
    if (name != "indirect" && name != "total" && name != "direct" && !is_bounce_layer(name, B))
      throw InputError("", "layers",
                       "\"" + name +
                           "\" is not a p2 layer (indirect, total, direct, indirect_b1 .. indirect_b" +
                           std::to_string(B) + ")");
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

}  // namespace hfbake
