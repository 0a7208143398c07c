#include "methods/p1/bake_p1.hpp"

#include "methods/p1/p1.hpp"

namespace hfbake {

LayerSet bake_p1(const Scene& scene, const nlohmann::json& params, const RunControl& rc) {
  Params in(params);
  const P1Params p = read_p1_params(in);
  P1Result r = compute_p1(scene, p, rc);
  LayerSet out;
  out.width = r.width;
  out.height = r.height;
  const std::size_t N = std::size_t(r.width) * std::size_t(r.height);
  // Layers in the order the job lists them (default: ao, vsky, direct).
  const std::vector<std::string> order = in.resolved()["layers"].get<std::vector<std::string>>();
  for (const std::string& name : order) {
    if (name == "ao") {
      out.add("ao", mono_channels()).data = std::move(r.ao);
    } else if (name == "vsky") {
      out.add("vsky", mono_channels()).data = std::move(r.vsky);
    } else if (name == "direct") {
      Layer& l = out.add("direct", rgb_channels());
      for (std::size_t i = 0; i < N; ++i) {
        l.data[3 * i] = r.direct[i].r, l.data[3 * i + 1] = r.direct[i].g, l.data[3 * i + 2] = r.direct[i].b;
      }
    } else if (name == "horizon") {
      out.add("horizon", indexed_channels(r.directions)).data = std::move(r.horizon);
    } else if (name == "horizon_distance") {
      out.add("horizon_distance", indexed_channels(r.directions)).data = std::move(r.horizon_distance);
    } else if (name == "bent_normal") {
      Layer& l = out.add("bent_normal", xyz_channels());
      for (std::size_t i = 0; i < N; ++i) {
        l.data[3 * i] = r.bent_normal[i].x, l.data[3 * i + 1] = r.bent_normal[i].y;
        l.data[3 * i + 2] = r.bent_normal[i].z;
      }
    }
  }
  out.attributes.emplace_back("hfbake:p1:horizon",
                              "sin(elevation) per direction k, azimuth 2 pi k / K from +x towards +y; "
                              "horizon_distance: world units to the caster, inf where none");
  return out;
}

MethodInfo p1_method() {
  MethodInfo m;
  m.name = "p1";
  m.summary = "exact horizons by the convex-hull stack on K line sweeps; ao, vsky, direct light from them";
  m.read = [](Params& in, const MethodContext&) { read_p1_params(in); };
  m.bake = bake_p1;
  // Normals, accumulators and the near field's lifts while the sweeps run (the layers are counted apart).
  m.working_bytes_per_texel = [](const nlohmann::json&, const MethodContext&) { return 60.0; };
  m.division = WorkDivision::directions;
  m.division_note = "partial sums over disjoint direction sets (each direction's sweep is independent)";
  return m;
}

}  // namespace hfbake
