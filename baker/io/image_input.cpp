#include "io/image_input.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <memory>
#include <mutex>
#include <optional>

#include "core/error.hpp"
#include "io/color.hpp"
#include "io/oiio_codec.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

[[noreturn]] void fail(const InputSite& site, const fs::path& file, const std::string& what) {
  throw InputError(site.job_file, site.pointer, file.string() + ": " + what);
}

// OpenImageIO's messages can span lines; keep the first non-empty one.
std::string first_line(std::string s) {
  while (!s.empty() && (s.front() == '\n' || s.front() == ' ')) s.erase(s.begin());
  const auto nl = s.find_first_of("\n\r");  // (a carriage return in a channel name too: one line)
  if (nl != std::string::npos) s.resize(nl);
  return s.empty() ? std::string("unknown error") : s;
}

// OpenEXR (3.1) allocates and clears an attribute's declared size, up to 2 GiB, before it notices that the
// file is shorter: a 500-byte file took 1.7 GB and 13 s to refuse (found by tests/fuzz/fuzz_environment).
// Walks the header's attributes (name, type, int32 size, value; an empty name ends a header, multi-part
// files have several) and refuses a size beyond the file before OpenEXR reads it. Not an EXR: nothing.

void check_exr_header(const fs::path& file, const InputSite& site) {
  std::ifstream in(file, std::ios::binary);
  unsigned char head[8] = {};
  if (!in.read(reinterpret_cast<char*>(head), 8) || head[0] != 0x76 || head[1] != 0x2f || head[2] != 0x31 ||
      head[3] != 0x01)
    return;
  std::error_code ec;
  const std::uint64_t length = fs::file_size(file, ec);
  if (ec) return;
  const bool multipart = (head[5] & 0x10) != 0;  // version flags: bit 12
  auto read_string = [&](std::string& out) {
    out.clear();
    for (char c; in.get(c);) {
      if (c == '\0') return true;
      if (out.size() >= 255) return false;
      out.push_back(c);
    }
    return false;
  };
  std::string name, type;
  for (int empty_run = 0; empty_run < (multipart ? 2 : 1);) {
    if (!read_string(name)) fail(site, file, "cannot read the image: a truncated or corrupt EXR header");
    if (name.empty()) {
      ++empty_run;
      continue;
    }
    empty_run = 0;
    unsigned char size_bytes[4] = {};
    if (!read_string(type) || !in.read(reinterpret_cast<char*>(size_bytes), 4))
      fail(site, file, "cannot read the image: a truncated or corrupt EXR header");
    const std::int32_t size =
        std::int32_t(std::uint32_t(size_bytes[0]) | std::uint32_t(size_bytes[1]) << 8 |
                     std::uint32_t(size_bytes[2]) << 16 | std::uint32_t(size_bytes[3]) << 24);
    const std::uint64_t at = std::uint64_t(in.tellg());
    if (size < 0 || at + std::uint64_t(size) > length)
      fail(site, file,
           "cannot read the image: its EXR header's attribute \"" + printable(name) + "\" claims " +
               std::to_string(size) + " bytes, more than the file's " + std::to_string(length) +
               " (corrupt or truncated?)");
    in.seekg(std::streamoff(size), std::ios::cur);
  }
}

// OpenImageIO (2.4) decodes a JPEG's Photoshop metadata (an APP13 segment: "Photoshop 3.0", then "8BIM"
// resource blocks; block 0x0404 holds IPTC datasets) trusting the sizes inside it, and reads past the segment
// when a size is damaged (found by tests/fuzz/fuzz_height_image: a heap over-read in decode_iptc_iim). Walks
// the markers before the image data and refuses an APP13 whose blocks or datasets claim more bytes than the
// segment holds (under either reading of block 0x0404's size), before OpenImageIO sees it. Not a JPEG:
// nothing.
void check_jpeg_metadata(const fs::path& file, const InputSite& site) {
  std::ifstream in(file, std::ios::binary);
  unsigned char soi[2] = {};
  if (!in.read(reinterpret_cast<char*>(soi), 2) || soi[0] != 0xFF || soi[1] != 0xD8) return;
  auto be16 = [](const unsigned char* b) { return std::uint32_t(b[0]) << 8 | b[1]; };
  auto be32 = [](const unsigned char* b) {
    return std::uint32_t(b[0]) << 24 | std::uint32_t(b[1]) << 16 | std::uint32_t(b[2]) << 8 | b[3];
  };
  auto damaged = [&](const std::string& what) {
    fail(site, file,
         "cannot read the image: its Photoshop metadata (JPEG APP13 segment) is damaged: " + what);
  };
  std::vector<unsigned char> d;
  for (int segments = 0; segments < 65536; ++segments) {
    // Find the next marker as libjpeg does: it skips (with a warning) any bytes before a 0xFF, then the
    // 0xFF fill bytes, and takes FF 00 for data, not a marker. (A walker that stopped at the first stray
    // byte missed an APP13 that libjpeg still hands to OpenImageIO: found by fuzz_height_image.)
    int c = in.get();
    while (c != EOF && c != 0xFF) c = in.get();
    while (c == 0xFF) c = in.get();
    if (c == 0) continue;
    if (c == EOF || c == 0xD9 || c == 0xDA) return;       // the end, or the image data begins
    if (c == 0x01 || (c >= 0xD0 && c <= 0xD7)) continue;  // markers without a segment
    unsigned char len_bytes[2] = {};
    if (!in.read(reinterpret_cast<char*>(len_bytes), 2)) return;
    const std::uint32_t len = be16(len_bytes);
    if (len < 2) return;
    if (c != 0xED) {
      in.seekg(std::streamoff(len - 2), std::ios::cur);
      continue;
    }
    d.assign(len - 2, 0);
    in.read(reinterpret_cast<char*>(d.data()), std::streamsize(d.size()));
    const std::size_t n = std::size_t(in.gcount());  // a segment cut short by the file's end: what is there
    if (n < 14 || std::memcmp(d.data(), "Photoshop 3.0\0", 14) != 0) {
      if (!in) return;
      continue;
    }
    std::size_t p = 14;
    while (p + 4 <= n && std::memcmp(d.data() + p, "8BIM", 4) == 0) {
      if (p + 7 > n) damaged("a resource block is cut short");
      const std::uint32_t id = be16(d.data() + p + 4);
      const std::size_t q = p + 6 + ((1 + std::size_t(d[p + 6]) + 1) & ~std::size_t(1));  // the name, even
      if (q + 4 > n) damaged("a resource block is cut short");
      const std::size_t size = be32(d.data() + q), begin = q + 4;
      if (size > n - begin)
        damaged("a resource block claims " + std::to_string(size) + " bytes, its segment holds " +
                std::to_string(n - begin));
      if (id == 0x0404) {
        // Read as a 4-byte gap and a 2-byte size too: either reading must stay inside the segment.
        if (p + 12 > n || be16(d.data() + p + 10) > n - (p + 12))
          damaged("the IPTC block's size runs past its segment");
        for (std::size_t r = begin, end = begin + size; r < end && d[r] == 0x1C;) {
          if (r + 5 > end) damaged("an IPTC dataset is cut short");
          const std::uint32_t dl = be16(d.data() + r + 3);
          if ((dl & 0x8000) || dl > end - (r + 5)) damaged("an IPTC dataset runs past its block");
          r += 5 + dl;
        }
      }
      p = begin + size + (size & 1);
    }
    if (!in) return;
  }
}

// The formats hfbake reads through OpenImageIO, and the reader each file goes to, told by its first bytes
// (the extension only for Targa, which has no signature). Left to itself, OpenImageIO tries every reader it
// has on a file its extension's reader refuses, including rarely used ones that abort on damaged input (a
// damaged Wavefront RLA file named .exr stopped the process on an assertion in OpenImageIO 2.4's RLA reader:
// found by tests/fuzz/fuzz_height_image). A file in no listed format is refused before any reader sees it.
// (A height raster GDAL reads never gets here: cli/scene_inputs sends it to io/georaster_input.)
constexpr const char* kReadableFormats = "EXR, TIFF, PNG, JPEG, HDR, PNM/PFM, BMP, TGA, GIF, WebP";

const char* reader_for(const fs::path& file, const InputSite& site) {
  std::ifstream in(file, std::ios::binary);
  unsigned char b[12] = {};
  in.read(reinterpret_cast<char*>(b), sizeof b);
  const std::size_t n = std::size_t(in.gcount());
  if (n == 0) fail(site, file, "is empty (0 bytes)");
  auto starts = [&](std::initializer_list<int> bytes) {
    if (bytes.size() > n) return false;
    std::size_t i = 0;
    for (const int v : bytes) {
      if (v >= 0 && b[i] != v) return false;  // v < 0: any byte
      ++i;
    }
    return true;
  };
  if (starts({0x76, 0x2f, 0x31, 0x01})) return "openexr";
  if (starts({'I', 'I', 42, 0}) || starts({'M', 'M', 0, 42}) || starts({'I', 'I', 43, 0}) ||
      starts({'M', 'M', 0, 43}))
    return "tiff";
  if (starts({0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a})) return "png";
  if (starts({0xff, 0xd8})) return "jpeg";  // libjpeg skips stray bytes before the next marker
  if (starts({'#', '?'})) return "hdr";     // #?RADIANCE, #?RGBE
  if (n >= 3 && b[0] == 'P' && std::strchr("123456fF", b[1]) && b[1] != 0 && std::isspace(b[2])) return "pnm";
  if (starts({'B', 'M'})) return "bmp";
  if (starts({'G', 'I', 'F', '8'})) return "gif";
  if (starts({'R', 'I', 'F', 'F', -1, -1, -1, -1, 'W', 'E', 'B', 'P'})) return "webp";
  // Targa: no signature at the start; a version-2 file ends with "TRUEVISION-XFILE.\0", an older one has
  // only its extension.
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".tga" || ext == ".tpic") return "targa";
  char tail[18] = {};
  in.clear();
  if (in.seekg(-18, std::ios::end) && in.read(tail, 18) && std::memcmp(tail, "TRUEVISION-XFILE.", 18) == 0)
    return "targa";
  fail(site, file,
       std::string("cannot read the image: not in a format hfbake reads (") + kReadableFormats +
           "); convert it, e.g. oiiotool FILE -o FILE.exr");
}

// The image libraries' own printing while an image is opened or decoded: libpng's default error handler
// writes "libpng error: IDAT: Read error", and libtiff's warnings reach GDAL's handler once GDAL is loaded,
// which prints "Warning 1: ...". stderr goes to a temporary file while any scope is open (scopes nest and
// may overlap across threads: the first redirects, the last restores), and only hfbake's own lines (another
// thread's progress) are printed after. What the library meant is in hfbake's one-line error (OpenImageIO's
// geterror()).
class LibraryStderr {
 public:
  LibraryStderr() {
    const std::lock_guard lock(state().mutex);
    State& st = state();
    if (st.depth++ > 0) return;
    std::fflush(stderr);
    st.captured = std::tmpfile();
    st.saved = st.captured ? dup(STDERR_FILENO) : -1;
    if (st.saved >= 0 && dup2(fileno(st.captured), STDERR_FILENO) < 0) {
      close(st.saved);
      st.saved = -1;
    }
  }
  ~LibraryStderr() {
    const std::lock_guard lock(state().mutex);
    State& st = state();
    if (--st.depth > 0) return;
    if (st.saved >= 0) {
      std::fflush(stderr);
      dup2(st.saved, STDERR_FILENO);
      close(st.saved);
      std::rewind(st.captured);
      char line[4096];
      while (std::fgets(line, sizeof line, st.captured))
        if (std::strncmp(line, "hfbake", 6) == 0) std::fputs(line, stderr);
    }
    if (st.captured) std::fclose(st.captured);
    st.captured = nullptr;
    st.saved = -1;
  }
  LibraryStderr(const LibraryStderr&) = delete;
  LibraryStderr& operator=(const LibraryStderr&) = delete;

 private:
  struct State {
    std::mutex mutex;
    int depth = 0;
    std::FILE* captured = nullptr;
    int saved = -1;
  };
  static State& state() {
    static State s;
    return s;
  }
};

std::unique_ptr<OiioReader> open_input(const fs::path& file, const InputSite& site) {
  std::error_code ec;
  if (!fs::exists(file, ec)) fail(site, file, "no such file");
  if (fs::is_directory(file, ec)) fail(site, file, "is a folder, not an image");
  const char* const reader = reader_for(file, site);
  check_exr_header(file, site);
  check_jpeg_metadata(file, site);
  // Only that format's reader: nothing falls back to the others.
  std::string why;
  auto in = oiio_codec().open(file.string(), reader, why);
  if (!in) fail(site, file, "cannot read the image: " + first_line(why));
  return in;
}

ImageInfo info_of(const OiioHeader& spec) {
  ImageInfo info;
  info.width = spec.width;
  info.height = spec.height;
  info.channels = spec.channels;
  info.channel_names = spec.channel_names;
  for (int c = int(info.channel_names.size()); c < info.channels; ++c)
    info.channel_names.push_back(std::to_string(c));
  info.float_data = oiio_sample_is_float(spec.format);
  info.format = spec.format_name;
  for (int c = 0; c < info.channels; ++c)
    info.sample_types.push_back(spec.channel_type_names[std::size_t(c)]);
  if (spec.more_subimages) info.unread = "it holds more than one part or page and only the first is read";
  const bool windowed = spec.full_width > 0 && spec.full_height > 0 &&
                        (spec.x != spec.full_x || spec.y != spec.full_y || spec.width != spec.full_width ||
                         spec.height != spec.full_height);
  if (windowed) {
    const auto box = [](int x, int y, int w, int h) {
      std::string b = "(";
      b += std::to_string(x), b += ", ", b += std::to_string(y), b += ")-(";
      b += std::to_string(x + w - 1), b += ", ", b += std::to_string(y + h - 1), b += ")";
      return b;
    };
    info.unread += std::string(info.unread.empty() ? "" : "; ") + "its data window " +
                   box(spec.x, spec.y, spec.width, spec.height) + " is not its display window " +
                   box(spec.full_x, spec.full_y, spec.full_width, spec.full_height) +
                   ": the field, and every output, is the data window's pixels from (0, 0)";
  }
  // Pixels are read as stored: a viewer that honours the tag shows the input turned against every output.
  if (spec.orientation != 1)
    info.unread += std::string(info.unread.empty() ? "" : "; ") + "its Orientation tag (" +
                   std::to_string(spec.orientation) +
                   ") is not applied: the field, and every output, is the pixels as stored, row 0 first "
                   "(a viewer that applies the tag shows the input turned or mirrored against the outputs)";
  return info;
}

// A PNM's maxval (P2, P3, P5, P6: magic, width, height, maxval, with # comments), or 0.
std::uint32_t pnm_maxval(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  char magic[2] = {};
  if (!in.read(magic, 2) || magic[0] != 'P' || !std::strchr("2356", magic[1])) return 0;
  std::uint64_t fields[3] = {};
  for (std::uint64_t& field : fields) {
    int ch = in.get();
    while (ch != EOF && (std::isspace(ch) || ch == '#')) {
      if (ch == '#')
        while (ch != EOF && ch != '\n') ch = in.get();
      ch = in.get();
    }
    if (ch == EOF || !std::isdigit(ch)) return 0;
    for (; ch != EOF && std::isdigit(ch) && field < 1000000; ch = in.get())
      field = field * 10 + unsigned(ch - '0');
  }
  return fields[2] <= 65535 ? std::uint32_t(fields[2]) : 0;
}

[[noreturn]] void pnm_misread(const InputSite& site, const fs::path& file, std::uint32_t maxval) {
  fail(site, file,
       "is a PNM of maxval " + std::to_string(maxval) +
           ", whose samples above 32767 OpenImageIO misreads: save it as a 16-bit PNG or TIFF");
}

void check_spec(const OiioHeader& spec, const fs::path& file, const InputSite& site) {
  if (spec.deep) fail(site, file, "deep images are not supported");
  // OpenImageIO stretches a PNM's samples to 0..65535 in 32-bit integers: those above 32767 overflow, but
  // for a maxval of 65535, where they come out one too low (stretch_of refuses those heights; a binary
  // PNM's heights are read through GDAL instead, io/georaster_input).
  if (spec.format_name == "pnm")
    if (const std::uint32_t maxval = pnm_maxval(file); maxval > 32767 && maxval < 65535)
      pnm_misread(site, file, maxval);
  if (spec.depth > 1) fail(site, file, "volume images are not supported");
  if (spec.width <= 0 || spec.height <= 0 || spec.channels <= 0)
    fail(site, file,
         "the image is empty (" + std::to_string(spec.width) + "x" + std::to_string(spec.height) + ")");
}

std::string lower(std::string s) {
  for (char& ch : s) ch = char(std::tolower(static_cast<unsigned char>(ch)));
  return s;
}

}  // namespace

ImageInfo probe_image(const fs::path& file, const InputSite& site) {
  const LibraryStderr quiet;
  auto in = open_input(file, site);
  const OiioHeader& spec = in->header();
  check_spec(spec, file, site);
  return info_of(spec);
}

namespace {

// How integer samples become floats: normalised as OpenImageIO does (255 -> 1 for 8 bits, 65535 -> 1 for
// 16 bits: colours), or as the stored integers (heights).
enum class IntegerSamples { normalised, stored };

// An integer type's samples as floats, the integers themselves: n samples of `type` at src.
template <class T>
void stored_to_float(const void* src, std::size_t n, float* dst) {
  const T* s = static_cast<const T*>(src);
  for (std::size_t i = 0; i < n; ++i) dst[i] = float(s[i]);
}

bool integer_to_float(OiioSample type, const void* src, std::size_t n, float* dst) {
  switch (type) {
    case OiioSample::uint8:
      stored_to_float<std::uint8_t>(src, n, dst);
      return true;
    case OiioSample::int8:
      stored_to_float<std::int8_t>(src, n, dst);
      return true;
    case OiioSample::uint16:
      stored_to_float<std::uint16_t>(src, n, dst);
      return true;
    case OiioSample::int16:
      stored_to_float<std::int16_t>(src, n, dst);
      return true;
    case OiioSample::uint32:
      stored_to_float<std::uint32_t>(src, n, dst);
      return true;
    case OiioSample::int32:
      stored_to_float<std::int32_t>(src, n, dst);
      return true;
    case OiioSample::uint64:
      stored_to_float<std::uint64_t>(src, n, dst);
      return true;
    case OiioSample::int64:
      stored_to_float<std::int64_t>(src, n, dst);
      return true;
    default:
      return false;
  }
}

// Where OpenImageIO stretches a file's integer samples over their type's whole range (a 12-bit TIFF's
// 0..4095 as 0..65535, a 4-bit grey PNG's 0..15 as 0..255, a PGM of maxval 1023 as 0..65535), the stored
// maximum and how the stretch rounds; GDAL reads the same files as stored, and so do heights
// (docs/heights.md).
struct Stretch {
  std::uint32_t stored_max = 0, type_max = 0;
  bool floors = false;  // x = floor(v * type_max / stored_max) (PNM); else the nearest (bit replication)
};

// A PNM of maxval 65535, which OpenImageIO reads one too low above 32767, is refused: its heights would shift
// (check_spec refuses the maxvals whose samples overflow, for colours too).
std::optional<Stretch> stretch_of(const fs::path& file, const InputSite& site, const OiioHeader& spec,
                                  OiioSample stored) {
  if (stored != OiioSample::uint8 && stored != OiioSample::uint16) return std::nullopt;
  Stretch s;
  s.type_max = stored == OiioSample::uint8 ? 255 : 65535;
  if (spec.format_name == "tiff" && spec.bits_per_sample > 0) {
    s.stored_max = (std::uint32_t(1) << spec.bits_per_sample) - 1;
  } else if (spec.format_name == "png") {
    // IHDR: the bit depth and colour type bytes follow the signature, the chunk's length and name, and the
    // width and height. A grey image of 1, 2 or 4 bits is expanded to 8 (a palette's indices are not
    // heights: its colours are read).
    unsigned char head[26] = {};
    std::ifstream in(file, std::ios::binary);
    if (!in.read(reinterpret_cast<char*>(head), sizeof head) || head[25] != 0 || head[24] >= 8)
      return std::nullopt;
    s.stored_max = (std::uint32_t(1) << head[24]) - 1;
  } else if (spec.format_name == "pnm") {
    s.stored_max = pnm_maxval(file);
    s.floors = true;
    if (s.stored_max == 65535) pnm_misread(site, file, s.stored_max);
  }
  if (s.stored_max == 0 || s.stored_max >= s.type_max) return std::nullopt;
  return s;
}

// The stored integers back from OpenImageIO's stretched ones (floats holding integers), in place; false
// where a value is not one the stretch gives.
bool unstretch(const Stretch& s, float* v, std::size_t n) {
  const std::uint64_t m = s.stored_max, t = s.type_max;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t x = std::uint64_t(v[i]);
    const std::uint64_t back = s.floors ? (x * m + t - 1) / t : (2 * x * m + t) / (2 * t);
    if (s.floors && back * t / m != x) return false;
    v[i] = float(back);
  }
  return true;
}

// Decodes channels [chbegin, chend) (clamped to the image's) as floats, interleaved, a band of rows at a time
// straight into the result (bands of whole tile rows for a tiled file, else of about 4 MiB of floats and at
// least 16 rows), reporting progress per band; info describes the whole file. With IntegerSamples::stored,
// a band of one integer channel is decoded in its own type into a scratch band, then converted.
Image read_channels(const fs::path& file, const InputSite& site, int chbegin, int chend,
                    IntegerSamples integers, const ReadProgress& progress = {}) {
  const LibraryStderr quiet;
  auto in = open_input(file, site);
  const OiioHeader spec = in->header();
  check_spec(spec, file, site);
  chbegin = std::clamp(chbegin, 0, spec.channels - 1);
  chend = std::clamp(chend, chbegin + 1, spec.channels);
  const std::size_t row = std::size_t(spec.width) * std::size_t(chend - chbegin);
  Image image;
  image.info = info_of(spec);
  image.pixels.resize(row * std::size_t(spec.height));
  const int band = spec.tile_width > 0 ? std::max(1, spec.tile_height)
                                       : std::max(16, int((std::size_t(4) << 20) / (4 * row)));
  const OiioSample stored = spec.channel_formats[std::size_t(chbegin)];
  const bool as_stored = integers == IntegerSamples::stored && chend - chbegin == 1 &&
                         !oiio_sample_is_float(stored) && oiio_sample_bytes(stored) > 0;
  const OiioSample read_type = as_stored ? stored : OiioSample::float32;
  const std::optional<Stretch> stretch = as_stored ? stretch_of(file, site, spec, stored) : std::nullopt;
  std::vector<unsigned char> scratch;
  if (as_stored) scratch.resize(std::size_t(band) * row * oiio_sample_bytes(stored));
  for (int y0 = 0; y0 < spec.height; y0 += band) {
    const int y1 = std::min(spec.height, y0 + band);
    float* out = image.pixels.data() + std::size_t(y0) * row;
    void* dst = as_stored ? static_cast<void*>(scratch.data()) : static_cast<void*>(out);
    std::string err;
    if (!in->read_rows(y0, y1, chbegin, chend, read_type, dst, err)) {
      fail(site, file,
           "cannot decode the image (corrupt or truncated?) in rows " + std::to_string(y0) + ".." +
               std::to_string(y1 - 1) + ": " + first_line(err));
    }
    if (as_stored && !integer_to_float(stored, scratch.data(), std::size_t(y1 - y0) * row, out))
      fail(site, file,
           "cannot decode the image: unsupported sample type " +
               spec.channel_type_names[std::size_t(chbegin)]);
    if (stretch && !unstretch(*stretch, out, std::size_t(y1 - y0) * row))
      fail(site, file,
           "cannot recover the stored integers of its " + std::to_string(stretch->stored_max) +
               "-level samples (OpenImageIO stretches them to " + std::to_string(stretch->type_max) +
               "): convert it to 8- or 16-bit");
    if (progress) progress(double(y1) / spec.height);
  }
  in.reset();
  return image;
}

}  // namespace

Image read_image(const fs::path& file, const InputSite& site) {
  return read_channels(file, site, 0, 1 << 30, IntegerSamples::normalised);
}

ChannelSelector channel_selector(const nlohmann::json& value) {
  if (value.is_string()) return value.get<std::string>();
  if (value.is_number_integer()) return value.get<int>();
  return FirstNonAlphaChannel{};
}

bool is_alpha_channel_name(const std::string& name) {
  const std::string n = lower(name);
  const auto ends = [&](const std::string& tail) {
    return n.size() >= tail.size() && n.compare(n.size() - tail.size(), tail.size(), tail) == 0;
  };
  return n == "a" || n == "alpha" || ends(".a") || ends(".alpha");
}

int find_channel(const ImageInfo& info, const ChannelSelector& channel, const fs::path& file,
                 const InputSite& channel_site) {
  std::string names;
  for (const std::string& n : info.channel_names) names += (names.empty() ? "" : ", ") + n;
  if (std::holds_alternative<FirstNonAlphaChannel>(channel)) {
    for (int c = 0; c < info.channels; ++c)
      if (!is_alpha_channel_name(info.channel_names[std::size_t(c)])) return c;
    return 0;
  }
  if (const int* index = std::get_if<int>(&channel)) {
    if (*index >= 0 && *index < info.channels) return *index;
    fail(channel_site, file,
         "has no channel " + std::to_string(*index) + " (it has " + std::to_string(info.channels) + ": " +
             names + ")");
  }
  const std::string& name = std::get<std::string>(channel);
  for (int c = 0; c < info.channels; ++c)
    if (info.channel_names[c] == name) return c;
  for (int c = 0; c < info.channels; ++c)
    if (lower(info.channel_names[c]) == lower(name)) return c;
  fail(channel_site, file, "has no channel \"" + name + "\" (it has: " + names + ")");
}

Plane read_image_channel(const fs::path& file, const ChannelSelector& channel, const InputSite& site,
                         const InputSite& channel_site, const ReadProgress& progress) {
  // The channel is checked on the header before anything is decoded or allocated.
  const int c = find_channel(probe_image(file, site), channel, file, channel_site);
  Image image = read_channels(file, site, c, c + 1, IntegerSamples::stored, progress);
  Plane plane;
  plane.width = image.info.width;
  plane.height = image.info.height;
  plane.values = std::move(image.pixels);
  const std::string& type = image.info.sample_types[std::size_t(c)];
  plane.sample_type = type;
  plane.integer = type != "half" && type != "float" && type != "double";
  return plane;
}

RgbImage read_rgb_image(const fs::path& file, const std::string& colorspace, const InputSite& site,
                        const InputSite& colorspace_site) {
  Image image =
      read_channels(file, site, 0, 3, IntegerSamples::normalised);  // at most the first three channels
  const int w = image.info.width, h = image.info.height;
  const int nc = std::min(image.info.channels, 3);
  const std::size_t n = std::size_t(w) * h;
  std::vector<float> rgb(n * 3);
  for (std::size_t i = 0; i < n; ++i) {
    const float* p = &image.pixels[i * nc];
    const bool grey = nc < 3;
    rgb[3 * i + 0] = p[0];
    rgb[3 * i + 1] = grey ? p[0] : p[1];
    rgb[3 * i + 2] = grey ? p[0] : p[2];
  }
  image.pixels.clear();
  image.pixels.shrink_to_fit();
  const std::string space = colorspace.empty() ? default_colorspace(image.info.float_data) : colorspace;
  convert_to_linear(rgb, 3, space, colorspace_site);
  RgbImage out;
  out.width = w;
  out.height = h;
  out.pixels.resize(n);
  for (std::size_t i = 0; i < n; ++i) out.pixels[i] = {rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]};
  return out;
}

}  // namespace hfbake
