// `hfbake bake` and `hfbake validate`: load jobs, bake them task-parallel, write outputs whole or not at all.
#pragma once

#include <atomic>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "cli/job_outcome.hpp"
#include "cli/progress.hpp"
#include "cli/reference_cache.hpp"
#include "cli/scene_loader.hpp"
#include "core/layers.hpp"
#include "farm/shard_plan.hpp"
#include "job/manifest.hpp"

namespace hfbake {

struct BakeOptions {
  std::vector<std::filesystem::path> jobs;
  std::optional<std::filesystem::path> out;      // --out: replaces every job's output.dir
  std::optional<std::filesystem::path> summary;  // --summary: machine-readable JSON summary
  bool quiet = false;
  // The reference cache (cli/reference_cache.hpp): --cache DIR, default under the user's cache home;
  // --no-cache turns it off.
  std::optional<std::filesystem::path> cache;
  bool no_cache = false;
  // The signal that set `cancel` (0 or null: SIGINT): an interrupted bake exits 128 + it (130 SIGINT,
  // 143 SIGTERM, 129 SIGHUP), the status a shell reports for a process that signal killed.
  const std::atomic<int>* interrupt_signal = nullptr;
  // --memory-limit: the budget a job's memory estimate must fit (default: the machine's available memory),
  // and the name messages give it (the Python module's is memory_limit).
  std::optional<std::size_t> memory_limit;
  std::string memory_limit_name = "--memory-limit";
  // The farm (cli/shard_command.hpp): --shard I/N bakes that shard of each job into its shard file;
  // merge (`hfbake merge`) writes each job's outputs from its shards instead of baking.
  std::optional<ShardId> shard;
  int stage = 0;  // --stage S (with --shard): stage S of the staged methods (p2's bounce S)
  bool merge = false;
  // --tiles: bake a georeferenced raster in spatial tiles within the memory budget (cli/tile_command.hpp),
  // the interiors' side from --tile-size when given.
  bool tiles = false;
  std::optional<int> tile_size;
  // --tile-task I/N (with --tiles): bake only task I's tiles of N into <out>/tiles/, for merge --tiles.
  std::optional<ShardId> tile_task;
  // --overwrite: replace outputs of the same job name that another job file baked into the folder
  // (docs/output_folders.md).
  bool overwrite = false;
};

// "512M", "8G", "1.5GiB", "2000000000": bytes (binary multiples K, M, G, T, optionally "iB" or "B"); nullopt
// when the text is not a size.
std::optional<std::size_t> parse_memory_size(const std::string& text);

// Refuses a job that cannot fit in `limit` bytes (default: the machine's available memory) before anything is
// allocated: an InputError at /height naming the estimate's parts, what shrinks the largest, and the limit as
// given (its bytes, and `limit_name`: the option or argument that set it). Returns the estimate
// (cli/scene_loader.hpp estimate_peak_bytes); `parts_text` (optional) receives its parts.
std::size_t check_job_memory(const Job& job, FieldSize size, std::optional<std::size_t> limit,
                             std::string* parts_text = nullptr,
                             const std::string& limit_name = "--memory-limit");

// Bakes one job that resolve_job accepted, as `hfbake bake` does: the memory check, the scene, each method,
// the reference and its report, the outputs staged and moved into job.output.dir whole. Fills `outcome`
// (seconds, metrics, outputs; a regressed threshold sets its status). `kept` (optional) receives the layers
// as written, by stem, the reference's as "reference". Throws InputError (bad input), Cancelled, or anything
// else (a failed job).
void bake_job(const Job& job, Progress& progress, const std::atomic<bool>& cancel, JobOutcome& outcome,
              const ReferenceCache* cache, const BakeOptions& options,
              std::map<std::string, LayerSet>* kept = nullptr);

// Exit status (docs/contract.md): 0 all baked and thresholds held, 1 a threshold or baseline regressed,
// 2 bad input or a failed job, 128 + the signal when interrupted (`cancel` was set: 130 SIGINT, 143 SIGTERM,
// 129 SIGHUP).
int run_bake(const BakeOptions& options, const std::atomic<bool>& cancel);

// Whether a stop signal (`cancel`) interrupted the bake: it stopped some job. A signal that came after every
// job had ended (its outputs moved into place, or its error found) stopped nothing, and the jobs' outcomes
// decide the exit status.
bool bake_interrupted(const std::vector<JobOutcome>& outcomes, bool cancel);
// run_bake's exit status: 128 + `signal` (0: SIGINT) when interrupted, else the worst of the outcomes.
int bake_exit_status(const std::vector<JobOutcome>& outcomes, bool interrupted, int signal);

// Schema and file checks without baking: 0 all valid, 2 otherwise. Prints one line per problem.
// `tiles`: as a tiled bake (cli/tile_command.hpp validate_tiled) with tiles of `tile_size` when given, its
// tiles/ folder as its tile tasks and merge find it (cli/outputs.hpp check_tiles_folder);
// `overwrite`: as a bake with --overwrite (outputs another job file baked may be replaced).
int run_validate(const std::vector<std::filesystem::path>& jobs, bool quiet,
                 std::optional<std::size_t> memory_limit = std::nullopt, bool tiles = false,
                 std::optional<int> tile_size = std::nullopt, bool overwrite = false);

}  // namespace hfbake
