// A job's output files: staged in a private folder inside the output folder and moved into place only
// when the whole job has succeeded, so a failure or an interrupt never leaves a partial output behind.
#pragma once

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/layers.hpp"
#include "core/safe_file.hpp"
#include "field/georeference.hpp"
#include "job/manifest.hpp"

namespace hfbake {

// The staging folder of a process: <output dir>/.hfbake-staging-<job name>-<pid>+<start>@<host>, <start> the
// process's start time (clock ticks after boot, /proc/<pid>/stat), so a reused process id is not taken for
// the owner.
struct StageOwner {
  std::string job;  // the job's name
  long long pid = 0;
  std::optional<unsigned long long> start;  // absent in stages of older hfbake
  std::string host;  // "" for a stage named without one (older hfbake): taken as this host
};
// A process's start time (clock ticks after boot); nullopt when it does not run (or /proc is not there).
std::optional<unsigned long long> process_start_time(long long pid);
// This process's staging folder name for a job.
std::string stage_name(const std::string& job_name);
// <output dir>/.hfbake-<name>.lock: the file a bake of the job locks (docs/output_folders.md).
std::filesystem::path output_lock_file(const Job& job);
// <output dir>/.hfbake-<name>.job: the job file whose outputs of that name the folder holds.
std::filesystem::path owner_record(const Job& job);
// <output dir>/textures when the job asks for textures (output.textures), else nullopt. Another job may bake
// into that folder: a job that writes textures owns its name there as in its output folder, with
// textures_lock_file held and textures_owner_record checked and written as the two above
// (docs/output_folders.md).
std::optional<std::filesystem::path> textures_folder(const Job& job);
// Refuses (InputError at /output/textures) the textures folder of a job that writes textures when the name is
// taken by anything but a folder (a link, a file: the textures are written inside the output folder only) or
// when this process cannot write into it: what resolve_job checks, and OutputStage's constructor before it
// locks there. Nothing there yet: nothing to refuse (the bake makes it).
void check_textures_folder(const Job& job);
// <output dir>/textures/.hfbake-<name>.lock and .hfbake-<name>.job: the lock and the owner record of a job
// that bakes into that folder under the same name.
std::filesystem::path textures_lock_file(const Job& job);
std::filesystem::path textures_owner_record(const Job& job);
// <output dir>/tiles: where a tiled bake's tile tasks write <name>+tile-<k>.<stem>.<layer>.tif
// (cli/tile_command.hpp). A job name holds no '+', so the name before the first '+' is the job's: no other
// job's tile file, and no output, lock or record of a job baking into that folder, has such a name
// (docs/output_folders.md).
std::filesystem::path tiles_folder(const Job& job);
// The first part of the job's tile files' names, "<name>+tile-".
std::string tile_file_prefix(const Job& job);
// <output dir>/tiles/.hfbake-<name>+tiles.lock and .hfbake-<name>+tiles.job: the lock under which a tile
// task claims the job's name in tiles/ (claim_tiles_folder), and the record of the job file whose tiles of
// that name the folder holds. No job's lock or record has these names.
std::filesystem::path tiles_lock_file(const Job& job);
std::filesystem::path tiles_owner_record(const Job& job);
// Refuses (InputError naming the job file) what a tile task or `merge --tiles` of `job` would find in
// tiles/: an entry there that is not a folder (/output/dir), its lock's name taken by anything but a file
// (/output/dir), and tiles of the job's name that tiles_owner_record says another job file baked (/name),
// unless `overwrite`. What `validate --tiles` and `merge --tiles` check.
void check_tiles_folder(const Job& job, bool overwrite);
// How long a tile task waits for tiles_lock_file while another task holds it (for one record's write).
inline constexpr std::chrono::seconds kTilesClaimPatience{10};
// What a tile task does before it bakes: makes tiles/, and holding tiles_lock_file (waited for up to
// kTilesClaimPatience; InputError at /output/dir naming the holder after that) checks it as
// check_tiles_folder does and records this job file as the owner of the job's name there. Tasks of one job
// file claim it together; a task of another job file with the same name is refused (InputError at /name)
// unless `overwrite`, which takes the name over.
void claim_tiles_folder(const Job& job, bool overwrite);
// <output dir>/shards: where a job's shard tasks write <name>.shard-<i>-of-<n>.hfshard and its staged
// entries' stage files (farm/shard_plan.hpp). Its lock and owner record, shards/.hfbake-<name>+shards.lock
// and .hfbake-<name>+shards.job, are named as tiles/' are, and no shard or stage file has those names.
std::filesystem::path shards_folder(const Job& job);
std::filesystem::path shards_lock_file(const Job& job);
std::filesystem::path shards_owner_record(const Job& job);
// Refuses (InputError naming the job file) what a shard task, `merge` or `slurm` of `job` would find in
// shards/: the folder a link or a file, its lock's name taken by anything but a file (/output/dir), and
// shards of the job's name that shards_owner_record says another job file baked (/name), unless `overwrite`.
void check_shards_owner(const Job& job, bool overwrite);
// What a shard task does before it bakes, as claim_tiles_folder does for tiles/: the tasks of one job file
// share the job's name in shards/; a task of another job file with that name is refused before it bakes
// (InputError at /name) unless `overwrite`, which takes the name over.
void claim_shards_folder(const Job& job, bool overwrite);
// <output dir>/.hfbake+report.lock: the file a bake or merge of a job with a reference locks as well, since
// report.json and report.html carry no job name (docs/output_folders.md). No job's lock has this name (a job
// name never starts with '+').
std::filesystem::path report_lock_file(const Job& job);
// Refuses (InputError at /output/dir) a job with a reference whose output folder holds a report.json that is
// not this job's (another job's, or no report of hfbake's): what `validate` checks, and OutputStage's
// constructor again under the report lock.
void check_report_owner(const Job& job);
// True when the stage's owner certainly no longer runs: same host, and no process with its id, or one
// that started at another time than the owner did.
bool stage_owner_is_gone(const StageOwner& owner);
// The owner a staging folder's name records; nullopt for any other name.
std::optional<StageOwner> parse_stage_name(const std::string& name);
// Removes the staging folders in `dir` whose owner is gone (stage_owner_is_gone) and returns them; those of
// live processes, of this process and of other hosts are kept.
std::vector<std::filesystem::path> remove_stale_stages(const std::filesystem::path& dir);
// The owner this process's temporaries carry (core/safe_file.hpp set_temporary_owner): <pid>+<start>@<host>,
// as a staging folder's name records it.
std::string temporary_owner();
// Removes the temporaries in `dir` (files and folders named <name>.tmp-<owner>-XXXXXX: shards, tile
// GeoTIFFs, reference-cache entries) whose owner certainly no longer runs (stage_owner_is_gone: this host,
// no such process or another one with that id); returns them. A temporary is never read as what it will
// become; this only frees the space of a killed process's.
std::vector<std::filesystem::path> remove_stale_temporaries(const std::filesystem::path& dir);
// The folder of a stage that holds its reference's checkpoints (cli/reference_checkpoint).
std::filesystem::path stage_checkpoint_dir(const std::filesystem::path& stage);
// Moves the checkpoint files of job `job_name`'s stages in `dir` whose owner is gone into `into` (a file
// already there is kept), so removing those stages does not lose a killed reference's work. Returns how many
// files it moved.
int adopt_stale_checkpoints(const std::filesystem::path& dir, const std::string& job_name,
                            const std::filesystem::path& into);

// Completes what a killed process of job `job`'s name (its owner gone, stage_owner_is_gone) left part moved:
// its stage's commit list names files that were whole when the moves began; those still in the stage are
// moved into place, the owner record last (docs/output_folders.md). Called under the job's lock; returns the
// stages it completed (then removed as stale stages).
std::vector<std::filesystem::path> complete_killed_commits(const Job& job);
// True while a job of this process moves its outputs into place (OutputStage::commit). Async-signal-safe:
// a stop signal's handler lets the moves finish rather than end the process part way.
bool outputs_moving() noexcept;

// The azimuth convention of a bake in words, with the compass mapping when the input's geotransform gives
// one (north-up: compass azimuth = (90 + phi) mod 360): written into every output's metadata.
std::string azimuth_convention(const Georeference& geo);

// Throws (a failed job, naming the stem, the layer, the first texel and its channel) when a layer holds a
// NaN or an infinity (+inf is allowed in horizon_distance, where nothing lies behind the texel), or when a
// fraction of the sky (ao, vsky, obscurance, svf) lies outside [0, 1] by more than a quadrature's error
// (0.05).
void check_layers_finite(const std::string& stem, const LayerSet& layers);

// What stands in the way of moving an output or an owner record to `target`: "" when rename(2) can replace
// what is there (nothing, a file, a link: the link is replaced, never followed), else the error's text
// ("<target> is a folder where an output goes: remove it"). Checked by resolve_job for the names the job
// writes, and by OutputStage::commit before any output moves.
std::string output_name_problem(const std::filesystem::path& target);

// Refuses (InputError at /name) a job whose output folder, or textures folder (textures_folder), records that
// another job file baked its outputs of the same job name (docs/output_folders.md), unless `overwrite`: what
// OutputStage's constructor and `validate` check before anything is baked.
void check_output_owner(const Job& job, bool overwrite);

class OutputStage {
 public:
  // Creates the output folder and the staging folder in it, after removing the stale staging folders of
  // dead processes there; InputError naming /output/dir if impossible. One folder, one owner per job name
  // (docs/output_folders.md): the lock <dir>/.hfbake-<name>.lock is held from here to destruction (another
  // process holding it: InputError), and outputs of <name> that <dir>/.hfbake-<name>.job records as baked
  // from another job file are refused (InputError) unless `overwrite`. A job with a reference holds
  // report_lock_file too and is refused over another job's report (check_report_owner); a job that writes
  // textures makes its textures folder and holds textures_lock_file too.
  explicit OutputStage(const Job& job, bool overwrite = false);
  // Removes the staging folder and anything left in it, and the output folder when this job made it and
  // did not commit (it is then empty unless another job writes there).
  ~OutputStage();
  OutputStage(const OutputStage&) = delete;
  OutputStage& operator=(const OutputStage&) = delete;

  // The input's georeferencing and holes, for the GeoTIFF outputs (default: none, pixel size 1).
  void set_georeference(const Georeference& georeference) { georeference_ = georeference; }
  // The field's texel sides in world units (x along columns, y along rows), for the EXRs' hfbake:texel_size.
  void set_texel_size(double x, double y) { texel_x_ = x, texel_y_ = y; }
  // Writes <name>.<stem>.exr (and previews <name>.<stem>.<layer>.preview.png, GeoTIFFs and textures when
  // the job asks for them) into the stage, after check_layers_finite. Returns the notices for the user, one
  // line each (a texture whose values were clipped, padding left out).
  [[nodiscard]] std::vector<std::string> write_layers(const std::string& stem, const LayerSet& layers);
  // Writes output.textures of `stem` (a bake output, or kHeightStem with the field's "normal" layer);
  // returns the notices as write_layers.
  [[nodiscard]] std::vector<std::string> write_textures(const std::string& stem, const LayerSet& layers);
  // Writes a text file (report.json, ...) into the stage.
  void write_text(const std::string& filename, const std::string& text);
  // The staging folder, for outputs written by parts (a tiled bake's GeoTIFFs, cli/tile_command.hpp): a
  // file made there is an output once adopt() names it; anything else there is removed with the stage.
  const std::filesystem::path& folder() const { return stage_held_.path(); }
  void adopt(const std::string& filename) { staged_.push_back(filename); }
  // The metadata items of a GeoTIFF output whose layers have `attributes` (LayerSet::attributes): each
  // "hfbake:key" as "HFBAKE_KEY", and the azimuth convention.
  std::vector<std::pair<std::string, std::string>> geotiff_metadata(
      const std::vector<std::pair<std::string, std::string>>& attributes) const;
  // Moves every staged file to its final place (each rename is atomic; a folder on the way that is a link
  // is refused) and records the job file as the outputs' owner (owner_record, and textures_owner_record for
  // a job that writes textures); returns the final paths.
  std::vector<std::filesystem::path> commit();
  // The files commit removed: outputs the previous bake of this job wrote (its owner record lists them)
  // that this bake does not write, so the folder holds one bake's outputs.
  const std::vector<std::filesystem::path>& removed() const { return removed_; }
  // What the constructor did to what other processes left, one line each for the user: the moves of a bake
  // killed while it moved its outputs, completed; stale staging folders, removed.
  std::vector<std::string> notes() const;
  // Where this job's reference checkpoints its bands: inside the stage, with the checkpoint files the
  // constructor adopted from this job's stale stages.
  std::filesystem::path checkpoint_dir() const { return checkpoint_held_.path(); }

 private:
  const Job& job_;
  // report_lock_: a job with a reference only; textures_lock_: a job that writes textures only.
  std::unique_ptr<FolderLock> lock_, report_lock_, textures_lock_;
  std::filesystem::path stage_;  // its name in the output folder
  // The folders written into, held from when they were made or checked (core/safe_file.hpp HeldFolder): a
  // link planted at one of their names while the job runs is never written through. The output folder (a
  // link the job names is followed once, when the stage is made), the stage, and the stage's checkpoint and
  // textures folders; the output folder's textures folder from the commit.
  HeldFolder out_held_, stage_held_, checkpoint_held_, stage_textures_held_, out_textures_held_;
  // Where `name` (relative to the stage: a file, or textures/<file>) is written in the stage.
  std::filesystem::path in_stage(const std::filesystem::path& name);
  // Runs `write` on `name`'s path in the stage; its InputError or OutputError names the output asked for.
  void write_staged(const std::filesystem::path& name,
                    const std::function<void(const std::filesystem::path&)>& write);
  void write_geotiffs(const std::string& stem, const LayerSet& layers);
  void remove_previous_outputs(const std::vector<std::filesystem::path>& previous);
  std::vector<std::filesystem::path> staged_;  // file names relative to the stage
  std::vector<std::filesystem::path> removed_;
  std::vector<std::filesystem::path> stale_removed_, moves_completed_;
  Georeference georeference_;
  double texel_x_ = 0, texel_y_ = 0;  // 0: not set, no attribute
  bool created_dir_ = false;          // the output folder did not exist before this job
  bool created_textures_ = false;     // nor its textures folder
  bool committed_ = false;
};

}  // namespace hfbake
