// hfbake init: each preset's job validates and bakes, for an image and for a georeferenced raster; its
// texel size and heights come from the file; --help lists the methods, their layers and the presets.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "run_hfbake.hpp"

namespace {
namespace fs = std::filesystem;
using hfbake::cli_test::Result;

class CliInit : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("hfbake_test_cli_init_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  Result run(const std::string& args) { return hfbake::cli_test::run_hfbake(dir_, args); }
  nlohmann::json read_json(const fs::path& p) {
    std::ifstream in(p);
    return nlohmann::json::parse(in);
  }
  fs::path dir_;
};

// A 32^2 16-bit height map: a bump from 0 up to nearly 65535. Returns the largest stored value.
int write_png16(const fs::path& p) {
  const int n = 32;
  std::vector<std::uint16_t> v(std::size_t(n) * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double x = (i - 15.5) / 6, y = (j - 15.5) / 6;
      v[std::size_t(j) * n + i] = std::uint16_t(std::lround(65535 * std::exp(-(x * x + y * y))));
    }
  auto out = OIIO::ImageOutput::create(p.string());
  const bool ok = out && out->open(p.string(), OIIO::ImageSpec(n, n, 1, OIIO::TypeDesc::UINT16)) &&
                  out->write_image(OIIO::TypeDesc::UINT16, v.data()) && out->close();
  EXPECT_TRUE(ok) << p;
  EXPECT_EQ(*std::min_element(v.begin(), v.end()), 0);
  return *std::max_element(v.begin(), v.end());
}

TEST_F(CliInit, EveryPresetValidatesAndBakes) {
  const int top = write_png16(dir_ / "rock.png");
  // A georeferenced copy (2-unit pixels, from an .aux.xml): its texel size comes from the file.
  fs::copy_file(dir_ / "rock.png", dir_ / "dem.png");
  std::ofstream(dir_ / "dem.png.aux.xml")
      << "<PAMDataset>\n  <GeoTransform>1000, 2, 0, 5000, 0, -2</GeoTransform>\n</PAMDataset>\n";
  for (const char* preset : {"game-ao", "gis-relief", "reference-check"}) {
    for (const char* file : {"rock.png", "dem.png"}) {
      SCOPED_TRACE(std::string(preset) + " " + file);
      const std::string job = std::string(preset) + "_" + file + ".json";
      const Result init =
          run("init " + (dir_ / file).string() + " --preset " + preset + " --out " + (dir_ / job).string());
      ASSERT_EQ(init.exit_code, 0) << init.err;
      EXPECT_NE(init.err.find("hfbake: wrote "), std::string::npos) << init.err;
      const nlohmann::json j = read_json(dir_ / job);
      if (std::string(file) == "dem.png") {
        EXPECT_FALSE(j["height"].contains("texel_size")) << j.dump();    // the raster's own 2
        EXPECT_FALSE(j["height"].contains("height_scale")) << j.dump();  // a raster's heights are data
        EXPECT_NE(init.err.find("32x32 texels of 2 (64 x 64 world units)"), std::string::npos) << init.err;
      } else {
        // 0..top over a 32-unit field is implausible: the scale that makes the relief a tenth of the side
        // (to the four digits written).
        EXPECT_EQ(j["height"]["texel_size"], 1.0);
        ASSERT_TRUE(j["height"].contains("height_scale")) << j.dump();
        EXPECT_NEAR(j["height"]["height_scale"].get<double>() * top, 3.2, 3.2 * 5e-4);
        EXPECT_NE(init.err.find("stored 0 .. " + std::to_string(top) + " x height_scale"), std::string::npos)
            << init.err;
      }
      const Result v = run("validate --quiet " + (dir_ / job).string());
      EXPECT_EQ(v.exit_code, 0) << v.err;
      const Result b = run("bake --quiet --no-cache " + (dir_ / job).string());
      EXPECT_EQ(b.exit_code, 0) << b.err;
      // The outputs the preset promises, in out/<stem> beside the job (the job file's stem: one height file
      // with several presets bakes into folders of their own).
      const std::string stem = fs::path(job).stem().string();
      const fs::path out = dir_ / "out" / stem;
      const fs::path promised = std::string(preset) == "game-ao" ? out / "textures" / (stem + ".p1.ao.png")
                                : std::string(preset) == "gis-relief" ? out / (stem + ".relief.svf.tif")
                                                                      : out / "report.html";
      EXPECT_TRUE(fs::exists(promised)) << promised;
      fs::remove_all(dir_ / "out");
    }
  }
  // An 8-bit map (levels 0..255 over 64 texels): a scale, not cliffs four times the field's side.
  std::vector<float> px(64 * 64);
  for (int t = 0; t < 64 * 64; ++t) px[std::size_t(t)] = float(t % 64) / 63.0f;
  auto out = OIIO::ImageOutput::create((dir_ / "h8.png").string());
  ASSERT_TRUE(out &&
              out->open((dir_ / "h8.png").string(), OIIO::ImageSpec(64, 64, 1, OIIO::TypeDesc::UINT8)) &&
              out->write_image(OIIO::TypeDesc::FLOAT, px.data()) && out->close());
  const Result h8 = run("init " + (dir_ / "h8.png").string() + " --preset reference-check --out " +
                        (dir_ / "h8.json").string());
  ASSERT_EQ(h8.exit_code, 0) << h8.err;
  EXPECT_NEAR(read_json(dir_ / "h8.json")["height"]["height_scale"].get<double>() * 255, 6.4, 6.4 * 5e-4);
  EXPECT_EQ(run("bake --quiet --no-cache " + (dir_ / "h8.json").string()).exit_code, 0);
}

TEST_F(CliInit, BadInputIsOneLineAndWritesNothing) {
  Result r =
      run("init " + (dir_ / "nope.png").string() + " --preset game-ao --out " + (dir_ / "a.json").string());
  EXPECT_EQ(r.exit_code, 2);
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_EQ(r.error_lines()[0], "hfbake: error: " + (dir_ / "nope.png").string() + ": no such file");
  EXPECT_FALSE(fs::exists(dir_ / "a.json"));

  std::ofstream(dir_ / "junk.png") << "not an image";
  r = run("init " + (dir_ / "junk.png").string() + " --preset game-ao --out " + (dir_ / "a.json").string());
  EXPECT_EQ(r.exit_code, 2);
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.error_lines()[0].find("junk.png: cannot read the image"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "a.json"));

  // Heights the job would refuse: the line names the height file (the job file is not written yet).
  {
    std::vector<float> v(8 * 6, 0.0f);
    v[3 * 8 + 5] = 1e20f;
    auto out = OIIO::ImageOutput::create((dir_ / "huge.exr").string());
    ASSERT_TRUE(out &&
                out->open((dir_ / "huge.exr").string(), OIIO::ImageSpec(8, 6, 1, OIIO::TypeDesc::FLOAT)) &&
                out->write_image(OIIO::TypeDesc::FLOAT, v.data()) && out->close());
  }
  r = run("init " + (dir_ / "huge.exr").string() + " --preset game-ao --out " + (dir_ / "a.json").string());
  EXPECT_EQ(r.exit_code, 2);
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_EQ(r.error_lines()[0].rfind("hfbake: error: " + (dir_ / "huge.exr").string() + ": texel (5, 3)", 0),
            0u)
      << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "a.json"));

  write_png16(dir_ / "h.png");
  std::ofstream(dir_ / "kept.json") << "{}";
  r = run("init " + (dir_ / "h.png").string() + " --preset game-ao --out " + (dir_ / "kept.json").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("kept.json: exists (--force writes over it)"), std::string::npos) << r.err;
  // A folder is no job file, with or without --force: refused naming it a folder, the folder kept.
  fs::create_directory(dir_ / "jobs");
  for (const char* force : {"", " --force"}) {
    r = run("init " + (dir_ / "h.png").string() + " --preset game-ao" + force + " --out " +
            (dir_ / "jobs").string());
    EXPECT_EQ(r.exit_code, 2) << force;
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_EQ(r.error_lines()[0], "hfbake: error: " + (dir_ / "jobs").string() +
                                      ": is a folder: --out names the job file to write (e.g. " +
                                      (dir_ / "jobs" / "h.json").string() + ")");
    EXPECT_TRUE(fs::is_directory(dir_ / "jobs") && fs::is_empty(dir_ / "jobs"));
  }
  r = run("init " + (dir_ / "h.png").string() + " --preset unknown");
  EXPECT_EQ(r.exit_code, 2);
  // --force over the height file itself: refused, the image kept.
  const auto size = fs::file_size(dir_ / "h.png");
  r = run("init " + (dir_ / "h.png").string() + " --preset game-ao --force --out " +
          (dir_ / "h.png").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("h.png: is the height file itself"), std::string::npos) << r.err;
  EXPECT_EQ(fs::file_size(dir_ / "h.png"), size);
  // Nor over a file GDAL reads with it: its world file, or a VRT's source.
  const std::string world = "1\n0\n0\n-1\n0.5\n-0.5\n";
  std::ofstream(dir_ / "h.pgw") << world;
  std::ofstream(dir_ / "h.vrt")
      << "<VRTDataset rasterXSize=\"32\" rasterYSize=\"32\"><VRTRasterBand dataType=\"UInt16\" "
         "band=\"1\"><SimpleSource><SourceFilename relativeToVRT=\"1\">h.png"
         "</SourceFilename><SourceBand>1</SourceBand></SimpleSource></VRTRasterBand>"
         "</VRTDataset>";
  for (const auto& [height, out] :
       {std::pair<std::string, std::string>{"h.png", "h.pgw"}, {"h.vrt", "h.png"}}) {
    r = run("init " + (dir_ / height).string() + " --preset gis-relief --force --out " +
            (dir_ / out).string());
    EXPECT_EQ(r.exit_code, 2) << height << " " << out;
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_NE(r.err.find(", which GDAL reads for the height file"), std::string::npos) << r.err;
  }
  EXPECT_EQ(fs::file_size(dir_ / "h.png"), size);
  std::ifstream in(dir_ / "h.pgw");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), world);
}

// game-ao on a georeferenced raster (here geographic, placed by an .aux.xml): a piece of the Earth does not
// tile, so the job clamps (a geographic raster cannot repeat), and it validates.
TEST_F(CliInit, GameAoOnAGeoreferencedRasterClamps) {
  write_png16(dir_ / "geo.tif");
  std::ofstream(dir_ / "geo.tif.aux.xml")
      << "<PAMDataset>\n  <SRS>EPSG:4326</SRS>\n  <GeoTransform>15, 1e-5, 0, 46.5, 0, -1e-5</GeoTransform>\n"
         "</PAMDataset>\n";
  const Result r =
      run("init " + (dir_ / "geo.tif").string() + " --preset game-ao --out " + (dir_ / "geo.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json job = read_json(dir_ / "geo.json");
  EXPECT_EQ(job["height"].value("wrap", "clamp"), "clamp") << job.dump();
  const Result v = run("validate " + (dir_ / "geo.json").string());
  EXPECT_EQ(v.exit_code, 0) << v.err;
}

// A georeferenced raster that declares how its stored values become heights (GDAL's scale and offset, a unit
// of its heights other than its pixels'): the job init writes applies them with height_scale and
// height_offset, so it bakes the heights the file declares. The next step init prints is a line a shell runs
// as it stands, whatever the job file's name.
TEST_F(CliInit, AJobAppliesWhatTheRasterDeclaresAndItsNextStepRuns) {
  const int top = write_png16(dir_ / "dem.tif");
  const double us_foot = 1200.0 / 3937.0;  // metres
  struct Case {
    std::string srs, band;
    double scale, offset;  // what the job must carry
  };
  const Case cases[] = {{"EPSG:32633", "<Scale>0.01</Scale><Offset>200</Offset>", 0.01, 200},
                        {"EPSG:2229", "<UnitType>m</UnitType>", 1 / us_foot, 0},
                        {"EPSG:2229", "<Scale>0.01</Scale><Offset>200</Offset><UnitType>m</UnitType>",
                         0.01 / us_foot, 200 / us_foot}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.band);
    std::ofstream(dir_ / "dem.tif.aux.xml")
        << "<PAMDataset>\n  <SRS>" << c.srs
        << "</SRS>\n  <GeoTransform>500000, 2, 0, 5000000, 0, -2</GeoTransform>\n"
        << "  <PAMRasterBand band=\"1\">" << c.band << "</PAMRasterBand>\n</PAMDataset>\n";
    const fs::path job = dir_ / "my dem (v2).json";
    const Result r = run("init " + (dir_ / "dem.tif").string() + " --preset gis-relief --force --out '" +
                         job.string() + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json h = read_json(job)["height"];
    EXPECT_NEAR(h.value("height_scale", 1.0), c.scale, 1e-12 * c.scale) << h.dump();
    EXPECT_NEAR(h.value("height_offset", 0.0), c.offset, 1e-9 * std::max(1.0, c.offset)) << h.dump();
    // The heights line: the stored 0 .. top as the file declares them.
    char range[96];
    std::snprintf(range, sizeof range, "-> heights %.6g .. %.6g world units", c.offset,
                  top * c.scale + c.offset);
    EXPECT_NE(r.err.find(range), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("not applied"), std::string::npos) << r.err;
    // The printed next step, run by a shell (hfbake on its PATH), validates the job.
    const std::string then = "hfbake: edit it, then: ";
    const std::size_t at = r.err.find(then);
    ASSERT_NE(at, std::string::npos) << r.err;
    std::string line = r.err.substr(at + then.size());
    line = line.substr(0, line.find('\n'));
    ASSERT_EQ(line.rfind("hfbake validate ", 0), 0u) << line;
    line = line.substr(0, line.find(" && "));
    const fs::path bin = fs::path(HFBAKE_BINARY).parent_path();
    const std::string shell = "cd '" + dir_.string() + "' && PATH='" + bin.string() + "':\"$PATH\" " + line +
                              " --quiet >/dev/null 2>&1";
    EXPECT_EQ(std::system(shell.c_str()), 0) << line;
  }
}

// --force replaces a link at the job's name; what it points to is never written.
TEST_F(CliInit, ForceReplacesALinkAndLeavesItsTarget) {
  write_png16(dir_ / "h.png");
  std::ofstream(dir_ / "target.json") << "kept";
  fs::create_symlink("target.json", dir_ / "link.json");
  const Result r = run("init " + (dir_ / "h.png").string() + " --preset game-ao --force --out " +
                       (dir_ / "link.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::is_symlink(dir_ / "link.json"));
  EXPECT_EQ(read_json(dir_ / "link.json")["name"], "link");
  std::ifstream in(dir_ / "target.json");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "kept");
}

// A job file is a file: a link to the process's standard output (as /dev/stdout is) redirected to a file,
// and a FIFO, are refused even with --force, and stay what they are (a rename would have replaced them).
TEST_F(CliInit, AStreamIsNoJobFile) {
  write_png16(dir_ / "h.png");
  fs::create_symlink("/proc/self/fd/1", dir_ / "stdout");
  ASSERT_EQ(mkfifo((dir_ / "fifo").c_str(), 0600), 0);
  for (const char* name : {"stdout", "fifo"}) {
    const std::string cmd = std::string(HFBAKE_BINARY) + " init " + (dir_ / "h.png").string() +
                            " --preset game-ao --force --out " + (dir_ / name).string() + " >" +
                            (dir_ / "captured").string() + " 2>" + (dir_ / "err.txt").string();
    const int status = std::system(cmd.c_str());
    std::ifstream err(dir_ / "err.txt");
    const std::string text{std::istreambuf_iterator<char>(err), {}};
    EXPECT_EQ(WEXITSTATUS(status), 2) << text;
    EXPECT_NE(text.find((dir_ / name).string() + ": is not a file"), std::string::npos) << text;
  }
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir_ / "stdout")));
  EXPECT_TRUE(fs::is_fifo(fs::symlink_status(dir_ / "fifo")));
  EXPECT_EQ(fs::file_size(dir_ / "captured"), 0u);
}

// A height file's stem with a space and a two-byte UTF-8 letter: each character a job name cannot hold is one
// _ in the job's name and its default file (docs/presets.md), not one per byte.
TEST_F(CliInit, EachCharacterANameCannotHoldIsOneUnderscore) {
  write_png16(dir_ / "my rock h\xc3\xa9.png");
  const std::string cmd = "cd " + dir_.string() + " && " + HFBAKE_BINARY +
                          " init 'my rock h\xc3\xa9.png' --preset game-ao >/dev/null 2>" +
                          (dir_ / "err.txt").string();
  const int status = std::system(cmd.c_str());
  std::ifstream err(dir_ / "err.txt");
  const std::string text{std::istreambuf_iterator<char>(err), {}};
  ASSERT_EQ(WEXITSTATUS(status), 0) << text;
  ASSERT_TRUE(fs::is_regular_file(dir_ / "my_rock_h_.json")) << text;
  EXPECT_EQ(read_json(dir_ / "my_rock_h_.json")["name"], "my_rock_h_");
}

TEST_F(CliInit, HelpListsMethodsLayersAndPresets) {
  // --help prints to stdout.
  const std::string cmd = std::string(HFBAKE_BINARY) + " --help > " + (dir_ / "help.txt").string();
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream in(dir_ / "help.txt");
  const std::string help((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const char* s :
       {"init", "p1 ", "relief ", "layers: ao, vsky, direct, horizon, horizon_distance, bent_normal",
        "layers: svf, openness_positive, openness_negative, horizon_deg", "game-ao", "gis-relief",
        "reference-check"})
    EXPECT_NE(help.find(s), std::string::npos) << s << "\n" << help;
}

}  // namespace
