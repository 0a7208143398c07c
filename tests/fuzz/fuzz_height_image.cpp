// libFuzzer harness: a height image's bytes through what `validate` and `bake` do with them: the header
// probe (the size the memory estimate is made from), then the banded decode of one channel straight into
// the field, then the NaN/Inf scan. The first byte picks the file's extension (OpenImageIO picks its reader
// by extension first, then by content), the rest is the file. A bad image must be a one-line error naming
// the job file and /height/image; anything else is a finding.
#include <cmath>
#include <cstdint>
#include <string>

#include "core/error.hpp"
#include "fuzz_support.hpp"
#include "io/image_input.hpp"

using namespace hfbake;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const char* const kExtensions[] = {".png", ".exr", ".tif", ".hdr", ".pgm", ".jpg", ".bmp", ".tga"};
  if (size < 1) return 0;
  const std::string name = std::string("height") + kExtensions[data[0] % 8];
  const std::filesystem::path file = fuzz::write_scratch(name, data + 1, size - 1);
  const InputSite site{"job.json", "/height/image"}, channel_site{"job.json", "/height/channel"};
  try {
    const ImageInfo info = probe_image(file, site);
    // bake and validate refuse a field beyond the memory budget from this header before decoding; the
    // fuzzer's budget is 2^22 texels (16 MiB of heights).
    if (std::uint64_t(info.width) * std::uint64_t(info.height) > (1u << 22)) return 0;
    const Plane plane = read_image_channel(file, ChannelSelector(int(data[0] / 8) % 3), site, channel_site);
    if (plane.values.size() != std::size_t(plane.width) * std::size_t(plane.height))
      fuzz::finding("the plane's size disagrees with its dimensions");
    std::size_t bad = 0;
    for (const float z : plane.values) bad += !std::isfinite(z);
    (void)bad;
  } catch (const InputError& e) {
    fuzz::check_error_line(e.line(), "job.json");
  }
  return 0;
}
