#include "io/preview.hpp"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/error.hpp"
#include "io/color.hpp"
#include "io/exr_output.hpp"

namespace hfbake {
namespace fs = std::filesystem;

void write_preview(const fs::path& file, const LayerSet& layers, const Layer& layer,
                   const PreviewOptions& options) {
  const int w = layers.width, h = layers.height, nc = layer.channel_count();
  const std::size_t n = std::size_t(w) * h;
  if ((nc != 1 && nc != 3) || layer.data.size() != n * std::size_t(nc))
    throw std::logic_error("write_preview: layer " + layer.name +
                           " is not a 1- or 3-channel layer of the set's size");
  std::vector<float> rgb(n * 3);
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) rgb[3 * i + c] = layer.data[i * nc + (nc == 1 ? 0 : c)];
  const bool direction = layer.name == "bent_normal";
  if (direction) {
    for (float& v : rgb) v = 0.5f + 0.5f * v;
  } else {
    convert_to_display(rgb, options.display, options.view, InputSite{file.string(), ""});
  }
  std::vector<std::uint8_t> bytes(rgb.size());
  for (std::size_t i = 0; i < rgb.size(); ++i) {
    const float v = std::isfinite(rgb[i]) ? std::clamp(rgb[i], 0.0f, 1.0f) : 0.0f;
    bytes[i] = std::uint8_t(std::lround(v * 255.0f));
  }

  std::error_code ec;
  const fs::path tmp = temporary_sibling(file);
  // The temporary name must still end in .png so OpenImageIO picks the PNG writer.
  const fs::path tmp_png = tmp.string() + ".png";
  auto out = OIIO::ImageOutput::create("png");
  OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::UINT8);
  spec.attribute("oiio:ColorSpace", direction ? "Raw" : "sRGB");
  if (!out || !out->open(tmp_png.string(), spec) || !out->write_image(OIIO::TypeDesc::UINT8, bytes.data()) ||
      !out->close()) {
    std::string err = out ? out->geterror() : OIIO::geterror();
    if (const auto nl = err.find('\n'); nl != std::string::npos) err.resize(nl);
    fs::remove(tmp_png, ec);
    throw InputError(file.string(), "", "cannot write the preview: " + err);
  }
  fs::rename(tmp_png, file, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp_png, ignored);
    throw InputError(file.string(), "", "cannot move the preview into place: " + ec.message());
  }
}

}  // namespace hfbake
