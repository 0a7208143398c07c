// The layered EXR writer and PNG previews: names, pixel types, compression, metadata, atomic writes,
// unwritable folders. Files are read back with OpenEXR's / OpenImageIO's readers.
#include <gtest/gtest.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfStringAttribute.h>
#include <ImfThreading.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <set>

#include "core/error.hpp"
#include "io/exr_output.hpp"
#include "io/preview.hpp"
#include "temp_folder.hpp"

namespace hfbake {
namespace {
namespace fs = std::filesystem;
using test::TempFolder;

LayerSet sample_layers(int w, int h) {
  LayerSet set;
  set.width = w;
  set.height = h;
  Layer& ao = set.add("ao", mono_channels());
  for (std::size_t i = 0; i < ao.data.size(); ++i) ao.data[i] = float(i) / float(ao.data.size());
  Layer& direct = set.add("direct", rgb_channels());
  for (std::size_t i = 0; i < direct.data.size(); ++i)
    direct.data[i] = 0.1f + 1e-4f * float(i) + 0.123456789f;
  Layer& horizon = set.add("horizon", indexed_channels(3));
  for (std::size_t i = 0; i < horizon.data.size(); ++i) horizon.data[i] = -0.5f + float(i % 7) * 0.1f;
  set.attributes = {{"hfbake/method", "p1"}, {"hfbake/directions", "64"}};
  return set;
}

std::set<std::string> files_in(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

// Reads channel `name` of an EXR as floats.
std::vector<float> read_channel(const fs::path& file, const std::string& name, int w, int h) {
  Imf::InputFile in(file.c_str());
  std::vector<float> v(std::size_t(w) * h);
  Imf::FrameBuffer fb;
  fb.insert(name, Imf::Slice(Imf::FLOAT, (char*)v.data(), sizeof(float), sizeof(float) * std::size_t(w)));
  in.setFrameBuffer(fb);
  in.readPixels(0, h - 1);
  return v;
}

TEST(ExrOutput, RoundTripHalfZip) {
  TempFolder dir;
  const LayerSet set = sample_layers(7, 5);
  const fs::path file = dir / "job.p1.exr";
  ExrOptions options;
  options.attributes = {{"hfbake/job", "cliff_01"}, {"hfbake/method", "p1 (override)"}};
  write_exr(file, set, options);
  EXPECT_EQ(files_in(dir.path()), std::set<std::string>{"job.p1.exr"});  // no temporary left behind

  Imf::InputFile in(file.c_str());
  const Imf::Header& header = in.header();
  EXPECT_EQ(header.compression(), Imf::ZIP_COMPRESSION);
  std::set<std::string> names;
  for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
    names.insert(it.name());
    EXPECT_EQ(it.channel().type, Imf::HALF) << it.name();
  }
  EXPECT_EQ(names, (std::set<std::string>{"ao.Y", "direct.R", "direct.G", "direct.B", "horizon.000",
                                          "horizon.001", "horizon.002"}));
  const auto* method = header.findTypedAttribute<Imf::StringAttribute>("hfbake/method");
  ASSERT_TRUE(method);
  EXPECT_EQ(method->value(), "p1 (override)");  // the caller's attribute wins
  ASSERT_TRUE(header.findTypedAttribute<Imf::StringAttribute>("hfbake/directions"));
  EXPECT_EQ(header.findTypedAttribute<Imf::StringAttribute>("hfbake/job")->value(), "cliff_01");

  // Half pixels: the value is the float rounded to the nearest half (Imath's conversion is the truth).
  const std::vector<float> g = read_channel(file, "direct.G", 7, 5);
  const Layer* direct = set.find("direct");
  for (int i = 0; i < 35; ++i) EXPECT_EQ(g[i], float(half(direct->data[std::size_t(i) * 3 + 1]))) << i;
  const std::vector<float> h1 = read_channel(file, "horizon.001", 7, 5);
  EXPECT_EQ(h1[34], float(half(set.find("horizon")->data[34 * 3 + 1])));
}

TEST(ExrOutput, RoundTripFloatPizIsExact) {
  TempFolder dir;
  const LayerSet set = sample_layers(16, 9);
  const fs::path file = dir / "f.exr";
  ExrOptions options;
  options.float_pixels = true;
  options.compression = "piz";
  write_exr(file, set, options);
  Imf::InputFile in(file.c_str());
  EXPECT_EQ(in.header().compression(), Imf::PIZ_COMPRESSION);
  EXPECT_EQ(in.header().channels().findChannel("ao.Y")->type, Imf::FLOAT);
  const std::vector<float> b = read_channel(file, "direct.B", 16, 9);
  for (int i = 0; i < 16 * 9; ++i) EXPECT_EQ(b[i], set.find("direct")->data[std::size_t(i) * 3 + 2]);
  const std::vector<float> ao = read_channel(file, "ao.Y", 16, 9);
  EXPECT_EQ(ao, set.find("ao")->data);
}

TEST(ExrOutput, HalfFilesSpanningSeveralBandsOfRows) {
  // The half writer converts 64 rows at a time: 150 rows cross two band boundaries.
  TempFolder dir;
  const LayerSet set = sample_layers(5, 150);
  write_exr(dir / "tall.exr", set);
  const std::vector<float> r = read_channel(dir / "tall.exr", "direct.R", 5, 150);
  const std::vector<float> ao = read_channel(dir / "tall.exr", "ao.Y", 5, 150);
  for (int i = 0; i < 5 * 150; ++i) {
    ASSERT_EQ(r[i], float(half(set.find("direct")->data[std::size_t(i) * 3]))) << i;
    ASSERT_EQ(ao[i], float(half(set.find("ao")->data[std::size_t(i)]))) << i;
  }
}

TEST(ExrOutput, ChannelsBeyondHalfRangeAreStoredAsFloat) {
  TempFolder dir;
  LayerSet set = sample_layers(4, 70);
  Layer& dist = set.add("horizon_distance", indexed_channels(2));
  for (std::size_t i = 0; i < dist.data.size(); ++i) dist.data[i] = i % 2 ? 1.5f : 1.0e6f + float(i);
  write_exr(dir / "d.exr", set);
  Imf::InputFile in((dir / "d.exr").c_str());
  EXPECT_EQ(in.header().channels().findChannel("horizon_distance.000")->type, Imf::FLOAT);
  EXPECT_EQ(in.header().channels().findChannel("horizon_distance.001")->type, Imf::HALF);
  EXPECT_EQ(in.header().channels().findChannel("ao.Y")->type, Imf::HALF);
  const std::vector<float> d0 = read_channel(dir / "d.exr", "horizon_distance.000", 4, 70);
  for (int i = 0; i < 4 * 70; ++i) ASSERT_EQ(d0[i], 1.0e6f + float(2 * i)) << i;
  const std::vector<float> d1 = read_channel(dir / "d.exr", "horizon_distance.001", 4, 70);
  EXPECT_EQ(d1[279], 1.5f);
  const std::vector<float> ao = read_channel(dir / "d.exr", "ao.Y", 4, 70);
  EXPECT_EQ(ao[279], float(half(set.find("ao")->data[279])));
}

// Relief's angles in degrees are stored as float in a half file: 87.4321° read back exactly as the float.
TEST(ExrOutput, DegreeLayersAreStoredAsFloatInAHalfFile) {
  TempFolder dir;
  LayerSet set = sample_layers(4, 7);
  set.add("openness_positive", mono_channels()).data.assign(28, 87.4321f);
  set.add("horizon_deg", indexed_channels(2)).data.assign(56, -33.3333f);
  write_exr(dir / "g.exr", set);
  Imf::InputFile in((dir / "g.exr").c_str());
  EXPECT_EQ(in.header().channels().findChannel("openness_positive.Y")->type, Imf::FLOAT);
  EXPECT_EQ(in.header().channels().findChannel("horizon_deg.001")->type, Imf::FLOAT);
  EXPECT_EQ(in.header().channels().findChannel("ao.Y")->type, Imf::HALF);
  EXPECT_EQ(read_channel(dir / "g.exr", "openness_positive.Y", 4, 7)[27], 87.4321f);
  EXPECT_EQ(read_channel(dir / "g.exr", "horizon_deg.001", 4, 7)[27], -33.3333f);
}

TEST(ExrOutput, NoCompressionAndReservedAttributeNames) {
  TempFolder dir;
  LayerSet set = sample_layers(3, 2);
  set.attributes.push_back({"compression", "this is metadata, not the EXR compression"});
  ExrOptions options;
  options.compression = "none";
  write_exr(dir / "n.exr", set, options);
  Imf::InputFile in((dir / "n.exr").c_str());
  EXPECT_EQ(in.header().compression(), Imf::NO_COMPRESSION);
  const auto* moved = in.header().findTypedAttribute<Imf::StringAttribute>("hfbake.compression");
  ASSERT_TRUE(moved);
  EXPECT_EQ(moved->value(), "this is metadata, not the EXR compression");
}

TEST(ExrOutput, ReplacesAnExistingFileAtomically) {
  TempFolder dir;
  const fs::path file = dir / "x.exr";
  std::ofstream(file) << "old";
  write_exr(file, sample_layers(4, 4));
  EXPECT_GT(fs::file_size(file), 3u);
  EXPECT_EQ(files_in(dir.path()).size(), 1u);
}

TEST(ExrOutput, UnwritableFolderIsAnInputError) {
  TempFolder dir;
  const fs::path missing = dir / "no" / "such" / "folder" / "x.exr";
  try {
    write_exr(missing, sample_layers(2, 2));
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), missing.string() + ": cannot write: the folder does not exist");
  }
  // A "folder" that is a file.
  std::ofstream(dir / "plain") << "x";
  EXPECT_THROW(write_exr(dir / "plain" / "x.exr", sample_layers(2, 2)), InputError);
  // A read-only folder (only meaningful when not running as root).
  if (geteuid() != 0) {
    fs::create_directory(dir / "ro");
    fs::permissions(dir / "ro", fs::perms::owner_read | fs::perms::owner_exec);
    try {
      write_exr(dir / "ro" / "x.exr", sample_layers(2, 2));
      ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
      EXPECT_EQ(e.line().rfind((dir / "ro" / "x.exr").string() + ": cannot write the EXR: ", 0), 0u)
          << e.line();
    }
    fs::permissions(dir / "ro", fs::perms::owner_all);
    EXPECT_TRUE(fs::is_empty(dir / "ro"));
  }
  EXPECT_THROW(write_exr(dir / "c.exr", sample_layers(2, 2), ExrOptions{false, "lzma", 0, 0, {}}),
               InputError);
}

TEST(ExrOutput, InconsistentLayersAreAProgrammingError) {
  TempFolder dir;
  LayerSet set = sample_layers(4, 4);
  set.layers[1].data.pop_back();
  EXPECT_THROW(write_exr(dir / "bad.exr", set), std::logic_error);
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

TEST(Preview, EncodesThroughTheSrgbDisplay) {
  TempFolder dir;
  LayerSet set;
  set.width = 3;
  set.height = 1;
  Layer& ao = set.add("ao", mono_channels());
  ao.data = {0.0f, 0.2140411f, 1.5f};  // linear 0.2140411 is sRGB 0.5 (IEC 61966-2-1); 1.5 clips
  Layer& bn = set.add("bent_normal", xyz_channels());
  bn.data = {0, 0, 1, 1, 0, 0, 0, -1, 0};
  write_preview(dir / "ao.png", set, *set.find("ao"));
  write_preview(dir / "bn.png", set, *set.find("bent_normal"));
  EXPECT_EQ(files_in(dir.path()), (std::set<std::string>{"ao.png", "bn.png"}));

  const auto read8 = [](const fs::path& f) {
    auto in = OIIO::ImageInput::open(f.string());
    EXPECT_TRUE(in);
    EXPECT_EQ(in->spec().format, OIIO::TypeDesc::UINT8);
    std::vector<unsigned char> px(std::size_t(in->spec().width) * in->spec().height * in->spec().nchannels);
    in->read_image(0, 0, 0, in->spec().nchannels, OIIO::TypeDesc::UINT8, px.data());
    return px;
  };
  const auto a = read8(dir / "ao.png");
  ASSERT_EQ(a.size(), 9u);
  EXPECT_EQ(a[0], 0);
  EXPECT_NEAR(a[3], 127.5, 0.51);  // 0.5 * 255
  EXPECT_EQ(a[3], a[5]);           // grey
  EXPECT_EQ(a[6], 255);
  const auto b = read8(dir / "bn.png");  // 0.5 + 0.5 xyz, no colour transform
  EXPECT_EQ(std::vector<unsigned char>(b.begin(), b.begin() + 3),
            (std::vector<unsigned char>{128, 128, 255}));
  EXPECT_EQ(std::vector<unsigned char>(b.begin() + 6, b.end()), (std::vector<unsigned char>{128, 0, 128}));
}

// A quantity in a unit of its own (PreviewOptions::stretch): grey from its least finite value (black) to its
// largest (white), no display transform, the two values in the PNG's ImageDescription; a constant layer is
// mid grey.
TEST(Preview, AQuantityIsShownOverItsRange) {
  TempFolder dir;
  LayerSet set;
  set.width = 4;
  set.height = 1;
  set.add("openness_positive", mono_channels()).data = {70.0f, 85.0f, 100.0f, 70.0f};
  set.add("sun_hours", mono_channels()).data = {12.0f, 12.0f, 12.0f, 12.0f};
  PreviewOptions o;
  o.stretch = true;
  write_preview(dir / "o.png", set, *set.find("openness_positive"), o);
  write_preview(dir / "h.png", set, *set.find("sun_hours"), o);
  const auto read8 = [](const fs::path& f, std::string* description) {
    auto in = OIIO::ImageInput::open(f.string());
    EXPECT_TRUE(in);
    if (description) *description = in->spec().get_string_attribute("ImageDescription");
    std::vector<unsigned char> px(std::size_t(in->spec().width) * in->spec().height * in->spec().nchannels);
    in->read_image(0, 0, 0, in->spec().nchannels, OIIO::TypeDesc::UINT8, px.data());
    return px;
  };
  std::string description;
  const auto a = read8(dir / "o.png", &description);
  ASSERT_EQ(a.size(), 12u);
  EXPECT_EQ(a[0], 0);
  EXPECT_EQ(a[3], 128);  // (85 - 70) / 30 * 255 = 127.5, rounded half away from zero
  EXPECT_EQ(a[6], 255);
  EXPECT_EQ(description, "openness_positive: black 70, white 100");
  const auto h = read8(dir / "h.png", nullptr);
  EXPECT_EQ(h[0], 128);
}

TEST(Preview, UnwritableFolderIsAnInputError) {
  TempFolder dir;
  LayerSet set;
  set.width = set.height = 2;
  set.add("ao", mono_channels());
  EXPECT_THROW(write_preview(dir / "missing" / "ao.png", set, set.layers[0]), InputError);
}

}  // namespace
}  // namespace hfbake

namespace hfbake {
namespace {

std::string file_bytes(const fs::path& f) {
  std::ifstream in(f, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Every channel of an EXR as OpenImageIO reads it (floats, interleaved), with the channel names.
std::pair<std::vector<std::string>, std::vector<float>> read_all(const fs::path& f) {
  auto in = OIIO::ImageInput::open(f.string());
  EXPECT_TRUE(in);
  const OIIO::ImageSpec& spec = in->spec();
  std::vector<float> px(std::size_t(spec.width) * spec.height * spec.nchannels);
  EXPECT_TRUE(in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, px.data()));
  return {spec.channelnames, px};
}

// Pseudo-random values in [lo, hi) into `values` (a fixed LCG: the same test data on every machine).
void fill_random(std::vector<float>& values, std::uint32_t seed, float lo, float hi) {
  for (float& v : values) {
    seed = seed * 1664525u + 1013904223u;
    v = lo + (hi - lo) * (float(seed >> 8) / float(1u << 24));
  }
}

// A 64-channel horizon layer and an ao layer of pseudo-random values, 157 x 83 (not a multiple of any
// chunk, band or tile).
LayerSet horizon_layers() {
  LayerSet set;
  set.width = 157;
  set.height = 83;
  fill_random(set.add("ao", mono_channels()).data, 5, 0, 1);
  fill_random(set.add("horizon", indexed_channels(64)).data, 6, -1, 1);
  return set;
}

TEST(ExrOutput, ThreadsDoNotChangeTheFileAndPixelsAreTheLayers) {
  TempFolder dir;
  const LayerSet set = horizon_layers();
  for (const char* compression : {"zip", "piz", "dwab", "none"})
    for (const bool as_float : {false, true})
      for (const int tile : {0, 64}) {
        const std::string what =
            std::string(compression) + (as_float ? " float" : " half") + (tile ? " tiled" : " scanline");
        ExrOptions o;
        o.compression = compression;
        o.float_pixels = as_float;
        o.tile_size = tile;
        Imf::setGlobalThreadCount(0);  // in the calling thread
        o.threads = 1;
        write_exr(dir / "one.exr", set, o);
        Imf::setGlobalThreadCount(4);  // four workers, eight chunks in flight
        o.threads = 8;
        write_exr(dir / "many.exr", set, o);
        Imf::setGlobalThreadCount(0);
        EXPECT_TRUE(file_bytes(dir / "one.exr") == file_bytes(dir / "many.exr")) << what;
        if (std::string(compression) == "dwab") continue;  // lossy: no exact pixels to compare
        const auto [names, px] = read_all(dir / "many.exr");
        ASSERT_EQ(names.size(), 65u) << what;
        const std::size_t texels = std::size_t(set.width) * set.height;
        std::size_t differ = 0;
        for (std::size_t c = 0; c < names.size(); ++c) {
          const std::string& n = names[c];
          const Layer* l = set.find(n.substr(0, n.rfind('.')));
          ASSERT_TRUE(l) << n;
          int k = 0;
          while (l->name + "." + l->channels[k] != n) ++k;
          for (std::size_t t = 0; t < texels; ++t) {
            const float v = l->data[t * l->channels.size() + k];
            differ += px[t * names.size() + c] != (as_float ? v : float(half(v)));
          }
        }
        EXPECT_EQ(differ, 0u) << what;
      }
}

TEST(ExrOutput, TiledFilesAreTiledAndDwaaIsAccepted) {
  TempFolder dir;
  ExrOptions o;
  o.tile_size = 64;
  write_exr(dir / "t.exr", horizon_layers(), o);
  auto in = OIIO::ImageInput::open((dir / "t.exr").string());
  ASSERT_TRUE(in);
  EXPECT_EQ(in->spec().tile_width, 64);
  EXPECT_EQ(in->spec().tile_height, 64);
  o = {};
  o.compression = "dwaa";
  write_exr(dir / "d.exr", horizon_layers(), o);
  EXPECT_EQ(Imf::InputFile((dir / "d.exr").c_str()).header().compression(), Imf::DWAA_COMPRESSION);
}

TEST(Preview, SizeIsTheSmallestIntegerReductionThatFits) {
  EXPECT_EQ(preview_size(2048, 1000, 2048).factor, 1);
  const PreviewSize p = preview_size(16384, 16384, 2048);
  EXPECT_EQ(p.factor, 8);
  EXPECT_EQ(p.width, 2048);
  const PreviewSize q = preview_size(10001, 3000, 2048);  // f = 5: 2001 x 600
  EXPECT_EQ(q.factor, 5);
  EXPECT_EQ(q.width, 2001);
  EXPECT_EQ(q.height, 600);
  EXPECT_EQ(preview_size(5000, 5000, 0).factor, 1);
}

// The sRGB encoding (IEC 61966-2-1), the truth for the built-in config's default display.
double srgb(double v) {
  v = std::clamp(v, 0.0, 1.0);
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
}

TEST(Preview, ReducedPreviewIsTheBoxFilterOfTheLayer) {
  TempFolder dir;
  LayerSet set;
  set.width = 50;
  set.height = 23;
  Layer& ao = set.add("ao", mono_channels());
  fill_random(ao.data, 9, 0, 1);
  ao.data[3] = std::numeric_limits<float>::quiet_NaN();  // left out of its block's mean
  Layer& bn = set.add("bent_normal", xyz_channels());
  fill_random(bn.data, 10, -1, 1);
  PreviewOptions o;
  o.max_size = 16;  // f = 4: 13 x 6, the last column of blocks 2 texels wide, the last row 3 texels high
  write_preview(dir / "ao.png", set, *set.find("ao"), o);
  write_preview(dir / "bn.png", set, *set.find("bent_normal"), o);
  const auto read = [](const fs::path& f, int& w, int& h) {
    auto in = OIIO::ImageInput::open(f.string());
    EXPECT_TRUE(in);
    w = in->spec().width;
    h = in->spec().height;
    std::vector<unsigned char> px(std::size_t(w) * h * 3);
    in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, px.data());
    return px;
  };
  // The box filter, computed here: the mean of the finite texels of each 4 x 4 block.
  const auto box = [&](const Layer& l, int px, int py, int c) {
    double sum = 0;
    int n = 0;
    for (int y = 4 * py; y < std::min(set.height, 4 * py + 4); ++y)
      for (int x = 4 * px; x < std::min(set.width, 4 * px + 4); ++x) {
        const float v = l.data[(std::size_t(y) * set.width + x) * l.channels.size() + c];
        if (std::isfinite(v)) sum += v, ++n;
      }
    return sum / n;
  };
  int w = 0, h = 0;
  const auto a = read(dir / "ao.png", w, h);
  ASSERT_EQ(w, 13);
  ASSERT_EQ(h, 6);
  const auto b = read(dir / "bn.png", w, h);
  for (int py = 0; py < h; ++py)
    for (int px = 0; px < w; ++px)
      for (int c = 0; c < 3; ++c) {
        const std::size_t k = (std::size_t(py) * w + px) * 3 + c;
        EXPECT_NEAR(a[k], 255 * srgb(box(ao, px, py, 0)), 0.51 + 1.0) << px << "," << py;
        EXPECT_NEAR(b[k], 255 * (0.5 + 0.5 * box(bn, px, py, c)), 0.51) << px << "," << py << "," << c;
      }
}

TEST(Preview, LayersThatFitAreNotReduced) {
  TempFolder dir;
  const LayerSet set = sample_layers(40, 30);
  PreviewOptions fits, unlimited;
  fits.max_size = 40;
  unlimited.max_size = 0;
  write_preview(dir / "a.png", set, *set.find("ao"), fits);
  write_preview(dir / "b.png", set, *set.find("ao"), unlimited);
  EXPECT_TRUE(file_bytes(dir / "a.png") == file_bytes(dir / "b.png"));
  auto in = OIIO::ImageInput::open((dir / "a.png").string());
  ASSERT_TRUE(in);
  EXPECT_EQ(in->spec().width, 40);
}

}  // namespace
}  // namespace hfbake
