// Reading images (any format OpenImageIO reads) into float planes, with one-line errors that name the
// job file, the JSON pointer of the key that named the image, and the image.
#pragma once

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <variant>
#include <vector>

#include "core/vec.hpp"

namespace hfbake {

// Where an image was named, for messages: InputError(job_file, pointer, "<image>: <what>").
struct InputSite {
  std::string job_file;  // the job file as the user gave it (may be empty)
  std::string pointer;   // JSON pointer of the key that names the image, e.g. "/height/image"
};

// What the header says (nothing is decoded): enough to refuse absurd sizes before allocating.
struct ImageInfo {
  int width = 0, height = 0, channels = 0;
  std::vector<std::string> channel_names;
  bool float_data = false;  // half/float/double samples (EXR, HDR, float TIFF); else integer (8/16-bit)
  std::string format;       // OpenImageIO's format name ("openexr", "png", "tiff", ...)
  std::vector<std::string> sample_types;  // each channel's stored type: "uint8", "uint16", "half", ...
  // What of the file is not read, in a phrase ("" when nothing): the parts or pages after the first; a data
  // window that is not the display window (an EXR's pixels are read from the data window's corner).
  std::string unread;
};
ImageInfo probe_image(const std::filesystem::path& file, const InputSite& site);

// All channels of the first subimage, as floats, interleaved: pixels[(y * width + x) * channels + c].
// Integer images are normalised to [0, 1] (OpenImageIO's convention); values are as stored (no colour
// conversion). Missing, unreadable, corrupt or truncated files throw InputError.
struct Image {
  ImageInfo info;
  std::vector<float> pixels;
  float at(int x, int y, int c) const {
    return pixels[(std::size_t(y) * info.width + x) * info.channels + c];
  }
};
Image read_image(const std::filesystem::path& file, const InputSite& site);

// No channel named: the first channel that is not an alpha channel (named A or alpha, or ending in .A or
// .alpha, in any case), channel 0 when every one is. An EXR stores its channels sorted by name, so a depth
// map with alpha lists A before Z.
struct FirstNonAlphaChannel {
  bool operator==(const FirstNonAlphaChannel&) const = default;
};
// A channel chosen by index (0-based) or by name ("R", "Y", "height.Z"; exact match first, then
// case-insensitive), or the default.
using ChannelSelector = std::variant<int, std::string, FirstNonAlphaChannel>;

// A job's "channel" value (integer index or string name; null / absent = FirstNonAlphaChannel).
ChannelSelector channel_selector(const nlohmann::json& value);

// Whether a channel's name marks it as alpha (FirstNonAlphaChannel's rule).
bool is_alpha_channel_name(const std::string& name);

// The channel's index in `info`, or InputError at `channel_site` naming the file and listing its channels.
int find_channel(const ImageInfo& info, const ChannelSelector& channel, const std::filesystem::path& file,
                 const InputSite& channel_site);

// One channel as a width x height plane (row-major, row 0 = first stored row), with the type its samples
// were stored in.
struct Plane {
  int width = 0, height = 0;
  std::vector<float> values;
  std::string sample_type;  // the reader's name for it: "uint16" (OpenImageIO), "UInt16" (GDAL), ...
  bool integer = false;     // integer samples (values are the stored integers)
};

// The progress of a long read: the fraction of the rows decoded so far, after each band of rows.
using ReadProgress = std::function<void(double)>;

// Decodes the one channel straight into the plane, a band of scanlines (or a row of tiles) at a time: the
// plane is the only full-size buffer (a 16384^2 16-bit PNG: 1 GiB of floats, nothing beside it). Values
// as stored: an integer channel gives its integers (a 16-bit PNG 0..65535, an 8-bit one 0..255), not
// OpenImageIO's [0, 1], so heights read here agree with GDAL's reading of the same file
// (docs/heights.md); float channels as read_image gives them.
Plane read_image_channel(const std::filesystem::path& file, const ChannelSelector& channel,
                         const InputSite& site, const InputSite& channel_site,
                         const ReadProgress& progress = {});

// A colour image converted to linear RGB through OpenColorIO: 1 channel -> grey, 2 channels -> grey
// (the second is taken as alpha), 3+ channels -> the first three. `colorspace` empty = the default for
// the data: linear for float images, sRGB for integer (8/16-bit) images. Unknown colour space ->
// InputError at `colorspace_site`.
struct RgbImage {
  int width = 0, height = 0;
  std::vector<Rgb> pixels;  // row-major
};
RgbImage read_rgb_image(const std::filesystem::path& file, const std::string& colorspace,
                        const InputSite& site, const InputSite& colorspace_site);

}  // namespace hfbake
