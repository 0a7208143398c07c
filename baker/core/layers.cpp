#include "core/layers.hpp"

#include <stdexcept>

#include <cstdio>

namespace hfbake {

std::vector<std::string> indexed_channels(int count) {
  std::vector<std::string> names;
  names.reserve(count);
  for (int k = 0; k < count; ++k) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "%03d", k);
    names.emplace_back(buf);
  }
  return names;
}

Layer& LayerSet::add(std::string name, std::vector<std::string> channels) {
  Layer layer;
  layer.name = std::move(name);
  layer.data.assign(std::size_t(width) * std::size_t(height) * channels.size(), 0.0f);
  layer.channels = std::move(channels);
  layers.push_back(std::move(layer));
  return layers.back();
}

Layer& LayerSet::adopt(std::string name, std::vector<std::string> channels, std::vector<float> data) {
  if (data.size() != std::size_t(width) * std::size_t(height) * channels.size())
    throw std::logic_error("LayerSet::adopt: layer " + name + " has " + std::to_string(data.size()) +
                           " values for " + std::to_string(width) + "x" + std::to_string(height) +
                           " texels x " + std::to_string(channels.size()) + " channels");
  Layer layer;
  layer.name = std::move(name);
  layer.channels = std::move(channels);
  layer.data = std::move(data);
  layers.push_back(std::move(layer));
  return layers.back();
}

const Layer* LayerSet::find(const std::string& name) const {
  for (const Layer& l : layers)
    if (l.name == name) return &l;
  return nullptr;
}

Layer* LayerSet::find(const std::string& name) {
  for (Layer& l : layers)
    if (l.name == name) return &l;
  return nullptr;
}

}  // namespace hfbake
