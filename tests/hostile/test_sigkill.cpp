// SIGKILL at random moments (the OOM killer, a node failure): 20 bakes of one output folder, each
// killed at a random moment of its run. After every kill:
//   - every file a later bake or `hfbake compare` reads as an output is whole: each EXR and PNG decodes,
//     report.json parses, and `compare` on the folder reads no report but the committed one (never one in
//     a staging folder);
//   - the next bake of the same folder succeeds, removes the killed bake's staging folder, and leaves no
//     staging folder of its own.
// The moments come from a fixed seed (reproducible), spread over the measured length of a whole bake. The
// second test does the same to a bake with a long reference, which resumes from its checkpoints.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>
#include "exr_pixels.hpp"

#include <OpenImageIO/imageio.h>
#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"

namespace {
namespace fs = std::filesystem;

pid_t start(const std::vector<std::string>& args, const fs::path& err) {
  return hfbake_test::start_hfbake(args, err);
}

using hfbake_test::is_stage;
using hfbake_test::stages_in;
using hfbake_test::wait_exit;

// The files outside staging folders: what a later bake or compare can take for outputs.
std::vector<fs::path> visible_files(const fs::path& dir) {
  std::vector<fs::path> out;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec)) {
    if (it->is_directory() && is_stage(it->path())) {
      it.disable_recursion_pending();
      continue;
    }
    if (it->is_regular_file()) out.push_back(it->path());
  }
  return out;
}

// A whole output: an image that decodes completely, or JSON that parses.
::testing::AssertionResult whole(const fs::path& p) {
  const std::string ext = p.extension().string();
  if (ext == ".json") {
    std::ifstream in(p);
    if (nlohmann::json::parse(in, nullptr, false).is_discarded())
      return ::testing::AssertionFailure() << p << " is not whole JSON";
    return ::testing::AssertionSuccess();
  }
  if (ext == ".exr" || ext == ".png") {
    auto in = OIIO::ImageInput::open(p.string());
    if (!in) return ::testing::AssertionFailure() << p << ": " << OIIO::geterror();
    const OIIO::ImageSpec& spec = in->spec();
    std::vector<float> px(std::size_t(spec.width) * spec.height * spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, px.data()) || in->has_error())
      return ::testing::AssertionFailure() << p << " does not decode: " << in->geterror();
    return ::testing::AssertionSuccess();
  }
  if (ext == ".html") return ::testing::AssertionSuccess();
  // The folder's owner files (docs/output_folders.md): a lock (the job's, or the report's of a job with a
  // reference), whatever a killed holder left in it, and the record of the job file whose outputs these are,
  // written whole or not at all.
  if ((p.filename().string().rfind(".hfbake-", 0) == 0 || p.filename() == ".hfbake+report.lock") &&
      ext == ".lock")
    return ::testing::AssertionSuccess();
  if (p.filename().string().rfind(".hfbake-", 0) == 0 && ext == ".job") {
    // Its first line; the outputs its bake wrote follow, one a line.
    std::ifstream in(p);
    const std::string text{std::istreambuf_iterator<char>(in), {}};
    const std::string owner = text.substr(0, text.find('\n'));
    if (owner.empty() || owner.front() != '/' || !fs::exists(owner))
      return ::testing::AssertionFailure() << p << " does not name a job file: " << owner;
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << p << " is not an output hfbake writes";
}

// compare reads the committed report.json only (none in a staging folder). A kill between the report and
// the commit leaves a staged report.json; one is planted every round too (a dead process's stage of job
// `job`). dir/baseline/report.json: a whole report of the job.
void expect_compare_reads_the_committed_report(const fs::path& dir, const fs::path& out,
                                               const std::string& job) {
  {
    const pid_t dead = fork();
    if (dead == 0) _exit(0);
    waitpid(dead, nullptr, 0);
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    const fs::path stage = out / (".hfbake-staging-" + job + "-" + std::to_string(dead) + "@" + host);
    fs::create_directories(stage);
    fs::copy_file(dir / "baseline" / "report.json", stage / "report.json",
                  fs::copy_options::overwrite_existing);
  }
  if (!fs::exists(out / "report.json")) return;
  const fs::path cmp = dir / "compare.json";
  fs::remove(cmp);
  const int code = wait_exit(
      start({"compare", out.string(), (dir / "baseline").string(), "--json", cmp.string(), "--quiet"},
            dir / "compare_err.txt"));
  EXPECT_TRUE(code == 0 || code == 1) << code;
  std::ifstream in(cmp);
  const nlohmann::json c = nlohmann::json::parse(in, nullptr, false);
  ASSERT_FALSE(c.is_discarded());
  for (const auto& comparison : c["comparisons"]) EXPECT_EQ(comparison.value("label", ""), "report.json");
}

TEST(SigKill, TwentyKilledBakesLeaveNothingALaterBakeOrCompareReadsAndTheNextBakeCleansUp) {
  const fs::path dir =
      fs::temp_directory_path() / ("hfbake_sigkill_" + std::to_string(std::random_device{}()));
  fs::create_directories(dir);
  // Methods, previews, a reference, report.json and report.html: every kind of output, written over about
  // a second; the reference cache is this test's own (a killed store must not damage later hits).
  const nlohmann::json job = {
      {"version", 1},
      {"name", "k"},
      {"height", {{"procedural", {{"kind", "fractal"}, {"size", {48, 48}}, {"seed", 5}}}}},
      {"bake",
       {{{"method", "p1"}, {"directions", 8}}, {{"method", "hbao"}, {"directions", 4}, {"radius", 4}}}},
      {"reference", {{"samples", 64}, {"seed", 1}}},
      {"output", {{"dir", "out"}, {"previews", true}}}};
  const fs::path job_file = dir / "k.json", out = dir / "out", err = dir / "stderr.txt";
  std::ofstream(job_file) << job.dump(2);
  const std::vector<std::string> bake = {"bake", job_file.string(), "--quiet", "--cache",
                                         (dir / "cache").string()};
  const std::vector<std::string> bake_no_cache = {"bake", job_file.string(), "--quiet", "--no-cache"};

  // A whole bake and how long it took (exit code 0 asserted by the caller).
  const auto timed_bake = [&](const std::vector<std::string>& args, int& code) {
    const auto t0 = std::chrono::steady_clock::now();
    code = wait_exit(start(args, err));
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  // Whole bakes: their lengths spread the kill moments, the shortest seen (a bake measured while the
  // machine was busier would spread the kills past the end of most later bakes); the first one's report is
  // the baseline compare reads against.
  int code = 0;
  double seconds = timed_bake(bake_no_cache, code);
  ASSERT_EQ(code, 0);
  fs::create_directories(dir / "baseline");
  fs::copy_file(out / "report.json", dir / "baseline" / "report.json");
  seconds = std::min(seconds, timed_bake(bake_no_cache, code));
  ASSERT_EQ(code, 0);
  // A bake that finds its reference in the cache is much shorter: its kills are spread over its own length
  // (one spread for both kinds left most cached bakes finished before the kill on a loaded machine), the
  // shortest of every whole cached bake so far.
  ASSERT_EQ(wait_exit(start(bake, err)), 0);  // fills the cache
  double cached_seconds = timed_bake(bake, code);
  ASSERT_EQ(code, 0);

  std::mt19937 rng(20);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int killed_mid_bake = 0;
  for (int round = 0; round < 20; ++round) {
    SCOPED_TRACE("round " + std::to_string(round));
    // Half the rounds hit the reference cache (short bakes), half compute it (long ones).
    const pid_t pid = start(round % 2 ? bake : bake_no_cache, err);
    std::this_thread::sleep_for(
        std::chrono::duration<double>(unit(rng) * 1.1 * (round % 2 ? cached_seconds : seconds)));
    kill(pid, SIGKILL);
    killed_mid_bake += wait_exit(pid) == -SIGKILL;

    for (const fs::path& p : visible_files(out)) EXPECT_TRUE(whole(p));
    expect_compare_reads_the_committed_report(dir, out, "k");
    // The next bake of the folder succeeds and leaves no staging behind (the killed one's is removed).
    cached_seconds = std::min(cached_seconds, timed_bake(bake, code));
    ASSERT_EQ(code, 0) << "round " << round;
    EXPECT_EQ(stages_in(out), 0);  // the killed bake's and the planted one are removed
    for (const fs::path& p : visible_files(out)) EXPECT_TRUE(whole(p));
    EXPECT_TRUE(fs::exists(out / "report.json"));
  }
  // The moments were spread over whole bakes: most kills hit a running bake (not one already done).
  EXPECT_GE(killed_mid_bake, 10);
  fs::remove_all(dir);
}

// The same with a long reference that checkpoints its bands (cli/reference_checkpoint.hpp): a kill leaves
// band files in the dead bake's stage, which the next bake adopts. They are never taken for outputs, the
// next bake succeeds, resumes from them with the bits of an uninterrupted bake, and leaves no stage (nor
// checkpoint) behind.
TEST(SigKill, TwentyKilledReferenceBakesResumeAndLeaveNothingALaterBakeOrCompareReads) {
  const fs::path dir =
      fs::temp_directory_path() / ("hfbake_sigkill_ref_" + std::to_string(std::random_device{}()));
  fs::create_directories(dir);
  const nlohmann::json job = {
      {"version", 1},
      {"name", "r"},
      {"height", {{"procedural", {{"kind", "fractal"}, {"size", {96, 96}}, {"seed", 5}}}}},
      {"bake", {{{"method", "p1"}, {"directions", 8}}}},
      {"reference", {{"samples", 256}, {"seed", 1}, {"layers", {"ao", "vsky"}}}},
      {"output", {{"dir", "out"}, {"pixel_type", "float"}}}};
  const fs::path job_file = dir / "r.json", out = dir / "out", err = dir / "stderr.txt";
  std::ofstream(job_file) << job.dump(2);
  const std::vector<std::string> bake = {"bake", job_file.string(), "--quiet", "--no-cache"};

  // An uninterrupted bake's time, the shorter of two: the first pays for cold caches (up to twice the
  // second on a loaded machine), and kill moments spread over it would miss the later, faster bakes.
  double seconds = 0;
  for (int run = 0; run < 2; ++run) {
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_EQ(wait_exit(start(bake, err)), 0);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    seconds = run == 0 ? s : std::min(seconds, s);
  }
  fs::create_directories(dir / "baseline");
  fs::copy_file(out / "report.json", dir / "baseline" / "report.json");
  const std::vector<float> truth = exr_pixels(out / "r.reference.exr");
  ASSERT_FALSE(truth.empty());

  std::mt19937 rng(21);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int killed_mid_bake = 0;
  for (int round = 0; round < 20; ++round) {
    SCOPED_TRACE("round " + std::to_string(round));
    const pid_t pid = start(bake, err);
    std::this_thread::sleep_for(std::chrono::duration<double>(unit(rng) * 1.1 * seconds));
    kill(pid, SIGKILL);
    killed_mid_bake += wait_exit(pid) == -SIGKILL;
    for (const fs::path& p : visible_files(out)) EXPECT_TRUE(whole(p));
    expect_compare_reads_the_committed_report(dir, out, "r");
    ASSERT_EQ(wait_exit(start(bake, err)), 0) << "round " << round;
    EXPECT_EQ(stages_in(out), 0);
    for (const fs::path& p : visible_files(out)) EXPECT_TRUE(whole(p));
    const std::vector<float> now = exr_pixels(out / "r.reference.exr");
    EXPECT_TRUE(now.size() == truth.size() && std::memcmp(now.data(), truth.data(), 4 * now.size()) == 0);
  }
  EXPECT_GE(killed_mid_bake, 10);
  fs::remove_all(dir);
}

}  // namespace
