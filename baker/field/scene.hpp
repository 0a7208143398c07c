// Everything a method bakes from: the height field with its normals, the surface, the lighting.
// Built once per job by the job loader; methods read it and never modify it.
#pragma once

#include <string>
#include <vector>

#include "env/environment.hpp"
#include "field/georeference.hpp"
#include "field/height_field.hpp"

namespace hfbake {

struct Surface {
  std::vector<Rgb> albedo;    // per texel, row-major like the field (always filled; constant albedo repeated)
  std::vector<Rgb> emission;  // per texel emitted radiance; empty = the surface emits nothing
};

struct Scene {
  std::string name;  // the job's name
  HeightField field;
  std::vector<Vec3f> normals;  // compute_normals(field)
  Surface surface;
  Environment environment;
  std::vector<DirectionalLight> lights;  // the job's lights plus the built-in sky's sun
  int bounces = 1;
  Georeference georeference;  // the input's CRS, geotransform and holes (for GeoTIFF outputs)
};

}  // namespace hfbake
