// `hfbake bake` of a job with a reference and a method writes report.json, valid against
// schemas/report.schema.json; thresholds turn into exit 1; a reference-only job reports too.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <OpenImageIO/imageio.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "job/schema_validation.hpp"

namespace {
namespace fs = std::filesystem;

class ReportCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("hfbake_test_report_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  int bake(const nlohmann::json& job, std::string& err, const std::string& extra = "") {
    const fs::path p = dir_ / "job.json";
    std::ofstream(p) << job.dump(2);
    // A private reference cache, so the test neither reads nor fills the user's.
    const std::string cmd = "XDG_CACHE_HOME=" + (dir_ / "cache").string() + " " + HFBAKE_BINARY + " bake " +
                            p.string() + " --quiet " + extra + " 2>" + (dir_ / "err.txt").string() +
                            " >/dev/null";
    const int status = std::system(cmd.c_str());
    std::ifstream in(dir_ / "err.txt");
    std::stringstream ss;
    ss << in.rdbuf();
    err = ss.str();
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  nlohmann::json report() {
    std::ifstream in(dir_ / "out" / "report.json");
    EXPECT_TRUE(in.good());
    return nlohmann::json::parse(in);
  }

  static nlohmann::json job(nlohmann::json bake, nlohmann::json thresholds = nlohmann::json::object()) {
    return {{"version", 1},
            {"name", "r"},
            {"height", {{"procedural", {{"kind", "pit"}, {"size", {17, 17}}, {"radius", 5}, {"depth", 4}}}}},
            {"environment", {{"uniform", 1}}},
            {"bounces", 0},
            {"bake", bake},
            {"reference", {{"samples", 16}, {"layers", {"ao", "vsky"}}}},
            {"output", {{"dir", "out"}}},
            {"report", {{"crop", 1}, {"thresholds", thresholds}}}};
  }

  fs::path dir_;
};

void expect_valid(const nlohmann::json& doc) {
  const auto violations = hfbake::validate_against_schema(doc, "report.schema.json");
  for (const auto& v : violations) ADD_FAILURE() << v.pointer << ": " << v.message;
}

TEST_F(ReportCli, MethodAndReferenceWriteAValidReport) {
  std::string err;
  const nlohmann::json entries = {
      {{"method", "p1"}, {"directions", 16}, {"layers", {"ao", "vsky", "horizon"}}}};
  ASSERT_EQ(bake(job(entries, {{"p1.ao.rmse", 0.5}}), err), 0) << err;
  const nlohmann::json r = report();
  expect_valid(r);
  EXPECT_TRUE(r["passed"].get<bool>());
  EXPECT_EQ(r["crop"], 1);
  const auto& ao = r["methods"]["p1"]["layers"]["ao"];
  for (const char* m : {"mae", "rmse", "max", "p99", "bias", "noise_rmse", "excess_rmse"})
    EXPECT_TRUE(ao.contains(m)) << m;
  EXPECT_GT(ao["noise_rmse"].get<double>(), 0);  // the pit's walls make the reference noisy
  // The horizons are scored against the reference's own (Embree bisection), by their elevation in degrees.
  EXPECT_EQ(r["methods"]["p1"]["not_compared"], nlohmann::json::array());
  const auto& horizon = r["methods"]["p1"]["layers"]["horizon"];
  ASSERT_TRUE(horizon.contains("angle_p99_deg")) << horizon;
  EXPECT_LT(horizon["angle_p99_deg"].get<double>(), 0.1) << horizon;
  EXPECT_TRUE(fs::exists(dir_ / "out" / "r.reference.exr"));
}

TEST_F(ReportCli, FailedThresholdExitsOne) {
  std::string err;
  const nlohmann::json entries = {{{"method", "p1"}, {"directions", 16}, {"layers", {"ao"}}}};
  EXPECT_EQ(bake(job(entries, {{"p1.ao.max", 1e-9}, {"p1.ao.rmse", 1.0}, {"p1.ao.psnr", 1000}}), err), 1)
      << err;
  EXPECT_NE(err.find("p1.ao.max = "), std::string::npos) << err;
  EXPECT_NE(err.find("p1.ao.psnr = "), std::string::npos) << err;
  const nlohmann::json r = report();  // the outputs are still written: the bake itself succeeded
  expect_valid(r);
  EXPECT_FALSE(r["passed"].get<bool>());
}

// A threshold on a layer the entry does not write: refused before anything is baked (exit 2), naming the
// threshold's key and the entry's layers.
TEST_F(ReportCli, ThresholdTypoIsRefusedNotASilentPass) {
  std::string err;
  const nlohmann::json entries = {{{"method", "p1"}, {"directions", 16}, {"layers", {"ao"}}}};
  EXPECT_EQ(bake(job(entries, {{"p1.occlusion.rmse", 1.0}}), err), 2) << err;
  EXPECT_NE(err.find("/report/thresholds/p1.occlusion.rmse: bake entry \"p1\" writes no layer \"occlusion\" "
                     "(its layers: ao)"),
            std::string::npos)
      << err;
}

TEST_F(ReportCli, ThresholdsOrABaselineWithoutAReferenceAreRefusedNotASilentPass) {
  const nlohmann::json entries = {{{"method", "p1"}, {"directions", 16}, {"layers", {"ao"}}}};
  for (const char* key : {"thresholds", "baseline"}) {
    nlohmann::json j = job(entries, {{"p1.ao.rmse", 1e-9}});
    j.erase("reference");
    if (std::string(key) == "baseline") {
      fs::create_directories(dir_ / "old");
      std::ofstream(dir_ / "old" / "report.json") << "{}";
      j["report"] = {{"baseline", "old/report.json"}};
    }
    std::string err;
    EXPECT_EQ(bake(j, err), 2) << key << ": " << err;
    EXPECT_NE(err.find("/report/" + std::string(key) +
                       ": scores the bake against the reference, but the job "
                       "has none"),
              std::string::npos)
        << err;
    EXPECT_FALSE(fs::exists(dir_ / "out")) << key;
  }
}

TEST_F(ReportCli, ReferenceOnlyJob) {
  std::string err;
  ASSERT_EQ(bake(job(nlohmann::json::array()), err), 0) << err;
  const nlohmann::json r = report();
  expect_valid(r);
  EXPECT_TRUE(r["methods"].empty());
  EXPECT_TRUE(r["reference"]["layers"].contains("vsky"));
}

}  // namespace

namespace {

std::vector<float> read_pixels(const fs::path& p) {
  auto in = OIIO::ImageInput::open(p.string());
  EXPECT_TRUE(in);
  if (!in) return {};
  const OIIO::ImageSpec& spec = in->spec();
  std::vector<float> pixels(std::size_t(spec.width) * spec.height * spec.nchannels);
  EXPECT_TRUE(in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels.data()));
  return pixels;
}

TEST_F(ReportCli, ReferenceBitsDoNotDependOnTheThreadCount) {
  nlohmann::json j = job(nlohmann::json::array());
  j["bounces"] = 1;
  j["height"]["procedural"] = {{"kind", "fractal"}, {"size", {24, 24}}};
  j["environment"] = {{"sky", nlohmann::json::object()}};
  j["reference"] = {{"samples", 16}};
  j["output"]["pixel_type"] = "float";
  std::string err;
  ASSERT_EQ(bake(j, err, "--threads 1"), 0) << err;
  const std::vector<float> one = read_pixels(dir_ / "out" / "r.reference.exr");
  fs::remove_all(dir_ / "out");
  fs::remove_all(dir_ / "cache");
  ASSERT_EQ(bake(j, err, "--threads 2"), 0) << err;
  const std::vector<float> two = read_pixels(dir_ / "out" / "r.reference.exr");
  ASSERT_EQ(one.size(), two.size());
  ASSERT_FALSE(one.empty());
  EXPECT_EQ(0, std::memcmp(one.data(), two.data(), one.size() * sizeof(float)));
}

}  // namespace
