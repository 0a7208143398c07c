// The turns the jobs of one call bake in (cli/bake_turns.hpp): together only while their combined estimate
// fits the budget, the process's own part counted once.
#include <gtest/gtest.h>

#include <vector>

#include "cli/bake_turns.hpp"

namespace {

using hfbake::BakeTurns;
using hfbake::JobMemory;

constexpr std::size_t MiB = std::size_t(1) << 20;

TEST(BakeTurns, TheProcessPartIsCountedOnceAndTheLargestOne) {
  EXPECT_EQ(hfbake::combined_peak_bytes({}), 0u);
  EXPECT_EQ(hfbake::combined_peak_bytes({{157 * MiB, 48 * MiB}}), 157 * MiB);
  EXPECT_EQ(hfbake::combined_peak_bytes({{157 * MiB, 48 * MiB}, {157 * MiB, 48 * MiB}}), 266 * MiB);
  // A job that loads OpenImageIO (150 MiB) beside one that does not (48 MiB): the libraries once.
  EXPECT_EQ(hfbake::combined_peak_bytes({{100 * MiB, 48 * MiB}, {200 * MiB, 150 * MiB}}), 252 * MiB);
}

TEST(BakeTurns, JobsBakeTogetherOnlyWhileTheirCombinedPeakFits) {
  const JobMemory job{157 * MiB, 48 * MiB};
  // Three jobs of 157 MiB: 375 MiB at once, 266 MiB for two.
  BakeTurns t = hfbake::plan_bake_turns({job, job, job}, 1024 * MiB);
  EXPECT_EQ(t.turns, (std::vector<std::vector<std::size_t>>{{0, 1, 2}}));
  EXPECT_EQ(t.peak, 375 * MiB);
  EXPECT_EQ(t.all, 375 * MiB);
  t = hfbake::plan_bake_turns({job, job, job}, 300 * MiB);
  EXPECT_EQ(t.turns, (std::vector<std::vector<std::size_t>>{{0, 1}, {2}}));
  EXPECT_EQ(t.peak, 266 * MiB);
  EXPECT_EQ(t.all, 375 * MiB);
  t = hfbake::plan_bake_turns({job, job, job}, 170 * MiB);
  EXPECT_EQ(t.turns, (std::vector<std::vector<std::size_t>>{{0}, {1}, {2}}));
  EXPECT_EQ(t.peak, 157 * MiB);
  // Every turn's peak is within the budget; a job alone over it (refused before baking) stands alone.
  t = hfbake::plan_bake_turns({{60 * MiB, 48 * MiB}, {400 * MiB, 48 * MiB}, {60 * MiB, 48 * MiB}}, 300 * MiB);
  EXPECT_EQ(t.turns, (std::vector<std::vector<std::size_t>>{{0}, {1}, {2}}));
  t = hfbake::plan_bake_turns({{60 * MiB, 48 * MiB}, {60 * MiB, 48 * MiB}, {280 * MiB, 48 * MiB}}, 300 * MiB);
  EXPECT_EQ(t.turns, (std::vector<std::vector<std::size_t>>{{0, 1}, {2}}));
  EXPECT_EQ(t.peak, 280 * MiB);  // all three: 304 MiB
}

// Every job's inputs are read before any bakes, loading the libraries each reads them with: a GeoTIFF job
// (GDAL: 64 MiB of its 162) in a turn of its own still has OpenImageIO (150 MiB) beside it when another job
// of the call reads a PNG. Measured with such a pair: 246 MiB baked in two turns, 260 MiB together.
TEST(BakeTurns, EveryTurnHasTheCallsLibrariesBesideIt) {
  const JobMemory geotiff{162 * MiB, 64 * MiB}, png{166 * MiB, 150 * MiB};
  BakeTurns t = hfbake::plan_bake_turns({geotiff, png}, 300 * MiB);
  EXPECT_EQ(t.turns, (std::vector<std::vector<std::size_t>>{{0, 1}}));
  EXPECT_EQ(t.peak, 264 * MiB);
  EXPECT_TRUE(t.fits);
  t = hfbake::plan_bake_turns({geotiff, png}, 260 * MiB);
  EXPECT_EQ(t.turns, (std::vector<std::vector<std::size_t>>{{0}, {1}}));
  EXPECT_EQ(t.peak, 248 * MiB);  // 150 + 98: the GeoTIFF job's turn
  EXPECT_TRUE(t.fits);
  t = hfbake::plan_bake_turns({png, geotiff}, 170 * MiB);
  EXPECT_EQ(t.peak, 248 * MiB);
  EXPECT_FALSE(t.fits);
  EXPECT_EQ(hfbake::bake_turns_text(t, "the 170 MiB of --memory-limit"),
            "2 jobs need about 248 MiB at the peak even one at a time (the libraries every job's inputs load "
            "stay loaded through the call), more than the 170 MiB of --memory-limit: bake them in calls of "
            "their own");
}

TEST(BakeTurns, ThePlanInOneLine) {
  const JobMemory job{157 * MiB, 48 * MiB};
  EXPECT_EQ(
      hfbake::bake_turns_text(hfbake::plan_bake_turns({job, job}, 1024 * MiB), "the 1 GiB of --memory-limit"),
      "2 jobs bake together: about 266 MiB at the peak, within the 1 GiB of --memory-limit");
  EXPECT_EQ(hfbake::bake_turns_text(hfbake::plan_bake_turns({job, job, job}, 300 * MiB),
                                    "the 300 MiB of --memory-limit"),
            "3 jobs bake in 2 turns (2 + 1 jobs): about 266 MiB at the peak, within the 300 MiB of "
            "--memory-limit (all at once: about 375 MiB)");
}

}  // namespace
