// A long reference resumes after a SIGKILL: the bake checkpoints every finished band of
// rows into its staging folder, and the next bake of the same job into the same folder takes the killed
// bake's bands instead of tracing them. Checked against independent truth, an uninterrupted bake of the same
// job: the resumed reference has the same bits (every channel, float pixels), and the summary shows it
// traced fewer bands. Damaged and foreign checkpoints (another seed of the job) are ignored: their bands are
// traced again, with the same bits.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>
#include "exr_pixels.hpp"

#include <OpenImageIO/imageio.h>
#include <sys/stat.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"

namespace {
namespace fs = std::filesystem;
using nlohmann::json;

pid_t start(const fs::path& dir, const std::vector<std::string>& args) {
  return hfbake_test::start_hfbake(args, dir / "stderr.txt", dir, 300);
}

using hfbake_test::is_stage;
using hfbake_test::stages_in;
using hfbake_test::wait_exit;

// The band files in the output folder's staging folders.
std::vector<fs::path> checkpoints(const fs::path& out) {
  std::vector<fs::path> files;
  std::error_code ec;
  for (fs::directory_iterator it(out, ec), end; !ec && it != end; it.increment(ec)) {
    if (!is_stage(it->path())) continue;
    std::error_code inner;
    for (fs::directory_iterator f(it->path() / "reference-checkpoint", inner), fend; !inner && f != fend;
         f.increment(inner))
      if (f->path().extension() == ".hfckpt") files.push_back(f->path());
  }
  return files;
}

// Starts a bake and SIGKILLs it as soon as `bands` band files exist. True when it was killed mid-reference.
bool bake_and_kill(const fs::path& dir, const std::string& job, const fs::path& out, std::size_t bands) {
  const pid_t pid = start(dir, {"bake", job, "--quiet", "--no-cache", "--out", out.string()});
  const auto t0 = std::chrono::steady_clock::now();
  while (checkpoints(out).size() < bands &&
         std::chrono::steady_clock::now() - t0 < std::chrono::seconds(240)) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) return false;  // finished (or failed) before any kill
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  kill(pid, SIGKILL);
  return wait_exit(pid) == -SIGKILL;
}

// Bakes to the end with a summary; the reference's "bands" object ({} if the bake failed).
json bake_summary(const fs::path& dir, const std::string& job, const fs::path& out) {
  const fs::path summary = dir / "summary.json";
  fs::remove(summary);
  const int code = wait_exit(start(
      dir, {"bake", job, "--quiet", "--no-cache", "--out", out.string(), "--summary", summary.string()}));
  EXPECT_EQ(code, 0);
  std::ifstream in(summary);
  const json s = json::parse(in, nullptr, false);
  if (s.is_discarded() || s["jobs"].empty()) return json::object();
  return s["jobs"][0]["methods"]["reference"].value("bands", json::object());
}

// Bit-identical floats (NaN-safe: compared as bytes).
::testing::AssertionResult same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  if (a.empty() || a.size() != b.size())
    return ::testing::AssertionFailure() << "sizes " << a.size() << " and " << b.size();
  for (std::size_t k = 0; k < a.size(); ++k)
    if (std::memcmp(&a[k], &b[k], sizeof(float)) != 0)
      return ::testing::AssertionFailure() << "value " << k << ": " << a[k] << " vs " << b[k];
  return ::testing::AssertionSuccess();
}

class ReferenceResume : public ::testing::Test {
 protected:
  // A reference-only job of 8 bands (128 x 128 texels, bands of 16 rows) that traces for a few seconds, with
  // float pixels so the comparison sees every bit of the reference; its uninterrupted bake, once.
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("hfbake_resume_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
    for (int seed : {1, 2}) {
      const json job = {
          {"version", 1},
          {"name", "r"},
          {"height", {{"procedural", {{"kind", "fractal"}, {"size", {128, 128}}, {"seed", 5}}}}},
          {"bake", json::array()},
          {"reference", {{"samples", 256}, {"seed", seed}, {"layers", {"ao", "vsky"}}}},
          {"output", {{"pixel_type", "float"}}}};
      std::ofstream(dir_ / ("seed" + std::to_string(seed) + ".json")) << job.dump(2);
    }
    const json whole = bake_summary(dir_, "seed1.json", dir_ / "whole");
    EXPECT_EQ(whole.value("traced", -1), kBands);
    truth_ = exr_pixels(dir_ / "whole" / "r.reference.exr");
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  void SetUp() override {
    ASSERT_FALSE(truth_.empty());
    fs::remove_all(dir_ / "out");
  }

  static constexpr int kBands = 8;
  static inline fs::path dir_;
  static inline std::vector<float> truth_;  // the uninterrupted bake's reference
};

TEST_F(ReferenceResume, AKilledReferenceResumesWithTheSameBitsAndTracesFewerBands) {
  const fs::path out = dir_ / "out";
  ASSERT_TRUE(bake_and_kill(dir_, "seed1.json", out, 2));
  const std::size_t left = checkpoints(out).size();
  ASSERT_GE(left, 2u);
  ASSERT_LT(left, std::size_t(kBands));
  const json bands = bake_summary(dir_, "seed1.json", out);
  EXPECT_EQ(bands.value("resumed", -1), int(left));
  EXPECT_EQ(bands.value("traced", -1), kBands - int(left));
  EXPECT_TRUE(same_bits(exr_pixels(out / "r.reference.exr"), truth_));
  EXPECT_EQ(stages_in(out), 0);  // the killed bake's stage and its checkpoints are gone
  // The next bake starts afresh (nothing left to resume) and still gives the same bits.
  EXPECT_EQ(bake_summary(dir_, "seed1.json", out).value("resumed", -1), 0);
  EXPECT_TRUE(same_bits(exr_pixels(out / "r.reference.exr"), truth_));
}

TEST_F(ReferenceResume, DamagedCheckpointsAreTracedAgain) {
  const fs::path out = dir_ / "out";
  ASSERT_TRUE(bake_and_kill(dir_, "seed1.json", out, 3));
  std::vector<fs::path> files = checkpoints(out);
  ASSERT_GE(files.size(), 3u);
  // One band with a flipped payload byte, one truncated, one replaced by a FIFO: all three traced again.
  {
    std::fstream f(files[0], std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(100);
    char c = 0;
    f.seekg(100);
    f.get(c);
    f.seekp(100);
    f.put(char(c ^ 0x10));
  }
  fs::resize_file(files[1], fs::file_size(files[1]) - 1);
  fs::remove(files[2]);
  ASSERT_EQ(mkfifo(files[2].c_str(), 0644), 0);
  const json bands = bake_summary(dir_, "seed1.json", out);
  EXPECT_EQ(bands.value("resumed", -1), int(files.size()) - 3);
  EXPECT_EQ(bands.value("traced", -1), kBands - (int(files.size()) - 3));
  EXPECT_TRUE(same_bits(exr_pixels(out / "r.reference.exr"), truth_));
  EXPECT_EQ(stages_in(out), 0);
}

TEST_F(ReferenceResume, AnotherJobsCheckpointsAreNotTaken) {
  // The job with another seed (the same name, folder and band layout) is killed; the seed-1 bake must not
  // take its bands: it traces all of them and matches its own uninterrupted bake.
  const fs::path out = dir_ / "out";
  ASSERT_TRUE(bake_and_kill(dir_, "seed2.json", out, 2));
  ASSERT_GE(checkpoints(out).size(), 2u);
  const json bands = bake_summary(dir_, "seed1.json", out);
  EXPECT_EQ(bands.value("resumed", -1), 0);
  EXPECT_EQ(bands.value("traced", -1), kBands);
  EXPECT_TRUE(same_bits(exr_pixels(out / "r.reference.exr"), truth_));
  EXPECT_EQ(stages_in(out), 0);
}

}  // namespace
