// Reading images: formats, channels, and the one-line errors for missing, corrupt, truncated files and
// missing channels.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "image_fixtures.hpp"
#include "io/image_input.hpp"
#include "temp_folder.hpp"

namespace hfbake {
namespace {
namespace fs = std::filesystem;
using test::TempFolder;
using test::write_test_image;

const InputSite kSite{"jobs/x.json", "/height/image"};
const InputSite kChannelSite{"jobs/x.json", "/height/channel"};

// The message the user sees, as the CLI prints it after "hfbake: error: ".
template <class F>
std::string error_line(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.line();
  }
  return "(no InputError)";
}

std::vector<float> ramp(int w, int h, int nc) {
  std::vector<float> v(std::size_t(w) * h * nc);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = float(i) * 0.25f;
  return v;
}

TEST(ImageInput, ReadsFloatExrAndTiffExactly) {
  TempFolder dir;
  const auto px = ramp(5, 3, 2);
  for (const char* name : {"a.exr", "a.tif"}) {
    write_test_image(dir / name, 5, 3, 2, px, OIIO::TypeDesc::FLOAT, {"height", "mask"});
    const ImageInfo info = probe_image(dir / name, kSite);
    EXPECT_EQ(info.width, 5);
    EXPECT_EQ(info.height, 3);
    EXPECT_EQ(info.channels, 2);
    EXPECT_TRUE(info.float_data);
    const Image img = read_image(dir / name, kSite);
    EXPECT_EQ(img.pixels, px) << name;
    EXPECT_FLOAT_EQ(img.at(4, 2, 1), px[(2 * 5 + 4) * 2 + 1]);
    // By index and by name (case-insensitive fallback), row 0 first.
    // TIFF keeps no channel names: select by name in the EXR, by index in both.
    const Plane p = std::string(name) == "a.exr"
                        ? read_image_channel(dir / name, std::string("MASK"), kSite, kChannelSite)
                        : read_image_channel(dir / name, 1, kSite, kChannelSite);
    ASSERT_EQ(p.values.size(), 15u);
    EXPECT_FLOAT_EQ(p.values[0], px[1]);
    EXPECT_FLOAT_EQ(p.values[14], px[29]);
    const Plane q = read_image_channel(dir / name, 0, kSite, kChannelSite);
    EXPECT_FLOAT_EQ(q.values[7], px[14]);
  }
}

TEST(ImageInput, IntegerImagesAreNormalised) {
  TempFolder dir;
  // 8-bit 255 -> 1.0, 51 -> 0.2; 16-bit 65535 -> 1.0.
  write_test_image(dir / "a.png", 2, 1, 1, {1.0f, 0.2f}, OIIO::TypeDesc::UINT8);
  const Image a = read_image(dir / "a.png", kSite);
  EXPECT_FALSE(a.info.float_data);
  EXPECT_FLOAT_EQ(a.pixels[0], 1.0f);
  EXPECT_FLOAT_EQ(a.pixels[1], 51.0f / 255.0f);
  write_test_image(dir / "b.png", 2, 1, 1, {1.0f, 0.5f}, OIIO::TypeDesc::UINT16);
  const Image b = read_image(dir / "b.png", kSite);
  EXPECT_FLOAT_EQ(b.pixels[0], 1.0f);
  EXPECT_NEAR(b.pixels[1], 0.5f, 1.0f / 65535);
}

// A height channel's integer samples are the stored integers, whatever the integer type and format (the
// rule GDAL follows too); float channels are as stored. The truth: the integers written.
TEST(ImageInput, HeightChannelsGiveStoredIntegers) {
  TempFolder dir;
  struct Case {
    const char* name;
    OIIO::TypeDesc type;
    std::vector<float> written;  // the samples as OpenImageIO's normalised floats
    std::vector<float> stored;   // the integers they are stored as
    const char* sample_type;
  };
  const std::vector<Case> cases = {
      {"u8.png", OIIO::TypeDesc::UINT8, {0.0f, 51 / 255.0f, 1.0f}, {0, 51, 255}, "uint8"},
      {"u16.png", OIIO::TypeDesc::UINT16, {0.0f, 1234 / 65535.0f, 1.0f}, {0, 1234, 65535}, "uint16"},
      {"u16.tif", OIIO::TypeDesc::UINT16, {0.0f, 40000 / 65535.0f, 1.0f}, {0, 40000, 65535}, "uint16"},
      {"u8.tif", OIIO::TypeDesc::UINT8, {0.0f, 7 / 255.0f, 1.0f}, {0, 7, 255}, "uint8"},
      {"i16.tif", OIIO::TypeDesc::INT16, {-1.0f, 0.0f, 300 / 32767.0f}, {-32767, 0, 300}, "int16"},
      {"f.exr", OIIO::TypeDesc::FLOAT, {-2.5f, 0.0f, 812.25f}, {-2.5f, 0.0f, 812.25f}, "float"},
  };
  for (const Case& c : cases) {
    write_test_image(dir / c.name, 3, 1, 1, c.written, c.type);
    const Plane p = read_image_channel(dir / c.name, 0, kSite, kChannelSite);
    EXPECT_EQ(p.values, c.stored) << c.name;
    EXPECT_EQ(p.sample_type, c.sample_type) << c.name;
    EXPECT_EQ(p.integer, c.type != OIIO::TypeDesc::FLOAT) << c.name;
  }
}

// A PNG written byte by byte (PNG 1.2: IHDR, optional chunks, one IDAT of stored deflate blocks, IEND), so
// that what is stored does not depend on the reader under test. rows: each row's samples, big-endian.
void write_raw_png(const fs::path& file, int w, int h, int bit_depth, int colour_type,
                   const std::vector<std::vector<std::uint8_t>>& rows,
                   const std::vector<std::pair<std::string, std::vector<std::uint8_t>>>& extra = {}) {
  const auto crc32 = [](const std::vector<std::uint8_t>& d) {
    std::uint32_t c = 0xffffffffu;
    for (std::uint8_t b : d) {
      c ^= b;
      for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
    }
    return c ^ 0xffffffffu;
  };
  const auto be32 = [](std::vector<std::uint8_t>& v, std::uint32_t x) {
    for (int s = 24; s >= 0; s -= 8) v.push_back(std::uint8_t(x >> s));
  };
  std::vector<std::uint8_t> out = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  const auto chunk = [&](const std::string& type, const std::vector<std::uint8_t>& data) {
    be32(out, std::uint32_t(data.size()));
    std::vector<std::uint8_t> td(type.begin(), type.end());
    td.insert(td.end(), data.begin(), data.end());
    out.insert(out.end(), td.begin(), td.end());
    be32(out, crc32(td));
  };
  std::vector<std::uint8_t> ihdr;
  be32(ihdr, std::uint32_t(w)), be32(ihdr, std::uint32_t(h));
  ihdr.insert(ihdr.end(), {std::uint8_t(bit_depth), std::uint8_t(colour_type), 0, 0, 0});
  chunk("IHDR", ihdr);
  for (const auto& [type, data] : extra) chunk(type, data);
  std::vector<std::uint8_t> raw;  // filter type 0 before each row
  for (const auto& r : rows) raw.push_back(0), raw.insert(raw.end(), r.begin(), r.end());
  std::vector<std::uint8_t> z = {0x78, 0x01, 0x01};  // one final stored block (raw is small)
  z.push_back(std::uint8_t(raw.size())), z.push_back(std::uint8_t(raw.size() >> 8));
  z.push_back(std::uint8_t(~raw.size())), z.push_back(std::uint8_t(~raw.size() >> 8));
  z.insert(z.end(), raw.begin(), raw.end());
  std::uint32_t a = 1, b = 0;  // Adler-32
  for (std::uint8_t x : raw) a = (a + x) % 65521, b = (b + a) % 65521;
  be32(z, (b << 16) | a);
  chunk("IDAT", z);
  chunk("IEND", {});
  std::ofstream(file, std::ios::binary)
      .write(reinterpret_cast<const char*>(out.data()), std::streamsize(out.size()));
}

std::vector<std::uint8_t> be16(std::initializer_list<int> values) {
  std::vector<std::uint8_t> v;
  for (int x : values) v.push_back(std::uint8_t(x >> 8)), v.push_back(std::uint8_t(x));
  return v;
}

TEST(ImageInput, HeightsInPngsWithTransparencyAreTheStoredIntegers) {
  TempFolder dir;
  // 16-bit grey + alpha: alpha 0, a half and 1 must not scale the grey.
  write_raw_png(dir / "ga16.png", 3, 1, 16, 4, {be16({20000, 0, 25000, 32768, 30000, 65535})});
  EXPECT_EQ(read_image_channel(dir / "ga16.png", 0, kSite, kChannelSite).values,
            (std::vector<float>{20000, 25000, 30000}));
  // 8-bit RGBA at half opacity: the red channel as stored.
  write_raw_png(dir / "rgba8.png", 2, 1, 8, 6, {{100, 1, 2, 128, 150, 3, 4, 128}});
  EXPECT_EQ(read_image_channel(dir / "rgba8.png", 0, kSite, kChannelSite).values,
            (std::vector<float>{100, 150}));
  // 16-bit grey whose tRNS chunk names one of its values transparent: that value stays a height.
  write_raw_png(dir / "trns16.png", 3, 1, 16, 0, {be16({1000, 1018, 1100})}, {{"tRNS", be16({1018})}});
  EXPECT_EQ(read_image_channel(dir / "trns16.png", 0, kSite, kChannelSite).values,
            (std::vector<float>{1000, 1018, 1100}));
}

// A baseline TIFF of one strip written byte by byte (little-endian; samples of `bits` bits packed MSB first,
// each row starting on a byte), so that what is stored does not depend on the reader under test.
void write_raw_tiff(const fs::path& file, int w, int h, int bits, const std::vector<std::uint32_t>& samples) {
  std::vector<std::uint8_t> data;
  for (int j = 0; j < h; ++j) {
    std::uint64_t acc = 0;
    int have = 0;
    for (int i = 0; i < w; ++i) {
      acc = (acc << bits) | samples[std::size_t(j * w + i)], have += bits;
      for (; have >= 8; have -= 8) data.push_back(std::uint8_t(acc >> (have - 8)));
    }
    if (have > 0) data.push_back(std::uint8_t(acc << (8 - have)));
  }
  std::vector<std::uint8_t> out = {'I', 'I', 42, 0, 8, 0, 0, 0};
  const auto le = [&](std::uint32_t x, int bytes) {
    for (int b = 0; b < bytes; ++b) out.push_back(std::uint8_t(x >> (8 * b)));
  };
  const std::uint16_t tags[][2] = {{256, 0}, {257, 0}, {258, 0}, {259, 1}, {262, 1},
                                   {273, 0}, {277, 1}, {278, 0}, {279, 0}};
  const std::uint32_t n = sizeof tags / sizeof tags[0];
  const std::uint32_t data_at = 8 + 2 + 12 * n + 4;
  le(n, 2);
  for (const auto& t : tags) {
    const std::uint32_t value = t[0] == 256   ? std::uint32_t(w)
                                : t[0] == 257 ? std::uint32_t(h)
                                : t[0] == 258 ? std::uint32_t(bits)
                                : t[0] == 273 ? data_at
                                : t[0] == 278 ? std::uint32_t(h)
                                : t[0] == 279 ? std::uint32_t(data.size())
                                              : t[1];
    le(t[0], 2), le(t[0] == 273 || t[0] == 279 ? 4 : 3, 2), le(1, 4), le(value, 4);  // LONG or SHORT
  }
  le(0, 4);  // no next IFD
  out.insert(out.end(), data.begin(), data.end());
  std::ofstream(file, std::ios::binary)
      .write(reinterpret_cast<const char*>(out.data()), std::streamsize(out.size()));
}

// Integers of fewer bits than their type (a 12-bit TIFF, a 1-, 2- or 4-bit grey PNG, a PGM of maxval 1023
// or 100) are heights as stored, as GDAL reads them: OpenImageIO stretches them over the type's range.
TEST(ImageInput, HeightsOfFewerBitsThanTheirTypeAreTheStoredIntegers) {
  TempFolder dir;
  const auto heights = [&](const char* name) {
    return read_image_channel(dir / name, 0, kSite, kChannelSite);
  };
  std::vector<std::uint32_t> twelve = {0, 1, 15, 16, 255, 256, 2048, 4000, 4094, 4095};
  write_raw_tiff(dir / "u12.tif", 5, 2, 12, twelve);
  EXPECT_EQ(heights("u12.tif").values, std::vector<float>(twelve.begin(), twelve.end()));
  EXPECT_TRUE(heights("u12.tif").integer);
  write_raw_png(dir / "g4.png", 16, 1, 4, 0, {{0x01, 0x23, 0x45, 0x67, 0x89, 0xab, 0xcd, 0xef}});
  std::vector<float> sixteen(16);
  for (int v = 0; v < 16; ++v) sixteen[std::size_t(v)] = float(v);
  EXPECT_EQ(heights("g4.png").values, sixteen);
  write_raw_png(dir / "g2.png", 4, 1, 2, 0, {{0b00011011}});
  EXPECT_EQ(heights("g2.png").values, (std::vector<float>{0, 1, 2, 3}));
  write_raw_png(dir / "g1.png", 8, 1, 1, 0, {{0b10110010}});
  EXPECT_EQ(heights("g1.png").values, (std::vector<float>{1, 0, 1, 1, 0, 0, 1, 0}));
  std::ofstream(dir / "m1023.pgm", std::ios::binary)
      << std::string("P5\n# a comment\n4 1\n1023\n") << std::string("\x00\x00\x00\x01\x02\x00\x03\xff", 8);
  EXPECT_EQ(heights("m1023.pgm").values, (std::vector<float>{0, 1, 512, 1023}));
  std::ofstream(dir / "m100.pgm", std::ios::binary)
      << std::string("P5 4 1 100\n") << std::string("\x00\x01\x32\x64", 4);
  EXPECT_EQ(heights("m100.pgm").values, (std::vector<float>{0, 1, 50, 100}));
  std::ofstream(dir / "a7.pgm") << "P2\n4 1\n7\n0 3 6 7\n";
  EXPECT_EQ(heights("a7.pgm").values, (std::vector<float>{0, 3, 6, 7}));
}

// What of a file is not read is named: the parts after an EXR's first, a data window that is not the
// display window (the pixels are the data window's).
TEST(ImageInput, PartsAndWindowsNotReadAreNamed) {
  TempFolder dir;
  const std::vector<float> px(16 * 8, 1.0f);
  {
    OIIO::ImageSpec a(16, 8, 1, OIIO::TypeDesc::FLOAT), b(4, 4, 1, OIIO::TypeDesc::FLOAT);
    a.channelnames = {"Z"}, b.channelnames = {"R"};
    a.attribute("oiio:subimagename", "heights"), b.attribute("oiio:subimagename", "other");
    b.full_width = 16, b.full_height = 8;  // the parts of one file share a display window
    const OIIO::ImageSpec specs[] = {a, b};
    auto out = OIIO::ImageOutput::create((dir / "two.exr").string());
    ASSERT_TRUE(out && out->open((dir / "two.exr").string(), 2, specs));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()));
    ASSERT_TRUE(out->open((dir / "two.exr").string(), b, OIIO::ImageOutput::AppendSubimage));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()) && out->close());
  }
  const ImageInfo two = probe_image(dir / "two.exr", kSite);
  EXPECT_EQ(two.width, 16);
  EXPECT_EQ(two.unread, "it holds more than one part or page and only the first is read");
  {
    OIIO::ImageSpec w(16, 8, 1, OIIO::TypeDesc::FLOAT);
    w.x = 10, w.y = 5, w.full_x = 0, w.full_y = 0, w.full_width = 100, w.full_height = 50;
    auto out = OIIO::ImageOutput::create((dir / "window.exr").string());
    ASSERT_TRUE(out && out->open((dir / "window.exr").string(), w));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()) && out->close());
  }
  EXPECT_EQ(
      probe_image(dir / "window.exr", kSite).unread,
      "its data window (10, 5)-(25, 12) is not its display window (0, 0)-(99, 49): the field, and every "
      "output, is the data window's pixels from (0, 0)");
  write_test_image(dir / "plain.exr", 16, 8, 1, px, OIIO::TypeDesc::FLOAT);
  EXPECT_EQ(probe_image(dir / "plain.exr", kSite).unread, "");
  // A TIFF whose Orientation tag turns it (4: mirrored top to bottom): read as stored, and said so.
  {
    OIIO::ImageSpec t(16, 8, 1, OIIO::TypeDesc::UINT16);
    t.attribute("Orientation", 4);
    auto out = OIIO::ImageOutput::create((dir / "turned.tif").string());
    ASSERT_TRUE(out && out->open((dir / "turned.tif").string(), t));
    const std::vector<std::uint16_t> v(16 * 8, 7);
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT16, v.data()) && out->close());
  }
  EXPECT_EQ(probe_image(dir / "turned.tif", kSite).unread.rfind("its Orientation tag (4) is not applied", 0),
            0u)
      << probe_image(dir / "turned.tif", kSite).unread;
  write_test_image(dir / "plain.tif", 16, 8, 1, px, OIIO::TypeDesc::FLOAT);
  EXPECT_EQ(probe_image(dir / "plain.tif", kSite).unread, "");
}

TEST(ImageInput, MissingFile) {
  TempFolder dir;
  const fs::path f = dir / "nope.exr";
  EXPECT_EQ(error_line([&] { read_image(f, kSite); }),
            "jobs/x.json: /height/image: " + f.string() + ": no such file");
  EXPECT_EQ(error_line([&] { probe_image(f, kSite); }),
            "jobs/x.json: /height/image: " + f.string() + ": no such file");
  EXPECT_EQ(error_line([&] { read_image(dir.path(), kSite); }),
            "jobs/x.json: /height/image: " + dir.path().string() + ": is a folder, not an image");
}

TEST(ImageInput, CorruptFile) {
  TempFolder dir;
  for (const char* name : {"bad.exr", "bad.png", "bad.tif"}) {
    {
      std::ofstream out(dir / name, std::ios::binary);
      for (int i = 0; i < 1000; ++i) out.put(char((i * 7919) % 251));
    }
    const std::string line = error_line([&] { read_image(dir / name, kSite); });
    const std::string prefix =
        "jobs/x.json: /height/image: " + (dir / name).string() + ": cannot read the image: ";
    EXPECT_EQ(line.substr(0, prefix.size()), prefix) << line;
    EXPECT_EQ(line.find('\n'), std::string::npos) << line;
  }
}

// Each listed format is read by the reader its first bytes name, whatever the file is called (Targa, which
// has no signature, by its extension or the version-2 footer).
TEST(ImageInput, ReadsEveryListedFormatByItsSignature) {
  TempFolder dir;
  std::vector<float> px(8 * 4 * 3);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = float(i % 5) / 4;
  for (const char* name :
       {"a.exr", "a.tif", "a.png", "a.jpg", "a.hdr", "a.ppm", "a.bmp", "a.tga", "a.gif", "a.webp"}) {
    write_test_image(dir / name, 8, 4, 3, px,
                     std::string(name) == "a.exr" || std::string(name) == "a.hdr" ? OIIO::TypeDesc::FLOAT
                                                                                  : OIIO::TypeDesc::UINT8);
    const ImageInfo info = probe_image(dir / name, kSite);
    EXPECT_EQ(info.width, 8) << name;
    EXPECT_EQ(info.height, 4) << name;
    EXPECT_EQ(read_image(dir / name, kSite).pixels.size(), std::size_t(8 * 4 * info.channels)) << name;
    if (std::string(name) == "a.tga") continue;
    const fs::path renamed = dir / (std::string(name) + ".height");
    fs::copy_file(dir / name, renamed);
    EXPECT_EQ(probe_image(renamed, kSite).width, 8) << renamed;
  }
}

// Formats OpenImageIO has readers for but hfbake does not list are refused before any reader sees them,
// under their own extension or a listed one (a damaged RLA file named .exr aborted the process inside
// OpenImageIO 2.4's RLA reader: tests/fuzz/regressions/height_image).
TEST(ImageInput, RefusesFormatsItDoesNotList) {
  TempFolder dir;
  const std::vector<float> px(4 * 4, 0.5f);
  for (const char* name : {"a.rla", "a.sgi", "a.dpx"}) {
    write_test_image(dir / name, 4, 4, 1, px, OIIO::TypeDesc::UINT8);
    const fs::path disguised = dir / (std::string(name) + ".exr");
    fs::copy_file(dir / name, disguised);
    for (const fs::path& f : {dir / name, disguised})
      EXPECT_EQ(
          error_line([&] { probe_image(f, kSite); }),
          "jobs/x.json: /height/image: " + f.string() +
              ": cannot read the image: not in a format hfbake reads (EXR, TIFF, PNG, JPEG, HDR, PNM/PFM, "
              "BMP, TGA, GIF, WebP); convert it, e.g. oiiotool FILE -o FILE.exr");
  }
}

// A JPEG whose Photoshop block (APP13) claims more bytes than its segment holds is refused before
// OpenImageIO decodes it (OpenImageIO 2.4 reads past the segment), also when stray bytes stand before the
// segment's marker: libjpeg skips them and still hands the segment over.
TEST(ImageInput, RefusesJpegPhotoshopBlocksLongerThanTheirSegment) {
  TempFolder dir;
  write_test_image(dir / "plain.jpg", 8, 8, 1, std::vector<float>(64, 0.5f), OIIO::TypeDesc::UINT8);
  std::string jpeg;
  {
    std::ifstream in(dir / "plain.jpg", std::ios::binary);
    jpeg.assign(std::istreambuf_iterator<char>(in), {});
  }
  ASSERT_GT(jpeg.size(), 4u);
  // "Photoshop 3.0\0", then resource 0x0404 (IPTC) with an empty name claiming 100 bytes, in 44 bytes.
  std::string app13 = std::string("Photoshop 3.0", 14) + "8BIM" + std::string("\x04\x04\0\0", 4) +
                      std::string("\0\0\0\x64", 4) + std::string(16, '\x1c');
  const std::size_t len = app13.size() + 2;
  app13 = std::string("\xff\xed") + char(len >> 8) + char(len & 0xff) + app13;
  for (const std::string& stray : {std::string(), std::string("\x13\x92\x02")}) {
    const fs::path f = dir / (stray.empty() ? "app13.jpg" : "app13_stray.jpg");
    {
      std::ofstream out(f, std::ios::binary);
      out << jpeg.substr(0, 2) << stray << app13 << jpeg.substr(2);
    }
    const std::string line = error_line([&] { probe_image(f, kSite); });
    EXPECT_EQ(line, "jobs/x.json: /height/image: " + f.string() +
                        ": cannot read the image: its Photoshop metadata (JPEG APP13 segment) is damaged: a "
                        "resource block claims 100 bytes, its segment holds 16");
  }
}

TEST(ImageInput, TruncatedFile) {
  TempFolder dir;
  std::vector<float> px(64 * 64 * 3);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = float((i * 37) % 101) / 100;
  for (const char* name : {"t.exr", "t.png", "t.tif"}) {
    write_test_image(dir / name, 64, 64, 3, px,
                     std::string(name) == "t.png" ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::FLOAT);
    fs::resize_file(dir / name, fs::file_size(dir / name) / 2);
    const std::string line = error_line([&] { read_image(dir / name, kSite); });
    const std::string prefix = "jobs/x.json: /height/image: " + (dir / name).string() + ": cannot ";
    EXPECT_EQ(line.substr(0, prefix.size()), prefix) << name << ": " << line;
    EXPECT_EQ(line.find('\n'), std::string::npos) << line;
  }
}

TEST(ImageInput, WrongChannel) {
  TempFolder dir;
  write_test_image(dir / "rgb.exr", 2, 2, 3, ramp(2, 2, 3));
  const fs::path f = dir / "rgb.exr";
  EXPECT_EQ(error_line([&] { read_image_channel(f, 3, kSite, kChannelSite); }),
            "jobs/x.json: /height/channel: " + f.string() + ": has no channel 3 (it has 3: R, G, B)");
  EXPECT_EQ(error_line([&] { read_image_channel(f, std::string("Z"), kSite, kChannelSite); }),
            "jobs/x.json: /height/channel: " + f.string() + ": has no channel \"Z\" (it has: R, G, B)");
  EXPECT_EQ(read_image_channel(f, std::string("G"), kSite, kChannelSite).values[0], 0.25f);
  // From the job's JSON value.
  EXPECT_EQ(read_image_channel(f, channel_selector(nlohmann::json("B")), kSite, kChannelSite).values[0],
            0.5f);
  EXPECT_EQ(read_image_channel(f, channel_selector(nlohmann::json(1)), kSite, kChannelSite).values[0], 0.25f);
  EXPECT_EQ(read_image_channel(f, channel_selector(nlohmann::json()), kSite, kChannelSite).values[0], 0.0f);
}

// No channel named: the first that is not alpha. An EXR stores its channels sorted by name (A before Z);
// the truth is the value each channel was written with.
TEST(ImageInput, WithoutAChannelTheFirstThatIsNotAlphaIsRead) {
  TempFolder dir;
  struct Case {
    std::vector<std::string> names;
    float expect;  // channel c is written as 10 c + 1 everywhere
  };
  const Case cases[] = {{{"A", "Z"}, 11},
                        {{"Z", "A"}, 1},
                        {{"alpha", "depth"}, 11},
                        {{"height.A", "height.Z"}, 11},
                        {{"Y", "A"}, 1},
                        {{"R", "G", "B", "A"}, 1},
                        {{"A"}, 1},
                        {{"a", "Alpha"}, 1}};  // all alpha: channel 0 as the reader lists them
  for (const Case& c : cases) {
    const int nc = int(c.names.size());
    std::vector<float> px(std::size_t(4 * 3 * nc));
    for (std::size_t i = 0; i < px.size(); ++i) px[i] = float(10 * (i % std::size_t(nc)) + 1);
    write_test_image(dir / "d.exr", 4, 3, nc, px, OIIO::TypeDesc::FLOAT, c.names);
    // Which channel holds which value as stored: the reader lists them in the file's order.
    const ImageInfo info = probe_image(dir / "d.exr", kSite);
    const int c0 = find_channel(info, channel_selector(nlohmann::json()), dir / "d.exr", kChannelSite);
    const Plane p =
        read_image_channel(dir / "d.exr", channel_selector(nlohmann::json()), kSite, kChannelSite);
    const std::string& read = info.channel_names[std::size_t(c0)];
    EXPECT_TRUE(!is_alpha_channel_name(read) ||
                std::all_of(c.names.begin(), c.names.end(),
                            [](const std::string& n) { return is_alpha_channel_name(n); }))
        << read;
    const auto written = std::find(c.names.begin(), c.names.end(), read) - c.names.begin();
    EXPECT_EQ(p.values[5], float(10 * written + 1)) << read;
    EXPECT_EQ(p.values[5], c.expect) << read;
    // Named or by index, alpha is still read.
    EXPECT_EQ(read_image_channel(dir / "d.exr", 0, kSite, kChannelSite).values.size(), 12u);
  }
  EXPECT_FALSE(is_alpha_channel_name("Z"));
  EXPECT_FALSE(is_alpha_channel_name("height.AZ"));
  EXPECT_TRUE(is_alpha_channel_name("rgba.A"));
}

TEST(ImageInput, RgbImagesConvertFromTheirDefaultColourSpace) {
  TempFolder dir;
  // 8-bit defaults to sRGB: 128/255 -> ((128/255 + 0.055) / 1.055)^2.4.
  write_test_image(dir / "a.png", 1, 1, 3, {128 / 255.f, 1.0f, 0.0f}, OIIO::TypeDesc::UINT8);
  const RgbImage a = read_rgb_image(dir / "a.png", "", kSite, {"jobs/x.json", "/surface/albedo/colorspace"});
  EXPECT_NEAR(a.pixels[0].r, std::pow((128 / 255.0 + 0.055) / 1.055, 2.4), 1e-5);
  EXPECT_NEAR(a.pixels[0].g, 1.0, 1e-5);
  EXPECT_NEAR(a.pixels[0].b, 0.0, 1e-6);
  // Float defaults to linear; a grey image is replicated.
  write_test_image(dir / "b.exr", 1, 1, 1, {0.5f});
  const RgbImage b = read_rgb_image(dir / "b.exr", "", kSite, {});
  EXPECT_FLOAT_EQ(b.pixels[0].r, 0.5f);
  EXPECT_FLOAT_EQ(b.pixels[0].b, 0.5f);
  // RGBA: alpha is ignored; 4 channels in, 3 out.
  write_test_image(dir / "c.exr", 1, 1, 4, {0.1f, 0.2f, 0.3f, 0.0f});
  const RgbImage c = read_rgb_image(dir / "c.exr", "linear", kSite, {});
  EXPECT_FLOAT_EQ(c.pixels[0].r, 0.1f);
  EXPECT_FLOAT_EQ(c.pixels[0].b, 0.3f);
  // Unknown colour space: an error at the colour space's pointer.
  const std::string line = error_line([&] {
    read_rgb_image(dir / "b.exr", "srgbb", kSite, {"j.json", "/x/colorspace"});
  });
  EXPECT_EQ(line.rfind("j.json: /x/colorspace: unknown OpenColorIO colour space \"srgbb\"", 0), 0u) << line;
}

}  // namespace
}  // namespace hfbake

namespace hfbake {
namespace {

// Pseudo-random values in [0, 1) that do not depend on the platform.
std::vector<float> noise(std::size_t n, std::uint32_t seed) {
  std::vector<float> v(n);
  for (std::size_t i = 0; i < n; ++i) {
    seed = seed * 1664525u + 1013904223u;
    v[i] = float(seed >> 8) / float(1u << 24);
  }
  return v;
}

// OpenImageIO's own whole-image read of channel c, as floats: the truth for the banded reader.
std::vector<float> oiio_whole_channel(const fs::path& file, int c) {
  auto in = OIIO::ImageInput::open(file.string());
  EXPECT_TRUE(in);
  const OIIO::ImageSpec& spec = in->spec();
  std::vector<float> all(std::size_t(spec.width) * spec.height * spec.nchannels);
  EXPECT_TRUE(in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, all.data()));
  std::vector<float> out(std::size_t(spec.width) * spec.height);
  for (std::size_t t = 0; t < out.size(); ++t) out[t] = all[t * spec.nchannels + c];
  return out;
}

TEST(ImageInput, BandedChannelReadEqualsTheWholeImageRead) {
  TempFolder dir;
  const int w = 517, h = 301;  // not multiples of the bands or tiles
  const auto px = noise(std::size_t(w) * h * 3, 7);
  write_test_image(dir / "h16.png", w, h, 3, px, OIIO::TypeDesc::UINT16);  // the engine heightmap format
  {
    // A tiled 16-bit TIFF: read by rows of tiles.
    auto out = OIIO::ImageOutput::create("tif");
    OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::UINT16);
    spec.tile_width = spec.tile_height = 64;
    ASSERT_TRUE(out->open((dir / "tiled.tif").string(), spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()));
    ASSERT_TRUE(out->close());
  }
  for (const char* name : {"h16.png", "tiled.tif"}) {
    std::vector<double> fractions;
    const Plane p =
        read_image_channel(dir / name, 1, kSite, kChannelSite, [&](double f) { fractions.push_back(f); });
    ASSERT_EQ(p.width, w);
    ASSERT_EQ(p.height, h);
    const std::vector<float> truth = oiio_whole_channel(dir / name, 1);
    ASSERT_EQ(p.values.size(), truth.size());
    std::size_t differ = 0;
    // OpenImageIO's [0, 1] reading times 65535: the stored integers.
    for (std::size_t t = 0; t < truth.size(); ++t) differ += p.values[t] != std::round(truth[t] * 65535.f);
    EXPECT_EQ(differ, 0u) << name;
    // Spot check against the written 16-bit value (an independent quantization of the input).
    EXPECT_FLOAT_EQ(p.values[1000], std::round(px[1000 * 3 + 1] * 65535.f)) << name;
    ASSERT_FALSE(fractions.empty()) << name;
    EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end())) << name;
    EXPECT_EQ(fractions.back(), 1.0) << name;
  }
}

// Sets a little-endian TIFF's RowsPerStrip (tag 278) to rows, stored as a LONG.
void set_rows_per_strip(const fs::path& file, std::uint32_t rows) {
  std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
  auto get = [&](std::streamoff at, int bytes) {
    unsigned char b[4] = {};
    f.seekg(at);
    f.read(reinterpret_cast<char*>(b), bytes);
    return std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 | std::uint32_t(b[2]) << 16 |
           std::uint32_t(b[3]) << 24;
  };
  auto put = [&](std::streamoff at, std::uint32_t v, int bytes) {
    const char b[4] = {char(v), char(v >> 8), char(v >> 16), char(v >> 24)};
    f.seekp(at);
    f.write(b, bytes);
  };
  ASSERT_EQ(get(0, 2), 0x4949u) << "a little-endian TIFF";
  const std::streamoff ifd = get(4, 4);
  const std::uint32_t entries = get(ifd, 2);
  for (std::uint32_t i = 0; i < entries; ++i) {
    const std::streamoff e = ifd + 2 + 12 * std::streamoff(i);
    if (get(e, 2) != 278) continue;
    put(e + 2, 4, 2);  // LONG
    put(e + 8, rows, 4);
    return;
  }
  FAIL() << "no RowsPerStrip in " << file;
}

// A strip may be taller than the image (the TIFF default is 2^32 - 1 rows: one strip): such a file reads in
// the image's memory. One that declares strips far taller (2^30 rows: OpenImageIO's TIFF reader would size a
// strip's buffer by them, terabytes) is one line naming the file, before anything is allocated for it. The
// truth: the integers written.
TEST(ImageInput, AStripTallerThanTheImageIsReadInTheImagesMemory) {
  TempFolder dir;
  const int w = 4096, h = 8;
  const auto px = noise(std::size_t(w) * h * 3, 11);
  write_test_image(dir / "tall.tif", w, h, 3, px, OIIO::TypeDesc::UINT16);
  set_rows_per_strip(dir / "tall.tif", 64);
  const Image img = read_image(dir / "tall.tif", kSite);
  ASSERT_EQ(img.pixels.size(), px.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < px.size(); ++i)
    differ += std::round(img.pixels[i] * 65535.f) != std::round(px[i] * 65535.f);
  EXPECT_EQ(differ, 0u);
  const Plane p = read_image_channel(dir / "tall.tif", 2, kSite, kChannelSite);
  EXPECT_EQ(p.values[5], std::round(px[5 * 3 + 2] * 65535.f));
  set_rows_per_strip(dir / "tall.tif", std::uint32_t(1) << 30);
  const std::string line = error_line([&] { read_image(dir / "tall.tif", kSite); });
  EXPECT_EQ(line.rfind("jobs/x.json: /height/image: " + (dir / "tall.tif").string() + ": cannot decode", 0),
            0u)
      << line;
  EXPECT_NE(line.find("its strips declare 1073741824 rows"), std::string::npos) << line;
}

TEST(ImageInput, TruncatedBigPngIsAOneLineErrorNamingTheFile) {
  TempFolder dir;
  const int w = 1024, h = 1024;
  write_test_image(dir / "big.png", w, h, 1, noise(std::size_t(w) * h, 3), OIIO::TypeDesc::UINT16);
  const auto size = fs::file_size(dir / "big.png");
  fs::resize_file(dir / "big.png", size / 2);
  const std::string line = error_line([&] { read_image_channel(dir / "big.png", 0, kSite, kChannelSite); });
  EXPECT_EQ(line.rfind("jobs/x.json: /height/image: " + (dir / "big.png").string() +
                           ": cannot decode the image (corrupt or truncated?) in rows ",
                       0),
            0u)
      << line;
  EXPECT_EQ(line.find('\n'), std::string::npos) << line;
}

}  // namespace
}  // namespace hfbake
