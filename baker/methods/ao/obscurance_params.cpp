#include "methods/ao/obscurance_params.hpp"

#include <algorithm>
#include <cmath>

#include "core/direction_blocks.hpp"
#include "core/error.hpp"

namespace hfbake {

std::optional<Falloff> written_falloff(const Params& in, const Falloff& f) {
  if (in.has("falloff") || in.has("radius")) return f;
  return std::nullopt;
}

Weighting read_weighting(Params& in, bool allow_uniform) {
  const std::string w = in.choice("weighting", "cosine", {"cosine", "uniform"});
  if (w == "uniform" && !allow_uniform) in.fail("weighting", "this method supports only \"cosine\"");
  return w == "uniform" ? Weighting::uniform : Weighting::cosine;
}

bool wants(const std::vector<std::string>& layers, const char* name) {
  return std::find(layers.begin(), layers.end(), name) != layers.end();
}

LayerSet obscurance_layers(int width, int height, const std::vector<std::string>& layers,
                           std::vector<float> light, std::vector<Vec3f> bent) {
  std::vector<float> bent_xyz(3 * bent.size());
  for (std::size_t t = 0; t < bent.size(); ++t)
    bent_xyz[3 * t] = bent[t].x, bent_xyz[3 * t + 1] = bent[t].y, bent_xyz[3 * t + 2] = bent[t].z;
  std::vector<Vec3f>().swap(bent);
  return obscurance_layers_xyz(width, height, layers, std::move(light), std::move(bent_xyz));
}

LayerSet obscurance_layers_xyz(int width, int height, const std::vector<std::string>& layers,
                               std::vector<float> light, std::vector<float> bent_xyz) {
  LayerSet out;
  out.width = width;
  out.height = height;
  std::size_t scalar_left = 0;
  for (const std::string& name : layers) scalar_left += name == "bent_normal" ? 0 : 1;
  for (const std::string& name : layers) {
    if (name == "bent_normal")
      out.adopt(name, xyz_channels(), std::move(bent_xyz));
    else if (--scalar_left == 0)
      out.adopt(name, mono_channels(), std::move(light));
    else
      out.adopt(name, mono_channels(), light);
  }
  return out;
}

BlockSums block_sum_layers(int width, int height, bool bent) {
  BlockSums b;
  b.set.width = width, b.set.height = height;
  b.sum = b.set.add("sum", {"Y"}).data.data();
  if (bent) b.bent = b.set.add("bent", {"X", "Y", "Z"}).data.data();
  return b;
}

void take_block_sums(LayerSet&& sums, bool bent, std::vector<float>* sum, std::vector<float>* bent_xyz) {
  *sum = take_block_layer(sums, "sum", 1);
  if (bent) *bent_xyz = take_block_layer(sums, "bent", 3);
  sums = LayerSet();
}

}  // namespace hfbake
