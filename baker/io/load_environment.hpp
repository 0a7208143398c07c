// Builds the job's distant lighting from its `environment` object (see docs/environment.md and
// schemas/environment.schema.json): uniform, cubemap (6 files), cross, latlong or the built-in sky, with
// colorspace, intensity and rotation_deg. Image conventions: env/env_mapping.hpp.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "env/environment.hpp"

namespace hfbake {

// The largest radiance a job's light may hold, per channel: a number's schema maximum (uniform, sky,
// emission) and the ceiling of an image's pixels times its intensity or scale, so that every sum of the
// bakes stays finite.
inline constexpr double kMaxRadiance = 1e9;

struct EnvironmentLoadOptions {
  std::string job_file;                  // for messages
  std::string pointer = "/environment";  // JSON pointer of the object, for messages
  int max_height = 1024;                 // rows of the world lat-long images are resampled into (power of 2)
};

// Images are resampled into a world-frame lat-long of height min(max_height, the next power of two of
// the input's latitude resolution: lat-long height, or twice the cube face size), each texel the
// solid-angle-weighted mean of up to 4 x 4 bilinear samples. Relative paths resolve against `base_dir`.
// Problems (missing file, corrupt image, wrong aspect, unequal cube faces, unknown colour space, an
// image over 2^27 pixels, pixels that are negative or
// not finite after the conversion to linear and the intensity) -> InputError at the key's JSON pointer; two
// sources at once -> InputError at the object's pointer. No source key at all -> uniform radiance 1 (times
// intensity).
EnvironmentLighting load_environment(const nlohmann::json& environment, const std::filesystem::path& base_dir,
                                     const EnvironmentLoadOptions& options = {});

// What load_environment allocates, from the images' headers alone (for the memory estimate). `loading`:
// the peak while the images are read and resampled, before anything below is kept (24 bytes a pixel of
// the image being read: its decoded channels and their linear RGB copy, 12 bytes a pixel of the others,
// all held until the resampling, and beside them the world lat-long as it is built). `world`: the world
// lat-long with its mip levels (16 bytes a texel: 12 and a third more), kept through the bake. `tables`:
// the reference's importance-sampling tables of it (16 bytes a texel), built only by the reference.
// Throws like load_environment for a file it cannot probe.
struct EnvironmentBytes {
  double loading = 0, world = 0, tables = 0;
};
EnvironmentBytes environment_bytes(const nlohmann::json& environment, const std::filesystem::path& base_dir,
                                   const EnvironmentLoadOptions& options = {});

}  // namespace hfbake
