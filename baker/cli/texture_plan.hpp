// The textures a job's "output.textures" asks for: which file each bake output gets, from which layers and
// channels, in which encoding (io/texture_output.hpp writes them; docs/textures.md). On a repeat field no
// padding is added: the texture keeps the field's size and tiles as it is. Checked by resolve_job against the
// methods' resolved layers, so validate refuses what bake could not write.
#pragma once

#include <string>
#include <vector>

#include "io/texture_output.hpp"
#include "job/manifest.hpp"

namespace hfbake {

struct PlannedTexture {
  std::string stem;  // the bake output it reads: "p1", "lsao-2", "reference"
  std::string file;  // relative to output.dir: "textures/<name>.<stem>.<layer or pack>.<ext>"
  TextureSpec spec;  // TextureSource::channel is still unset; `suffixes` names the channels
  std::vector<std::string> suffixes;  // per channel: the layer channel's suffix ("Y", "R", "X", ...)
  std::string note;  // what the user should know about it (padding left out on a repeat field), or ""
};

// The output stem of what the height field itself gives textures: its "normal" layer (3 channels X, Y, Z:
// the unit surface normal, field/normals.hpp), written as textures/<name>.height.normal.<ext>.
inline constexpr const char* kHeightStem = "height";

// Every texture of the job, in the order of output.textures and, within one entry, of its layers and of
// the bake entries. Needs the resolved layers (resolve_job). Bad entries -> InputError naming the job file
// and the pointer (/output/textures/<i>/<key>).
std::vector<PlannedTexture> plan_textures(const Job& job);

// The channel suffixes of an output layer from its name and channel count (bent_normal: X, Y, Z; colours:
// R, G, B; scalars: Y; stacks: 000, 001, ...), the EXR writer's names.
std::vector<std::string> layer_suffixes(const std::string& layer, int channels);

}  // namespace hfbake
