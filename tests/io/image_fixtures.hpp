// Writes small test images with OpenImageIO (only io tests include this).
#pragma once

#include <OpenImageIO/imageio.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace hfbake::test {

// Writes interleaved float pixels as `type` (FLOAT, HALF, UINT8, UINT16) with optional channel names.
inline void write_test_image(const std::filesystem::path& file, int w, int h, int nc,
                             const std::vector<float>& px, OIIO::TypeDesc type = OIIO::TypeDesc::FLOAT,
                             std::vector<std::string> names = {}) {
  auto out = OIIO::ImageOutput::create(file.string());
  if (!out) throw std::runtime_error("no writer for " + file.string());
  OIIO::ImageSpec spec(w, h, nc, type);
  if (!names.empty()) spec.channelnames = names;
  if (!out->open(file.string(), spec) || !out->write_image(OIIO::TypeDesc::FLOAT, px.data()) || !out->close())
    throw std::runtime_error("cannot write " + file.string() + ": " + out->geterror());
}

}  // namespace hfbake::test
