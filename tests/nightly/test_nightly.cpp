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
#include <vector>

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
    nlohmann::json job = job_doc(name);
    if (!report.empty()) job["report"] = report;
    return write_doc(name + ".json", job);
  }
  static nlohmann::json job_doc(const std::string& name) {
    return {{"version", 1},
            {"name", name},
            {"height", {{"procedural", {{"kind", "fractal"}, {"size", {40, 36}}, {"seed", 5}}}}},
            {"environment", {{"uniform", 1.0}}},
            {"bake", {{{"method", "p1"}, {"directions", {4, 8, 16}}, {"layers", {"ao"}}}}},
            {"reference", {{"samples", 256}, {"seed", 1}, {"layers", {"ao"}}}},
            {"output", {{"dir", "out/" + name}}}};
  }
  fs::path write_doc(const std::string& file, const nlohmann::json& job) {
    const fs::path p = dir_ / file;
    std::ofstream(p) << job.dump(2);
    return p;
  }
  // Bakes `job` (written to <file>) and returns its report.json.
  fs::path bake_doc(const std::string& file, const nlohmann::json& job) {
    const Result r = hfbake("bake " + write_doc(file, job).string() + " --no-cache --quiet");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return dir_ / job["output"]["dir"].get<std::string>() / "report.json";
  }
  static std::vector<std::string> error_lines(const std::string& err) {
    std::vector<std::string> lines;
    std::istringstream in(err);
    for (std::string l; std::getline(in, l);)
      if (l.rfind("hfbake: error: ", 0) == 0) lines.push_back(l);
    return lines;
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

// The environment is read through a colour space of $OCIO's config whose LUT file is edited between
// bakes: the reference depends on the LUT's bytes, so the edit misses the cache (a stale reference would
// score the methods against light of another strength), and the LUT put back hits again.
TEST_F(Nightly, AnEditedOcioLutMissesTheReferenceCache) {
  std::ofstream(dir_ / "sky.ppm") << "P3\n4 2\n255\n"
                                  << std::string(8, ' ') + "200 180 160 120 130 140 90 90 90 "
                                  << "250 250 250 60 60 60 30 30 30 10 10 10 100 100 100\n";
  std::ofstream(dir_ / "lut.ocio") << "ocio_profile_version: 2\nsearch_path: \"" << dir_.string()
                                   << "\"\nroles:\n  default: lin\n  scene_linear: lin\n"
                                      "displays:\n  d:\n    - !<View> {name: v, colorspace: lin}\n"
                                      "colorspaces:\n  - !<ColorSpace>\n    name: lin\n"
                                      "  - !<ColorSpace>\n    name: graded\n"
                                      "    to_scene_reference: !<FileTransform> {src: grade.spi1d, "
                                      "interpolation: linear}\n";
  const auto lut = [&](double top) {
    std::ofstream(dir_ / "grade.spi1d")
        << "Version 1\nFrom 0.0 1.0\nLength 2\nComponents 1\n{\n 0.0\n " << top << "\n}\n";
  };
  nlohmann::json doc = job_doc("graded");
  doc["environment"] = {{"latlong", "sky.ppm"}, {"colorspace", "graded"}};
  doc["bake"][0]["layers"] = {"direct"};
  doc["reference"]["layers"] = {"direct"};
  doc["reference"]["samples"] = 16;
  const fs::path job = write_doc("graded.json", doc);
  const std::string args = "bake " + job.string() + " --quiet --cache " + (dir_ / "cache").string() +
                           " --summary " + (dir_ / "summary.json").string();
  const std::string env = "OCIO=" + (dir_ / "lut.ocio").string();
  lut(1.0);
  ASSERT_EQ(hfbake(args, env).exit_code, 0) << read_file(dir_ / "stderr.txt");
  EXPECT_EQ(cache_state(), "miss");
  ASSERT_EQ(hfbake(args, env).exit_code, 0);
  EXPECT_EQ(cache_state(), "hit");
  lut(4.0);
  ASSERT_EQ(hfbake(args, env).exit_code, 0);
  EXPECT_EQ(cache_state(), "miss");
  lut(1.0);
  ASSERT_EQ(hfbake(args, env).exit_code, 0);
  EXPECT_EQ(cache_state(), "hit");
}

// A --cache folder that cannot hold the reference (a file stands at its name): the bake goes on and says so
// as a warning, shown with --quiet too (the next bake will trace the reference again).
TEST_F(Nightly, AnUnusableCacheIsAWarningEvenWhenQuiet) {
  std::ofstream(dir_ / "cache_file") << "not a folder";
  const Result r =
      hfbake("bake " + write_job("unusable").string() + " --quiet --cache " + (dir_ / "cache_file").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("hfbake: warning: unusable: the reference cache cannot keep this reference: "),
            std::string::npos)
      << r.err;
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

// A suite run twice, the second time with p1 broken: exit 1, JUnit failures, the folders compare, and the
// suite's index shows each job's comparison with its baseline and its last results.
TEST_F(Nightly, SuiteWithABrokenMethodExitsOneAndFoldersCompare) {
  // Thresholds the code holds (p1 with 16 directions: rmse about 0.015 against a 256-sample reference);
  // broken on purpose, p1's error grows by 0.05.
  for (const char* name : {"a", "b"}) write_job(name, {{"thresholds", {{"p1-directions16.ao.rmse", 0.03}}}});
  std::ofstream(dir_ / "suite.json") << R"({"version": 1, "suite": "mini", "jobs": ["a.json", "b.json"],
      "output": {"dir": "suite_out"}})";
  const std::string bake = "bake " + (dir_ / "suite.json").string() + " --no-cache --quiet";
  const fs::path out = dir_ / "suite_out", base = dir_ / "suite_baseline";
  // Nine earlier runs in the suite's history: after two more, the oldest has made way (10 are kept).
  nlohmann::json runs = nlohmann::json::array();
  for (int k = 1; k <= 9; ++k)
    runs.push_back({{"finished", "2000-01-0" + std::to_string(k) + "T00:00:00Z"},
                    {"jobs", {{"a", {{"status", "ok"}, {"seconds", 1.0}}}}}});
  fs::create_directories(out);
  std::ofstream(out / "history.json") << nlohmann::json{{"runs", runs}}.dump();
  Result r = hfbake(bake);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_EQ(hfbake("compare " + out.string() + " " + base.string() + " --update-baseline --quiet").exit_code,
            0);
  EXPECT_TRUE(fs::exists(base / "a" / "report.json"));
  EXPECT_TRUE(fs::exists(base / "b" / "report.json"));

  // Job a names its baseline; b names none.
  write_job("a", {{"thresholds", {{"p1-directions16.ao.rmse", 0.03}}},
                  {"baseline", "suite_baseline/a/report.json"}});
  r = hfbake(bake, "HFBAKE_TEST_BREAK=p1");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  const std::string junit = read_file(out / "junit.xml");
  EXPECT_NE(junit.find("<failure"), std::string::npos) << junit;
  EXPECT_NE(junit.find("p1-directions16.ao.rmse"), std::string::npos) << junit;
  r = hfbake("compare " + out.string() + " " + base.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("a/report.json: REGRESSION"), std::string::npos) << r.out;

  // The suite's reports carry a's comparison with its baseline, as a's report.json has it.
  const nlohmann::json a_report = nlohmann::json::parse(read_file(out / "a" / "report.json"));
  const nlohmann::json& regressions = a_report["baseline"]["regressions"];
  ASSERT_FALSE(regressions.empty());
  const nlohmann::json summary = nlohmann::json::parse(read_file(out / "suite.json"));
  ASSERT_EQ(summary["jobs"].size(), 2u);
  EXPECT_EQ(summary["jobs"][0]["baseline"]["regressions"], regressions);
  EXPECT_FALSE(summary["jobs"][1].contains("baseline"));
  // The history: the newest 10 runs, oldest first; this run's a regressed against its baseline.
  const nlohmann::json history = nlohmann::json::parse(read_file(out / "history.json"));
  ASSERT_EQ(history["runs"].size(), 10u);
  EXPECT_EQ(history["runs"][0]["finished"], "2000-01-02T00:00:00Z");
  const nlohmann::json &previous = history["runs"][8]["jobs"], last = history["runs"][9]["jobs"];
  EXPECT_EQ(previous["a"]["status"], "ok");
  EXPECT_EQ(previous["b"]["status"], "ok");
  EXPECT_FALSE(previous["a"].contains("baseline_regressions"));
  EXPECT_EQ(last["a"]["status"], "regressed");
  EXPECT_EQ(last["a"]["baseline_regressions"], regressions.size());
  EXPECT_EQ(last["b"]["status"], "regressed");
  EXPECT_FALSE(last["b"].contains("baseline_regressions"));
  // The index: per job, the baseline comparison (a: the regressed metrics; b: none) and the last 10 results.
  const std::string index = read_file(out / "index.html");
  const std::size_t row_a = index.find("<tr><td>a</td>"), row_b = index.find("<tr><td>b</td>");
  ASSERT_NE(row_a, std::string::npos) << index;
  ASSERT_NE(row_b, std::string::npos) << index;
  const std::string a_row = index.substr(row_a, index.find("</tr>", row_a) - row_a),
                    b_row = index.substr(row_b, index.find("</tr>", row_b) - row_b);
  EXPECT_NE(index.find("last 10 runs"), std::string::npos);
  EXPECT_NE(a_row.find(std::to_string(regressions.size()) +
                       " regressed</span> against suite_baseline/a/report.json"),
            std::string::npos)
      << a_row;
  EXPECT_NE(a_row.find(regressions[0]["key"].get<std::string>()), std::string::npos) << a_row;
  EXPECT_NE(b_row.find("<td>&ndash;</td>"), std::string::npos) << b_row;
  auto count = [](const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count(a_row, ">ok</span>"), 9u) << a_row;  // 8 seeded runs and the first bake
  EXPECT_EQ(count(a_row, ">regressed</span>"), 1u) << a_row;
  EXPECT_EQ(count(b_row, ">ok</span>"), 1u) << b_row;
  EXPECT_EQ(count(b_row, "not in this run"), 8u) << b_row;

  // A damaged history is started afresh, with a warning.
  std::ofstream(out / "history.json") << "{\"runs\": [";
  r = hfbake(bake, "HFBAKE_TEST_BREAK=p1");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("history.json: not a suite history"), std::string::npos) << r.err;
  EXPECT_EQ(nlohmann::json::parse(read_file(out / "history.json"))["runs"].size(), 1u);
}

TEST_F(Nightly, NightlyJobsAreValid) {
  // tests/nightly must keep validating as the method schemas evolve (it is what CI runs every night).
  // validate expands the suite into its jobs. The dem job reads a window of the lidar DEM beside the
  // repository (../shared/data, through tests/nightly/data/dem_400_300_160.vrt), which a checkout may not
  // have: the suite's "needs" entry then skips it with a notice, and the suite stays valid.
  const fs::path nightly = fs::path(HFBAKE_SOURCE_DIR) / "tests" / "nightly";
  const bool have_dem =
      fs::exists(fs::path(HFBAKE_SOURCE_DIR) / ".." / "shared" / "data" / "TM1_564_146.tif");
  const Result r = hfbake("validate " + (nightly / "suite.json").string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find(have_dem ? "suite of 12 jobs" : "suite of 11 jobs"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("dem.json: skipped: ") != std::string::npos, !have_dem) << r.err;
}

// A suite entry's "needs": a job whose file is missing is skipped with a notice (validate and bake, and in
// suite.json); a job whose files are all present runs; a suite whose every job is skipped is an error.
TEST_F(Nightly, SuiteSkipsAJobWhoseDataIsMissing) {
  const fs::path dir = dir_ / "needs";
  fs::create_directories(dir / "fields");
  nlohmann::json a = job_doc("a");
  a["output"] = {{"dir", "out_a"}};
  std::ofstream(dir / "fields" / "a.json") << a.dump();
  nlohmann::json b = job_doc("b");
  b["output"] = {{"dir", "out_b"}};
  std::ofstream(dir / "fields" / "b.json") << b.dump();
  std::ofstream(dir / "present.bin") << "x";
  const nlohmann::json suite = {
      {"version", 1},
      {"suite", "s"},
      {"jobs", {"fields/*.json", {{"job", "fields/b.json"}, {"needs", {"present.bin", "absent/data.tif"}}}}},
      {"output", {{"dir", "out"}}}};
  std::ofstream(dir / "suite.json") << suite.dump();
  Result r = hfbake("validate " + (dir / "suite.json").string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("hfbake: note: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("b.json: skipped: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("data.tif is not on this machine"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("suite of 1 jobs"), std::string::npos) << r.err;

  r = hfbake("bake --quiet --no-cache " + (dir / "suite.json").string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("b.json: skipped: "), std::string::npos) << r.err;
  const nlohmann::json summary = nlohmann::json::parse(read_file(dir / "out" / "suite.json"));
  EXPECT_EQ(summary["jobs"].size(), 1u) << summary.dump();
  ASSERT_EQ(summary["skipped"].size(), 1u) << summary.dump();
  EXPECT_FALSE(fs::exists(dir / "out" / "b"));

  nlohmann::json only_b = suite;
  only_b["jobs"] = {{{"job", "fields/b.json"}, {"needs", {"absent/data.tif"}}}};
  std::ofstream(dir / "suite.json") << only_b.dump();
  r = hfbake("validate " + (dir / "suite.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("every job is skipped"), std::string::npos) << r.err;
}

// A baseline of another job (a wrong path in a nightly) must not pass as "ok: 0 regressed": hfbake compare
// refuses it with one line naming the baseline and what differs, exit 2, unless --allow-different-job.
TEST_F(Nightly, CompareRefusesABaselineOfAnotherJob) {
  const nlohmann::json base = job_doc("a");
  const fs::path baseline = bake_doc("a.json", base);
  struct Case {
    std::string what;  // a phrase the error line must contain
    nlohmann::json job;
  };
  std::vector<Case> cases;
  nlohmann::json other_name = base;
  other_name["name"] = "b";
  cases.push_back({"job name \"a\" (new: \"b\")", other_name});
  nlohmann::json other_field = base;
  other_field["height"]["procedural"]["seed"] = 6;
  cases.push_back({"scene.height.procedural.seed 5 (new: 6)", other_field});
  nlohmann::json other_size = base;
  other_size["height"]["procedural"]["size"] = {36, 36};
  cases.push_back({"field size [40,36] (new: [36,36])", other_size});
  nlohmann::json other_reference = base;
  other_reference["reference"]["samples"] = 128;
  cases.push_back({"reference.samples 256 (new: 128)", other_reference});
  nlohmann::json other_sky = base;
  other_sky["environment"]["uniform"] = 2.0;
  cases.push_back({"scene.environment.uniform", other_sky});
  for (std::size_t i = 0; i < cases.size(); ++i) {
    Case& c = cases[i];
    c.job["output"]["dir"] = "out/case" + std::to_string(i);
    const fs::path report = bake_doc("case" + std::to_string(i) + ".json", c.job);
    Result r = hfbake("compare " + report.string() + " " + baseline.string());
    EXPECT_EQ(r.exit_code, 2) << c.what << "\n" << r.out;
    const std::vector<std::string> lines = error_lines(r.err);
    ASSERT_EQ(lines.size(), 1u) << r.err;
    EXPECT_EQ(lines[0].rfind("hfbake: error: " + baseline.string() + ": a report of another job: ", 0), 0u)
        << lines[0];
    EXPECT_NE(lines[0].find(c.what), std::string::npos) << lines[0];
    EXPECT_EQ(r.out.find("ok:"), std::string::npos) << r.out;
    // Nothing is updated from a refused comparison either.
    const std::string before = read_file(baseline);
    r = hfbake("compare " + report.string() + " " + baseline.string() + " --update-baseline");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_EQ(read_file(baseline), before);
    // Deliberately: compared, with the differences as a note.
    r = hfbake("compare " + report.string() + " " + baseline.string() + " --allow-different-job");
    EXPECT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.err;
    EXPECT_TRUE(error_lines(r.err).empty()) << r.err;
    EXPECT_NE(r.out.find("note: " + baseline.string() + ": a report of another job"), std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find(c.what), std::string::npos) << r.out;
  }
  // Folders: the pair of another job is refused, the others still compared.
  fs::create_directories(dir_ / "new" / "x");
  fs::create_directories(dir_ / "old" / "x");
  fs::copy_file(dir_ / "out" / "case0" / "report.json", dir_ / "new" / "x" / "report.json");
  fs::copy_file(baseline, dir_ / "old" / "x" / "report.json");
  const Result r = hfbake("compare " + (dir_ / "new").string() + " " + (dir_ / "old").string());
  EXPECT_EQ(r.exit_code, 2);
  ASSERT_EQ(error_lines(r.err).size(), 1u) << r.err;
  EXPECT_NE(error_lines(r.err)[0].find((dir_ / "old" / "x" / "report.json").string()), std::string::npos);
}

// The same job with other method parameters is comparable: the changes are listed with the metrics.
TEST_F(Nightly, CompareListsParameterChanges) {
  nlohmann::json job = job_doc("a");
  job["bake"] = {{{"method", "p1"}, {"directions", 8}, {"layers", {"ao"}}}};
  const fs::path baseline = bake_doc("a.json", job);
  job["bake"][0]["directions"] = 16;
  job["bake"][0]["near_radius"] = 3;
  job["output"]["dir"] = "out/a2";
  const fs::path report = bake_doc("a2.json", job);
  const Result r = hfbake("compare " + report.string() + " " + baseline.string() + " --json " +
                          (dir_ / "cmp.json").string());
  EXPECT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.err;  // 16 directions are usually better
  EXPECT_TRUE(error_lines(r.err).empty()) << r.err;
  EXPECT_NE(r.out.find("p1.directions: 8 -> 16"), std::string::npos) << r.out;
  // Resolved parameters: the baseline records p1's default near radius, 2.
  EXPECT_NE(r.out.find("p1.near_radius: 2.0 -> 3.0"), std::string::npos) << r.out;
  const nlohmann::json cmp = nlohmann::json::parse(read_file(dir_ / "cmp.json"));
  const nlohmann::json& changes = cmp["comparisons"][0]["parameter_changes"];
  ASSERT_EQ(changes.size(), 2u) << changes;
  EXPECT_EQ(changes[0], (nlohmann::json{{"key", "p1.directions"}, {"value", 16}, {"baseline", 8}}));
  EXPECT_EQ(changes[1], (nlohmann::json{{"key", "p1.near_radius"}, {"value", 3.0}, {"baseline", 2.0}}));
  EXPECT_TRUE(cmp["comparisons"][0]["job_differences"].empty());
}

// report.baseline follows the same rule, before anything is baked: exit 2, one line, no outputs.
TEST_F(Nightly, ReportBaselineOfAnotherJobIsRefusedBeforeBaking) {
  const fs::path baseline = bake_doc("a.json", job_doc("a"));
  nlohmann::json job = job_doc("a");
  job["height"]["procedural"]["seed"] = 6;
  job["output"]["dir"] = "out/other";
  job["report"] = {{"baseline", "out/a/report.json"}};
  const Result r = hfbake("bake " + write_doc("other.json", job).string() + " --no-cache --quiet");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const std::vector<std::string> lines = error_lines(r.err);
  ASSERT_EQ(lines.size(), 1u) << r.err;
  EXPECT_NE(lines[0].find("other.json: /report/baseline: " + baseline.string() +
                          " is a report of another job: scene.height.procedural.seed 5 (new: 6)"),
            std::string::npos)
      << lines[0];
  EXPECT_FALSE(fs::exists(dir_ / "out" / "other" / "report.json"));
  // The same job naming its own earlier report is compared as before.
  job["height"]["procedural"]["seed"] = 5;
  EXPECT_EQ(hfbake("bake " + write_doc("other.json", job).string() + " --no-cache --quiet").exit_code, 0);
}

}  // namespace
