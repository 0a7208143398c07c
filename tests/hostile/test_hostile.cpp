// The bad-input corpus, case by case, against the hfbake binary: each case is an input a user, a
// script or a damaged disk can hand hfbake, with what must happen: the exit code, one line
// "hfbake: error: <file>: <JSON pointer>: <what>" naming the file and the pointer, and nothing new in the
// output folder (no half-written file, no staging folder, no empty folder). A hang fails the case (each run
// is killed after 120 s), so do a crash (a signal instead of an exit code).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>
#include "exr_pixels.hpp"

#include <OpenImageIO/imageio.h>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {
namespace fs = std::filesystem;
using nlohmann::json;

// One hfbake run: its exit code (or -signal), its stderr and stdout, its peak resident memory.
struct HfbakeRun {
  int exit_code = 0;
  std::string err, out;
  long max_rss_kb = 0;
  std::vector<std::string> error_lines() const {
    std::vector<std::string> lines;
    std::istringstream in(err);
    for (std::string l; std::getline(in, l);)
      if (l.rfind("hfbake: error: ", 0) == 0) lines.push_back(l.substr(15));
    return lines;
  }
};

// Runs hfbake with `args` in `dir`, stderr to a file; killed (and reported as -SIGKILL) after 120 s.
// file_size_limit > 0: the largest file the run may write (RLIMIT_FSIZE, SIGXFSZ ignored: a write beyond it
// fails with EFBIG, as on a full disk). address_space_limit > 0: the most virtual memory the run may map
// (RLIMIT_AS: an allocation beyond it fails, as on a machine with that much memory).
HfbakeRun run_hfbake(const fs::path& dir, const std::vector<std::string>& args, long file_size_limit = 0,
                     long address_space_limit = 0) {
  const fs::path err = dir / "stderr.txt", out = dir / "stdout.txt";
  const pid_t pid = fork();
  if (pid == 0) {
    if (!freopen(err.c_str(), "w", stderr) || !freopen(out.c_str(), "w", stdout)) _exit(126);
    if (chdir(dir.c_str()) != 0) _exit(126);
    alarm(120);  // SIGALRM's default kills a hung hfbake: the case fails instead of hanging the suite
    if (file_size_limit > 0) {
      signal(SIGXFSZ, SIG_IGN);
      const struct rlimit limit { rlim_t(file_size_limit), rlim_t(file_size_limit) };
      if (setrlimit(RLIMIT_FSIZE, &limit) != 0) _exit(126);
    }
    if (address_space_limit > 0) {
      const struct rlimit limit { rlim_t(address_space_limit), rlim_t(address_space_limit) };
      if (setrlimit(RLIMIT_AS, &limit) != 0) _exit(126);
    }
    std::vector<char*> argv{const_cast<char*>("hfbake")};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(HFBAKE_BINARY, argv.data());
    _exit(127);
  }
  int status = 0;
  struct rusage usage {};
  wait4(pid, &status, 0, &usage);
  HfbakeRun r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
  r.max_rss_kb = usage.ru_maxrss;
  auto read = [](const fs::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  r.err = read(err);
  r.out = read(out);
  fs::remove(out);
  return r;
}

// Every path under `dir` (files and folders), relative, and "." for the folder itself; empty when it does
// not exist (so an empty folder left behind is a change).
std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> out;
  std::error_code ec;
  if (!fs::exists(dir, ec)) return out;
  out.insert(".");
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec))
    out.insert(it->path().lexically_relative(dir).string());  // not fs::relative: it follows links
  return out;
}

void write_image(const fs::path& p, int w, int h, int channels, const std::vector<float>& pixels,
                 OIIO::TypeDesc type = OIIO::TypeDesc::FLOAT) {
  auto out = OIIO::ImageOutput::create(p.string());
  ASSERT_TRUE(out) << p;
  OIIO::ImageSpec spec(w, h, channels, type);
  ASSERT_TRUE(out->open(p.string(), spec)) << out->geterror();
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, pixels.data())) << out->geterror();
  out->close();
}

json base_job() {
  return {{"version", 1},
          {"name", "t"},
          {"height", {{"procedural", {{"kind", "fractal"}, {"size", {16, 16}}}}}},
          {"bake", {{{"method", "p1"}, {"directions", 4}}}},
          {"output", {{"dir", "out"}}}};
}

// What a case does in its folder: writes its files and returns hfbake's arguments.
struct CaseSetup {
  std::vector<std::string> args;
  std::string file;      // the file the error names ("" = the job, dir/job.json)
  std::string pointer;   // the JSON pointer (or "line L, column C" for malformed JSON) it names
  std::string what;      // a phrase the message holds
  bool bake_too = true;  // a validate case: bake must refuse it the same way
};

struct Case {
  std::string name;
  std::function<CaseSetup(const fs::path& dir)> setup;
  int exit_code = 2;
  int error_lines = 1;
};

std::string write_job(const fs::path& dir, const json& j, const std::string& name = "job.json") {
  std::ofstream(dir / name) << j.dump(2);
  return (dir / name).string();
}
std::string write_text(const fs::path& dir, const std::string& text, const std::string& name = "job.json") {
  std::ofstream(dir / name, std::ios::binary) << text;
  return (dir / name).string();
}

// validate and bake alike: both must refuse before anything is baked.
// A base job baking the height image `image` (a name in `d`), written into `d`; its path.
std::string image_job(const fs::path& d, const std::string& image) {
  json j = base_job();
  j["height"] = {{"image", image}};
  return write_job(d, j);
}

CaseSetup both(const std::string& job, std::string pointer, std::string what) {
  return {{"validate", job}, "", std::move(pointer), std::move(what)};
}

std::vector<Case> cases() {
  std::vector<Case> c;
  auto add = [&](std::string name, std::function<CaseSetup(const fs::path&)> setup, int exit_code = 2,
                 int lines = 1) {
    c.push_back({std::move(name), std::move(setup), exit_code, lines});
  };

  // --- the parser ---------------------------------------------------------------------------------------
  add("NumberBeyondDouble", [](const fs::path& d) {
    std::string t = base_job().dump();
    t.insert(t.find("\"procedural\""), "\"texel_size\": 1e309, ");
    return both(write_text(d, t), "", "number overflow");
  });
  add("IntegerBeyondInt64", [](const fs::path& d) {
    json j = base_job();
    std::string t = j.dump();
    t.replace(t.find("\"directions\":4"), 14, "\"directions\":123456789012345678901234567890");
    return both(write_text(d, t), "/bake/0/directions", "");
  });
  add("NestedArrays100k", [](const fs::path& d) {
    return both(write_text(d, std::string(100000, '[') + std::string(100000, ']')), "line 1, column 65",
                "nested deeper than 64 levels");
  });
  add("DuplicateKey", [](const fs::path& d) {
    std::string t = base_job().dump();
    t.replace(t.find("\"directions\":4"), 14, "\"directions\":4,\"directions\":8");
    return both(write_text(d, t), "/bake/0/directions", "duplicate key");
  });
  add("NotUtf8", [](const fs::path& d) {
    std::string t = base_job().dump();
    t.replace(t.find("\"t\""), 3, "\"t\xff\xfe\"");
    return both(write_text(d, t), "line 1", "malformed JSON");
  });
  add("HugeJobFile", [](const fs::path& d) {
    json j = base_job();
    j["description"] = std::string(17u << 20, 'x');
    return both(write_job(d, j), "", "may be at most 16777216");
  });
  // --- bounds: sizes a small file can ask for ----------------------------------------------------------
  // A pattern is matched by std::regex, which recursed once per character (30 000: SIGSEGV).
  add("LongJobName30000", [](const fs::path& d) {
    json j = base_job();
    j["name"] = std::string(30000, 'a');
    return both(write_job(d, j), "/name", "a string of 30000 bytes; hfbake's JSON files hold at most 4096");
  });
  add("LongJobName4000", [](const fs::path& d) {  // within the file's bound: the schema's maxLength first
    json j = base_job();
    j["name"] = std::string(4000, 'a');
    return both(write_job(d, j), "/name", "must be at most 128 characters long");
  });
  add("LongPackName4000", [](const fs::path& d) {
    json j = base_job();
    j["output"]["textures"] = {{{"pack", std::string(4000, 'p')}, {"channels", {{"R", "ao"}}}}};
    return both(write_job(d, j), "/output/textures/0/pack", "must be at most 128 characters long");
  });
  add("LongSuiteName30000", [](const fs::path& d) {
    write_job(d, base_job());
    const json suite = {{"version", 1}, {"suite", std::string(30000, 's')}, {"jobs", {"job.json"}}};
    const std::string file = write_job(d, suite, "suite.json");
    return CaseSetup{{"validate", file}, file, "/suite", "a string of 30000 bytes", true};
  });
  add("LongKey30000", [](const fs::path& d) {
    json j = base_job();
    j["output"][std::string(30000, 'k')] = 1;
    return both(write_job(d, j), "/output", "a string of 30000 bytes");
  });
  // Each equal pair was a line: 1000 x "ao" printed 499 500 lines (10 000: 8 GB, then std::bad_alloc).
  add("LayerListed1000Times", [](const fs::path& d) {
    json j = base_job();
    j["bake"][0]["layers"] = std::vector<std::string>(1000, "ao");
    return both(write_job(d, j), "/bake/0/layers/1", "\"ao\" is listed 1000 times");
  });
  add("LayerListed10000Times", [](const fs::path& d) {
    json j = base_job();
    j["bake"][0]["layers"] = std::vector<std::string>(10000, "ao");
    return both(write_job(d, j), "/bake/0/layers", "an array of more than 4096 items");
  });
  add(
      "TwoLayersListedTwiceEach",
      [](const fs::path& d) {
        json j = base_job();
        j["bake"][0]["layers"] = {"ao", "vsky", "ao", "vsky", "ao"};
        return both(write_job(d, j), "/bake/0/layers/2", "\"ao\" is listed 3 times");
      },
      2, 2);
  add("MillionBakeEntries", [](const fs::path& d) {
    std::string t = base_job().dump();
    std::string entries;
    for (int i = 0; i < 1000000; ++i) entries += "{\"method\":\"p1\"},";
    entries.pop_back();
    t.replace(t.find("[{\"directions\""), std::string("[{\"directions\":4,\"method\":\"p1\"}]").size(),
              "[" + entries + "]");
    return both(write_text(d, t), "/bake", "an array of more than 4096 items");
  });
  add("BakeEntries300", [](const fs::path& d) {
    json j = base_job();
    j["bake"] = std::vector<json>(300, {{"method", "p1"}, {"directions", 4}});
    return both(write_job(d, j), "/bake/256", "a job bakes at most 256");
  });
  add("SweepOf65535Values", [](const fs::path& d) {
    json j = base_job();
    std::vector<int> k(65535);
    for (int i = 0; i < 65535; ++i) k[std::size_t(i)] = i + 1;
    j["bake"][0]["directions"] = k;
    return both(write_job(d, j), "/bake/0/directions", "an array of more than 4096 items");
  });
  add("SweepOf4000Values", [](const fs::path& d) {
    json j = base_job();
    std::vector<int> k(4000);
    for (int i = 0; i < 4000; ++i) k[std::size_t(i)] = i + 1;
    j["bake"][0]["directions"] = k;
    return both(write_job(d, j), "/bake/0/directions", "the job would bake 4000+ entries with this sweep");
  });
  // Two parameters swept in one entry: the refusal alone, not also a type error per list.
  add("SweepOfTwoParameters", [](const fs::path& d) {
    json j = base_job();
    j["bake"] = {{{"method", "hbao"}, {"radius", {1, 2}}, {"directions", {4, 8}}}};
    return both(write_job(d, j), "/bake/0", "sweep one parameter per bake entry");
  });
  // A value that fits no alternative (a number or "from_file") is one line, not one per alternative.
  add("TexelSizeOfWrongType", [](const fs::path& d) {
    json j = base_job();
    j["height"]["texel_size"] = "big";
    return both(write_job(d, j), "/height/texel_size", "");
  });
  add("SuiteIncludingItself", [](const fs::path& d) {
    const json suite = {{"version", 1}, {"suite", "s"}, {"jobs", {"suite.json"}}};
    const std::string file = write_job(d, suite, "suite.json");
    return CaseSetup{{"validate", file}, file, "/jobs/0", "is a suite, not a job", true};
  });
  add("DevZeroAsJob", [](const fs::path&) {
    return CaseSetup{{"validate", "/dev/zero"}, "/dev/zero", "", "not a regular file"};
  });
  add("FifoAsJob", [](const fs::path& d) {
    mkfifo((d / "job.json").c_str(), 0600);
    return both((d / "job.json").string(), "", "not a regular file");
  });
  add("FolderAsJob", [](const fs::path& d) {
    fs::create_directories(d / "job.json");
    return CaseSetup{{"validate", (d / "job.json").string()}, "", "", "not a regular file", false};
  });
  add("FolderAsJobBake",
      [](const fs::path& d) {  // bake's command line parser (CLI11) refuses it, in its words
        fs::create_directories(d / "job.json");
        return CaseSetup{{"bake", (d / "job.json").string()},
                         "command line",
                         "jobs",
                         "directory: " + (d / "job.json").string()};
      });

  // --- ranges: values a user could mistype ------------------------------------------------------------
  auto range = [&](std::string name, std::function<void(json&)> edit, std::string pointer) {
    add(std::move(name), [edit, pointer](const fs::path& d) {
      json j = base_job();
      edit(j);
      return both(write_job(d, j), pointer, "");
    });
  };
  range(
      "TexelSize1e308", [](json& j) { j["height"]["texel_size"] = 1e308; }, "/height/texel_size");
  range(
      "TexelSizeDenormal", [](json& j) { j["height"]["texel_size"] = 1e-310; }, "/height/texel_size");
  range(
      "AlbedoFive",
      [](json& j) {
        j["surface"] = {{"albedo", 5}};
      },
      "/surface/albedo");
  range(
      "LightIrradiance1e308",
      [](json& j) {
        j["lights"] = {{{"directional", {{"direction", {0, 0, 1}}, {"irradiance", 1e308}}}}};
      },
      "/lights/0/directional/irradiance");
  range(
      "TinyLightDirection",
      [](json& j) {
        j["lights"] = {{{"directional", {{"direction", {1e-200, 0, 1e-200}}, {"irradiance", 1}}}}};
      },
      "/lights/0/directional/direction");
  range(
      "ProceduralSizeBeyondTheLimit",
      [](json& j) {
        j["height"]["procedural"]["size"] = {2, 2000000};
      },
      "/height/procedural/size/1");
  // The memory estimate itself used to allocate for the sweeps' plan (8 GB for this one) before refusing.
  range(
      "ProceduralMillionSquared",
      [](json& j) {
        j["height"]["procedural"]["size"] = {1000000, 1000000};
      },
      "/height");
  range(
      "EnvironmentRotation1e308",
      [](json& j) {
        j["environment"] = {{"sky", json::object()}, {"rotation_deg", 1e308}};
      },
      "/environment/rotation_deg");

  // --- the data: validate reads what bake reads --------------------------------------------------------
  add("TruncatedPng", [](const fs::path& d) {
    std::vector<float> px(64 * 64);
    for (std::size_t i = 0; i < px.size(); ++i) px[i] = float(i % 97) / 97.0f;
    write_image(d / "h.png", 64, 64, 1, px, OIIO::TypeDesc::UINT16);
    fs::resize_file(d / "h.png", fs::file_size(d / "h.png") * 2 / 3);
    return both(image_job(d, "h.png"), "/height/image", "cannot decode the image");
  });
  add("NanHeights", [](const fs::path& d) {
    std::vector<float> px(16 * 16, 1.0f);
    px[3 * 16 + 5] = std::numeric_limits<float>::quiet_NaN();
    write_image(d / "h.exr", 16, 16, 1, px);
    return both(image_job(d, "h.exr"), "/height/image", "texel (5, 3) is NaN");
  });
  add("Heights1e38", [](const fs::path& d) {
    std::vector<float> px(16 * 16, 1.0f);
    px[17] = 1e38f;
    write_image(d / "h.exr", 16, 16, 1, px);
    return both(image_job(d, "h.exr"), "/height", "texel (1, 1) is 1e+38 world units high");
  });
  add("HeightPatternPlusMinus3e38", [](const fs::path& d) {
    std::vector<float> px(16 * 16);
    for (std::size_t t = 0; t < px.size(); ++t) px[t] = t % 2 ? -3e38f : 3e38f;
    write_image(d / "h.exr", 16, 16, 1, px);
    return both(image_job(d, "h.exr"), "/height", "world units high");
  });
  add("LatlongPixelMinus5", [](const fs::path& d) {
    std::vector<float> px(16 * 8 * 3, 1.0f);
    px[(2 * 16 + 7) * 3 + 1] = -5.0f;
    write_image(d / "sky.exr", 16, 8, 3, px);
    json j = base_job();
    j["environment"] = {{"latlong", "sky.exr"}};
    return both(write_job(d, j), "/environment/latlong", "pixel (7, 2) is negative");
  });
  add("CrossTiffWithStripsTallerThanTheImage", [](const fs::path& d) {  // found by fuzz_environment
    // 65535x4 float RGB declaring 65311-row strips (reading it allocated 51 GB) and tags past its end
    // (libtiff's warnings, printed by GDAL's handler once GDAL is loaded). The seed's first byte is the
    // harness's layout selector.
    std::ifstream in(
        fs::path(HFBAKE_SOURCE_DIR) / "tests/fuzz/regressions/environment/tiff_strip_taller_than_the_image",
        std::ios::binary);
    const std::string bytes{std::istreambuf_iterator<char>(in), {}};
    write_text(d, bytes.substr(1), "sky.tif");
    write_image(d / "h.exr", 16, 16, 1, std::vector<float>(16 * 16, 1.0f));  // an image height loads GDAL
    json j = base_job();
    j["height"] = {{"image", "h.exr"}};
    j["environment"] = {{"cross", "sky.tif"}};
    return both(write_job(d, j), "/environment/cross", "cannot decode the image");
  });
  add("LatlongPixelInf", [](const fs::path& d) {
    std::vector<float> px(16 * 8 * 3, 1.0f);
    px[5] = std::numeric_limits<float>::infinity();
    write_image(d / "sky.exr", 16, 8, 3, px);
    json j = base_job();
    j["environment"] = {{"latlong", "sky.exr"}};
    return both(write_job(d, j), "/environment/latlong", "is not finite");
  });
  add("EmissionMapNegative", [](const fs::path& d) {
    std::vector<float> px(16 * 16 * 3, 0.0f);
    px[3 * 10] = -1.0f;
    write_image(d / "glow.exr", 16, 16, 3, px);
    json j = base_job();
    j["surface"] = {{"emission", {{"image", "glow.exr"}}}};
    return both(write_job(d, j), "/surface/emission/image", "is negative or not finite");
  });
  add("ReportCropLeavesNoTexel", [](const fs::path& d) {
    json j = base_job();
    j["report"] = {{"crop", 8}};
    return both(write_job(d, j), "/report/crop", "8 leaves no texel of the 16x16 field");
  });
  add("ThresholdOfNoBakeEntry", [](const fs::path& d) {
    json j = base_job();
    j["reference"] = {{"samples", 4}};
    j["report"] = {{"thresholds", {{"p2.indirect.mae", 0.1}}}};
    return both(write_job(d, j), "/report/thresholds/p2.indirect.mae", "the job has no bake entry \"p2\"");
  });
  add("OutputFolderInsideAFile", [](const fs::path& d) {
    std::ofstream(d / "file") << "x";
    json j = base_job();
    j["output"]["dir"] = "file/out";
    return both(write_job(d, j), "/output/dir", "is not a folder");
  });
  add("OutputFolderALinkLoop", [](const fs::path& d) {
    fs::create_symlink("loop", d / "loop");
    json j = base_job();
    j["output"]["dir"] = "loop";
    return both(write_job(d, j), "/output/dir", "loop is a link that leads to nothing");
  });
  add("OutFolderInsideAFile", [](const fs::path& d) {  // the command line's folder is named as such
    std::ofstream(d / "file") << "x";
    return CaseSetup{{"bake", write_job(d, base_job()), "--out", (d / "file" / "out").string(), "--quiet"},
                     "",
                     "--out",
                     "is not a folder",
                     false};
  });
  add("OneJobFileNamedTwice", [](const fs::path& d) {  // the second naming is refused, not baked again
    const std::string j = write_job(d, base_job());
    return CaseSetup{{"validate", j, j}, "", "", "is named more than once", false};
  });
  add("OutputFolderNameTooLong", [](const fs::path& d) {  // mkdir's ENAMETOOLONG, found by validate too
    json j = base_job();
    j["output"]["dir"] = "out/" + std::string(256, 'b') + "/x";
    return both(write_job(d, j), "/output/dir", "File name too long (256 bytes in a name, at most 255)");
  });
  // A raster's pixel size becomes the texel size: the range the job's texel_size has (a GeoTIFF of 1e-9 m
  // pixels baked ao up to 1.026).
  add("RasterPixelsOf1em9", [](const fs::path& d) {
    std::string grid = "ncols 16\nnrows 16\nxllcorner 0\nyllcorner 0\ncellsize 1e-9\n";
    for (int k = 0; k < 16 * 16; ++k) grid += std::to_string(k % 11) + (k % 16 == 15 ? "\n" : " ");
    write_text(d, grid, "h.asc");
    return both(image_job(d, "h.asc"), "/height/image", "has a pixel size of 1e-09");
  });
  add("AlbedoMapOfFive", [](const fs::path& d) {  // the image holds what the number may not
    write_image(d / "a.exr", 16, 16, 3, std::vector<float>(16 * 16 * 3, 5.0f));
    json j = base_job();
    j["surface"] = {{"albedo", {{"image", "a.exr"}}}};
    return both(write_job(d, j), "/surface/albedo/image", "pixel (0, 0) is (5, 5, 5) after the scale");
  });
  add("EmissionMapBeyondTheNumbersCeiling", [](const fs::path& d) {  // 1 x 1e20: finite, its sums are not
    write_image(d / "e.exr", 16, 16, 3, std::vector<float>(16 * 16 * 3, 1.0f));
    json j = base_job();
    j["surface"] = {{"emission", {{"image", "e.exr"}, {"scale", 1e20}}}};
    j["bounces"] = 1;
    return both(write_job(d, j), "/surface/emission/image",
                "pixel (0, 0) is (1e+20, 1e+20, 1e+20) after the scale; an emission lies in [0, 1e9]");
  });
  add("HsaoRadiusCrossingARepeatFieldsTilingFarTooLong", [](const fs::path& d) {  // hours of rays, refused
    json j = base_job();
    j["height"]["wrap"] = "repeat";
    j["bake"] = {{{"method", "hsao"}, {"directions", 1}, {"radius", 1e9}}};
    return both(write_job(d, j), "/bake/0/radius", "on a repeat field each ray crosses the tiling");
  });
  add("HbaoDistanceCrossingARepeatFieldsTilingFarTooLong", [](const fs::path& d) {  // hours of steps, refused
    json j = base_job();
    j["height"]["wrap"] = "repeat";
    j["bake"] = {{{"method", "hbao"}, {"directions", 16}, {"max_distance", 5e6}}};
    return both(write_job(d, j), "/bake/0/max_distance", "on a repeat field each march crosses the tiling");
  });
  add("ATexturesNameLeavesNoRoomForItsTemporaryName", [](const fs::path& d) {  // 246 of 255 bytes
    json j = base_job();
    j["name"] = std::string(128, 'a');
    j["bake"] = {{{"method", "p1"}, {"directions", 4}, {"layers", {"ao"}}}};
    j["output"]["textures"] = {{{"pack", std::string(110, 'p')}, {"channels", {{"R", "ao"}}}}};
    return both(write_job(d, j), "/output/textures",
                "246 bytes, more than the 223 an output's name may have");
  });
  add("AlbedoMapOfAnotherSize", [](const fs::path& d) {
    write_image(d / "a.exr", 8, 8, 3, std::vector<float>(8 * 8 * 3, 0.5f));
    json j = base_job();
    j["surface"] = {{"albedo", {{"image", "a.exr"}}}};
    return both(write_job(d, j), "/surface/albedo/image", "the height field is 16x16");
  });
  add("HeightImageWiderThanSupported", [](const fs::path& d) {
    const int w = (1 << 20) + 1;
    write_image(d / "wide.tif", w, 2, 1, std::vector<float>(std::size_t(w) * 2, 0.5f), OIIO::TypeDesc::UINT8);
    return both(image_job(d, "wide.tif"), "/height/image",
                "fields of up to 1048576 texels a side are supported");
  });
  add("HeightImageIsAFolder", [](const fs::path& d) {
    fs::create_directories(d / "h.png");
    return both(image_job(d, "h.png"), "/height/image", "h.png is a folder, not a file");
  });
  add("HeightImageIsADevice", [](const fs::path& d) {
    return both(image_job(d, "/dev/zero"), "/height/image", "/dev/zero is not a regular file");
  });
  add("HeightImageIsALinkLoop", [](const fs::path& d) {
    fs::create_symlink("b.png", d / "a.png");
    fs::create_symlink("a.png", d / "b.png");
    return both(image_job(d, "a.png"), "/height/image", "a.png is a link that leads back to itself (a loop)");
  });
  add("HeightImageIsEmpty", [](const fs::path& d) {
    std::ofstream(d / "h.png");
    return both(image_job(d, "h.png"), "/height/image", "h.png: is empty (0 bytes)");
  });
  // Files a bake would replace or refuse only after baking, refused by validate.
  add("HeightImageNamedAsAnOutput", [](const fs::path& d) {
    fs::create_directories(d / "out");
    write_image(d / "out" / "t.p1.exr", 16, 16, 1, std::vector<float>(16 * 16, 1.0f));
    return both(image_job(d, "out/t.p1.exr"), "/height/image", "t.p1.exr is where this job writes an output");
  });
  add("JobFileNamedAsAnOutput", [](const fs::path& d) {
    fs::create_directories(d / "out");
    json j = base_job();
    j["output"]["dir"] = ".";
    j["reference"] = {{"samples", 4}};
    write_job(d / "out", j, "report.json");
    const std::string job = (d / "out" / "report.json").string();
    return CaseSetup{{"validate", job}, job, "", "report.json is where this job writes an output"};
  });
  add("LockNameTakenByALink", [](const fs::path& d) {
    fs::create_directories(d / "out");
    fs::create_symlink("../elsewhere", d / "out" / ".hfbake-t.lock");
    return both(write_job(d, base_job()), "/output/dir",
                ".hfbake-t.lock is no lock file of hfbake's (a link)");
  });
  add("TexturesFolderIsALink", [](const fs::path& d) {
    fs::create_directories(d / "out");
    fs::create_directories(d / "elsewhere");
    fs::create_symlink("../elsewhere", d / "out" / "textures");
    json j = base_job();
    j["output"]["textures"] = {{{"layers", {"ao"}}, {"format", "png"}}};
    return both(write_job(d, j), "/output/textures", "textures is not a folder (a link)");
  });
  add("ReportLockNameTakenByALink", [](const fs::path& d) {
    fs::create_directories(d / "out");
    fs::create_symlink("../elsewhere", d / "out" / ".hfbake+report.lock");
    json j = base_job();
    j["reference"] = {{"samples", 4}};
    return both(write_job(d, j), "/output/dir", ".hfbake+report.lock is no lock file of hfbake's (a link)");
  });
  // A path is a C string to the system: a NUL in it would name another file (the part before it).
  add("HeightImagePathHoldingANul", [](const fs::path& d) {
    write_image(d / "h.exr", 16, 16, 1, std::vector<float>(16 * 16, 1.0f));
    return both(image_job(d, std::string("h.exr\0.png", 10)), "/height/image", "holds a NUL character");
  });
  add("OutputDirHoldingANul", [](const fs::path& d) {
    json j = base_job();
    j["output"]["dir"] = std::string("out\0x", 5);
    return both(write_job(d, j), "/output/dir", "holds a NUL character");
  });
  add("SummaryWhereTheJobWritesAnOutput", [](const fs::path& d) {
    const std::string job = write_job(d, base_job()), summary = (d / "out" / "t.p1.exr").string();
    return CaseSetup{{"bake", "--no-cache", "--quiet", "--summary", summary, job},
                     summary,
                     "--summary",
                     "is where job t writes its outputs"};
  });
  add("SuiteOutputDirHoldingANul", [](const fs::path& d) {
    write_job(d, base_job());
    const json suite = {{"version", 1},
                        {"suite", "s"},
                        {"jobs", {"job.json"}},
                        {"output", {{"dir", std::string("out\0x", 5)}}}};
    const std::string file = write_job(d, suite, "suite.json");
    return CaseSetup{{"validate", file}, file, "/output/dir", "holds a NUL character", true};
  });
  add("SummaryWhereTheSuiteWritesItsHistory", [](const fs::path& d) {
    write_job(d, base_job());
    const json suite = {{"version", 1}, {"suite", "s"}, {"jobs", {"job.json"}}, {"output", {{"dir", "out"}}}};
    const std::string file = write_job(d, suite, "suite.json"),
                      summary = (d / "out" / "history.json").string();
    return CaseSetup{{"bake", "--no-cache", "--quiet", "--summary", summary, file},
                     summary,
                     "--summary",
                     "is where suite s writes history.json"};
  });
  add("SummaryOverTheJobFile", [](const fs::path& d) {
    const std::string job = write_job(d, base_job());
    return CaseSetup{
        {"bake", "--no-cache", "--quiet", "--summary", job, job}, job, "--summary", "which this bake reads"};
  });
  add(
      "SummaryOverAnInvalidJobsHeightImage",
      [](const fs::path& d) {
        write_image(d / "h.exr", 16, 16, 1, std::vector<float>(16 * 16, 1.0f));
        json j = base_job();
        j["height"] = {{"image", "h.exr"}};
        j["unknown"] = 1;
        const std::string job = write_job(d, j), summary = (d / "h.exr").string();
        return CaseSetup{
            {"bake", "--no-cache", "--quiet", "--summary", summary, job}, "", "/unknown", "unknown key"};
      },
      2, 2);
  add("ShardsEntryIsAFile", [](const fs::path& d) {
    fs::create_directories(d / "out");
    std::ofstream(d / "out" / "shards") << "x";
    const std::string job = write_job(d, base_job());
    return CaseSetup{{"merge", job, "--no-cache", "--quiet"},
                     job,
                     "/output/dir",
                     (d / "out" / "shards").string() + " is not a folder (a file)"};
  });
  add("HeightImageOneByOne", [](const fs::path& d) {
    write_image(d / "h.exr", 1, 1, 1, {1.0f});
    return both(image_job(d, "h.exr"), "/height/image", "h.exr is 1x1 texels; at least 2x2 are needed");
  });

  // --- bake: the same refusals, and nothing left behind --------------------------------------------------
  add("BakeTruncatedPngLeavesNoFolder", [](const fs::path& d) {
    std::vector<float> px(64 * 64, 0.25f);
    write_image(d / "h.png", 64, 64, 1, px, OIIO::TypeDesc::UINT8);
    fs::resize_file(d / "h.png", fs::file_size(d / "h.png") / 2);
    json j = base_job();
    j["height"] = {{"image", "h.png"}};
    return CaseSetup{{"bake", write_job(d, j), "--no-cache", "--quiet"}, "", "/height/image", ""};
  });
  add(
      "BakeCollidingJobs",
      [](const fs::path& d) {
        fs::create_directories(d / "x");
        fs::create_directories(d / "y");
        const std::string a = write_job(d, base_job(), "x/job.json"),
                          b = write_job(d, base_job(), "y/job.json");
        // Without a reference neither writes a report: the line names only what they write.
        return CaseSetup{{"bake", a, b, "--out", (d / "out").string(), "--quiet"},
                         a,
                         "/name",
                         ".exr) would be the same files"};
      },
      2, 2);
  add(
      "ValidateCollidingJobs",  // as bake refuses them, the folder however written
      [](const fs::path& d) {
        fs::create_directories(d / "x");
        fs::create_directories(d / "y");
        json a = base_job(), b = base_job();
        a["output"]["dir"] = "../out", b["output"]["dir"] = ".././out/";
        const std::string ja = write_job(d, a, "x/job.json"), jb = write_job(d, b, "y/job.json");
        return CaseSetup{{"validate", ja, jb}, ja, "/name", "would be the same files"};
      },
      2, 2);
  add(
      "ReportsOfTwoJobsInOneFolder",  // report.json carries no job name
      [](const fs::path& d) {
        json a = base_job(), b = base_job();
        a["reference"] = b["reference"] = {{"samples", 4}};
        b["name"] = "u";
        const std::string ja = write_job(d, a, "a.json"), jb = write_job(d, b, "b.json");
        return CaseSetup{
            {"bake", ja, jb, "--no-cache", "--quiet"}, ja, "/output/dir", "both have a reference"};
      },
      2, 2);
  add("AnotherJobsReportInTheFolder", [](const fs::path& d) {
    fs::create_directories(d / "out");
    std::ofstream(d / "out" / "report.json") << R"({"job": {"name": "other"}})";
    json j = base_job();
    j["reference"] = {{"samples", 4}};
    return both(write_job(d, j), "/output/dir", "report.json is job \"other\"'s report");
  });
  add("SummaryIsAFolder", [](const fs::path& d) {  // refused before anything is baked
    fs::create_directories(d / "sums");
    return CaseSetup{
        {"bake", write_job(d, base_job()), "--quiet", "--no-cache", "--summary", (d / "sums").string()},
        (d / "sums").string(),
        "--summary",
        "is a folder",
        false};
  });
  add("SummaryIntoAFileNotAFolder", [](const fs::path& d) {  // refused before anything is baked
    std::ofstream(d / "file") << "x";
    return CaseSetup{{"bake", write_job(d, base_job()), "--quiet", "--no-cache", "--summary",
                      (d / "file/sums/s.json").string()},
                     (d / "file/sums/s.json").string(),
                     "--summary",
                     (d / "file").string() + " is not a folder",
                     false};
  });
  add("CompareReportWithWrongTypes", [](const fs::path& d) {  // found by fuzz_report: compare aborted
    const fs::path seed =
        fs::path(HFBAKE_SOURCE_DIR) / "tests/fuzz/regressions/report/scene_hash_not_a_string";
    std::ifstream in(seed);
    const std::string text{std::istreambuf_iterator<char>(in), {}};
    const auto sep = text.find("\n@@\n");
    fs::create_directories(d / "a");
    fs::create_directories(d / "b");
    write_text(d, text.substr(0, sep), "a/report.json");
    write_text(d, text.substr(sep + 4), "b/report.json");
    return CaseSetup{{"compare", (d / "a").string(), (d / "b").string()},
                     (d / "b/report.json").string(),
                     "/job/scene_hash",
                     "not a report.json as hfbake writes it"};
  });
  return c;
}

class Hostile : public ::testing::TestWithParam<Case> {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("hfbake_hostile_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_P(Hostile, OneLineErrorExitCodeAndNothingNewInTheOutputFolder) {
  const Case& k = GetParam();
  const CaseSetup s = k.setup(dir_);
  const std::string file = s.file.empty() ? (dir_ / "job.json").string() : s.file;
  std::vector<std::vector<std::string>> runs{s.args};
  if (s.args.front() == "validate" && s.bake_too) {  // and bake refuses it too, before baking
    std::vector<std::string> bake = s.args;
    bake.front() = "bake";
    bake.insert(bake.end(), {"--no-cache", "--quiet"});
    runs.push_back(bake);
  }
  for (const auto& args : runs) {
    const auto before = listing(dir_ / "out");
    const HfbakeRun r = run_hfbake(dir_, args);
    SCOPED_TRACE(args.front());
    EXPECT_EQ(r.exit_code, k.exit_code) << r.err;
    const auto lines = r.error_lines();
    ASSERT_EQ(int(lines.size()), k.error_lines) << r.err;
    EXPECT_EQ(lines[0].rfind(file + ": " + (s.pointer.empty() ? "" : s.pointer)), 0u)
        << "expected \"" << file << ": " << s.pointer << "\" in: " << lines[0];
    EXPECT_NE(lines[0].find(s.what), std::string::npos) << lines[0];
    EXPECT_EQ(listing(dir_ / "out"), before) << "the output folder changed";
    EXPECT_EQ(r.err.find("AddressSanitizer"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("runtime error"), std::string::npos) << r.err;
    if (args.front() == "validate") {  // nothing but hfbake's lines (no image library printing its own)
      std::istringstream in(r.err);
      for (std::string l; std::getline(in, l);) EXPECT_EQ(l.rfind("hfbake: ", 0), 0u) << l;
    }
  }
  // Nothing half-written beside the job either (temporaries of the summary, the cache, ...).
  for (const auto& p : listing(dir_)) EXPECT_EQ(p.find(".tmp-"), std::string::npos) << p;
}

INSTANTIATE_TEST_SUITE_P(Corpus, Hostile, ::testing::ValuesIn(cases()),
                         [](const ::testing::TestParamInfo<Case>& info) { return info.param.name; });

}  // namespace

namespace {

// A process's start time as /proc/<pid>/stat gives it (field 22), read here independently of hfbake.
unsigned long long start_time_of(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat;
  std::getline(in, stat);
  std::istringstream fields(stat.substr(stat.rfind(')') + 2));
  std::string f;
  for (int k = 3; k <= 22; ++k) fields >> f;
  return std::stoull(f);
}

// A process that runs until the test ends (killed and reaped then), and the owner names a stage or a
// temporary records (<pid>+<start>@<host>): its own, and one of the same id that started at another time
// (the id reused by another process since).
struct LiveProcess {
  pid_t pid = fork();
  std::string owner, reused;
  LiveProcess() {
    if (pid == 0) {
      pause();
      _exit(0);
    }
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    const unsigned long long start = start_time_of(pid);
    owner = std::to_string(pid) + "+" + std::to_string(start) + "@" + host;
    reused = std::to_string(pid) + "+" + std::to_string(start + 1) + "@" + host;
  }
  ~LiveProcess() {
    kill(pid, SIGKILL);
    waitpid(pid, nullptr, 0);
  }
  LiveProcess(const LiveProcess&) = delete;
  LiveProcess& operator=(const LiveProcess&) = delete;
};

// SIGKILL leaves a staging folder; its process id may by then belong to another process (after a reboot, on
// a busy node). The stage records the owner's start time, so the next bake removes the stage of a live id
// that started at another time, and keeps the stage of a process that still runs.
TEST(Staging, AStageWhoseProcessIdWasReusedIsRemovedAndALiveOwnersIsKept) {
  const fs::path dir = fs::temp_directory_path() / ("hfbake_stage_" + std::to_string(std::random_device{}()));
  fs::create_directories(dir / "out");
  LiveProcess live;
  const fs::path reused = dir / "out" / (".hfbake-staging-t-" + live.reused);
  const fs::path owner = dir / "out" / (".hfbake-staging-u-" + live.owner);
  for (const fs::path& p : {reused, owner}) {
    fs::create_directories(p);
    std::ofstream(p / "t.p1.exr") << "half-written";
  }
  const HfbakeRun r = run_hfbake(dir, {"bake", write_job(dir, base_job()), "--no-cache"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(reused)) << r.err;
  EXPECT_TRUE(fs::exists(owner / "t.p1.exr"));
  EXPECT_NE(r.err.find("removed " + reused.string()), std::string::npos) << r.err;
  // The bake's own stage carries its id and start time, and is gone after it.
  for (const auto& e : fs::directory_iterator(dir / "out")) {
    if (e.path().filename().string().rfind(".hfbake-staging-", 0) == 0) {
      EXPECT_EQ(e.path(), owner);
    }
  }
  fs::remove_all(dir);
}

}  // namespace

namespace {

// A killed process's temporaries (a reference-cache entry's file, a tile GeoTIFF's folder) carry their
// owner, <pid>+<start>@<host>: a later bake removes those whose owner no longer runs (an id reused by
// another process included) and keeps a live owner's.
TEST(Temporaries, AKilledProcessesAreRemovedAndALiveOnesKept) {
  const fs::path dir = fs::temp_directory_path() / ("hfbake_tmps_" + std::to_string(std::random_device{}()));
  fs::create_directories(dir / "cache");
  LiveProcess live;
  const fs::path dead_file = dir / "cache" / ("k1.hfref.tmp-" + live.reused + "-Ab12Cd"),
                 dead_folder = dir / "cache" / (".t.tif.tmp-" + live.reused + "-Ef34Gh"),
                 live_file = dir / "cache" / ("k2.hfref.tmp-" + live.owner + "-Ij56Kl");
  std::ofstream(dead_file) << "half-written";
  fs::create_directories(dead_folder);
  std::ofstream(dead_folder / "t.tif") << "half-written";
  std::ofstream(live_file) << "being written";
  json j = base_job();
  j["reference"] = {{"samples", 4}};
  const HfbakeRun r =
      run_hfbake(dir, {"bake", write_job(dir, j), "--cache", (dir / "cache").string(), "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(dead_file));
  EXPECT_FALSE(fs::exists(dead_folder));
  EXPECT_TRUE(fs::exists(live_file));
  fs::remove_all(dir);
}

}  // namespace

namespace {

// Two members of one suite whose outputs would be the same files (x/job.json and y/job.json, both
// named "t", one output folder) are refused up front, naming both, in every one of 20 runs, and nothing is
// written; two members with different names in that folder are baked side by side 20 times and neither
// ever loses its outputs (each EXR is its own job's field: the two seeds give different files).
TEST(Suite, MembersWithTheSameOutputsAreRefusedAndDistinctOnesNeverLoseAnOutputIn20Runs) {
  const fs::path dir = fs::temp_directory_path() / ("hfbake_suite_" + std::to_string(std::random_device{}()));
  fs::create_directories(dir / "x");
  fs::create_directories(dir / "y");
  json a = base_job(), b = base_job();
  a["output"]["dir"] = b["output"]["dir"] = "../out";  // the suite's output folder takes their place
  b["height"]["procedural"]["seed"] = 5;
  const std::string ja = write_job(dir / "x", a), jb = write_job(dir / "y", b);
  const json suite = {{"version", 1},
                      {"suite", "s"},
                      {"jobs", {"x/job.json", "y/job.json"}},
                      {"output", {{"dir", "suite_out"}}}};
  const std::string js = write_job(dir, suite, "suite.json");
  for (int run = 0; run < 20; ++run) {
    const HfbakeRun r = run_hfbake(dir, {"bake", js, "--no-cache", "--quiet"});
    ASSERT_EQ(r.exit_code, 2) << run << ": " << r.err;
    const auto lines = r.error_lines();
    ASSERT_GE(lines.size(), 1u) << r.err;
    EXPECT_NE(r.err.find(ja), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(jb), std::string::npos) << r.err;
    // Nothing baked (the suite's own record, suite.json and junit.xml, says why).
    EXPECT_FALSE(fs::exists(dir / "suite_out" / "job")) << run;
  }
  b["name"] = "u";
  write_job(dir / "y", b);
  // An output's job name (hfbake:job) and its pixels (the file's metadata holds the bake's wall time).
  auto content = [](const fs::path& p) {
    std::string s;
    auto in = OIIO::ImageInput::open(p.string());
    if (!in) return s;
    const OIIO::ImageSpec& spec = in->spec();
    std::vector<float> px(std::size_t(spec.width) * spec.height * spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, px.data())) return s;
    s = std::string(spec.get_string_attribute("hfbake:job")) + ":";
    s.append(reinterpret_cast<const char*>(px.data()), px.size() * sizeof(float));
    return s;
  };
  std::string first_t, first_u;
  for (int run = 0; run < 20; ++run) {
    fs::remove_all(dir / "suite_out");
    const HfbakeRun r = run_hfbake(dir, {"bake", js, "--no-cache", "--quiet"});
    ASSERT_EQ(r.exit_code, 0) << run << ": " << r.err;
    // The suite's output folder: each member in <suite output>/<job file stem>/.
    const fs::path out = dir / "suite_out" / "job";
    const std::string t = content(out / "t.p1.exr"), u = content(out / "u.p1.exr");
    ASSERT_EQ(t.rfind("t:", 0), 0u) << run;
    ASSERT_EQ(u.rfind("u:", 0), 0u) << run;
    if (run == 0) {
      first_t = t, first_u = u;
      EXPECT_NE(t.substr(2), u.substr(2));  // two fields: never one job's pixels under the other's name
    }
    EXPECT_TRUE(t == first_t) << run;  // same job, same bits
    EXPECT_TRUE(u == first_u) << run;
    for (const auto& p : listing(dir / "suite_out"))
      EXPECT_EQ(p.find(".hfbake-staging-"), std::string::npos) << p;
  }
  fs::remove_all(dir);
}

// The memory estimate counts the environment image: while it is read it takes about 24 bytes a pixel (its
// decoded channels and their linear RGB copy), before the world lat-long it becomes is kept. The estimate
// must be within 25 % of the measured peak of the bake (without sanitizers: their shadow memory is not the
// program's): a half EXR, and an 8-bit PNG, whose sRGB values OpenColorIO converts to linear.
TEST(MemoryEstimate, CountsTheEnvironmentImage) {
  const fs::path dir =
      fs::temp_directory_path() / ("hfbake_envmem_" + std::to_string(std::random_device{}()));
  fs::create_directories(dir);
  const struct {
    const char* file;
    int w, h;
    OIIO::TypeDesc type;
  } images[] = {{"sky.exr", 2048, 1024, OIIO::TypeDesc::HALF},
                {"sky.png", 4096, 2048, OIIO::TypeDesc::UINT8}};
  for (const auto& image : images) {
    SCOPED_TRACE(image.file);
    const int w = image.w, h = image.h;
    std::vector<float> px(std::size_t(w) * h * 3);
    for (std::size_t i = 0; i < px.size(); ++i) px[i] = 0.25f + float(i % 7) * 0.0625f;
    write_image(dir / image.file, w, h, 3, px, image.type);
    json j = base_job();
    j["environment"] = {{"latlong", image.file}};
    const std::string job = write_job(dir, j);
    const HfbakeRun v = run_hfbake(dir, {"validate", job});
    ASSERT_EQ(v.exit_code, 0) << v.err;
    // "...: valid (16x16, about N MiB to bake: scene S MiB, p1 P MiB, environment E MiB)", on stderr
    const std::string said = v.err;
    const std::size_t at = said.find("about ");
    ASSERT_NE(at, std::string::npos) << said;
    [[maybe_unused]] const double estimate_mib = std::stod(said.substr(at + 6));  // unread under ASan
    const std::size_t env_at = said.find("environment ");
    ASSERT_NE(env_at, std::string::npos) << said;
    EXPECT_GE(std::stod(said.substr(env_at + 12)), 24.0 * w * h / (1 << 20) * 0.99) << said;
#if !defined(__SANITIZE_ADDRESS__)  // peak memory is measured without sanitizers
    const HfbakeRun r = run_hfbake(dir, {"bake", job, "--no-cache", "--quiet", "--threads", "2"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const double peak_mib = r.max_rss_kb / 1024.0;
    EXPECT_GE(estimate_mib, peak_mib) << said;
    EXPECT_LE(estimate_mib, 1.25 * peak_mib) << said;
#endif
  }
  fs::remove_all(dir);
}

// output.previews on a job whose layers the previews do not show (a horizon stack, relief's horizon_deg)
// writes no PNG and loads no image library: its estimate is the job's without previews, within 25 % of the
// measured peak (a 777^2 relief horizon_deg job was estimated at 1.73x its peak, and a --memory-limit it
// fits was refused).
TEST(MemoryEstimate, PreviewsOfLayersNotPreviewedCostNothing) {
  const fs::path dir =
      fs::temp_directory_path() / ("hfbake_previewmem_" + std::to_string(std::random_device{}()));
  fs::create_directories(dir);
  for (const json& entry :
       {json{{"method", "relief"}, {"directions", 16}, {"search_radius", 20}, {"layers", {"horizon_deg"}}},
        json{{"method", "p1"}, {"directions", 32}, {"layers", {"horizon"}}}}) {
    SCOPED_TRACE(entry.dump());
    std::string said[2];
    for (const bool previews : {false, true}) {
      json j = base_job();
      j["height"]["procedural"]["size"] = {512, 512};
      j["bake"] = json::array({entry});
      j["output"]["previews"] = previews;
      const HfbakeRun v = run_hfbake(dir, {"validate", write_job(dir, j)});
      ASSERT_EQ(v.exit_code, 0) << v.err;
      said[previews] = v.err.substr(v.err.find("about "));
    }
    EXPECT_EQ(said[1], said[0]);
#if !defined(__SANITIZE_ADDRESS__)  // peak memory is measured without sanitizers
    const HfbakeRun r = run_hfbake(dir, {"bake", (dir / "job.json").string(), "--no-cache", "--quiet"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const double estimate_mib = std::stod(said[1].substr(6)), peak_mib = r.max_rss_kb / 1024.0;
    EXPECT_LE(estimate_mib, 1.25 * peak_mib) << said[1];
    EXPECT_GE(estimate_mib, 0.75 * peak_mib) << said[1];
#endif
    for (const auto& p : listing(dir / "out")) EXPECT_EQ(p.find(".png"), std::string::npos) << p;
  }
  fs::remove_all(dir);
}

// A constant albedo (a number or [r, g, b]) is held once, not 12 bytes a texel (a 16384^2 hbao
// job with "albedo": 0.5 must not be charged, or hold, 3 GiB for it): validate's scene part of a 2048^2 p2
// job is the process's fixed part (at most 150 MiB), the heights and the normals p2 reads, and p2 and the
// reference bake the same bits from the constant as from an image holding it in every texel.
TEST(MemoryEstimate, ConstantAlbedoIsHeldOnceAndBakesLikeAnImageOfIt) {
  const fs::path dir =
      fs::temp_directory_path() / ("hfbake_albedo_" + std::to_string(std::random_device{}()));
  fs::create_directories(dir);
  json j = base_job();
  j["height"]["procedural"]["size"] = {2048, 2048};
  j["surface"] = {{"albedo", {0.3, 0.5, 0.7}}};
  j["bake"] = {{{"method", "p2"}, {"directions", 4}}};
  const HfbakeRun v = run_hfbake(dir, {"validate", write_job(dir, j, "big.json")});
  ASSERT_EQ(v.exit_code, 0) << v.err;
  const std::size_t at = v.err.find("scene ");
  ASSERT_NE(at, std::string::npos) << v.err;
  const double scene_mib = std::stod(v.err.substr(at + 6));
  const double texels_mib = 2048.0 * 2048.0 / (1 << 20);
  EXPECT_LT(scene_mib, 150 + 16 * texels_mib + 1) << v.err;  // heights, normals (an albedo image: + 12)

  const int n = 48;
  j["height"]["procedural"]["size"] = {n, n};
  j["bounces"] = 1;
  j["reference"] = {{"samples", 4}, {"seed", 1}};
  j["output"] = {{"dir", "constant"}, {"previews", false}};
  const HfbakeRun a = run_hfbake(dir, {"bake", write_job(dir, j, "constant.json"), "--no-cache", "--quiet"});
  ASSERT_EQ(a.exit_code, 0) << a.err;
  std::vector<float> albedo(std::size_t(n) * n * 3);
  for (std::size_t t = 0; t < albedo.size(); t += 3)
    albedo[t] = 0.3f, albedo[t + 1] = 0.5f, albedo[t + 2] = 0.7f;
  write_image(dir / "albedo.exr", n, n, 3, albedo);
  j["surface"] = {{"albedo", {{"image", "albedo.exr"}}}};
  j["output"]["dir"] = "image";
  const HfbakeRun b = run_hfbake(dir, {"bake", write_job(dir, j, "image.json"), "--no-cache", "--quiet"});
  ASSERT_EQ(b.exit_code, 0) << b.err;
  int compared = 0;
  for (const auto& e : fs::directory_iterator(dir / "constant")) {
    if (e.path().extension() != ".exr") continue;
    const std::vector<float> x = exr_pixels(e.path()), y = exr_pixels(dir / "image" / e.path().filename());
    ASSERT_FALSE(x.empty()) << e.path();
    EXPECT_EQ(x, y) << e.path().filename();
    ++compared;
  }
  EXPECT_GE(compared, 2);  // p2's layers and the reference's
  fs::remove_all(dir);
}

}  // namespace

namespace {

// Thin fields: a 70000 x 2 height image must not make the bake allocate 39 GB, nor a 20000 x 2 field with
// lsao take 9.5 GB and 161 s while 2 x 70000 takes 0.4 s (line sweeps that walk every column of every line
// grow with the long side squared). Both orientations of a 20000 x 2 image validate with an
// estimate near the process's fixed part (150 MiB: an EXR heights file loads OpenImageIO) and bake (exit 0)
// in that memory: the Release build's peak stays within the estimate (the sweep's own work count is
// tests/sweep SweepThin).
// A header that declares more texels than the machine holds, let through by a --memory-limit above the
// machine's memory (here 2 GiB of address space): one line at /height/image naming the declared size, not an
// allocator's exception.
TEST(DeclaredSize, AHeaderDeclaringMoreThanMemoryHoldsIsOneLineAtTheImage) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer maps more address space than the limit";
#endif
  const fs::path dir =
      fs::temp_directory_path() / ("hfbake_declared_" + std::to_string(std::random_device{}()));
  fs::create_directories(dir);
  std::ofstream(dir / "huge.pgm", std::ios::binary) << "P5\n100000 100000\n65535\n" << std::string(4, '\1');
  const std::string job = image_job(dir, "huge.pgm");
  const HfbakeRun r = run_hfbake(dir, {"validate", job, "--memory-limit", "900G", "--quiet"}, 0, 2L << 30);
  fs::remove_all(dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const auto lines = r.error_lines();
  ASSERT_EQ(lines.size(), 1u) << r.err;
  EXPECT_EQ(lines[0].rfind(job + ": /height/image: huge.pgm: its 100000x100000 texels do not fit", 0), 0u)
      << lines[0];
}

TEST(ThinField, BothOrientationsOfA20000x2ImageBakeWithinTheEstimate) {
  const fs::path dir = fs::temp_directory_path() / ("hfbake_thin_" + std::to_string(std::random_device{}()));
  fs::create_directories(dir);
  const int long_side = 20000;
  for (bool wide : {true, false}) {
    const int w = wide ? long_side : 2, h = wide ? 2 : long_side;
    std::vector<float> px(std::size_t(w) * h);
    for (std::size_t i = 0; i < px.size(); ++i) px[i] = float((i * 2654435761u) % 1000) / 1000.0f;
    write_image(dir / "thin.exr", w, h, 1, px);
    json j = base_job();
    j["height"] = {{"image", "thin.exr"}};
    j["bake"] = {{{"method", "lsao"}, {"directions", 16}, {"layers", {"obscurance"}}}};
    const std::string job = write_job(dir, j);
    const HfbakeRun v = run_hfbake(dir, {"validate", job});
    ASSERT_EQ(v.exit_code, 0) << v.err;
    const std::size_t at = v.err.find("about ");
    ASSERT_NE(at, std::string::npos) << v.err;
    const double estimate_mib = std::stod(v.err.substr(at + 6));
    EXPECT_LT(estimate_mib, 200) << v.err;  // the process's fixed 150 MiB, a few MiB for the field
    const HfbakeRun r = run_hfbake(dir, {"bake", job, "--no-cache", "--quiet", "--threads", "2"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(fs::exists(dir / "out" / "t.lsao.exr"));
#if !defined(__SANITIZE_ADDRESS__)
    EXPECT_LE(r.max_rss_kb / 1024.0, estimate_mib) << (wide ? "wide" : "tall");
#endif
    fs::remove_all(dir / "out");
  }
  fs::remove_all(dir);
}

}  // namespace

namespace {

// A full disk under the last buffered write of an EXR: OpenEXR flushes its stream when the file closes and
// does not look at the result, so a truncated EXR (1 KiB of a 2 KiB file) was moved into place and the bake
// exited 0. Every EXR is read back (header and chunk table) before it is moved into place: the bake fails
// with one line naming the EXR, and leaves no output folder and no temporary.
TEST(FullDisk, AnExrCutShortByTheDiskIsNeverMovedIntoPlace) {
  const fs::path dir = fs::temp_directory_path() / ("hfbake_full_" + std::to_string(std::random_device{}()));
  fs::create_directories(dir);
  const std::string job = write_job(dir, base_job());
  const HfbakeRun r =
      run_hfbake(dir, {"bake", job, "--no-cache", "--quiet", "--summary", (dir / "s.json").string()}, 1024);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const auto lines = r.error_lines();
  ASSERT_EQ(lines.size(), 1u) << r.err;
  EXPECT_NE(lines[0].find("t.p1.exr: cannot write the EXR"), std::string::npos) << lines[0];
  // It names the output asked for, not the held folder the writer was given (/proc/self/fd/N).
  EXPECT_NE(lines[0].find((dir / "out" / "t.p1.exr").string() + ": cannot write"), std::string::npos)
      << lines[0];
  EXPECT_EQ(lines[0].find("/proc/self/fd"), std::string::npos) << lines[0];
  // The job is not at fault: "failed" (a farm may retry elsewhere), not "invalid".
  std::ifstream summary(dir / "s.json");
  EXPECT_EQ(json::parse(summary)["jobs"][0]["status"], "failed");
  EXPECT_TRUE(listing(dir / "out").empty()) << "the output folder is left behind";
  for (const auto& p : listing(dir)) EXPECT_EQ(p.find(".tmp"), std::string::npos) << p;
  fs::remove_all(dir);
}

// A full disk under a texture: OpenImageIO's PNG and TGA writers do not check what their writes return, so
// only the checked file they write through (io/oiio_module.cpp) keeps a cut texture from being moved into
// place; a TIFF is read back. The height's normal texture, written while the scene loads (before any EXR):
// the bake fails with one line naming the texture and leaves no output folder.
TEST(FullDisk, ATextureCutShortByTheDiskFailsTheBakeNamingIt) {
  for (const std::string format : {"png", "tga", "tif"}) {
    SCOPED_TRACE(format);
    const fs::path dir =
        fs::temp_directory_path() / ("hfbake_full_texture_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir);
    json j = base_job();
    j["height"]["procedural"]["size"] = {64, 64};
    j["output"]["textures"] = {{{"layers", {"normal"}}, {"methods", {"height"}}, {"format", format}}};
    const std::string job = write_job(dir, j);
    const HfbakeRun r = run_hfbake(dir, {"bake", job, "--no-cache", "--quiet"}, 1024);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    const auto lines = r.error_lines();
    ASSERT_EQ(lines.size(), 1u) << r.err;
    EXPECT_NE(lines[0].find("textures/t.height.normal." + format + ": cannot write the texture"),
              std::string::npos)
        << lines[0];
    EXPECT_TRUE(listing(dir / "out").empty()) << "the output folder is left behind";
    fs::remove_all(dir);
  }
}

}  // namespace
