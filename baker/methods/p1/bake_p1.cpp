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
  // Layers in the order the job lists them (default: ao, vsky, direct); compute_p1's arrays are the
  // layers' data already (moved, never copied).
  const std::vector<std::string> order = in.resolved()["layers"].get<std::vector<std::string>>();
  for (const std::string& name : order) {
    if (name == "ao") {
      out.adopt("ao", mono_channels(), std::move(r.ao));
    } else if (name == "vsky") {
      out.adopt("vsky", mono_channels(), std::move(r.vsky));
    } else if (name == "direct") {
      out.adopt("direct", rgb_channels(), std::move(r.direct));
    } else if (name == "horizon") {
      out.adopt("horizon", indexed_channels(r.directions), std::move(r.horizon));
    } else if (name == "horizon_distance") {
      out.adopt("horizon_distance", indexed_channels(r.directions), std::move(r.horizon_distance));
    } else if (name == "bent_normal") {
      out.adopt("bent_normal", xyz_channels(), std::move(r.bent_normal));
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
  m.reads_normals = false;  // recomputed per tile from the heights (normal_at)
  m.reads_albedo = false;
  m.summary = "exact horizons by the convex-hull stack on K line sweeps; ao, vsky, direct light from them";
  m.read = [](Params& in, const MethodContext&) { read_p1_params(in); };
  m.bake = bake_p1;
  // Beyond its layers (the accumulators become the layers): see p1_working_bytes.
  m.working_bytes = [](const nlohmann::json& r, const MethodContext& c) {
    return p1_working_bytes(c.field, parse_p1_params(r));
  };
  m.division = WorkDivision::directions;
  m.division_note = "partial sums over disjoint direction sets (each direction's sweep is independent)";
  return m;
}

}  // namespace hfbake
