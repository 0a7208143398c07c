// The nightly accuracy regression as a user runs it: hfbake bake (sweeps, report.html, reference cache),
// hfbake compare against a baseline, and a method broken on purpose (HFBAKE_TEST_BREAK) that must turn the
// exit status to 1 and show which metric regressed.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

namespace {
namespace fs = std::filesystem;

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct Result {
  int exit_code = -1;
  std::string out, err;
};

class Nightly : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("hfbake_test_nightly_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }

  Result hfbake(const std::string& args, const std::string& env = "") {
    const fs::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
    const std::string cmd =
        env + " " + HFBAKE_BINARY + " " + args + " >" + out.string() + " 2>" + err.string();
    const int status = std::system(cmd.c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, read_file(out), read_file(err)};
  }

  // A small job: a p1 sweep over three direction counts against one reference.
  fs::path write_job(const std::string& name, const nlohmann::json& report = nlohmann::json::object()) {
    nlohmann::json job = {
        {"version", 1},
        {"name", name},
        {"height", {{"procedural", {{"kind", "fractal"}, {"size", {40, 36}}, {"seed", 5}}}}},
        {"environment", {{"uniform", 1.0}}},
        {"bake", {{{"method", "p1"}, {"directions", {4, 8, 16}}, {"layers", {"ao"}}}}},
        {"reference", {{"samples", 256}, {"seed", 1}, {"layers", {"ao"}}}},
        {"output", {{"dir", "out/" + name}}}};
    if (!report.empty()) job["report"] = report;
    const fs::path p = dir_ / (name + ".json");
    std::ofstream(p) << job.dump(2);
    return p;
  }

  nlohmann::json summary() { return nlohmann::json::parse(read_file(dir_ / "summary.json")); }
  std::string cache_state() { return summary()["jobs"][0]["methods"]["reference"].value("cache", ""); }

  fs::path dir_;
};

TEST_F(Nightly, SweepWritesRunsReportPageAndConvergencePlot) {
  const fs::path job = write_job("sweep");
  const Result r =
      hfbake("bake " + job.string() + " --no-cache --quiet --summary " + (dir_ / "summary.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const fs::path out = dir_ / "out" / "sweep";
  for (const char* f : {"sweep.p1-directions4.exr", "sweep.p1-directions8.exr", "sweep.p1-directions16.exr",
                        "sweep.reference.exr", "report.json", "report.html"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  const nlohmann::json report = nlohmann::json::parse(read_file(out / "report.json"));
  ASSERT_TRUE(report["methods"].contains("p1-directions16"));
  // More directions, less error: the sweep is what the convergence plot shows.
  EXPECT_LT(report["methods"]["p1-directions16"]["layers"]["ao"]["rmse"].get<double>(),
            report["methods"]["p1-directions4"]["layers"]["ao"]["rmse"].get<double>());
  const std::string html = read_file(out / "report.html");
  EXPECT_NE(html.find("Convergence"), std::string::npos);
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_NE(html.find("data:image/png;base64,"), std::string::npos);
  EXPECT_FALSE(summary()["jobs"][0]["methods"]["reference"].contains("cache"));  // --no-cache
}

TEST_F(Nightly, ReferenceCacheMissHitAndDamagedEntryRebuilt) {
  const fs::path job = write_job("cached");
  const std::string args = "bake " + job.string() + " --cache " + (dir_ / "cache").string() + " --summary " +
                           (dir_ / "summary.json").string();
  Result r = hfbake(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(cache_state(), "miss");
  const std::string first_report = read_file(dir_ / "out" / "cached" / "report.json");

  r = hfbake(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(cache_state(), "hit");
  EXPECT_NE(r.err.find("reference cache hit"), std::string::npos) << r.err;
  EXPECT_GT(summary()["jobs"][0]["methods"]["reference"].value("cache_saved_seconds", 0.0), 0.0);
  // The cached reference gives the same metrics, bit for bit.
  const auto a = nlohmann::json::parse(first_report)["methods"],
             b = nlohmann::json::parse(read_file(dir_ / "out" / "cached" / "report.json"))["methods"];
  for (auto& [stem, m] : a.items()) EXPECT_EQ(m["layers"], b[stem]["layers"]) << stem;

  // Damage the entry: detected, recomputed, replaced.
  fs::path entry;
  for (const auto& e : fs::directory_iterator(dir_ / "cache")) entry = e.path();
  ASSERT_FALSE(entry.empty());
  {
    std::fstream io(entry, std::ios::in | std::ios::out | std::ios::binary);
    io.seekp(-8, std::ios::end);
    io.write("garbage!", 8);
  }
  r = hfbake(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(cache_state(), "rebuilt");
  EXPECT_NE(r.err.find("was damaged"), std::string::npos) << r.err;
  r = hfbake(args);
  EXPECT_EQ(cache_state(), "hit");

  // Another sweep of the method shares the reference; a change to what determines the reference misses.
  nlohmann::json doc = nlohmann::json::parse(read_file(job));
  doc["bake"][0]["directions"] = {8, 32};
  std::ofstream(job) << doc.dump(2);
  r = hfbake(args);
  EXPECT_EQ(cache_state(), "hit");
  doc["reference"]["seed"] = 2;
  std::ofstream(job) << doc.dump(2);
  r = hfbake(args);
  EXPECT_EQ(cache_state(), "miss");
}

TEST_F(Nightly, BaselineCompareAndABrokenMethod) {
  const fs::path job = write_job("base");
  ASSERT_EQ(hfbake("bake " + job.string() + " --no-cache --quiet").exit_code, 0);
  const fs::path report = dir_ / "out" / "base" / "report.json",
                 baseline = dir_ / "baselines" / "base.report.json";

  // No baseline yet: an error, never created implicitly.
  Result r = hfbake("compare " + report.string() + " " + baseline.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--update-baseline"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(baseline));
  r = hfbake("compare " + report.string() + " " + baseline.string() + " --update-baseline");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(fs::exists(baseline));
  EXPECT_EQ(hfbake("compare " + report.string() + " " + baseline.string()).exit_code, 0);

  // The job names the baseline; p1 broken on purpose: exit 1, the report and the comparison say what.
  const fs::path job2 = write_job("base", {{"baseline", "baselines/base.report.json"}});
  r = hfbake("bake " + job2.string() + " --no-cache --quiet", "HFBAKE_TEST_BREAK=p1");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("p1-directions16.ao.rmse"), std::string::npos) << r.err;
  const std::string html = read_file(dir_ / "out" / "base" / "report.html");
  EXPECT_NE(html.find("FAILED"), std::string::npos);
  EXPECT_NE(html.find("class=\"bad\""), std::string::npos);
  r = hfbake("compare " + report.string() + " " + baseline.string() + " --json " +
             (dir_ / "cmp.json").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("p1-directions4.ao.rmse"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("REGRESSED"), std::string::npos) << r.out;
  EXPECT_TRUE(nlohmann::json::parse(read_file(dir_ / "cmp.json"))["regression"].get<bool>());
}

TEST_F(Nightly, SuiteWithABrokenMethodExitsOneAndFoldersCompare) {
  // Thresholds the code holds (p1 with 16 directions: rmse about 0.015 against a 256-sample reference);
  // broken on purpose, p1's error grows by 0.05.
  for (const char* name : {"a", "b"}) write_job(name, {{"thresholds", {{"p1-directions16.ao.rmse", 0.03}}}});
  std::ofstream(dir_ / "suite.json") << R"({"version": 1, "suite": "mini", "jobs": ["a.json", "b.json"],
      "output": {"dir": "suite_out"}})";
  const std::string bake = "bake " + (dir_ / "suite.json").string() + " --no-cache --quiet";
  Result r = hfbake(bake);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const fs::path out = dir_ / "suite_out", base = dir_ / "suite_baseline";
  ASSERT_EQ(hfbake("compare " + out.string() + " " + base.string() + " --update-baseline --quiet").exit_code,
            0);
  EXPECT_TRUE(fs::exists(base / "a" / "report.json"));
  EXPECT_TRUE(fs::exists(base / "b" / "report.json"));

  r = hfbake(bake, "HFBAKE_TEST_BREAK=p1");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  const std::string junit = read_file(out / "junit.xml");
  EXPECT_NE(junit.find("<failure"), std::string::npos) << junit;
  EXPECT_NE(junit.find("p1-directions16.ao.rmse"), std::string::npos) << junit;
  r = hfbake("compare " + out.string() + " " + base.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("a/report.json: REGRESSION"), std::string::npos) << r.out;
}

TEST_F(Nightly, NightlyJobsAreValid) {
  // jobs/nightly must keep validating as the method schemas evolve (it is what CI runs every night).
  // validate expands the suite into its jobs.
  const fs::path suite = fs::path(HFBAKE_SOURCE_DIR) / "jobs" / "nightly" / "suite.json";
  const Result r = hfbake("validate " + suite.string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("suite of 7 jobs"), std::string::npos) << r.err;
}

}  // namespace
