// The file-reading half of building a Scene: the height image, the albedo and emission maps and the
// lighting. Kept apart from scene_loader.cpp so the loader's logic (procedural fields, scaling, normals)
// does not pull in the image libraries' headers. Every problem is an InputError naming the job file,
// the JSON pointer and, where there is one, the image.
#pragma once

#include "cli/scene_loader.hpp"

namespace hfbake {

// The size of the height image from its header (nothing decoded).
FieldSize probe_image_field_size(const Job& job);

// The height image's chosen channel as a field (heights as stored: scale and offset are applied by the
// caller), with nodata handling: NaN/Inf texels (and texels equal to height.nodata_value) are an error
// naming the count and the first texel, unless height.nodata is "fill".
HeightField load_image_field(const Job& job, double texel_size, Wrap wrap);

// Fills `texels` (already sized to the field) from the surface key at `pointer` ("/surface/albedo" or
// "/surface/emission"): a number, [r, g, b], or {"image", "colorspace", "scale"} of the field's size.
void load_surface_map(const Job& job, const std::string& pointer, const HeightField& field,
                      std::vector<Rgb>& texels);

// The job's environment (absent: uniform radiance 1) and the lights that belong to it (the built-in
// sky's sun) into scene.environment and scene.lights.
void load_lighting(const Job& job, Scene& scene);

}  // namespace hfbake
