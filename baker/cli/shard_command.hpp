// `hfbake bake JOB --shard I/N` and `hfbake merge JOB`: the farm's two halves of a bake (baker/farm says
// which work a shard does and how its file is laid out).
#pragma once

#include <atomic>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cli/job_outcome.hpp"
#include "cli/progress.hpp"
#include "cli/reference_cache.hpp"
#include "core/layers.hpp"
#include "core/run_control.hpp"
#include "farm/shard_file.hpp"
#include "field/scene.hpp"
#include "job/manifest.hpp"

namespace hfbake {

// What a shard (stage file) of this job must carry to be merged: the job's name and hash, shard_version().
ShardIdentity shard_identity(const Job& job, ShardId id, int width, int height);
// A staged entry's stage file: "shard" index = the stage, count = the entry's stages.
ShardIdentity stage_identity(const Job& job, int entry, int stage, int width, int height);
// A piece of a stage's file (farm/shard_plan.hpp StageItem): stage_identity for a whole stage; a block's
// "shard" index = the block, count = the stage's blocks.
ShardIdentity stage_item_identity(const Job& job, int stage, StageItem item, int width, int height);

// Whether the tasks of stage `stage` (> 0) of a staged entry are to (re)write the state file of stage
// `stage - 1` (stage_path) from that stage's blocks even when their own pieces are complete: stage
// `stage - 1` is divided by direction blocks, its file is missing or not complete, and something still
// reads it (the state after `stage` is no complete file: the merge or stage `stage + 1` reads it). Its
// re-run, by hand or by `hfbake slurm --resume`, then repairs the file.
bool stage_state_to_rebuild(const Job& job, int entry, int stage, int width, int height);

// The files that give a staged entry's state after stage `stage`: the stage's file when complete (or the
// stage is whole), else, for a stage divided by direction blocks, the previous stage's file and the stage's
// block files (stage 0: its block files alone), merged on load (MethodInfo::finish_stage_blocks). Opened and
// checked on construction (InputError naming the first file missing, truncated or of another job).
class StageSources {
 public:
  StageSources(const Job& job, int entry, int stage, int width, int height);
  bool merged() const { return !blocks_.empty(); }  // made from blocks (not yet a stage file)
  LayerSet load(const Scene& scene, const RunControl& rc);
  double seconds() const;  // the entry's seconds up to this stage, every shard's summed
  double cpu_seconds() const;

 private:
  const Job& job_;
  int entry_ = 0, stage_ = 0;
  std::optional<ShardReader> state_;
  std::vector<ShardReader> blocks_;
};

// The version a shard records: hfbake_version() (the version and git revision CMake configured), then
// "+build." and the executable's GNU build id (farm/build_id.hpp), which changes whenever the binary does.
std::string shard_version();

// Computes shard `id` of a valid job into its shard file (farm/shard_plan.hpp shard_path) and returns the
// path. A complete shard file of the same job and hfbake is kept as it is (a re-run does nothing). With a
// cache holding the job's reference, the shard's reference rows are read from it. Staged entries (p2) of
// the shard run stage `stage` into their stage files (farm/shard_plan.hpp stage_path) from the previous
// stage's; stage 0 comes with the shard's other work, a later stage alone (`bake --shard I/N --stage S`),
// which also makes the state file before the stage again wherever stage_state_to_rebuild says so.
std::filesystem::path bake_shard(const Job& job, ShardId id, Progress& progress,
                                 const std::atomic<bool>& cancel, JobOutcome& outcome,
                                 const ReferenceCache* cache, int stage = 0);

// What `hfbake slurm --shards N` checks before it submits anything (InputError naming the folder): the job's
// shards folder is a real folder or absent, and holds no shards of the job's name for another count (its
// merge would refuse the mix).
void check_shards_folder(const Job& job, int count);

// The shards of a job, opened and checked for `hfbake merge`: every shard 0..N-1 present, whole, of this job
// and this hfbake (InputError naming the shard otherwise, before anything is baked or written).
class MergedShards {
 public:
  MergedShards(const Job& job, int width, int height);
  int count() const { return count_; }
  // Bake entry `entry` as `hfbake bake` computes it: the whole method from its shard, or its direction
  // blocks added in order and finished (MethodInfo::finish_blocks).
  LayerSet method(int entry, const Scene& scene, const RunControl& rc);
  LayerSet reference();
  // The seconds (and CPU seconds) the shards spent on an entry (-1: the reference), summed.
  double seconds(int entry) const;
  double cpu_seconds(int entry) const;

 private:
  const Job& job_;
  int count_ = 0, height_ = 0;
  std::vector<ShardReader> readers_;
  std::map<int, StageSources> stages_;  // staged entries: the last stage's files
  // Per entry (-1: the reference) the layers of its first block or row band: (name, channels).
  std::map<int, std::vector<std::pair<std::string, std::size_t>>> part_layouts_;
};

}  // namespace hfbake
