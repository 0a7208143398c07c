// Where a job's results come from (cli/bake_command bake_job): computed here, each entry through its method
// and the reference traced in checkpointed bands, or read from the farm's shards (`hfbake merge`). The
// reference cache sits in front of either source's reference (bake_command.cpp).
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli/outputs.hpp"
#include "cli/scene_loader.hpp"
#include "cli/shard_command.hpp"
#include "core/layers.hpp"
#include "core/run_control.hpp"
#include "field/scene.hpp"
#include "job/manifest.hpp"

namespace hfbake {

struct SourcedLayers {
  LayerSet layers;
  double seconds = 0, cpu_seconds = 0;  // wall and CPU seconds it took (a merge: the shards', summed)
  std::vector<std::string> notices;     // for the progress log
  nlohmann::json record = nlohmann::json::object();  // what the job's summary adds for it
};

struct ResultSource {
  // Bake entry `entry`'s layers, as its method bakes them.
  std::function<SourcedLayers(int entry, const RunControl& rc)> method;
  // The reference's path-traced layers (job_reference_options).
  std::function<SourcedLayers(const RunControl& rc)> reference;
};

// Computed here: each entry by its method (run_method); the reference traced band by band, each band
// checkpointed into `stage` and the bands a killed bake of this job left taken instead of traced
// (cli/reference_checkpoint.hpp). `job`, `scene` and `stage` must outlive the source.
ResultSource computed_results(const Job& job, const Scene& scene, OutputStage& stage, FieldSize size);

// Read from the farm's shards (MergedShards checks them all when it is made). `shards` and `scene` must
// outlive the source.
ResultSource merged_results(MergedShards& shards, const Scene& scene);

}  // namespace hfbake
