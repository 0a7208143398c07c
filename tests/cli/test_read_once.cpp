// A bake entry's parameters are read once, by its method's reader in resolve_job: every later step (the
// bake, the memory estimate, the farm's plan, the reference's options and its relief layers) takes the
// typed config kept on the job. Checked by spoiling the job document after resolve_job: a step that read an
// entry again would fail on the spoiled values or bake something else.
#include <gtest/gtest.h>

#include <filesystem>

#include "cli/method_dispatch.hpp"
#include "cli/scene_loader.hpp"
#include "core/direction_blocks.hpp"
#include "farm/shard_plan.hpp"
#include "methods/p1/p1.hpp"
#include "methods/relief/relief.hpp"

namespace hfbake {
namespace {

namespace fs = std::filesystem;

nlohmann::json job_document() {
  return {
      {"version", 1},
      {"name", "once"},
      {"height", {{"procedural", {{"kind", "fractal"}, {"size", {24, 20}}, {"seed", 2}, {"amplitude", 4}}}}},
      {"bake",
       {{{"method", "p1"}, {"directions", 12}, {"layers", {"horizon", "ao"}}},
        {{"method", "hbao"}, {"directions", 4}, {"radius", 3}},
        {{"method", "relief"}, {"directions", 5}, {"layers", {"horizon_deg"}}}}},
      {"reference", {{"samples", 4}}},
      {"output", {{"dir", fs::temp_directory_path().string()}}}};
}

TEST(ReadOnce, NothingReadsTheJobDocumentsEntriesAfterResolveJob) {
  JobLoad load = load_job_document(job_document(), "once.json", std::nullopt);
  ASSERT_TRUE(load.job) << (load.errors.empty() ? "" : load.errors[0]);
  Job& job = *load.job;
  ASSERT_EQ(resolve_job(job), std::vector<std::string>());
  const std::size_t estimate = estimate_peak_bytes(job, {24, 20});

  // Every entry and the reference spoiled, in the document and in the entries' own copies.
  const nlohmann::json spoiled = {{"directions", "spoiled"},
                                  {"radius", -1},
                                  {"layers", {"nothing"}},
                                  {"samples", "spoiled"},
                                  {"falloff", 7}};
  for (BakeEntry& e : job.bakes) e.params.update(spoiled);
  for (auto& entry : job.doc["bake"]) entry.update(spoiled);
  job.doc["reference"].update(spoiled);

  EXPECT_EQ(estimate_peak_bytes(job, {24, 20}), estimate);
  EXPECT_EQ(entry_direction_blocks(job.bakes[0]), direction_block_count(12));
  EXPECT_EQ(entry_direction_blocks(job.bakes[1]), direction_block_count(4));
  const ReferenceOptions& reference = job_reference_options(job);
  EXPECT_EQ(reference.samples, 4);
  EXPECT_EQ(reference.falloff.kind, FalloffKind::step);  // hbao's, the first obscurance entry's
  EXPECT_EQ(reference.falloff.radius, 3.0);
  EXPECT_EQ(reference.layers, (std::vector<std::string>{"ao", "obscurance", "bent_normal"}));
  EXPECT_EQ(entry_config(job.bakes[0]).get<P1Params>().directions, 12);
  EXPECT_EQ(entry_config(job.bakes[2]).get<ReliefSettings>().directions, 5);

  const Scene scene = load_scene(job);
  const LayerSet p1 = run_method(job.bakes[0], scene, {});
  ASSERT_EQ(p1.layers.size(), 2u);
  EXPECT_EQ(p1.layers[0].name, "horizon");  // the order the entry wrote
  EXPECT_EQ(p1.layers[0].channel_count(), 12);
  const LayerSet relief = run_method(job.bakes[2], scene, {});
  ASSERT_NE(relief.find("horizon_deg"), nullptr);
  EXPECT_EQ(relief.find("horizon_deg")->channel_count(), 5);
}

}  // namespace
}  // namespace hfbake
