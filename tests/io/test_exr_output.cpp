// The layered EXR writer and PNG previews: names, pixel types, compression, metadata, atomic writes,
// unwritable folders. Files are read back with OpenEXR's / OpenImageIO's readers.
#include <gtest/gtest.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfStringAttribute.h>
#include <OpenImageIO/imageio.h>

#include <cmath>
#include <fstream>
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
  EXPECT_THROW(write_exr(dir / "c.exr", sample_layers(2, 2), ExrOptions{false, "lzma", {}}), InputError);
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

TEST(Preview, UnwritableFolderIsAnInputError) {
  TempFolder dir;
  LayerSet set;
  set.width = set.height = 2;
  set.add("ao", mono_channels());
  EXPECT_THROW(write_preview(dir / "missing" / "ao.png", set, set.layers[0]), InputError);
}

}  // namespace
}  // namespace hfbake
