// hfbake: bakes ambient occlusion and lighting for height fields. See README.md and docs/.
#include <tbb/global_control.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <csignal>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <system_error>
#include <thread>

#include "cli/bake_command.hpp"
#include "cli/compare_command.hpp"
#include "cli/horizon_command.hpp"
#include "cli/init_command.hpp"
#include "cli/outputs.hpp"
#include "cli/slurm_command.hpp"
#include "cli/version.hpp"
#include "core/instruction_set.hpp"
#include "core/safe_file.hpp"
#include "io/exr_output.hpp"

namespace {

// The process-wide state a signal handler may touch (both lock-free atomics).
std::atomic<bool> g_interrupted{false};
std::atomic<int> g_signal{0};  // the first signal that stopped the bake: its exit status is 128 + it
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<bool>::is_always_lock_free);

// SIGINT (Ctrl-C), SIGTERM (kill, timeout, cron, CI) and SIGHUP (the terminal went away) all stop the bake
// at its next check; the staging folders are removed on the way out. A second signal stops at once: the
// staging folders left behind carry this process's id and the next bake of that folder removes them. While
// a job moves its outputs into place it does not: the moves finish first, and the process stops after them
// (docs/output_folders.md).
extern "C" void on_stop_signal(int sig) {
  int none = 0;
  g_signal.compare_exchange_strong(none, sig);
  if (g_interrupted.exchange(true) && !hfbake::outputs_moving()) std::_Exit(128 + sig);
}

// A path option given empty (an unset shell variable: --out "$OUT") is refused, not taken for the option's
// absence, which would send the output elsewhere.
CLI::Validator named(const std::string& kind, const std::string& what) {
  return CLI::Validator(
      [what](std::string& text) { return text.empty() ? "is empty: name " + what : std::string(); }, kind);
}

// A whole number from `lo` to `hi`: the check of every integer option, whose message says whether the text is
// a number at all ("--threads: not a whole number: abc (it must be from 1 to 4096)") or out of the range.
CLI::Validator whole_number(int lo, int hi) {
  const std::string range = std::to_string(lo) + " to " + std::to_string(hi);
  return CLI::Validator(
      [lo, hi, range](std::string& text) {
        long long value = 0;
        const char* end = text.data() + text.size();
        const auto [stop, error] = std::from_chars(text.data(), end, value);
        if (text.empty() || stop != end || (error != std::errc() && error != std::errc::result_out_of_range))
          return "not a whole number: " + text + " (it must be from " + range + ")";
        if (error != std::errc() || value < lo || value > hi)
          return "must be from " + range + " (it is " + text + ")";
        return std::string();
      },
      "INT in " + range);
}

// The options of every command that bakes (bake, merge, slurm), one meaning and one help text each.
struct RunOptions {
  std::string out, cache;
  bool no_cache = false, quiet = false;
};

void add_run_options(CLI::App* cmd, RunOptions& o) {
  cmd->add_option("-o,--out", o.out,
                  "Output folder, replacing each job's output.dir (the shards: <out>/shards)")
      ->check(named("DIR", "the output folder"));
  cmd->add_flag("--quiet", o.quiet, "No progress output (warnings and errors are still printed)");
  cmd->add_option("--cache", o.cache,
                  "Reference cache folder (default: $XDG_CACHE_HOME/hfbake/references or "
                  "~/.cache/hfbake/references; on a cluster, a folder every node sees)");
  cmd->add_flag("--no-cache", o.no_cache, "Always compute references; do not read or write the cache");
}

// The options of the commands that write a job's outputs here (bake, merge).
struct JobOptions {
  std::string summary;
  bool overwrite = false;
  int threads = 0;
};

void add_job_options(CLI::App* cmd, JobOptions& o) {
  cmd->add_option("--threads", o.threads, "Worker threads (default: all cores)")
      ->check(whole_number(1, 4096));
  cmd->add_flag("--overwrite", o.overwrite,
                "Replace outputs of the same job name that another job file baked into the output folder");
  cmd->add_option("--summary", o.summary, "Write a machine-readable JSON summary to FILE");
}

// A baking command's BakeOptions from its option groups.
hfbake::BakeOptions bake_options(const std::vector<std::string>& jobs, const RunOptions& run,
                                 const JobOptions& job) {
  hfbake::BakeOptions o;
  o.jobs.assign(jobs.begin(), jobs.end());
  if (!run.out.empty()) o.out = run.out;
  if (!run.cache.empty()) o.cache = run.cache;
  o.no_cache = run.no_cache;
  o.quiet = run.quiet;
  if (!job.summary.empty()) o.summary = job.summary;
  o.overwrite = job.overwrite;
  return o;
}

}  // namespace

namespace {
int run(int argc, char** argv) {
  hfbake::set_temporary_owner(hfbake::temporary_owner());  // temporaries a later process can clean up
  CLI::App app{"hfbake: offline baker of ambient occlusion and lighting for height fields"};
  app.require_subcommand(0, 1);
  app.set_version_flag("--version", std::string("hfbake ") + hfbake::hfbake_version());

  std::vector<std::string> bake_jobs, validate_jobs;
  bool validate_quiet = false;

  RunOptions bake_run;
  JobOptions bake_writes;
  CLI::App* bake_cmd = app.add_subcommand("bake", "Bake every job (continues past a failed job)");
  bake_cmd->add_option("jobs", bake_jobs, "Job files or suites (JSON)")->required()->check(CLI::ExistingFile);
  add_run_options(bake_cmd, bake_run);
  add_job_options(bake_cmd, bake_writes);
  const auto memory_size = CLI::Validator(
      [](std::string& text) {
        return hfbake::parse_memory_size(text) ? std::string()
                                               : "not a size (e.g. 512M, 8G, 1.5GiB, or bytes): " + text;
      },
      "SIZE");
  std::string memory_limit;
  bake_cmd
      ->add_option(
          "--memory-limit", memory_limit,
          "The process's memory budget: refuse a job whose estimate exceeds SIZE, and bake jobs "
          "together only while their estimates fit it, else in turns (default: the available memory)")
      ->check(memory_size);

  bool tiles = false;
  bake_cmd->add_flag(
      "--tiles", tiles,
      "Bake a georeferenced raster in spatial tiles within the memory budget, into Cloud-Optimised "
      "GeoTIFFs only (docs/large-fields.md)");
  int tile_size = 0;
  bake_cmd
      ->add_option("--tile-size", tile_size,
                   "N: with --tiles, tiles of N^2 texels (default: from --memory-limit)")
      ->check(whole_number(16, 1 << 20));
  std::string tile_task;
  bake_cmd->add_option(
      "--tile-task", tile_task,
      "I/N: with --tiles and --tile-size, bake only task I's tiles of N into <out>/tiles/ (see "
      "merge --tiles)");
  std::string shard;
  bake_cmd->add_option(
      "--shard", shard,
      "I/N: bake only shard I (0-based) of N of each job into <out>/shards/ (see hfbake merge)");
  int stage = 0;
  bake_cmd
      ->add_option(
          "--stage", stage,
          "S: with --shard, stage S of the staged methods (p2: stage 0 direct light, S its bounce S; "
          "stage S needs stage S - 1 of the same job)")
      ->check(whole_number(0, 64));
  // hfbake merge: the outputs of `bake` from a job's shards.
  std::vector<std::string> merge_jobs;
  RunOptions merge_run;
  JobOptions merge_writes;
  CLI::App* merge_cmd = app.add_subcommand(
      "merge", "Write each job's outputs from its shards (bake --shard I/N): the same files bake writes");
  merge_cmd->add_option("jobs", merge_jobs, "Job files (JSON) or suites")
      ->required()
      ->check(CLI::ExistingFile);
  add_run_options(merge_cmd, merge_run);
  add_job_options(merge_cmd, merge_writes);
  bool merge_tiles = false;
  merge_cmd->add_flag("--tiles", merge_tiles, "Write the COGs of a tiled bake from its tile tasks' files");
  int merge_tile_size = 0;
  merge_cmd->add_option("--tile-size", merge_tile_size, "N: the tile tasks' --tile-size")
      ->check(whole_number(16, 1 << 20));

  // hfbake slurm: shards as a Slurm job array, then the merge.
  hfbake::SlurmOptions slurm;
  std::vector<std::string> slurm_inputs;
  RunOptions slurm_run;
  CLI::App* slurm_cmd = app.add_subcommand(
      "slurm", "Bake on a Slurm cluster: one array task per job and shard, then a merge job (afterok)");
  slurm_cmd->add_option("jobs", slurm_inputs, "Job files (JSON) or suites")
      ->required()
      ->check(CLI::ExistingFile);
  slurm_cmd->add_option("--shards", slurm.shards, "Shards per job (bake --shard I/N)")
      ->required()
      ->check(whole_number(1, 4096));
  slurm_cmd->add_option("--partition", slurm.partition, "sbatch --partition");
  slurm_cmd->add_option("--time", slurm.time, "sbatch --time (per task)");
  slurm_cmd->add_option("--mem", slurm.mem,
                        "sbatch --mem per task (default: the job's memory estimate + 20 %)");
  slurm_cmd->add_option("--sbatch-arg", slurm.sbatch_args, "Any further sbatch option (repeatable)");
  slurm_cmd->add_flag("--wait", slurm.wait, "Wait for the merge and exit with its status");
  bool slurm_tiles = false;
  slurm_cmd->add_flag("--tiles", slurm_tiles,
                      "A tiled bake: --shards tile tasks (bake --tiles --tile-task), then merge --tiles");
  slurm_cmd->add_option("--tile-size", slurm.tile_size, "N: with --tiles, tiles of N^2 texels")
      ->check(whole_number(16, 1 << 20));
  slurm_cmd->add_flag("--resume", slurm.resume, "Submit only the shards whose file is not complete");
  add_run_options(slurm_cmd, slurm_run);
  slurm_cmd->add_option("--threads", slurm.threads, "Threads per task (--cpus-per-task; default 1)")
      ->check(whole_number(1, 4096));
  slurm_cmd->add_flag(
      "--dry-run", slurm.dry_run,
      "Print the two sbatch scripts and the sbatch commands to stdout; write and submit nothing");

  hfbake::CompareOptions compare;
  std::string compare_json;
  CLI::App* compare_cmd = app.add_subcommand(
      "compare",
      "Compare a report.json (or every report.json under a folder) with a baseline; exit 1 on regression");
  compare_cmd
      ->add_option("new", compare.now, "The new report.json (or a folder of them, e.g. a suite's output)")
      ->required();
  compare_cmd->add_option("baseline", compare.baseline, "The baseline report.json (or folder)")->required();
  compare_cmd->add_option("--tolerance", compare.tolerances,
                          "METRIC=REL[,ABS]: check METRIC (mae, rmse, rel_mae, excess_rmse, p99, max, psnr, "
                          "bias, noise_rmse, seconds) with these tolerances (default: mae, rmse, excess_rmse "
                          "at 0.05,1e-5)");
  compare_cmd->add_flag("--all", compare.all, "List every checked metric, not only the changes");
  compare_cmd->add_flag("--update-baseline", compare.update_baseline,
                        "After comparing, write NEW over BASELINE (the only way a baseline changes)");
  compare_cmd->add_flag("--allow-different-job", compare.allow_different_job,
                        "Compare even when BASELINE is a report of another job (other name, field, scene or "
                        "reference settings); the differences are printed");
  compare_cmd->add_option("--json", compare_json, "Also write the comparison as JSON to FILE");
  compare_cmd->add_flag("--quiet", compare.quiet, "Print only errors");

  hfbake::InitOptions init;
  std::string init_height, init_out;
  std::vector<std::string> preset_names;
  for (const hfbake::InitPreset& p : hfbake::init_presets()) preset_names.push_back(p.name);
  CLI::App* init_cmd = app.add_subcommand(
      "init",
      "Write a job to edit for a height file: texel size and height range read from it, a preset's bake");
  init_cmd->add_option("height_file", init_height, "The height image or georeferenced raster")->required();
  init_cmd->add_option("--preset", init.preset, "What the job bakes")
      ->required()
      ->check(CLI::IsMember(preset_names));
  init_cmd->add_option("-o,--out", init_out,
                       "The job file to write (default: <height file's stem>.json here, each character a job "
                       "name cannot hold as _)");
  init_cmd->add_flag("--force", init.force, "Write over an existing job file");

  CLI::App* validate_cmd = app.add_subcommand("validate", "Check jobs against the schema and their files");
  validate_cmd->add_option("jobs", validate_jobs, "Job files or suites (JSON)")->required();
  validate_cmd->add_flag("--quiet", validate_quiet, "Print only problems");
  std::string validate_memory_limit;
  validate_cmd
      ->add_option("--memory-limit", validate_memory_limit,
                   "As bake's --memory-limit: each job's estimate, and the turns of several jobs")
      ->check(memory_size);
  bool validate_tiles = false;
  validate_cmd->add_flag("--tiles", validate_tiles,
                         "As bake --tiles: the tile plan, every tile's heights read");
  int validate_tile_size = 0;
  validate_cmd->add_option("--tile-size", validate_tile_size, "As bake's --tile-size")
      ->check(whole_number(16, 1 << 20));
  bool validate_overwrite = false;
  validate_cmd->add_flag("--overwrite", validate_overwrite,
                         "As bake's --overwrite: outputs of the same job name from another job file may go");
  int validate_threads = 0;
  validate_cmd
      ->add_option(
          "--threads", validate_threads,
          "As bake's --threads: the memory estimate counts each thread's scratch (default: all cores)")
      ->check(whole_number(1, 4096));

  // hfbake horizon: the horizon profile at a point of a DEM.
  hfbake::HorizonOptions horizon;
  CLI::App* horizon_cmd =
      app.add_subcommand("horizon", "Print the exact horizon profile at a point of a georeferenced DEM");
  horizon_cmd->add_option("dem", horizon.dem, "The DEM (a raster GDAL reads, with a geotransform)")
      ->required();
  horizon_cmd->add_option("--at", horizon.at, "X,Y in the raster's CRS (LON,LAT in WGS 84 with --lonlat)")
      ->required();
  horizon_cmd->add_flag("--lonlat", horizon.lonlat, "--at is longitude,latitude in WGS 84 degrees");
  horizon_cmd->add_option("--observer-height", horizon.observer_height,
                          "Eye height above the surface, in the heights' unit (default 0)");
  double horizon_scale = 1, horizon_offset = 0;
  CLI::Option* horizon_scale_opt =
      horizon_cmd->add_option("--height-scale", horizon_scale,
                              "Heights are the stored values x this (a job's height_scale; default 1)");
  CLI::Option* horizon_offset_opt = horizon_cmd->add_option(
      "--height-offset", horizon_offset, "... + this, after the scale (a job's height_offset; default 0)");
  horizon_cmd->add_option("--directions", horizon.directions,
                          "K compass azimuths 360 k / K, clockwise from north (default 360)");
  horizon_cmd->add_option("--band", horizon.band, "Band of the heights, 0-based (default 0)");
  horizon_cmd->add_option("--format", horizon.format, "csv (default) or json");
  horizon_cmd->add_option("-o,--out", horizon.out, "Write to FILE instead of standard output")
      ->check(named("FILE", "the file"));
  horizon_cmd
      ->add_option("--plot", horizon.plot,
                   "Also write a polar plot PNG: seen from above, north up, the zenith at the centre")
      ->check(named("FILE", "the file"));
  horizon_cmd->add_option("--plot-size", horizon.plot_size,
                          "The plot's width and height in pixels (default 512)");
  bool curvature_on = false, curvature_off = false;
  horizon_cmd->add_flag("--curvature", curvature_on,
                        "Lower each point by d^2 (1 - k) / (2 R) (the default for a geographic CRS)");
  horizon_cmd->add_flag("--no-curvature", curvature_off, "A flat Earth (the default for a projected CRS)");
  double refraction = 0;
  CLI::Option* refraction_opt = horizon_cmd->add_option(
      "--refraction", refraction, "Refraction coefficient k with curvature (default 0.13, Gauss's)");
  // The methods and presets under hfbake --help and the commands that take them (bake, init), set once every
  // command exists (a footer set earlier is copied into the commands made after it).
  const std::string methods_help = "\n" + hfbake::methods_and_presets_help();
  app.footer(methods_help);
  bake_cmd->footer(methods_help);
  init_cmd->footer(methods_help);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    // An argument no command takes is the mistake to name, even where a word after it failed a check first
    // (a misspelt --output's folder taken as a job file).
    const std::vector<std::string> unknown = app.remaining(true);
    std::fprintf(stderr, "hfbake: error: command line: %s\n",
                 unknown.empty() ? e.what() : CLI::ExtrasError(unknown).what());
    return 2;
  }
  try {
    hfbake::instruction_set_cap();  // HFBAKE_ISA checked before any command starts
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "hfbake: error: environment: %s\n", e.what());
    return 2;
  }
  if (app.got_subcommand(horizon_cmd)) {
    if (curvature_on && curvature_off) {
      std::fprintf(stderr, "hfbake: error: command line: --curvature and --no-curvature together\n");
      return 2;
    }
    if (curvature_on || curvature_off) horizon.curvature = curvature_on;
    if (refraction_opt->count() > 0) horizon.refraction = refraction;
    if (horizon_scale_opt->count() > 0) horizon.height_scale = horizon_scale;
    if (horizon_offset_opt->count() > 0) horizon.height_offset = horizon_offset;
    return hfbake::run_horizon(horizon);
  }
  if (app.got_subcommand(validate_cmd)) {
    std::vector<std::filesystem::path> files(validate_jobs.begin(), validate_jobs.end());
    std::optional<tbb::global_control> cap;
    if (validate_tile_size > 0 && !validate_tiles) {
      std::fprintf(stderr, "hfbake: error: command line: --tile-size needs --tiles\n");
      return 2;
    }
    if (validate_threads > 0) cap.emplace(tbb::global_control::max_allowed_parallelism, validate_threads);
    return hfbake::run_validate(
        files, validate_quiet,
        validate_memory_limit.empty() ? std::nullopt : hfbake::parse_memory_size(validate_memory_limit),
        validate_tiles, validate_tile_size > 0 ? std::optional<int>(validate_tile_size) : std::nullopt,
        validate_overwrite);
  }
  if (app.got_subcommand(init_cmd)) {
    init.height_file = init_height;
    if (!init_out.empty()) init.out = init_out;
    return hfbake::run_init(init);
  }
  if (app.got_subcommand(compare_cmd)) {
    if (!compare_json.empty()) compare.json = compare_json;
    return hfbake::run_compare(compare);
  }
  if (app.got_subcommand(slurm_cmd)) {
    slurm.inputs.assign(slurm_inputs.begin(), slurm_inputs.end());
    if (!slurm_run.out.empty()) slurm.out = slurm_run.out;
    if (!slurm_run.cache.empty()) slurm.cache = slurm_run.cache;
    slurm.no_cache = slurm_run.no_cache;
    slurm.quiet = slurm_run.quiet;
    if (slurm_tiles != (slurm.tile_size > 0)) {
      std::fprintf(stderr,
                   "hfbake: error: command line: slurm --tiles needs --tile-size N (and only with it)\n");
      return 2;
    }
    return hfbake::run_slurm(slurm);
  }
  hfbake::BakeOptions bake;
  int threads = 0;
  if (app.got_subcommand(merge_cmd)) {
    bake = bake_options(merge_jobs, merge_run, merge_writes);
    bake.merge = true;
    bake.tiles = merge_tiles;
    if (merge_tile_size > 0) bake.tile_size = merge_tile_size;
    if (merge_tiles != (merge_tile_size > 0)) {
      std::fprintf(stderr, "hfbake: error: command line: merge --tiles needs --tile-size N (the tasks')\n");
      return 2;
    }
    threads = merge_writes.threads;
  } else if (app.got_subcommand(bake_cmd)) {
    bake = bake_options(bake_jobs, bake_run, bake_writes);
    threads = bake_writes.threads;
    if (!memory_limit.empty()) bake.memory_limit = hfbake::parse_memory_size(memory_limit);
    bake.stage = stage;
    bake.tiles = tiles;
    if (tile_size > 0) bake.tile_size = tile_size;
    if (tile_size > 0 && !tiles) {
      std::fprintf(stderr, "hfbake: error: command line: --tile-size needs --tiles\n");
      return 2;
    }
    if (!tile_task.empty()) {
      bake.tile_task = hfbake::parse_shard_id(tile_task);
      if (!bake.tile_task || !tiles || tile_size == 0) {
        std::fprintf(stderr,
                     "hfbake: error: command line: --tile-task %s: must be I/N with 0 <= I < N <= 4096, with "
                     "--tiles and --tile-size\n",
                     tile_task.c_str());
        return 2;
      }
    }
    if (tiles && !shard.empty()) {
      std::fprintf(stderr, "hfbake: error: command line: --tiles and --shard do not combine\n");
      return 2;
    }
    if (stage > 0 && shard.empty()) {
      std::fprintf(stderr, "hfbake: error: command line: --stage needs --shard I/N\n");
      return 2;
    }
    if (!shard.empty()) {
      bake.shard = hfbake::parse_shard_id(shard);
      if (!bake.shard) {
        std::fprintf(stderr, "hfbake: error: command line: --shard %s: must be I/N with 0 <= I < N <= 4096\n",
                     shard.c_str());
        return 2;
      }
    }
  } else {
    std::fputs(app.help().c_str(), stdout);
    return 2;
  }
  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  std::size_t(threads));
  // EXR outputs compress their chunks on OpenEXR's thread pool, as many workers as the bake has (the files'
  // bytes do not depend on it).
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  hfbake::start_exr_thread_pool(threads > 0 ? threads : int(cores));
  bake.interrupt_signal = &g_signal;
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction action {};
    action.sa_handler = on_stop_signal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESTART;
    sigaction(sig, &action, nullptr);
  }
  return hfbake::run_bake(bake, g_interrupted);
}

}  // namespace

// Every command reports its own errors; what escapes one (a module that cannot be loaded, memory) is still
// one line and a non-zero exit.
int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::string what = e.what();
    if (const auto nl = what.find('\n'); nl != std::string::npos) what.resize(nl);
    std::fprintf(stderr, "hfbake: error: %s\n", what.c_str());
    return 1;
  }
}
