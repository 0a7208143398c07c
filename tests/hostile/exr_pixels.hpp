// Every channel of an image's first subimage as floats (empty when it cannot be read): the one reader the
// hostile tests compare outputs with.
#pragma once

#include <OpenImageIO/imageio.h>

#include <filesystem>
#include <vector>

inline std::vector<float> exr_pixels(const std::filesystem::path& exr) {
  auto in = OIIO::ImageInput::open(exr.string());
  if (!in) return {};
  const OIIO::ImageSpec& spec = in->spec();
  std::vector<float> px(std::size_t(spec.width) * spec.height * spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, px.data())) return {};
  return px;
}
