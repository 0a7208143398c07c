// 8-bit PNG previews of layers through an OpenColorIO display/view, and the in-memory image building
// blocks of report.html (PNG encoding and down-sampling, both by OpenImageIO).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/layers.hpp"

namespace hfbake {

struct PreviewOptions {
  std::string display, view;  // empty: the config's default display / that display's default view
  // The preview's longer side at most (texels); 0: no limit. A larger layer is reduced by the smallest
  // integer factor f that fits: each preview pixel is the mean of the finite values of an f x f block of
  // texels (fewer at the right and bottom edges), taken in linear light before the display transform.
  int max_size = 2048;
  // A quantity in a unit of its own (degrees, Wh/m², hours), not light: shown grey from the least of its
  // finite values (black) to the largest (white), without the display transform (mid grey when it is
  // constant); the PNG's ImageDescription names the two values.
  bool stretch = false;
};

// The preview's size for a width x height layer: (ceil(width / f), ceil(height / f)) with f the reduction
// factor described at PreviewOptions::max_size (f = 1 when the layer fits).
struct PreviewSize {
  int width = 0, height = 0, factor = 1;
};
PreviewSize preview_size(int width, int height, int max_size);

// Whether output.previews shows layer `name` of `channels` channels: what a person can look at, scalars and
// colours, not per-direction or SH stacks, nor a reference's standard errors (<layer>_stderr).
bool is_previewed(std::string_view name, int channels);

// Writes `layer` (1 channel: grey; 3 channels: RGB) of `layers` as an 8-bit RGB PNG. Light-like values
// go scene-linear -> display/view; direction layers (bent_normal) are data and are shown as
// 0.5 + 0.5 * xyz without a colour transform. A layer larger than options.max_size is reduced first, a band
// of f rows at a time (no full-size copy: the extra memory is that of the preview). Atomic like write_exr.
// Errors -> InputError naming the file.
void write_preview(const std::filesystem::path& file, const LayerSet& layers, const Layer& layer,
                   const PreviewOptions& options = {});

// An 8-bit PNG file's bytes (channels 1 = grey, 3 = RGB; rows top first), encoded in memory by
// OpenImageIO's PNG writer. A bad size or channel count -> std::invalid_argument; a writer failure ->
// std::runtime_error.
std::string encode_png(int width, int height, int channels, const std::vector<std::uint8_t>& pixels);

// Interleaved float pixels (`channels` per texel, rows top first) resized to out_width x out_height by
// OpenImageIO's ImageBufAlgo::resize with the named filter ("box": each output texel is the mean of the
// input texels under it when the sizes divide). Bad sizes -> std::invalid_argument.
std::vector<float> resize_pixels(const std::vector<float>& pixels, int width, int height, int channels,
                                 int out_width, int out_height, const std::string& filter = "box");

}  // namespace hfbake
