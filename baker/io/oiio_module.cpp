// libhfbake_oiio.so: OpenImageIO behind io/oiio_codec.hpp's boundary. It links OpenImageIO and nothing of
// hfbake's; the executable loads it with dlopen the first time an image file is read or written.
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "io/oiio_codec.hpp"

namespace hfbake {
namespace {

// Each sample type and OpenImageIO's base type for it; one table both ways.
constexpr std::pair<OiioSample, OIIO::TypeDesc::BASETYPE> kSamples[] = {
    {OiioSample::uint8, OIIO::TypeDesc::UINT8},   {OiioSample::int8, OIIO::TypeDesc::INT8},
    {OiioSample::uint16, OIIO::TypeDesc::UINT16}, {OiioSample::int16, OIIO::TypeDesc::INT16},
    {OiioSample::uint32, OIIO::TypeDesc::UINT32}, {OiioSample::int32, OIIO::TypeDesc::INT32},
    {OiioSample::uint64, OIIO::TypeDesc::UINT64}, {OiioSample::int64, OIIO::TypeDesc::INT64},
    {OiioSample::half, OIIO::TypeDesc::HALF},     {OiioSample::float32, OIIO::TypeDesc::FLOAT},
    {OiioSample::float64, OIIO::TypeDesc::DOUBLE}};

OiioSample sample_of(OIIO::TypeDesc t) {
  for (const auto& [sample, base] : kSamples)
    if (t.basetype == base) return sample;
  return OiioSample::other;
}

OIIO::TypeDesc type_of(OiioSample s) {
  for (const auto& [sample, base] : kSamples)
    if (s == sample) return base;
  return OIIO::TypeDesc::UNKNOWN;
}

// The object's message, else the library's global one.
std::string message(const std::string& own) {
  return own.empty() ? OIIO::geterror() : own;
}

class Reader final : public OiioReader {
 public:
  explicit Reader(std::unique_ptr<OIIO::ImageInput> in) : in_(std::move(in)) {
    const OIIO::ImageSpec& s = in_->spec();
    h_.width = s.width, h_.height = s.height, h_.channels = s.nchannels, h_.depth = s.depth;
    h_.x = s.x, h_.y = s.y, h_.z = s.z;
    h_.tile_width = s.tile_width, h_.tile_height = s.tile_height;
    h_.deep = s.deep;
    h_.format = sample_of(s.format);
    h_.channel_names = s.channelnames;
    for (int c = 0; c < s.nchannels; ++c) {
      h_.channel_formats.push_back(sample_of(s.channelformat(c)));
      h_.channel_type_names.push_back(s.channelformat(c).c_str());
    }
    h_.format_name = in_->format_name();
    const int bits = s.get_int_attribute("oiio:BitsPerSample", 0);
    if (bits > 0 && bits < int(8 * s.format.size())) h_.bits_per_sample = bits;
    h_.full_x = s.full_x, h_.full_y = s.full_y, h_.full_width = s.full_width, h_.full_height = s.full_height;
    h_.orientation = s.get_int_attribute("Orientation", 1);
    // Whether an EXR or TIFF holds a second part or page, then back to the first (the one every read uses);
    // a failed seek's message is cleared (the reads look at the error state). Other readers are not asked:
    // seeking decodes again in some (WebP), and their files hold one image or an animation's frames.
    if (h_.format_name == "openexr" || h_.format_name == "tiff") {
      h_.more_subimages = in_->seek_subimage(1, 0);
      in_->seek_subimage(0, 0);
      (void)in_->geterror();
    }
  }
  ~Reader() override { in_->close(); }
  const OiioHeader& header() const override { return h_; }
  bool read_rows(int y0, int y1, int c0, int c1, OiioSample as, void* dst, std::string& error) override {
    const OIIO::TypeDesc t = type_of(as);
    const bool ok = h_.tile_width > 0 ? in_->read_tiles(0, 0, h_.x, h_.x + h_.width, h_.y + y0, h_.y + y1,
                                                        h_.z, h_.z + 1, c0, c1, t, dst)
                                      : read_scanlines(y0, y1, c0, c1, t, static_cast<char*>(dst), error);
    // Some readers report a short file only through the error state.
    if (ok && !in_->has_error()) return true;
    if (error.empty()) error = message(in_->geterror());
    return false;
  }

 private:
  // Rows [y0, y1) of channels [c0, c1) as type t, interleaved. Decoded as stored into a scratch band, then
  // converted: ImageInput::read_scanlines converts through a buffer of whole strips sized from the file's
  // RowsPerStrip, not its height, so a TIFF declaring strips of 2^30 rows in a 4-row image would need
  // terabytes before a byte is read. Here the memory is the band's.
  bool read_scanlines(int y0, int y1, int c0, int c1, OIIO::TypeDesc t, char* dst, std::string& error) {
    const OIIO::ImageSpec& s = in_->spec();
    // OpenImageIO's TIFF reader sizes a strip's buffer by the strips' declared rows: a strip far taller than
    // the image (more than the image again and 64 MiB) is refused before anything is allocated for it.
    const double strip_rows = double(s.get_int_attribute("tiff:RowsPerStrip", 0));
    if (strip_rows > double(s.height) &&
        strip_rows * double(s.scanline_bytes(true)) > 2.0 * double(s.image_bytes(true)) + 64.0 * (1 << 20)) {
      error = "its strips declare " + std::to_string(std::int64_t(strip_rows)) +
              " rows (RowsPerStrip) in an image of " + std::to_string(s.height) +
              ": rewrite it (gdal_translate or oiiotool FILE -o FILE.tif)";
      return false;
    }
    const bool per_channel = !s.channelformats.empty();
    if (!per_channel && s.format == t)
      return in_->read_native_scanlines(0, 0, h_.y + y0, h_.y + y1, h_.z, c0, c1, dst);
    const std::size_t rows = std::size_t(y1 - y0), width = std::size_t(s.width);
    const std::size_t stored_pixel = s.pixel_bytes(c0, c1, true);
    scratch_.resize(stored_pixel * width * rows);
    if (!in_->read_native_scanlines(0, 0, h_.y + y0, h_.y + y1, h_.z, c0, c1, scratch_.data())) return false;
    const OIIO::stride_t out_pixel = OIIO::stride_t(t.size()) * (c1 - c0);
    // Runs of channels stored in one type are converted together.
    for (int c = c0; c < c1;) {
      const OIIO::TypeDesc from = per_channel ? s.channelformats[std::size_t(c)] : s.format;
      int n = 1;
      while (per_channel && c + n < c1 && s.channelformats[std::size_t(c + n)] == from) ++n;
      if (!OIIO::convert_image(n, s.width, int(rows), 1, scratch_.data() + s.pixel_bytes(c0, c, true), from,
                               OIIO::stride_t(stored_pixel), OIIO::stride_t(stored_pixel * width),
                               OIIO::AutoStride, dst + std::size_t(c - c0) * t.size(), t, out_pixel,
                               out_pixel * OIIO::stride_t(width), OIIO::AutoStride))
        return false;
      c += n;
    }
    return true;
  }

  std::unique_ptr<OIIO::ImageInput> in_;
  OiioHeader h_;
  std::vector<char> scratch_;
};

std::unique_ptr<OiioReader> open(const std::string& path, const std::string& reader, std::string& error) {
  try {
    // create() by format name does not open, so nothing falls back to the other readers.
    auto in = OIIO::ImageInput::create(reader);
    if (!in) {
      error = message("");
      return nullptr;
    }
    // Samples as stored: a PNG reader would otherwise multiply the colour channels by alpha (and a tRNS
    // chunk's colour by an alpha of 0), and heights, albedo and emission are data, not colours to composite.
    OIIO::ImageSpec spec, config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    if (!in->open(path, spec, config)) {
      error = message(in->geterror());
      return nullptr;
    }
    return std::make_unique<Reader>(std::move(in));
  } catch (const std::exception& e) {
    error = e.what();
    return nullptr;
  }
}

OIIO::ImageSpec spec_of(const OiioWrite& w) {
  OIIO::ImageSpec spec(w.width, w.height, w.channels, type_of(w.stored));
  if (!w.channel_names.empty()) spec.channelnames = w.channel_names;
  spec.alpha_channel = w.alpha_channel;
  for (const auto& [name, value] : w.text_attributes) spec.attribute(name, value);
  for (const auto& [name, value] : w.int_attributes) spec.attribute(name, value);
  return spec;
}

// The file a writer writes through, every write(2) and close(2) checked: some of OpenImageIO's writers (PNG
// and TGA among them) do not check what their stdio writes return, so a full disk would leave a cut file
// they call written. failure() is the first error, "" when none.
class CheckedFile final : public OIIO::Filesystem::IOProxy {
 public:
  explicit CheckedFile(const std::string& path) : IOProxy(path, Write) {
    fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ < 0) fail(errno), m_mode = Closed;
  }
  ~CheckedFile() override { close(); }
  const char* proxytype() const override { return "hfbake_checked_file"; }
  void close() override {
    if (fd_ >= 0 && ::close(fd_) != 0) fail(errno);
    fd_ = -1;
    m_mode = Closed;
  }
  size_t write(const void* buf, size_t size) override {
    const size_t n = pwrite(buf, size, m_pos);
    m_pos += std::int64_t(n);
    return n;
  }
  size_t pwrite(const void* buf, size_t size, int64_t offset) override {
    size_t done = 0;
    while (fd_ >= 0 && done < size) {
      const ssize_t n =
          ::pwrite(fd_, static_cast<const char*>(buf) + done, size - done, offset + off_t(done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        fail(n < 0 ? errno : ENOSPC);
        break;
      }
      done += size_t(n);
      end_ = std::max(end_, offset + std::int64_t(done));
    }
    return done;
  }
  size_t read(void*, size_t) override { return 0; }
  size_t pread(void*, size_t, int64_t) override { return 0; }
  size_t size() const override { return size_t(end_); }
  const std::string& failure() const { return failure_; }

 private:
  void fail(int err) {
    if (failure_.empty()) failure_ = std::error_code(err, std::generic_category()).message();
  }
  int fd_ = -1;
  std::int64_t end_ = 0;
  std::string failure_;
};

// Whether `path` reads back as the image `w` describes, every scanline (one row held at a time). A TIFF's
// check: libtiff writes its directories as the file closes, which OpenImageIO's TIFF writer does not check.
bool reads_back(const std::string& path, const OiioWrite& w, std::string& error) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    error = "the file written does not read back: " + message("");
    return false;
  }
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.width != w.width || spec.height != w.height || spec.nchannels != w.channels) {
    error = "the file written reads back as another image";
    return false;
  }
  std::vector<float> row(std::size_t(spec.width) * std::size_t(spec.nchannels));
  for (int y = 0; y < spec.height; ++y)
    if (!in->read_scanline(y, 0, OIIO::TypeDesc::FLOAT, row.data())) {
      error = "the file written does not read back: " + message(in->geterror());
      return false;
    }
  return true;
}

bool write(const std::string& path, const OiioWrite& w, const void* pixels, std::string& error) {
  try {
    // OpenImageIO's TIFF writer through an IOProxy (OpenImageIO 2.4) cuts its first directory off the file
    // when it adds an EXIF block (the sRGB tag's): TIFFs are written by the library to the path, then read
    // back whole.
    if (w.format == "tif" || w.format == "tiff") {
      auto out = OIIO::ImageOutput::create(w.format);
      if (!out || !out->open(path, spec_of(w)) || !out->write_image(type_of(w.given), pixels) ||
          !out->close()) {
        error = out ? message(out->geterror()) : message("");
        return false;
      }
      return reads_back(path, w, error);
    }
    CheckedFile file(path);
    auto out = OIIO::ImageOutput::create(w.format);
    if (!out || !out->supports("ioproxy") || !out->set_ioproxy(&file) || !out->open(path, spec_of(w)) ||
        !out->write_image(type_of(w.given), pixels) || !out->close()) {
      error = !file.failure().empty() ? file.failure()
              : !out                  ? message("")
              : out->supports("ioproxy")
                  ? message(out->geterror())
                  : "the " + w.format + " writer does not write through a checked file";
      return false;
    }
    file.close();
    if (!file.failure().empty()) {
      error = file.failure();
      return false;
    }
    return true;
  } catch (const std::exception& e) {
    error = e.what();
    return false;
  }
}

bool encode_png(int width, int height, int channels, const std::uint8_t* pixels, std::string& png,
                std::string& error) {
  try {
    std::vector<unsigned char> bytes;
    OIIO::Filesystem::IOVecOutput proxy(bytes);
    // The name only selects the PNG writer; nothing is written to disk through the proxy.
    auto out = OIIO::ImageOutput::create("memory.png");
    const OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
    if (!out || !out->supports("ioproxy") || !out->set_ioproxy(&proxy) || !out->open("memory.png", spec) ||
        !out->write_image(OIIO::TypeDesc::UINT8, pixels) || !out->close()) {
      error = out ? out->geterror() : OIIO::geterror();
      if (error.empty()) error = "the PNG writer does not write to memory";
      return false;
    }
    png.assign(bytes.begin(), bytes.end());
    return true;
  } catch (const std::exception& e) {
    error = e.what();
    return false;
  }
}

bool resize(const float* pixels, int width, int height, int channels, int out_width, int out_height,
            const std::string& filter, std::vector<float>& out, std::string& error) {
  try {
    const OIIO::ImageSpec in_spec(width, height, channels, OIIO::TypeDesc::FLOAT);
    // Wraps the caller's pixels without a copy (ImageBuf only reads them here).
    const OIIO::ImageBuf src(in_spec, const_cast<float*>(pixels));
    OIIO::ImageBuf dst(OIIO::ImageSpec(out_width, out_height, channels, OIIO::TypeDesc::FLOAT));
    out.assign(std::size_t(out_width) * out_height * channels, 0.0f);
    if (!OIIO::ImageBufAlgo::resize(dst, src, filter, 0.0f, OIIO::ROI(), 1) ||
        !dst.get_pixels(OIIO::ROI(0, out_width, 0, out_height, 0, 1, 0, channels), OIIO::TypeDesc::FLOAT,
                        out.data())) {
      error = dst.geterror();
      return false;
    }
    return true;
  } catch (const std::exception& e) {
    error = e.what();
    return false;
  }
}

const OiioCodec kCodec{kOiioCodecVersion, open, write, encode_png, resize};

}  // namespace
}  // namespace hfbake

extern "C" __attribute__((visibility("default"))) const hfbake::OiioCodec* hfbake_oiio_codec() {
  return &hfbake::kCodec;
}
