#include "farm/merge_blocks.hpp"

#include "core/direction_blocks.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace hfbake {

void add_direction_block(LayerSet& total, LayerSet&& block) {
  if (total.layers.empty()) {
    total = std::move(block);
    return;
  }
  for (auto& a : block.attributes)  // per-block attributes (p2's "<count>@<b>"): kept
    if (std::none_of(total.attributes.begin(), total.attributes.end(),
                     [&](const auto& x) { return x.first == a.first; }))
      total.attributes.push_back(std::move(a));
  for (Layer& l : block.layers) {
    Layer* t = l.name.find('@') == std::string::npos ? total.find(l.name) : nullptr;
    if (!t) {
      total.adopt(l.name, l.channels, std::move(l.data));
      continue;
    }
    if (t->data.size() != l.data.size()) throw std::runtime_error("blocks of different sizes for " + l.name);
    float* a = t->data.data();
    const float* b = l.data.data();
    if (l.name.size() > 3 && l.name.compare(l.name.size() - 3, 3, "#2f") == 0) {
      // Doubles as (hi, lo) float pairs (core/direction_blocks.hpp add_split).
      for (std::size_t i = 0; i + 1 < t->data.size(); i += 2) {
        SplitDouble s{a[i], a[i + 1]};
        add_split(s, {b[i], b[i + 1]});
        a[i] = s.hi, a[i + 1] = s.lo;
      }
      continue;
    }
    for (std::size_t i = 0; i < t->data.size(); ++i) a[i] += b[i];
  }
}

LayerSet stack_row_bands(std::vector<LayerSet>&& bands, int height) {
  LayerSet out;
  if (bands.empty()) return out;
  out.width = bands.front().width;
  out.height = height;
  out.attributes = bands.front().attributes;
  for (const Layer& l : bands.front().layers) out.add(l.name, l.channels);
  std::size_t row = 0;
  for (LayerSet& band : bands) {
    if (band.width != out.width || band.layers.size() != out.layers.size())
      throw std::runtime_error("row bands of different layouts");
    for (std::size_t k = 0; k < band.layers.size(); ++k) {
      Layer& dst = out.layers[k];
      const Layer& src = band.layers[k];
      const std::size_t at = row * std::size_t(out.width) * dst.channels.size();
      if (src.name != dst.name || at + src.data.size() > dst.data.size())
        throw std::runtime_error("row bands of different layouts");
      std::copy(src.data.begin(), src.data.end(), dst.data.begin() + std::ptrdiff_t(at));
    }
    row += std::size_t(band.height);
    band = LayerSet();
  }
  if (row != std::size_t(height)) throw std::runtime_error("row bands do not cover the field");
  return out;
}

}  // namespace hfbake
