#include "cli/outputs.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "cli/texture_plan.hpp"
#include "core/error.hpp"
#include "core/safe_file.hpp"
#include "io/exr_output.hpp"
#include "io/geotiff_output.hpp"
#include "io/preview.hpp"
#include "io/texture_output.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

constexpr std::string_view kStagePrefix = ".hfbake-staging-";
// In a stage whose files are all whole and are being moved into place: their names, one a line, the owner
// record last (OutputStage::commit; docs/output_folders.md).
constexpr char kCommitList[] = "commit-list";
// The commits under way in this process (read by a signal handler: a lock-free atomic).
std::atomic<int> g_moving{0};
static_assert(std::atomic<int>::is_always_lock_free);
// The longest side of a field whose EXRs are written as scanlines (larger ones are tiled).

}  // namespace

std::string azimuth_convention(const Georeference& geo) {
  std::string s =
      "phi (directions, horizon channel k: phi_k = 360 k / K degrees) is measured from +x (image columns, i) "
      "towards +y (image rows, j)";
  if (!geo.from_file || geo.crs_wkt.empty()) return s + "; the raster has no CRS";
  // A direction phi: east = east_x cos phi, north = north_y sin phi (grid_axes); compass azimuth A has
  // east = sin A, north = cos A.
  const GridAxes axes = grid_axes(geo);
  const bool east = axes.east_x > 0, north_up = axes.north_y < 0;
  if (east && north_up)
    return s + "; north-up raster: +x = east, +y = south, compass azimuth = (90 + phi) mod 360";
  if (east && !north_up)
    return s + "; south-up raster: +x = east, +y = north, compass azimuth = (90 - phi) mod 360";
  if (!east && north_up)
    return s +
           "; north-up, east-to-west raster: +x = west, +y = south, compass azimuth = (270 - phi) mod 360";
  return s + "; +x = west, +y = north, compass azimuth = (270 + phi) mod 360";
}

std::optional<unsigned long long> process_start_time(long long pid) {
  // /proc/<pid>/stat: "pid (comm) state ..." with starttime the 22nd field; comm may hold spaces and ')'.
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat;
  if (!std::getline(in, stat)) return std::nullopt;
  const auto close = stat.rfind(')');
  if (close == std::string::npos) return std::nullopt;
  std::istringstream fields(stat.substr(close + 1));
  std::string field;
  for (int k = 3; k <= 22; ++k)
    if (!(fields >> field)) return std::nullopt;
  try {
    return std::stoull(field);
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

namespace {

// Digits only, below 2^62; nullopt otherwise.
std::optional<unsigned long long> parse_count(std::string_view s) {
  if (s.empty() || s.size() > 18) return std::nullopt;
  unsigned long long v = 0;
  for (const char c : s) {
    if (c < '0' || c > '9') return std::nullopt;
    v = v * 10 + unsigned(c - '0');
  }
  return v;
}

}  // namespace

namespace {

// An owner tag, <pid>[+<start>][@<host>] (older stages had neither a start time nor a host): the owner
// without its job; nullopt for anything else.
std::optional<StageOwner> parse_owner_tag(std::string tag) {
  StageOwner owner;
  const auto at = tag.find('@');  // hosts may hold '-' or '+', a pid and a start time do not
  if (at != std::string::npos) {
    owner.host = tag.substr(at + 1);
    tag.resize(at);
  }
  const auto plus = tag.find('+');
  if (plus != std::string::npos) {
    owner.start = parse_count(std::string_view(tag).substr(plus + 1));
    if (!owner.start) return std::nullopt;
    tag.resize(plus);
  }
  const std::optional<unsigned long long> pid = parse_count(tag);
  if (!pid || *pid == 0 || *pid > (1ull << 40)) return std::nullopt;
  owner.pid = (long long)*pid;
  return owner;
}

}  // namespace

std::optional<StageOwner> parse_stage_name(const std::string& name) {
  if (name.compare(0, kStagePrefix.size(), kStagePrefix) != 0) return std::nullopt;
  const std::string rest = name.substr(kStagePrefix.size());
  // <job>-<tag>: job names have no '@' or '+' (schema), so the tag starts after the last '-' before them.
  const auto dash = rest.rfind('-', rest.find_first_of("@+"));
  if (dash == std::string::npos) return std::nullopt;
  std::optional<StageOwner> owner = parse_owner_tag(rest.substr(dash + 1));
  if (owner) owner->job = rest.substr(0, dash);
  return owner;
}

std::string temporary_owner() {
  const long long pid = getpid();
  const std::optional<unsigned long long> start = process_start_time(pid);
  std::string tag = std::to_string(pid);
  if (start) tag.append("+").append(std::to_string(*start));  // (appends: GCC 12 warns on "+" + string)
  return tag.append("@").append(host_name());
}

std::string stage_name(const std::string& job_name) {
  return std::string(kStagePrefix) + job_name + "-" + temporary_owner();
}

bool stage_owner_is_gone(const StageOwner& owner) {
  if (!owner.host.empty() && owner.host != host_name()) return false;  // another machine's: unknowable
  if (owner.pid == getpid()) return false;  // this process's own (another job's) stage
  // kill(pid, 0): 0 = alive, EPERM = alive but another user's, ESRCH = no such process.
  if (kill(pid_t(owner.pid), 0) != 0 && errno == ESRCH) return true;
  // A process runs under that id; it is the owner only if it started when the owner did (ids are reused:
  // after a reboot, or on a busy node, a SIGKILLed bake's id may belong to anything).
  if (!owner.start) return false;  // an older stage without a start time: keep it while the id lives
  const std::optional<unsigned long long> now = process_start_time(owner.pid);
  if (now && *now != *owner.start) return true;
  // The owner itself, exited but not yet collected by its parent (a zombie, state Z or X in
  // /proc/<pid>/stat): it never runs again.
  std::ifstream in("/proc/" + std::to_string(owner.pid) + "/stat");
  std::string stat;
  if (!std::getline(in, stat)) return false;
  const auto close = stat.rfind(')');
  std::istringstream fields(close == std::string::npos ? std::string() : stat.substr(close + 1));
  std::string state;
  return fields >> state && (state == "Z" || state == "X");
}

std::vector<fs::path> remove_stale_stages(const fs::path& dir) {
  std::vector<fs::path> removed;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::optional<StageOwner> owner = parse_stage_name(it->path().filename().string());
    // A link named like a stage is no stage: removed itself, its target untouched (remove_tree). A stage
    // killed during its moves is kept for the next bake of its job name (complete_killed_commits).
    if (!owner || !stage_owner_is_gone(*owner)) continue;
    struct stat st {};
    if (is_real_directory(it->path()) && lstat((it->path() / kCommitList).c_str(), &st) == 0) continue;
    if (remove_tree(it->path())) removed.push_back(it->path());
  }
  return removed;
}

std::vector<fs::path> remove_stale_temporaries(const fs::path& dir) {
  std::vector<fs::path> removed;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    const auto tmp = name.rfind(".tmp-");
    if (tmp == std::string::npos) continue;
    // <name>.tmp-<owner>-XXXXXX (core/safe_file), or <name>.tmp-<owner>-<n>; the owner judged as a staging
    // folder's, by the same rule.
    const std::string rest = name.substr(tmp + 5);
    const std::optional<StageOwner> owner = parse_owner_tag(rest.substr(0, rest.rfind('-')));
    if (!owner || !stage_owner_is_gone(*owner)) continue;
    if (remove_tree(it->path())) removed.push_back(it->path());  // a link is removed, never its target
  }
  return removed;
}

fs::path stage_checkpoint_dir(const fs::path& stage) {
  return stage / "reference-checkpoint";
}

int adopt_stale_checkpoints(const fs::path& dir, const std::string& job_name, const fs::path& into) {
  int moved = 0;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::optional<StageOwner> owner = parse_stage_name(it->path().filename().string());
    // The stage and its checkpoint folder must be folders themselves: files are never taken through a link.
    if (!owner || owner->job != job_name || !is_real_directory(it->path()) || !stage_owner_is_gone(*owner))
      continue;
    const fs::path from = stage_checkpoint_dir(it->path());
    if (!is_real_directory(from)) continue;
    std::error_code walk;
    for (fs::directory_iterator f(from, walk), fend; !walk && f != fend; f.increment(walk)) {
      // Whole band files only (a killed writer's temporary is left to be removed with its stage).
      if (f->path().extension() != ".hfckpt" || !f->is_regular_file(walk) || f->is_symlink(walk)) continue;
      std::error_code move;
      fs::create_directories(into, move);
      if (fs::exists(into / f->path().filename(), move)) continue;
      fs::rename(f->path(), into / f->path().filename(), move);  // same file system: atomic
      moved += !move;
    }
  }
  return moved;
}

fs::path output_lock_file(const Job& job) {
  return job.output.dir / (".hfbake-" + job.name + ".lock");
}

std::optional<fs::path> textures_folder(const Job& job) {
  if (!job.doc.contains("output") || !job.doc["output"].contains("textures")) return std::nullopt;
  return job.output.dir / "textures";
}

void check_textures_folder(const Job& job) {
  const std::optional<fs::path> textures = textures_folder(job);
  std::error_code ec;
  const fs::file_status status = textures ? fs::symlink_status(*textures, ec) : fs::file_status();
  if (!textures || !fs::exists(status)) return;
  if (!fs::is_directory(status))
    throw InputError(job.file.string(), "/output/textures",
                     textures->string() + " is not a folder (" +
                         (fs::is_symlink(status) ? "a link" : "a file") +
                         "): the textures are written inside " + job.output.dir.string() + " only");
  if (access(textures->c_str(), W_OK | X_OK) != 0)
    throw InputError(job.file.string(), "/output/textures",
                     "cannot write into " + textures->string() + ": " +
                         std::error_code(errno, std::generic_category()).message());
}

fs::path textures_lock_file(const Job& job) {
  return job.output.dir / "textures" / output_lock_file(job).filename();
}

fs::path textures_owner_record(const Job& job) {
  return job.output.dir / "textures" / owner_record(job).filename();
}

fs::path report_lock_file(const Job& job) {
  return job.output.dir / ".hfbake+report.lock";
}

void check_report_owner(const Job& job) {
  if (!job.has_reference) return;
  std::error_code ec;
  const fs::path report = job.output.dir / "report.json";
  if (!fs::exists(fs::symlink_status(report, ec))) return;
  std::string owner;  // "" for a file that is no report (unreadable, or no string at /job/name)
  try {
    owner = read_json_file(report).value(nlohmann::json::json_pointer("/job/name"), std::string());
  } catch (const std::exception&) {
  }
  if (owner != job.name)
    throw InputError(
        job.file.string(), job.output.dir_key,
        report.string() + " is " +
            (owner.empty() ? std::string("no report of hfbake's") : "job \"" + owner + "\"'s report") +
            ": this job's report would replace it; give the job an output folder of its own "
            "(a job with a reference writes report.json and report.html there), or remove it");
}

fs::path owner_record(const Job& job) {
  return job.output.dir / (".hfbake-" + job.name + ".job");
}

namespace {

// The job file's absolute path as an owner record holds it: one line of printable text, a backslash and
// each control character (a tab or a newline in a folder's name) escaped as \\ and \xHH.
std::string job_identity(const Job& job) {
  std::error_code ec;
  const fs::path p = fs::weakly_canonical(fs::absolute(job.file), ec);
  const std::string path = (ec ? fs::absolute(job.file) : p).string();
  std::string text;
  for (const char c : path) {
    if (c == '\\') {
      text += "\\\\";
    } else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", unsigned(static_cast<unsigned char>(c)));
      text += hex;
    } else {
      text += c;
    }
  }
  return text;
}

// The longest owner record's first line read: job_identity of a path of PATH_MAX (4096) bytes, each
// escaped.
constexpr std::size_t kOwnerRecordBytes = 4 * 4096;
// The most of an owner record read: its first line and the names of the outputs it lists after it (a job of
// 256 entries with previews, GeoTIFFs and textures lists a few thousand).
constexpr std::size_t kOwnerRecordFileBytes = std::size_t(8) << 20;

// An owner record's text (at most kOwnerRecordFileBytes + 1 bytes), read from a regular file of its own
// (never through a link); nullopt when it cannot be opened so.
std::optional<std::string> owner_record_text(const fs::path& record) {
  std::string why, text;
  const int fd = open_regular_file(record, why);
  if (fd < 0) return std::nullopt;
  std::vector<char> buf(1 << 16);
  for (ssize_t n; text.size() <= kOwnerRecordFileBytes && (n = read(fd, buf.data(), buf.size())) > 0;)
    text.append(buf.data(), std::size_t(n));
  close(fd);
  return text;
}

}  // namespace

namespace {

// The job file `record`, an owner record, names (its first line); "" when there is none. Read as hfbake
// writes it: a regular file of its own (a link planted there is not read, and is replaced when a record is
// written), a first line of printable text that an error may quote.
std::string read_owner_record(const fs::path& record) {
  // Named, so that a user who knows it for a stray file can remove it instead of giving --overwrite.
  const std::string foreign = "a record that is not hfbake's (" + record.string();
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(record, ec);
  if (!fs::exists(status)) return "";
  // hfbake writes its records whole (write_file_atomically), as files: a link, an empty file or anything
  // else at the name was put there by something else, and is no licence to replace the outputs.
  if (!fs::is_regular_file(status)) return foreign + (fs::is_symlink(status) ? ", a link)" : ")");
  const std::optional<std::string> text = owner_record_text(record);
  if (!text || text->size() > kOwnerRecordFileBytes) return foreign + ")";
  const std::string recorded = text->substr(0, text->find('\n'));
  if (recorded.empty() || recorded.size() > kOwnerRecordBytes ||
      std::any_of(recorded.begin(), recorded.end(), [](char c) { return (unsigned char)c < 0x20; }))
    return foreign + ")";
  return recorded;
}

// Refuses (InputError at /name) the job when `record`, the owner record of its name in `folder`, names
// another job file, unless `overwrite`. `what`: what the record is of ("outputs", "tiles").
void check_owner_record(const Job& job, const fs::path& record, const fs::path& folder, bool overwrite,
                        const std::string& what = "outputs") {
  const std::string recorded = read_owner_record(record);
  if (!recorded.empty() && recorded != job_identity(job) && !overwrite)
    throw InputError(job.file.string(), "/name",
                     "the " + what + " of job " + job.name + " in " + folder.string() + " were baked from " +
                         recorded + ": give this job another name or output folder, or give --overwrite");
}

}  // namespace

void check_output_owner(const Job& job, bool overwrite) {
  check_owner_record(job, owner_record(job), job.output.dir, overwrite);
  if (const std::optional<fs::path> textures = textures_folder(job))
    check_owner_record(job, textures_owner_record(job), *textures, overwrite);
}

fs::path tiles_folder(const Job& job) {
  return job.output.dir / "tiles";
}

std::string tile_file_prefix(const Job& job) {
  return job.name + "+tile-";
}

fs::path tiles_lock_file(const Job& job) {
  return tiles_folder(job) / (".hfbake-" + job.name + "+tiles.lock");
}

fs::path tiles_owner_record(const Job& job) {
  return tiles_folder(job) / (".hfbake-" + job.name + "+tiles.job");
}

namespace {

// What a task folder of the job (tiles/, shards/) must be before a task writes into it: a real folder or
// absent (a link or file would take the task's files outside the output folder: InputError at /output/dir),
// with its lock's name free or a file and nothing but a file at its owner record's name. `what`: the files
// the folder holds ("tiles", "shards").
void check_task_folder(const Job& job, const fs::path& folder, const fs::path& lock_file,
                       const fs::path& record, const std::string& what) {
  std::error_code ec;
  const fs::file_status s = fs::symlink_status(folder, ec);
  if (fs::exists(s) && !fs::is_directory(s))
    throw InputError(job.file.string(), job.output.dir_key,
                     folder.string() + " is not a folder (" + (fs::is_symlink(s) ? "a link" : "a file") +
                         "): the " + what + " are written inside " + job.output.dir.string() + " only");
  if (const std::string problem = lock_name_problem(lock_file); !problem.empty())
    throw InputError(job.file.string(), job.output.dir_key, problem);
  // A folder at the owner record's name: a task could not write there.
  if (const std::string problem = output_name_problem(record); !problem.empty())
    throw InputError(job.file.string(), job.output.dir_key, problem);
}

}  // namespace

void check_tiles_folder(const Job& job, bool overwrite) {
  const fs::path folder = tiles_folder(job);
  check_task_folder(job, folder, tiles_lock_file(job), tiles_owner_record(job), "tiles");
  std::error_code ec;
  // A folder at a tile file's name: a task could not write there.
  if (fs::is_directory(fs::symlink_status(folder, ec)))
    for (const fs::directory_entry& e : fs::directory_iterator(folder, ec))
      if (e.path().filename().string().rfind(tile_file_prefix(job), 0) == 0)
        if (const std::string problem = output_name_problem(e.path()); !problem.empty())
          throw InputError(job.file.string(), job.output.dir_key, problem);
  check_owner_record(job, tiles_owner_record(job), folder, overwrite, "tiles");
}

namespace {

// What a task does before it writes files of the job's name into `folder` (tiles/, shards/): makes the
// folder and, holding `lock` (waited for up to kTilesClaimPatience; InputError at /output/dir naming the
// holder after that), runs `check` (the folder's own checks and its owner record) and records this job
// file as the owner of the job's name there. `what`: the files claimed ("tiles", "shards").
template <class Check>
void claim_task_folder(const Job& job, const fs::path& folder, const fs::path& lock_file,
                       const fs::path& record, const std::string& what, const Check& check) {
  std::error_code ec;
  fs::create_directories(folder, ec);
  check();  // the folder a folder itself, and the lock's name free or a file
  const FolderLock lock(lock_file, kTilesClaimPatience);
  if (!lock.held())
    throw InputError(job.file.string(), job.output.dir_key,
                     lock.problem().empty() ? lock.holder_words() + " has been claiming the " + what +
                                                  " of job " + job.name + " in " + folder.string() + " for " +
                                                  std::to_string(kTilesClaimPatience.count()) +
                                                  " s: wait for it, then bake again"
                                            : not_a_lock_file(lock_file, lock.problem()));
  check();
  if (read_owner_record(record) == job_identity(job)) return;
  try {
    write_file_atomically(record, job_identity(job));
  } catch (const std::system_error& e) {
    throw InputError(job.file.string(), job.output.dir_key,
                     "cannot write " + record.string() + ": " + e.code().message());
  }
}

}  // namespace

void claim_tiles_folder(const Job& job, bool overwrite) {
  claim_task_folder(job, tiles_folder(job), tiles_lock_file(job), tiles_owner_record(job), "tiles",
                    [&] { check_tiles_folder(job, overwrite); });
}

fs::path shards_folder(const Job& job) {
  return job.output.dir / "shards";
}

fs::path shards_lock_file(const Job& job) {
  return shards_folder(job) / (".hfbake-" + job.name + "+shards.lock");
}

fs::path shards_owner_record(const Job& job) {
  return shards_folder(job) / (".hfbake-" + job.name + "+shards.job");
}

void check_shards_owner(const Job& job, bool overwrite) {
  const fs::path folder = shards_folder(job);
  check_task_folder(job, folder, shards_lock_file(job), shards_owner_record(job), "shards");
  check_owner_record(job, shards_owner_record(job), folder, overwrite, "shards");
}

void claim_shards_folder(const Job& job, bool overwrite) {
  claim_task_folder(job, shards_folder(job), shards_lock_file(job), shards_owner_record(job), "shards",
                    [&] { check_shards_owner(job, overwrite); });
}

std::string output_name_problem(const fs::path& target) {
  std::error_code ec;
  if (fs::symlink_status(target, ec).type() != fs::file_type::directory) return "";
  return target.string() + " is a folder where an output goes: remove it";
}

bool outputs_moving() noexcept {
  return g_moving.load() > 0;
}

namespace {

// A name the commit list may hold: a file of the stage or of its textures/ folder, as OutputStage stages
// them (no absolute path, no "..", no hidden name but the owner records).
bool committable_name(const fs::path& name, const Job& job) {
  if (name.empty() || name.is_absolute()) return false;
  const std::vector<fs::path> parts(name.begin(), name.end());
  const fs::path record = owner_record(job).filename();
  if (parts.size() == 1) return parts[0] == record || parts[0].string()[0] != '.';
  return parts.size() == 2 && parts[0] == "textures" && (parts[1] == record || parts[1].string()[0] != '.');
}

// The outputs `record`, the job's owner record, lists after its first line: those of the bake that wrote
// it. Names that are not this job's outputs as OutputStage stages them (committable_name; report.json,
// report.html, or "<name>." at their start and an image's extension: exr, png, tif, tga) are left out; none
// when the record cannot be read as hfbake writes it.
std::vector<fs::path> recorded_outputs(const fs::path& record, const Job& job) {
  std::vector<fs::path> names;
  const std::optional<std::string> text = owner_record_text(record);
  if (!text || text->size() > kOwnerRecordFileBytes) return names;
  std::istringstream lines(*text);
  std::string line;
  std::getline(lines, line);  // the job file
  while (std::getline(lines, line)) {
    const fs::path name = line;
    const std::string file = name.filename().string(), ext = name.extension().string();
    const bool report = !name.has_parent_path() && (file == "report.json" || file == "report.html");
    const bool image = file.rfind(job.name + ".", 0) == 0 &&
                       (ext == ".exr" || ext == ".png" || ext == ".tif" || ext == ".tga");
    if (committable_name(name, job) && (report || image)) names.push_back(name);
  }
  return names;
}

}  // namespace

std::vector<fs::path> complete_killed_commits(const Job& job) {
  std::vector<fs::path> completed;
  std::error_code ec;
  for (fs::directory_iterator it(job.output.dir, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path stage = it->path();
    const std::optional<StageOwner> owner = parse_stage_name(stage.filename().string());
    if (!owner || owner->job != job.name || !is_real_directory(stage) || !stage_owner_is_gone(*owner))
      continue;
    std::string why;
    const int fd = open_regular_file(stage / kCommitList, why);
    if (fd < 0) continue;  // killed before its files were whole: nothing of it is an output
    std::string list;
    char buf[4096];
    for (ssize_t n; (n = read(fd, buf, sizeof buf)) > 0;) list.append(buf, std::size_t(n));
    close(fd);
    std::istringstream lines(list);
    for (std::string line; std::getline(lines, line);) {
      const fs::path name = line;
      if (!committable_name(name, job)) continue;
      struct stat st {};
      // A folder in the name (textures/) is a real folder on both sides: a link planted in the stage would
      // move a file from outside the output folder into it.
      if (name.has_parent_path() && (!is_real_directory(stage / name.parent_path()) ||
                                     !is_real_directory(job.output.dir / name.parent_path())))
        continue;
      if (lstat((stage / name).c_str(), &st) != 0 || !S_ISREG(st.st_mode)) continue;  // moved already
      std::error_code mv;
      fs::rename(stage / name, job.output.dir / name, mv);
    }
    sync_folder(job.output.dir);
    unlink((stage / kCommitList).c_str());  // then an ordinary stale stage: remove_stale_stages takes it
    completed.push_back(stage);
  }
  return completed;
}

OutputStage::OutputStage(const Job& job, bool overwrite) : job_(job) {
  std::error_code ec;
  created_dir_ = !fs::exists(job.output.dir, ec);
  fs::create_directories(job.output.dir, ec);
  if (ec || !fs::is_directory(job.output.dir))
    throw InputError(job.file.string(), job.output.dir_key,
                     "cannot create " + job.output.dir.string() + ": " +
                         (ec ? ec.message() : std::string("not a folder")));
  // Before a refusal: the locks given up, and the folders this job made removed (when still empty).
  const auto release = [&] {
    textures_lock_.reset();
    report_lock_.reset();
    lock_.reset();
    std::error_code rm;
    if (created_textures_) fs::remove(job.output.dir / "textures", rm);
    if (created_dir_) fs::remove(job.output.dir, rm);
  };
  // Takes `slot`'s lock on `file`, or gives up every lock and refuses: not a lock file, or held by another
  // process (busy: what that process does, after FolderLock::holder_words).
  const auto take = [&](std::unique_ptr<FolderLock>& slot, const fs::path& file, const std::string& busy) {
    slot = std::make_unique<FolderLock>(file);
    if (slot->held()) return;
    const std::string problem = slot->problem(), holder = slot->holder_words();
    release();
    throw InputError(job.file.string(), job.output.dir_key,
                     problem.empty() ? holder + " " + busy : not_a_lock_file(file, problem));
  };
  // One writer per job name and folder (docs/output_folders.md).
  take(lock_, output_lock_file(job),
       "is baking or merging job " + job.name + " into " + job.output.dir.string() +
           " now: wait for it, or give this job another name or folder");
  // A job with a reference also writes report.json and report.html, which carry no job name: one such job
  // at a time per folder, and only over its own report (docs/output_folders.md).
  if (job.has_reference)
    take(report_lock_, report_lock_file(job),
         "is baking or merging a job with a reference into " + job.output.dir.string() +
             " now (report.json and report.html carry no job name): wait for it, or give this job an output "
             "folder of its own");
  // A job that writes textures holds its name's lock in the textures folder too: another job may bake into
  // that folder (docs/output_folders.md).
  if (const std::optional<fs::path> textures = textures_folder(job)) {
    created_textures_ = !fs::exists(fs::symlink_status(*textures, ec));
    fs::create_directory(*textures, ec);
    try {
      check_textures_folder(job);
    } catch (const InputError&) {
      release();
      throw;
    }
    take(textures_lock_, textures_lock_file(job),
         "is baking or merging job " + job.name + " into " + textures->string() +
             ", where this job writes its textures, now: wait for it, or give this job another name or "
             "folder");
  }
  // A process killed while it moved this job's outputs (it held the lock) left them part moved: its moves
  // are completed first, so that the folder holds one bake's outputs and the record names its job file.
  moves_completed_ = complete_killed_commits(job);
  try {
    check_output_owner(job, overwrite);
    check_report_owner(job);
  } catch (const InputError&) {
    release();
    throw;
  }
  // Hidden, per process (id and start time), host and job: concurrent jobs and concurrent hfbake processes
  // never share a stage, and a later bake can tell when its owner is gone. A name already there (a link
  // included) is removed, never followed, and the folder made afresh.
  // Everything below happens inside the folder held now: a link planted at the output folder's name, the
  // stage's or a folder in it, while the job runs, is never written through.
  out_held_ = HeldFolder(job.output.dir, /*follow_link=*/true);
  stage_ = job.output.dir / stage_name(job.name);
  const fs::path stage_in_held = out_held_.path() / stage_name(job.name);
  remove_tree(stage_in_held);
  if (!out_held_.held() || !fs::create_directory(stage_in_held, ec) || ec ||
      !(stage_held_ = HeldFolder(stage_in_held, false)).held() ||
      !fs::create_directory(stage_held_.path() / "reference-checkpoint", ec) || ec ||
      !(checkpoint_held_ = HeldFolder(stage_held_.path() / "reference-checkpoint", false)).held()) {
    release();
    throw InputError(
        job.file.string(), job.output.dir_key,
        "cannot write into " + job.output.dir.string() + ": " +
            (ec ? ec.message() : std::string("its staging folder was replaced while it was made")));
  }
  // Stages that processes which no longer run left behind (killed by SIGKILL, a second signal, a crash):
  // this job's reference checkpoints are taken over first (a resumed reference), then the stages removed.
  adopt_stale_checkpoints(job.output.dir, job.name, checkpoint_dir());
  stale_removed_ = remove_stale_stages(job.output.dir);
}

std::vector<std::string> OutputStage::notes() const {
  std::vector<std::string> lines;
  for (const fs::path& p : moves_completed_)
    lines.push_back("completed the moves of " + p.string() +
                    " (a bake killed while it moved its outputs into place): the folder holds that bake's "
                    "outputs until this one's replace them");
  for (const fs::path& p : stale_removed_)
    lines.push_back("removed " + p.string() + " (left by a process that no longer runs)");
  return lines;
}

OutputStage::~OutputStage() {
  std::error_code ec;
  // The stage held, emptied (wherever its name now points), then its name removed (a link, never followed).
  if (stage_held_.held()) {
    std::vector<fs::path> entries;
    for (fs::directory_iterator it(stage_held_.path(), ec), end; !ec && it != end; it.increment(ec))
      entries.push_back(it->path());
    for (const fs::path& e : entries) remove_tree(e);
  }
  if (out_held_.held()) remove_tree(out_held_.path() / stage_.filename());
  textures_lock_.reset();
  report_lock_.reset();
  lock_.reset();
  // A job that failed or was stopped leaves no empty output or textures folder behind it (only if it made
  // the folder, and only while it is empty: another job's stage or outputs keep it).
  if (created_textures_ && !committed_) fs::remove(job_.output.dir / "textures", ec);
  if (created_dir_ && !committed_) fs::remove(job_.output.dir, ec);
}

namespace {

// The index of the first value `ok` refuses (values.size(): none). Chunks of values are tested without
// branches, and only a chunk holding a refused value is searched. A whole chunk's loop has a fixed count
// and an int accumulator, which is what GCC vectorises (a 64-channel horizon stack is 256 MiB of values).
template <class Ok>
std::size_t first_bad(const std::vector<float>& values, const Ok& ok) {
  constexpr std::size_t kChunk = 4096;
  const float* d = values.data();
  const std::size_t n = values.size();
  for (std::size_t k0 = 0; k0 < n; k0 += kChunk) {
    const float* c = d + k0;
    int all = 1;
    if (n - k0 >= kChunk) {
      for (std::size_t k = 0; k < kChunk; ++k) all &= int(ok(c[k]));
    } else {
      for (std::size_t k = 0; k < n - k0; ++k) all &= int(ok(c[k]));
    }
    if (all) continue;
    std::size_t k = k0;
    while (ok(d[k])) ++k;
    return k;
  }
  return values.size();
}

}  // namespace

void check_layers_finite(const std::string& stem, const LayerSet& layers) {
  // Layers broken on purpose (cli/test_break.hpp: +0.05 everywhere) are meant to reach the report.
  const bool broken = std::any_of(layers.attributes.begin(), layers.attributes.end(),
                                  [](const auto& a) { return a.first == "hfbake:test_break"; });
  for (const Layer& layer : layers.layers) {
    // A distance is +inf where nothing lies behind the texel (documented); NaN is never a result.
    const LayerKind* kind = find_layer_kind(layer.name);
    const bool plus_inf_allowed = kind && kind->values == LayerValues::distance;
    // Fractions of the sky (README, outputs): in [0, 1], up to a quadrature's error (p1 with 4 directions
    // on a 16x16 fractal reaches an ao of 1.0019); beyond 5 % the inputs left the methods' range.
    const bool fraction = !broken && kind && kind->values == LayerValues::fraction;
    constexpr float kRounding = 0.05f;
    const std::size_t nc = layer.channels.size();
    const float largest = std::numeric_limits<float>::max();
    const std::size_t k =
        fraction ? first_bad(layer.data, [&](float v) { return (v >= -kRounding) & (v <= 1 + kRounding); })
                 : first_bad(layer.data, [&](float v) {
                     return (std::abs(v) <= largest) | (plus_inf_allowed & (v > 0));
                   });
    if (k < layer.data.size()) {
      const float v = layer.data[k];
      const std::size_t texel = k / nc;
      char value[32];
      std::snprintf(value, sizeof value, "%g", double(v));
      throw std::runtime_error(
          stem + ": layer " + layer.name + ": texel (" + std::to_string(texel % std::size_t(layers.width)) +
          ", " + std::to_string(texel / std::size_t(layers.width)) + ") channel " + layer.name + "." +
          layer.channels[k % nc] + " is " + value + (fraction ? ", outside [0, 1]" : "") +
          "; nothing of this job was written (such a result is a bug or an input "
          "beyond the method's range: please report it)");
    }
  }
}

namespace {

std::string short_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2g", v);
  return buf;
}

// v in as few significant digits (two at least) as tell it from `other` (a value above 1 from 1, an
// exposure from the one given), rounded down when `down` (an exposure that brings a value to 1 stays at
// most that).
std::string distinct_number(double v, double other, bool down = false) {
  char buf[32], them[32];
  for (int d = 2; d <= 9; ++d) {
    double t = v;
    if (down && v > 0) {
      const double unit = std::pow(10.0, std::floor(std::log10(v)) - (d - 1));
      t = std::floor(v / unit) * unit;
    }
    std::snprintf(buf, sizeof buf, "%.*g", d, t);
    std::snprintf(them, sizeof them, "%.*g", d, other);
    if (std::strtod(buf, nullptr) != std::strtod(them, nullptr)) return buf;
  }
  return buf;
}

// "textures/x.p1.direct.png: 73.2 % of its values were above 1 and clipped (largest 3.7); "exposure": 0.27
// would bring 99 % of them into range" (the exposure that maps the 99th percentile, or the largest value
// when under 1 % clip, to 1).
// A pack that also holds masks or directions (a layer whose values are not light: ao, bent_normal, ...) gets
// no exposure advice, since an exposure would scale those too (and the pack's own exposure already did);
// it is told to give the light a file of its own.
std::string clipping_notice(const std::string& file, const TextureClipping& c, const TextureSpec& spec) {
  char share[32];
  std::snprintf(share, sizeof share, "%.1f", 100.0 * double(c.clipped) / double(c.values));
  const std::string head = "warning: " + file + ": " + share +
                           " % of its values were above 1 and clipped to 1 (largest " +
                           distinct_number(c.largest, 1.0) + "); ";
  for (const TextureSource& t : spec.channels) {
    const LayerKind* kind = t.layer.empty() ? nullptr : find_layer_kind(t.layer);
    if (kind && (kind->values == LayerValues::fraction || kind->channels == LayerChannels::xyz))
      return head +
             (spec.exposure != 1 ? "its \"exposure\" of " + short_number(spec.exposure) + " scales its "
                                 : std::string("an \"exposure\" would scale its ")) +
             t.layer + " channel too: give the light layers a texture of their own, with an exposure";
  }
  const bool few = double(c.clipped) <= 0.01 * double(c.values);
  const double suggested = spec.exposure / (few ? c.largest : c.p99);
  return head + "\"exposure\": " + distinct_number(suggested, spec.exposure, true) + " would bring " +
         (few ? "all" : "99 %") + " of them into range";
}

}  // namespace

std::vector<std::string> OutputStage::write_layers(const std::string& stem, const LayerSet& layers) {
  check_layers_finite(stem, layers);  // before anything is written: no output holds a NaN or an Inf
  const std::string exr = job_.name + "." + stem + ".exr";
  ExrOptions options;
  options.float_pixels = job_.output.float_pixels;
  options.compression =
      job_.output.compression.empty() ? default_exr_compression(layers) : job_.output.compression;
  // Tiles of 256 once a field is larger than a preview: OpenImageIO's cache (oiiotool, iv) and Nuke then read
  // what they show, not the whole file (a 512^2 crop of a 16384^2 scanline EXR: 9.6 s and 1.25 GB; tiled:
  // 0.55 s, 0.14 GB), for 0.2 % more bytes. Smaller fields stay scanline files, as before.
  options.tile_size = std::max(layers.width, layers.height) > kLargestScanlineExr ? 256 : 0;
  options.attributes.emplace_back("hfbake:azimuth_convention", azimuth_convention(georeference_));
  if (texel_x_ > 0) {
    char sides[64];
    std::snprintf(sides, sizeof sides, "%.15g %.15g", texel_x_, texel_y_);
    options.attributes.emplace_back("hfbake:texel_size", sides);
  }
  write_staged(exr, [&](const fs::path& at) { write_exr(at, layers, options); });
  staged_.push_back(exr);
  if (job_.output.geotiff) write_geotiffs(stem, layers);
  std::vector<std::string> notices = write_textures(stem, layers);
  if (!job_.output.previews) return notices;
  PreviewOptions preview;
  preview.display = job_.output.preview_display;
  preview.view = job_.output.preview_view;
  for (const Layer& layer : layers.layers) {
    if (!is_previewed(layer.name, layer.channel_count())) continue;
    const std::string png = job_.name + "." + stem + "." + layer.name + ".preview.png";
    // Light and fractions of the sky through the display transform; a quantity in a unit of its own
    // (openness in degrees, the sun's irradiation and hours: mono layers that are neither) over its range.
    const LayerKind* kind = find_layer_kind(layer.name);
    preview.stretch = layer.channel_count() == 1 && (!kind || kind->values == LayerValues::finite);
    write_staged(png, [&](const fs::path& at) { write_preview(at, layers, layer, preview); });
    staged_.push_back(png);
  }
  return notices;
}

std::vector<std::pair<std::string, std::string>> OutputStage::geotiff_metadata(
    const std::vector<std::pair<std::string, std::string>>& attributes) const {
  std::vector<std::pair<std::string, std::string>> metadata;
  for (const auto& [key, value] : attributes) {
    std::string k = key;  // "hfbake:method" -> "HFBAKE_METHOD" (GDAL metadata names)
    for (char& c : k) c = c == ':' ? '_' : char(std::toupper(static_cast<unsigned char>(c)));
    metadata.emplace_back(k, value);
  }
  metadata.emplace_back("HFBAKE_AZIMUTH_CONVENTION", azimuth_convention(georeference_));
  if (texel_x_ > 0) {  // as the EXR's hfbake:texel_size
    char sides[64];
    std::snprintf(sides, sizeof sides, "%.15g %.15g", texel_x_, texel_y_);
    metadata.emplace_back("HFBAKE_TEXEL_SIZE", sides);
  }
  return metadata;
}

void OutputStage::write_geotiffs(const std::string& stem, const LayerSet& layers) {
  GeoTiffOptions options;
  options.metadata = geotiff_metadata(layers.attributes);
  for (const Layer& layer : layers.layers) {
    const std::string tif = job_.name + "." + stem + "." + layer.name + ".tif";
    write_staged(tif, [&](const fs::path& at) { write_geotiff(at, layers, layer, georeference_, options); });
    staged_.push_back(tif);
  }
}

std::vector<std::string> OutputStage::write_textures(const std::string& stem, const LayerSet& layers) {
  std::vector<std::string> notices;
  for (PlannedTexture& t : plan_textures(job_)) {
    if (t.stem != stem) continue;
    for (std::size_t c = 0; c < t.spec.channels.size(); ++c) {  // suffix -> the layer's channel index
      TextureSource& s = t.spec.channels[c];
      if (s.layer.empty()) continue;
      const Layer* layer = layers.find(s.layer);
      const auto at = layer ? std::find(layer->channels.begin(), layer->channels.end(), t.suffixes[c])
                            : std::vector<std::string>::const_iterator();
      if (!layer || at == layer->channels.end())
        throw std::logic_error("texture " + t.file + ": " + stem + " has no channel " + s.layer + "." +
                               t.suffixes[c]);
      s.channel = int(at - layer->channels.begin());
    }
    TextureClipping clipped;
    write_staged(t.file, [&](const fs::path& at) { clipped = write_texture(at, layers, t.spec); });
    staged_.push_back(t.file);
    if (!t.note.empty()) notices.push_back(t.note);
    if (clipped.clipped > 0) notices.push_back(clipping_notice(t.file, clipped, t.spec));
    if (clipped.negative > 0) {
      char share[32];
      std::snprintf(share, sizeof share, "%.1f", 100.0 * double(clipped.negative) / double(clipped.values));
      notices.push_back("warning: " + t.file + ": " + share +
                        " % of its values were below 0 and clipped to 0 (a signed channel, such as a bent "
                        "normal's or a horizon's, needs a texture of its own: docs/textures.md)");
    }
  }
  return notices;
}

void OutputStage::write_staged(const fs::path& name, const std::function<void(const fs::path&)>& write) {
  const fs::path held = in_stage(name);
  try {
    write(held);
  } catch (const InputError& e) {
    // The writer named the held folder's path (/proc/self/fd/N/...): the error names the output asked for,
    // and a temporary beside it by the stage's name in the output folder.
    std::string what = e.what();
    const std::string from = held.parent_path().string(), to = (stage_ / name.parent_path()).string();
    for (std::size_t at = what.find(from); at != std::string::npos; at = what.find(from, at + to.size()))
      what.replace(at, from.size(), to);
    const std::string file = (job_.output.dir / name).string();
    if (dynamic_cast<const OutputError*>(&e)) throw OutputError(file, e.where(), what);
    throw InputError(file, e.where(), what);
  }
}

fs::path OutputStage::in_stage(const fs::path& name) {
  if (!name.has_parent_path()) return stage_held_.path() / name;
  // The stage's textures folder (the only folder a name holds), made and held at its first file.
  if (!stage_textures_held_.held()) {
    std::error_code ec;
    fs::create_directory(stage_held_.path() / name.parent_path(), ec);
    stage_textures_held_ = HeldFolder(stage_held_.path() / name.parent_path(), false);
    if (!stage_textures_held_.held())
      throw OutputError((stage_ / name.parent_path()).string(), "",
                        "cannot write into it: it was replaced (by a link?) while the job ran");
  }
  return stage_textures_held_.path() / name.filename();
}

void OutputStage::write_text(const std::string& filename, const std::string& text) {
  std::ofstream out(in_stage(filename), std::ios::binary);
  out << text;
  out.close();
  if (!out) throw OutputError((job_.output.dir / filename).string(), "", "cannot write file");
  staged_.push_back(filename);
}

void OutputStage::remove_previous_outputs(const std::vector<fs::path>& previous) {
  // textures/ is a folder another job may bake into: its previous textures are this job's to remove only
  // under the name's lock there and while the folder's record still names this job file (a job of this
  // name baking into textures/ with --overwrite took them over). A bake that writes textures holds both.
  std::unique_ptr<FolderLock> textures_lock;
  bool textures_ours = textures_lock_ != nullptr;
  const auto take_textures = [&] {
    if (!is_real_directory(out_held_.path() / "textures")) return false;
    if (!out_textures_held_.held()) out_textures_held_ = HeldFolder(out_held_.path() / "textures", false);
    if (!out_textures_held_.held()) return false;
    textures_lock =
        std::make_unique<FolderLock>(out_textures_held_.path() / textures_lock_file(job_).filename());
    return textures_lock->held() &&
           read_owner_record(out_textures_held_.path() / owner_record(job_).filename()) == job_identity(job_);
  };
  bool textures_tried = textures_ours;
  for (const fs::path& name : previous) {
    if (std::find(staged_.begin(), staged_.end(), name) != staged_.end()) continue;
    if (name.has_parent_path()) {
      if (!textures_tried) textures_ours = take_textures(), textures_tried = true;
      if (!textures_ours || !out_textures_held_.held()) continue;
    }
    const fs::path at =
        name.has_parent_path() ? out_textures_held_.path() / name.filename() : out_held_.path() / name;
    struct stat st {};
    if (lstat(at.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) continue;
    if (unlink(at.c_str()) == 0) removed_.push_back(job_.output.dir / name);
  }
}

std::vector<fs::path> OutputStage::commit() {
  std::vector<fs::path> final_paths;
  // A name rename(2) cannot replace (a folder there, the owner record's included) fails the job before any
  // output moves or any folder is made, so that the folder keeps the previous outputs whole.
  auto refuse_folder = [this](const fs::path& name) {
    if (const std::string problem = output_name_problem(job_.output.dir / name); !problem.empty())
      throw InputError(job_.file.string(),
                       name.has_parent_path() ? std::string("/output/textures") : job_.output.dir_key,
                       problem);
  };
  // The owner records, moved after the outputs: the textures folder's (a job that writes textures), then the
  // output folder's, last.
  std::vector<fs::path> records;
  if (textures_folder(job_)) records.push_back(fs::path("textures") / owner_record(job_).filename());
  records.push_back(owner_record(job_).filename());
  std::vector<fs::path> moves = staged_;
  moves.insert(moves.end(), records.begin(), records.end());
  for (const fs::path& name : moves) refuse_folder(name);
  for (const fs::path& name : moves) {  // textures/: made here, never a link to elsewhere
    if (!name.has_parent_path() || out_textures_held_.held()) continue;
    const fs::path folder = (job_.output.dir / name).parent_path();
    std::error_code ec;
    fs::create_directories(out_held_.path() / name.parent_path(), ec);
    out_textures_held_ = HeldFolder(out_held_.path() / name.parent_path(), false);
    if (!out_textures_held_.held())
      throw InputError(
          folder.string(), "",
          "is not a folder (a link?): outputs are written inside " + job_.output.dir.string() + " only");
  }
  // Where a move puts `name`: in the held output folder, or its held textures folder.
  const auto in_output = [&](const fs::path& name) {
    return name.has_parent_path() ? out_textures_held_.path() / name.filename() : out_held_.path() / name;
  };
  // Every output on the disk before any moves (core/safe_file.hpp sync_file): a machine that crashes after
  // the moves finds whole files under the outputs' names, and a disk that could not take a file (a full
  // network disk reports it only at the flush) fails the job while the previous outputs are still there.
  for (const fs::path& name : staged_)
    if (const int e = sync_file(in_stage(name)))
      throw OutputError((job_.output.dir / name).string(), "",
                        "cannot write file: " + std::error_code(e, std::generic_category()).message());
  // The owner records are written in the stage like the outputs, then the commit list: from the list on,
  // the stage is whole, and a process killed during the moves leaves a stage the next bake of this job name
  // completes (complete_killed_commits); killed before it, its stage is removed and no output moved.
  // The main record lists the outputs after the job file: the next bake of the job removes those it no
  // longer writes.
  std::string listed = job_identity(job_);
  for (const fs::path& name : staged_) listed.append("\n").append(name.string());
  const std::vector<fs::path> previous =
      recorded_outputs(out_held_.path() / owner_record(job_).filename(), job_);
  try {
    for (const fs::path& name : records)
      write_file_atomically(in_stage(name), name == records.back() ? listed : job_identity(job_));
    std::string list;
    for (const fs::path& name : moves) list += name.string() + "\n";
    write_file_atomically(in_stage(kCommitList), list);
  } catch (const std::system_error& e) {
    throw OutputError(owner_record(job_).string(), "", std::string("cannot write: ") + e.code().message());
  }
  // A stop signal during the moves lets them finish (outputs_moving).
  struct Moving {
    Moving() { ++g_moving; }
    ~Moving() { --g_moving; }
  } moving;
  for (std::size_t k = 0; k < moves.size(); ++k) {
    // Between the outputs and the records: the previous bake's outputs that this one does not write, files
    // only (a link or a folder at such a name is not hfbake's output), from the held folders.
    if (k == staged_.size()) remove_previous_outputs(previous);
    const fs::path target = job_.output.dir / moves[k];
    std::error_code ec;
    fs::rename(in_stage(moves[k]), in_output(moves[k]), ec);  // same folder tree: an atomic replace
    if (ec) throw OutputError(target.string(), "", "cannot move into place: " + ec.message());
    if (k < staged_.size()) final_paths.push_back(target);
  }
  // The moves themselves on the disk: the output folder's entries (and textures/'s).
  sync_folder(out_held_.path());
  if (out_textures_held_.held()) sync_folder(out_textures_held_.path());
  staged_.clear();
  committed_ = true;
  return final_paths;
}

}  // namespace hfbake
