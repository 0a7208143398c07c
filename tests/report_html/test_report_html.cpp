// report.html: the PNG encoder (io/preview.hpp, OpenImageIO in memory) is checked by decoding its bytes
// from a file, the down-sampling against brute-force box means, base64 by RFC 4648's vectors, and the
// page by a real browser: headless Chromium loads it from disk with the network disabled, must log no
// console message, must decode every image and render the tables, and leaves a screenshot behind.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <OpenImageIO/imageio.h>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>

#include "core/error.hpp"
#include "io/preview.hpp"
#include "report/report_document.hpp"
#include "report/report_html.hpp"

namespace hfbake {
namespace {

// The report fields every fixture here shares: a test version, the job `name`, a 64-sample reference.
ReportSpec fixture_spec(const std::string& name) {
  ReportSpec spec;
  spec.hfbake_version = "0.1.0-test";
  spec.job_name = name;
  spec.job_file = "jobs/" + name + ".json";
  spec.job_hash = "0123456789abcdef";
  spec.reference_parameters = {{"samples", 64}, {"seed", 1}};
  return spec;
}
namespace fs = std::filesystem;

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

class TempDir {
 public:
  TempDir()
      : dir_(fs::temp_directory_path() / ("hfbake_test_html_" + std::to_string(std::random_device{}()))) {
    fs::create_directories(dir_);
  }
  ~TempDir() { fs::remove_all(dir_); }
  const fs::path& path() const { return dir_; }

 private:
  fs::path dir_;
};

TEST(ReportHtml, Base64MatchesRfc4648) {
  EXPECT_EQ(base64(""), "");
  EXPECT_EQ(base64("f"), "Zg==");
  EXPECT_EQ(base64("fo"), "Zm8=");
  EXPECT_EQ(base64("foo"), "Zm9v");
  EXPECT_EQ(base64("foob"), "Zm9vYg==");
  EXPECT_EQ(base64("fooba"), "Zm9vYmE=");
  EXPECT_EQ(base64("foobar"), "Zm9vYmFy");
  EXPECT_EQ(base64(std::string("\xff\xfe\x00", 3)), "//4A");
}

TEST(ReportHtml, PngDecodesToTheSamePixels) {
  TempDir tmp;
  for (int channels : {1, 3}) {
    const int w = 13, h = 7;
    std::vector<std::uint8_t> px(std::size_t(w) * h * channels);
    for (std::size_t i = 0; i < px.size(); ++i) px[i] = std::uint8_t((i * 37 + 11) % 256);
    const fs::path p = tmp.path() / ("img" + std::to_string(channels) + ".png");
    std::ofstream(p, std::ios::binary) << encode_png(w, h, channels, px);
    auto in = OIIO::ImageInput::open(p.string());
    ASSERT_TRUE(in) << OIIO::geterror();
    const OIIO::ImageSpec& spec = in->spec();
    EXPECT_EQ(spec.width, w);
    EXPECT_EQ(spec.height, h);
    EXPECT_EQ(spec.nchannels, channels);
    std::vector<std::uint8_t> back(px.size());
    ASSERT_TRUE(in->read_image(0, 0, 0, channels, OIIO::TypeDesc::UINT8, back.data()));
    EXPECT_EQ(back, px);
  }
  EXPECT_THROW(encode_png(2, 2, 4, std::vector<std::uint8_t>(16)), std::invalid_argument);
  EXPECT_THROW(encode_png(2, 2, 1, std::vector<std::uint8_t>(3)), std::invalid_argument);
}

// When the sizes divide, the box filter gives each output texel the mean of its f x f block of input.
TEST(ReportHtml, BoxResizeIsTheBlockMean) {
  for (const auto& [w, h, f, nc] :
       {std::array<int, 4>{12, 8, 4, 1}, std::array<int, 4>{9, 6, 3, 3}, std::array<int, 4>{10, 10, 2, 3}}) {
    std::vector<float> px(std::size_t(w) * h * nc);
    for (std::size_t i = 0; i < px.size(); ++i) px[i] = float((i * 7919 + 13) % 101) / 100.0f;
    const int ow = w / f, oh = h / f;
    const std::vector<float> out = resize_pixels(px, w, h, nc, ow, oh, "box");
    ASSERT_EQ(out.size(), std::size_t(ow) * oh * nc);
    for (int oy = 0; oy < oh; ++oy)
      for (int ox = 0; ox < ow; ++ox)
        for (int c = 0; c < nc; ++c) {
          double sum = 0;
          for (int y = oy * f; y < oy * f + f; ++y)
            for (int x = ox * f; x < ox * f + f; ++x) sum += px[(std::size_t(y) * w + x) * nc + c];
          EXPECT_NEAR(out[(std::size_t(oy) * ow + ox) * nc + c], sum / (f * f), 1e-5)
              << w << "x" << h << " f " << f << " at " << ox << "," << oy << "," << c;
        }
  }
  // A constant stays constant at any ratio; the same size is returned unchanged.
  const std::vector<float> flat(37 * 23, 0.25f);
  for (float v : resize_pixels(flat, 37, 23, 1, 11, 7, "box")) EXPECT_NEAR(v, 0.25f, 1e-6);
  EXPECT_EQ(resize_pixels(flat, 37, 23, 1, 37, 23), flat);
  EXPECT_THROW(resize_pixels(flat, 37, 22, 1, 11, 7), std::invalid_argument);
}

TEST(ReportHtml, DivergingScaleEndsAndMiddle) {
  std::uint8_t c[3];
  diverging_colour(0, c);
  EXPECT_EQ(c[0], c[1]);  // neutral grey at zero
  EXPECT_EQ(c[1], c[2]);
  diverging_colour(-1, c);
  EXPECT_GT(c[2], c[0]);  // blue below
  diverging_colour(1, c);
  EXPECT_GT(c[0], c[2]);  // red above
  std::uint8_t d[3];
  diverging_colour(5, d);  // clamped
  EXPECT_EQ(std::vector<int>(c, c + 3), std::vector<int>(d, d + 3));
}

TEST(ReportHtml, PlotHasOnePolylinePerSeriesAndLogTicks) {
  const std::string svg = svg_line_plot("p1 ao", "directions", "error",
                                        {{"rmse", "#f00", {{4, 0.1}, {8, 0.05}, {16, 0.025}}, false},
                                         {"noise", "#777", {{4, 0.001}, {16, 0.001}}, true}},
                                        true, true);
  EXPECT_EQ(std::count(svg.begin(), svg.end(), '\n'), 0);
  std::size_t polylines = 0;
  for (std::size_t p = svg.find("<polyline"); p != std::string::npos; p = svg.find("<polyline", p + 1))
    ++polylines;
  EXPECT_EQ(polylines, 2u);
  EXPECT_NE(svg.find("(log)"), std::string::npos);
  EXPECT_NE(svg.find(">16<"), std::string::npos);    // x ticks at the swept values
  EXPECT_NE(svg.find(">0.01<"), std::string::npos);  // a decade tick on y
  // A non-positive value makes the axis linear.
  const std::string lin = svg_line_plot("t", "x", "y", {{"a", "#000", {{1, 0}, {2, 1}}, false}}, true, true);
  EXPECT_EQ(lin.find("y (log)"), std::string::npos);
}

// A small job's worth of data: a reference (ao, direct, their stderr) and a three-run sweep of "p1".
struct Fixture {
  int w = 48, h = 40;
  LayerSet reference;
  std::vector<LayerSet> runs;
  nlohmann::json report;
  std::vector<HtmlMethod> methods;

  Fixture() {
    reference.width = w, reference.height = h;
    Layer& ao = reference.add("ao", mono_channels());
    Layer& direct = reference.add("direct", rgb_channels());
    Layer& ao_err = reference.add("ao_stderr", mono_channels());
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const std::size_t i = std::size_t(y) * w + x;
        ao.data[i] = float(0.6 + 0.3 * std::sin(x * 0.2) * std::cos(y * 0.15));
        for (int c = 0; c < 3; ++c) direct.data[3 * i + c] = float((0.5 + 0.1 * c) * ao.data[i]);
        ao_err.data[i] = 0.002f;
      }
    const int ks[] = {4, 8, 16};
    std::vector<ReportMethodInput> inputs;
    runs.resize(3);
    for (int r = 0; r < 3; ++r) {
      LayerSet& s = runs[r];
      s.width = w, s.height = h;
      Layer& a = s.add("ao", mono_channels());
      Layer& d = s.add("direct", rgb_channels());
      s.add("horizon", indexed_channels(ks[r]));  // no reference layer: listed as not compared
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          const std::size_t i = std::size_t(y) * w + x;
          const float e = float(0.08 / ks[r] * std::sin(0.5 * x + y));  // error halves with K
          a.data[i] = reference.layers[0].data[i] + e;
          for (int c = 0; c < 3; ++c) d.data[3 * i + c] = reference.layers[1].data[3 * i + c] - e;
        }
    }
    for (int r = 0; r < 3; ++r) {
      const std::string stem = "p1-directions" + std::to_string(ks[r]);
      inputs.push_back({stem, "p1", 0.1 * (r + 1), {{"method", "p1"}, {"directions", ks[r]}}, &runs[r]});
      methods.push_back({stem, "p1", &runs[r], "directions", double(ks[r]), 0});
    }
    ReportSpec spec = fixture_spec("html_fixture");
    spec.reference_seconds = 3.5;
    spec.thresholds = {{"p1-directions16.ao.rmse", 0.01}, {"p1-directions4.ao.rmse", 0.001}};  // one fails
    report = build_report(spec, inputs, reference).doc;
  }

  std::string html() const {
    HtmlInputs in;
    in.report = report;
    in.methods = methods;
    in.reference = &reference;
    return report_html(in);
  }
};

TEST(ReportHtml, PageIsSelfContainedAndComplete) {
  const Fixture f;
  const std::string html = f.html();
  // Nothing is fetched: no external src/href/url(); the only "http" is the SVG namespace name.
  const std::regex external(R"((src|href)\s*=\s*"(https?:|//)|url\(\s*['"]?(https?:|//)|@import)");
  EXPECT_FALSE(std::regex_search(html, external));
  // 3 runs x 2 layers x (method, reference, error) images.
  std::size_t images = 0;
  for (std::size_t p = html.find("<img src=\"data:image/png;base64,"); p != std::string::npos;
       p = html.find("<img src=\"data:image/png;base64,", p + 1))
    ++images;
  EXPECT_EQ(images, 18u);
  for (const char* s : {"html_fixture", "0123456789abcdef", "0.1.0-test", "excess_rmse", "p99", "psnr",
                        "noise", "Convergence", "<svg", "&quot;directions&quot;:16", "horizon", "FAILED"})
    EXPECT_NE(html.find(s), std::string::npos) << s;
}

// Decodes standard base64 (RFC 4648, with padding), independently of the code under test.
std::string unbase64(const std::string& text) {
  const std::string t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::uint32_t acc = 0;
  int bits = 0;
  for (char ch : text) {
    const auto k = t.find(ch);
    if (k == std::string::npos) break;  // '=' padding
    acc = (acc << 6) | std::uint32_t(k), bits += 6;
    if (bits >= 8) bits -= 8, out.push_back(char((acc >> bits) & 0xff));
  }
  return out;
}

// The images of a page, decoded by OpenImageIO from their data URIs: (width, height, channels, pixels).
struct Decoded {
  int w = 0, h = 0, nc = 0;
  std::vector<std::uint8_t> px;
};
std::vector<Decoded> page_images(const std::string& html, const fs::path& dir) {
  std::vector<Decoded> out;
  const std::string tag = "<img src=\"data:image/png;base64,";
  for (std::size_t p = html.find(tag); p != std::string::npos; p = html.find(tag, p + 1)) {
    const std::size_t b = p + tag.size(), e = html.find('"', b);
    const fs::path file = dir / ("page" + std::to_string(out.size()) + ".png");
    std::ofstream(file, std::ios::binary) << unbase64(html.substr(b, e - b));
    auto in = OIIO::ImageInput::open(file.string());
    if (!in) return {};
    Decoded d{in->spec().width, in->spec().height, in->spec().nchannels, {}};
    d.px.resize(std::size_t(d.w) * d.h * d.nc);
    if (!in->read_image(0, 0, 0, d.nc, OIIO::TypeDesc::UINT8, d.px.data())) return {};
    out.push_back(std::move(d));
  }
  return out;
}

// Light goes through the built-in config's default display/view (sRGB, "Standard" = the sRGB curve, the
// closed form below); a scalar layer stays linear grey; a field larger than max_image_size is shown
// box-filtered to that size.
TEST(ReportHtml, LightThroughTheDisplayScalarsLinearAndDownSampled) {
  if (std::getenv("OCIO")) GTEST_SKIP() << "$OCIO is set: the expected view is the built-in config's";
  const int w = 64, h = 32;
  LayerSet ref;
  ref.width = w, ref.height = h;
  Layer& ao = ref.add("ao", mono_channels());
  Layer& direct = ref.add("direct", rgb_channels());
  // Left half a, right half b; the top-right texel of the light sets the display scale (p99.5 = max).
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * w + x;
      ao.data[i] = x < w / 2 ? 0.2f : 0.6f;
      for (int c = 0; c < 3; ++c) direct.data[3 * i + c] = x < w / 2 ? 0.05f * (c + 1) : 0.25f * (c + 1);
    }
  LayerSet run = ref;
  ReportSpec spec;
  spec.hfbake_version = "t";
  spec.job_name = "light";
  const std::vector<ReportMethodInput> inputs{{"m", "m", 0.1, {{"method", "m"}}, &run}};
  HtmlInputs in;
  in.report = build_report(spec, inputs, ref).doc;
  HtmlMethod hm;
  hm.stem = hm.method = "m";
  hm.layers = &run;
  in.methods = {hm};
  in.reference = &ref;
  in.max_image_size = 16;  // 64 x 32 -> 16 x 8: 4 x 4 boxes
  const std::string html = report_html(in);
  EXPECT_NE(html.find("64&times;32 box-filtered to 16&times;8"), std::string::npos);
  TempDir tmp;
  const auto imgs = page_images(html, tmp.path());
  ASSERT_EQ(imgs.size(), 6u);  // ao: method, reference, error; direct: the same
  auto srgb = [](double v) { return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055; };
  for (int k : {0, 1}) {  // ao, scaled by its max 0.6: linear grey
    const Decoded& d = imgs[k];
    ASSERT_EQ(d.w, 16);
    ASSERT_EQ(d.h, 8);
    ASSERT_EQ(d.nc, 1);
    EXPECT_NEAR(d.px[2 * 16 + 1], 255.0 * 0.2 / 0.6, 0.6);
    EXPECT_EQ(d.px[2 * 16 + 12], 255);
  }
  for (int k : {3, 4}) {  // direct, scaled by its max 0.75: the sRGB curve per channel
    const Decoded& d = imgs[k];
    ASSERT_EQ(d.w, 16);
    ASSERT_EQ(d.nc, 3);
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(d.px[3 * (2 * 16 + 1) + c], 255.0 * srgb(0.05 * (c + 1) / 0.75), 1.0) << c;
      EXPECT_NEAR(d.px[3 * (2 * 16 + 12) + c], 255.0 * srgb(0.25 * (c + 1) / 0.75), 1.0) << c;
    }
  }
  // The job's display/view (output.preview_display/_view) is used, as for the PNG previews: "Raw" is linear.
  in.display = "sRGB";
  in.view = "Raw";
  const std::string raw_html = report_html(in);
  EXPECT_NE(raw_html.find("view Raw"), std::string::npos);
  const auto raw = page_images(raw_html, tmp.path());
  ASSERT_EQ(raw.size(), 6u);
  for (int k : {3, 4})
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(raw[k].px[3 * (2 * 16 + 1) + c], 255.0 * 0.05 * (c + 1) / 0.75, 1.0) << c;
      EXPECT_NEAR(raw[k].px[3 * (2 * 16 + 12) + c], 255.0 * 0.25 * (c + 1) / 0.75, 1.0) << c;
    }
  // A view the config does not have is an error naming the job field, not a silent default.
  in.view = "NoSuchView";
  EXPECT_THROW(report_html(in), InputError);
}

// Runs `command`, returns its exit status; stdout and stderr go to files.
int run(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string find_chromium() {
  for (const char* name : {"chromium", "chromium-browser"}) {
    if (run(std::string("command -v ") + name + " >/dev/null 2>&1") == 0) return name;
  }
  return "";
}

// Headless, offline, no profile of its own: the page alone (the user data folder follows the last flag).
const char* const kChromiumFlags =
    " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking"
    " --disable-component-update --disable-sync --disable-extensions --hide-scrollbars"
    " --virtual-time-budget=5000 --enable-logging=stderr --v=0 --user-data-dir=";

TEST(ReportHtml, RendersInHeadlessChromium) {
  const std::string chromium = find_chromium();
  if (chromium.empty()) GTEST_SKIP() << "chromium is not installed (./setup.sh test installs it)";
  TempDir tmp;
  const fs::path page = tmp.path() / "report.html";
  std::ofstream(page) << Fixture().html();
  const std::string flags = kChromiumFlags;

  // One browser run: the DOM after load (the page's own check records how many images decoded) and a
  // screenshot, kept in the build folder.
  const fs::path dom = tmp.path() / "dom.html", log = tmp.path() / "chromium.log";
  const fs::path shot = fs::path(HFBAKE_TEST_BINARY_DIR) / "report_html_screenshot.png";
  fs::remove(shot);
  ASSERT_EQ(run("timeout 120 " + chromium + flags + (tmp.path() / "profile").string() +
                " --window-size=1200,1800 --screenshot=" + shot.string() + " --dump-dom file://" +
                page.string() + " >" + dom.string() + " 2>" + log.string()),
            0)
      << read_file(log);
  const std::string dom_text = read_file(dom), log_text = read_file(log);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(dom_text, m, std::regex(R"re(data-images="(\d+)")re")))
      << dom_text.substr(0, 400);
  const int images = std::stoi(m[1]);
  ASSERT_TRUE(std::regex_search(dom_text, m, std::regex(R"re(data-images-decoded="(\d+)")re")));
  EXPECT_EQ(std::stoi(m[1]), images);
  EXPECT_EQ(images, 18);
  ASSERT_TRUE(std::regex_search(dom_text, m, std::regex(R"re(data-tables="(\d+)")re")));
  EXPECT_GE(std::stoi(m[1]), 5);  // meta, summary, thresholds, one metrics table per run
  // No console message at all (errors, uncaught exceptions, failed loads log as CONSOLE lines).
  std::istringstream lines(log_text);
  for (std::string line; std::getline(lines, line);)
    EXPECT_EQ(line.find(":CONSOLE"), std::string::npos) << line;

  // The screenshot must show more than a blank page.
  auto in = OIIO::ImageInput::open(shot.string());
  ASSERT_TRUE(in) << "no screenshot at " << shot;
  const int w = in->spec().width, h = in->spec().height, nc = in->spec().nchannels;
  EXPECT_EQ(w, 1200);
  std::vector<std::uint8_t> px(std::size_t(w) * h * nc);
  ASSERT_TRUE(in->read_image(0, 0, 0, nc, OIIO::TypeDesc::UINT8, px.data()));
  // Count distinct colours: text, tables and images give many; a blank or error page gives a few.
  std::set<std::uint32_t> colours;
  for (std::size_t i = 0; i + 2 < px.size(); i += nc)
    colours.insert(px[i] << 16 | px[i + 1] << 8 | px[i + 2]);
  EXPECT_GT(colours.size(), 200u);
  std::printf("screenshot: %s (%dx%d, %zu colours)\n", shot.c_str(), w, h, colours.size());
}

// The bent normal's angles as a browser shows them: a method whose bent normal leans 5 degrees from the
// reference's on the left half of the field and 15 degrees on the right (mean 10, p99 and max 15), and a
// radius-limited bent normal listed as not compared, with the reason.
TEST(ReportHtml, BentNormalAnglesInHeadlessChromium) {
  const std::string chromium = find_chromium();
  if (chromium.empty()) GTEST_SKIP() << "chromium is not installed (./setup.sh test installs it)";
  const int w = 32, h = 24;
  const double kDeg = 3.14159265358979323846 / 180.0;
  LayerSet reference, leaning, limited;
  for (LayerSet* s : {&reference, &leaning, &limited}) s->width = w, s->height = h;
  Layer& up = reference.add("bent_normal", xyz_channels());
  Layer& lean = leaning.add("bent_normal", xyz_channels());
  limited.add("bent_normal", xyz_channels());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t t = (std::size_t(y) * w + x) * 3;
      const double a = (x < w / 2 ? 5.0 : 15.0) * kDeg, turn = 0.7 * y;  // leaning in any azimuth
      up.data[t + 2] = 1.0f;
      lean.data[t] = float(std::sin(a) * std::cos(turn));
      lean.data[t + 1] = float(std::sin(a) * std::sin(turn));
      lean.data[t + 2] = float(std::cos(a));
    }
  limited.layers[0].data = lean.data;
  const ReportSpec spec = fixture_spec("bent_fixture");
  const std::vector<ReportMethodInput> inputs = {
      {"p1", "p1", 0.1, {{"method", "p1"}, {"directions", 16}}, &leaning},
      {"hbao", "hbao", 0.1, {{"method", "hbao"}, {"radius", 8}}, &limited, {"step", 8, true, {}}}};
  HtmlInputs in;
  in.report = build_report(spec, inputs, reference).doc;
  in.methods = {{"p1", "p1", &leaning, "", 0, -1}, {"hbao", "hbao", &limited, "", 0, -1}};
  in.reference = &reference;
  TempDir tmp;
  const fs::path page = tmp.path() / "report.html", dom = tmp.path() / "dom.html",
                 log = tmp.path() / "chromium.log";
  std::ofstream(page) << report_html(in);
  ASSERT_EQ(run("timeout 120 " + chromium + kChromiumFlags + (tmp.path() / "profile").string() +
                " --dump-dom file://" + page.string() + " >" + dom.string() + " 2>" + log.string()),
            0)
      << read_file(log);
  const std::string text = read_file(dom);
  // The row of the directions table, as the browser's DOM has it.
  std::smatch m;
  ASSERT_TRUE(std::regex_search(
      text, m,
      std::regex(
          R"re(<tr><td>p1</td><td>bent_normal</td><td>([0-9.]+)</td><td>([0-9.]+)</td><td>([0-9.]+)</td></tr>)re")))
      << text.substr(0, 2000);
  EXPECT_NEAR(std::stod(m[1]), 10.0, 0.01);
  EXPECT_NEAR(std::stod(m[2]), 15.0, 0.01);
  EXPECT_NEAR(std::stod(m[3]), 15.0, 0.01);
  EXPECT_NE(text.find("mean angle"), std::string::npos);
  // The radius-limited bent normal is not scored against the unlimited reference: no row, and the reason.
  EXPECT_EQ(text.find("<tr><td>hbao</td><td>bent_normal</td>"), std::string::npos);
  EXPECT_NE(text.find("radius-limited"), std::string::npos) << text.substr(0, 2000);
}

}  // namespace
}  // namespace hfbake
