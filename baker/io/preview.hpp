// 8-bit PNG previews of layers through an OpenColorIO display/view.
#pragma once

#include <filesystem>
#include <string>

#include "core/layers.hpp"

namespace hfbake {

struct PreviewOptions {
  std::string display, view;  // empty: the config's default display / that display's default view
};

// Writes `layer` (1 channel: grey; 3 channels: RGB) of `layers` as an 8-bit RGB PNG. Light-like values
// go scene-linear -> display/view; direction layers (bent_normal) are data and are shown as
// 0.5 + 0.5 * xyz without a colour transform. Atomic like write_exr. Errors -> InputError naming the file.
void write_preview(const std::filesystem::path& file, const LayerSet& layers, const Layer& layer,
                   const PreviewOptions& options = {});

}  // namespace hfbake
