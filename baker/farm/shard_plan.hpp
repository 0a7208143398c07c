// Which part of a job shard I of N computes. The work of a job divides into units that do not depend on N:
//   - a direction-dividing method (MethodInfo::bake_block: p1, hbao) into its direction blocks
//     (core/direction_blocks.hpp); shard I takes blocks [I B / N, (I + 1) B / N);
//   - the reference into bands of kReferenceBandRows receiver rows; shard I takes bands [I R / N, (I + 1) R /
//   N)
//     (one contiguous run of rows), each traced against the whole field;
//   - a staged method (MethodInfo::stages: p2, stage 0 its direct light, stage b its bounce b) runs stage
//     s after stage s - 1 (`bake --shard I/N --stage s`; stage 0 with the shard's other work): a whole
//     stage in shard (entry index mod N), into its own stage file (stage_path); a stage divided by
//     direction blocks (MethodInfo::stage_blocks: every stage of p2) as blocks, shard I taking blocks
//     [I B / N, (I + 1) B / N), each into its own block file (stage_block_path). Whoever first needs the
//     state after such a stage (the next stage's tasks, the merge) adds its blocks to the state before it
//     (MethodInfo::finish_stage_blocks); the next stage's tasks also write it as the stage's file (and
//     write it again when it is missing or damaged while read: cli/shard_command stage_state_to_rebuild);
//   - any other method runs whole, in shard (entry index mod N).
// Shards beyond a method's block count simply have none of its blocks.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "job/manifest.hpp"

namespace hfbake {

struct ShardId {
  int index = 0, count = 1;  // shard `index` of `count`
};
// "I/N" with 0 <= I < N <= 4096; nullopt otherwise.
std::optional<ShardId> parse_shard_id(const std::string& text);
std::string shard_id_text(ShardId id);  // "I/N"

inline constexpr int kReferenceBandRows = 32;

// Direction blocks of a resolved bake entry (0: the method runs whole).
int entry_direction_blocks(const BakeEntry& entry);

// Stages of a resolved bake entry (0: not staged).
int entry_stages(const BakeEntry& entry);
// The most stages of any entry of the job (0: none staged).
int job_stages(const Job& job);
// Direction blocks of stage `stage` of a resolved staged entry (0: the stage runs whole).
int entry_stage_blocks(const BakeEntry& entry, int stage);

// One piece of a stage: a staged entry's whole stage (block -1) or one direction block of it.
struct StageItem {
  int entry = 0;
  int block = -1;
};
// What shard `id` computes of stage `stage`: a whole stage in shard (entry index mod N), a divided one's
// blocks [I B / N, (I + 1) B / N), in entry order and block order.
std::vector<StageItem> stage_work(const Job& job, ShardId id, int stage);

struct ShardWork {
  struct Entry {
    int entry = 0;       // index into Job::bakes
    bool whole = false;  // the whole method; else blocks [block_begin, block_end)
    int block_begin = 0, block_end = 0;
  };
  std::vector<Entry> entries;      // in job order; entries with nothing for this shard are left out
  int row_begin = 0, row_end = 0;  // the reference's receiver rows (empty: none, or no reference)
  std::vector<int> staged;         // staged entries whose stages this shard runs (not in `entries`)
};
ShardWork shard_work(const Job& job, int field_height, ShardId id);

// <output dir>/shards/<name>.shard-<I>-of-<N>.hfshard
std::filesystem::path shard_path(const Job& job, ShardId id);
// <output dir>/shards/<name>.<stem>.stage-<s>.hfshard: a staged entry's state after stage s (any N).
std::filesystem::path stage_path(const Job& job, int entry, int stage);
// <output dir>/shards/<name>.<stem>.stage-<s>.block-<b>.hfshard: direction block b of stage s (any N).
std::filesystem::path stage_block_path(const Job& job, int entry, int stage, int block);
// The file of a stage item: stage_path or stage_block_path.
std::filesystem::path stage_item_path(const Job& job, int stage, StageItem item);
// Whether `filename` (a name in <output dir>/shards/) is one a shard task of `job` may write: a shard file of
// any I and N, or a stage or stage block file of one of its entries.
bool is_shard_file_name(const Job& job, const std::string& filename);

}  // namespace hfbake
