// The result of a bake: named layers of per-texel values, what the EXR writer stores.
#pragma once

#include <cstddef>
#include <deque>
#include <string>
#include <utility>
#include <vector>

namespace hfbake {

// One layer, e.g. "ao" (1 channel, suffix "Y"), "direct" (R, G, B), "horizon" (K channels "000".."K-1").
// Values are interleaved per texel: data[(j * width + i) * channels.size() + c], row j = image row j.
struct Layer {
  std::string name;
  std::vector<std::string> channels;  // channel suffixes; the EXR channel is name + "." + suffix
  std::vector<float> data;

  int channel_count() const { return int(channels.size()); }
};

// Layer channel suffix sets used across hfbake (see docs/contract.md).
inline std::vector<std::string> mono_channels() {
  return {"Y"};
}
inline std::vector<std::string> rgb_channels() {
  return {"R", "G", "B"};
}
inline std::vector<std::string> xyz_channels() {
  return {"X", "Y", "Z"};
}
std::vector<std::string> indexed_channels(int count);  // "000", "001", ... (zero-padded to 3 digits)

struct LayerSet {
  int width = 0, height = 0;
  std::deque<Layer> layers;  // a deque: add() never moves the layers already there
  // Metadata written into the EXR header as string attributes (method, parameters, ...).
  std::vector<std::pair<std::string, std::string>> attributes;

  // Adds a zero-filled layer and returns it. The reference stays valid as more layers are added (several
  // tests and bakes fill layers they added earlier: AddressSanitizer found one reading a moved layer).
  Layer& add(std::string name, std::vector<std::string> channels);
  // Adds a layer holding `data` (moved in, not copied: width * height * channels values, checked).
  Layer& adopt(std::string name, std::vector<std::string> channels, std::vector<float> data);
  const Layer* find(const std::string& name) const;
  Layer* find(const std::string& name);
};

}  // namespace hfbake
