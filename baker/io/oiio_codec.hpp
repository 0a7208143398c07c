// OpenImageIO behind a boundary. The library and the 250-odd shared libraries it loads (codecs, video,
// medical and volume formats) cost a process about 0.4 s of CPU to map and relocate at start-up. They live
// in a module of their own, libhfbake_oiio.so (oiio_module.cpp), loaded the first time
// an image file is read or written: a bake of a GeoTIFF or procedural field that writes EXRs and GeoTIFFs,
// `validate` and `--help` never load it. image_input, preview and texture_output call it through
// oiio_codec().
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace hfbake {

// A sample type as OpenImageIO names it (TypeDesc::BASETYPE), as far as hfbake reads or writes it; the
// order is oiio_sample_bytes's table.
enum class OiioSample : int {
  other,
  uint8,
  int8,
  uint16,
  int16,
  uint32,
  int32,
  uint64,
  int64,
  half,
  float32,
  float64
};
std::size_t oiio_sample_bytes(OiioSample s);  // 0 for other
inline bool oiio_sample_is_float(OiioSample s) {
  return s == OiioSample::half || s == OiioSample::float32 || s == OiioSample::float64;
}

// What an image file's header says (OpenImageIO's ImageSpec of its first subimage).
struct OiioHeader {
  int width = 0, height = 0, channels = 0, depth = 1;
  int x = 0, y = 0, z = 0;
  int tile_width = 0, tile_height = 0;  // 0: scanlines
  bool deep = false;
  OiioSample format = OiioSample::other;  // the image's sample type
  std::vector<std::string> channel_names;
  std::vector<OiioSample> channel_formats;      // per channel
  std::vector<std::string> channel_type_names;  // per channel: "uint8", "uint16", "half", ...
  std::string format_name;                      // the reader's ("png", "openexr", ...)
  // The file's bits per integer sample where the reader names fewer than its type's (a 12-bit TIFF read
  // as uint16: 12), else 0. OpenImageIO stretches such samples over the type's range.
  int bits_per_sample = 0;
  // The display window (OpenEXR's; every other format's is the data window x, y, width, height).
  int full_x = 0, full_y = 0, full_width = 0, full_height = 0;
  bool more_subimages = false;  // a second part (EXR) or page (TIFF) follows the one read
  int orientation = 1;  // the file's Exif/TIFF Orientation tag (1: as stored; 2-8: turned or mirrored)
};

// An open image file.
class OiioReader {
 public:
  virtual ~OiioReader() = default;
  virtual const OiioHeader& header() const = 0;
  // Rows [y0, y1) (0 = the first stored row) of channels [c0, c1), interleaved, as `as` (float32, or a
  // channel's own integer type) into dst. false: the library's message in `error`.
  virtual bool read_rows(int y0, int y1, int c0, int c1, OiioSample as, void* dst, std::string& error) = 0;
};

// An image to write: `pixels` hold width x height x channels samples of `given`, interleaved; the file
// stores them as `stored`.
struct OiioWrite {
  std::string format;  // the writer: "png", "exr", "tif", "tga", ...
  int width = 0, height = 0, channels = 0;
  OiioSample stored = OiioSample::uint8, given = OiioSample::uint8;
  std::vector<std::string> channel_names;  // empty: the writer's defaults
  int alpha_channel = -1;
  std::vector<std::pair<std::string, std::string>> text_attributes;  // e.g. {"compression", "zip"}
  std::vector<std::pair<std::string, int>> int_attributes;
};

// The module's functions. Every one reports a failure through its `error` (one line or several: callers keep
// the first) and never throws.
struct OiioCodec {
  int version = 0;  // kOiioCodecVersion: the module and the executable were built together
  // Opens `path` with only the named reader (nothing falls back to another format); null on failure.
  std::unique_ptr<OiioReader> (*open)(const std::string& path, const std::string& reader, std::string& error);
  bool (*write)(const std::string& path, const OiioWrite& spec, const void* pixels, std::string& error);
  // An 8-bit PNG (1 or 3 channels) encoded in memory.
  bool (*encode_png)(int width, int height, int channels, const std::uint8_t* pixels, std::string& png,
                     std::string& error);
  // ImageBufAlgo::resize with the named filter, one thread (the result does not depend on the thread count).
  bool (*resize)(const float* pixels, int width, int height, int channels, int out_width, int out_height,
                 const std::string& filter, std::vector<float>& out, std::string& error);
};
inline constexpr int kOiioCodecVersion = 1;

// The module's functions, loaded on the first call: libhfbake_oiio.so beside the code that calls this (the
// Python package's extension), else where `cmake --install` puts it relative to the executable
// (<prefix>/lib/hfbake/), else the build tree's. std::runtime_error (one line, naming the paths tried)
// when none loads.
const OiioCodec& oiio_codec();

}  // namespace hfbake
