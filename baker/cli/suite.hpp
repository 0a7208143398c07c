// Suites: a JSON file listing jobs (paths or globs) that run together, e.g. a nightly accuracy run.
// A file given to `hfbake bake` is a suite when it has a "suite" key (schema: schemas/suite.schema.json).
#pragma once

#include <chrono>
#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cli/job_outcome.hpp"

namespace hfbake {

struct Suite {
  std::filesystem::path file;
  std::string name;
  std::filesystem::path output_dir;         // absolute; every job writes to output_dir/<job file stem>/
  std::vector<std::filesystem::path> jobs;  // expanded, sorted within each glob, duplicates removed
  // Jobs left out because a file they need (the entry's "needs") is not on this machine: one line each,
  // "<job>: skipped: <file> is not on this machine", for the caller to print as a notice.
  std::vector<std::string> skipped;
};

// nullopt when `file` is not a suite (or is not JSON at all: the job loader reports that).
// Problems with a suite file are appended to `errors` as one-line messages.
std::optional<Suite> load_suite(const std::filesystem::path& file, std::vector<std::string>& errors);

// A job of one call (bake, merge, validate, slurm): a job file given as such, or one that a suite of the
// call lists.
struct CallJob {
  std::filesystem::path file;
  // The output folder the call gives the job in place of its output.dir: <suite output folder>/<job file
  // stem>/ for a suite's job; with --out DIR, DIR for the call's only job file and DIR/<job file stem>/ for
  // one of several; nullopt: the job's own output.dir.
  std::optional<std::filesystem::path> out;
  int suite = -1;  // index into CallJobs::suites; -1: a job file given as such
  // What gave `out`, as messages name it: "--out", or the suite's own output.dir.
  std::string out_key = "--out";
};

struct CallJobs {
  std::vector<CallJob> jobs;  // in the order of the files, a suite's in its order
  std::vector<Suite> suites;  // each with its output folder (--out DIR: DIR/<suite name>)
  // One line each: a suite that cannot be read or whose folder is refused (suite_folder_problem); none of
  // its jobs is listed.
  std::vector<std::string> errors;
};

// The jobs of one call from the files given (job files and suites) and --out (`out`): the one home of which
// jobs a call runs and where each writes, for bake, merge, validate and slurm alike. A file that is not a
// suite (or not JSON at all) is a job; load_job reports what is wrong with it.
CallJobs call_jobs(const std::vector<std::filesystem::path>& files,
                   const std::optional<std::filesystem::path>& out);

// How many runs history.json keeps (the newest; the index shows them per job).
inline constexpr std::size_t kSuiteHistoryRuns = 10;

// One run of the suite as history.json records it: {"finished": UTC "YYYY-MM-DDTHH:MM:SSZ", "hfbake_version",
// "seconds", "jobs": {<job file's path from the suite's folder, without its extension>: {"status", "seconds",
// "baseline_regressions" (only when the job names a baseline)}}}.
nlohmann::json suite_history_run(const Suite& suite, const std::vector<JobOutcome>& outcomes, double seconds,
                                 const std::string& finished);

// `history` (history.json's document, {"runs": [...]}, oldest first) with `run` appended, keeping the newest
// kSuiteHistoryRuns runs. A document of another shape (damaged or hand-edited) is dropped: the result starts
// afresh with `run`, and `dropped` says so.
nlohmann::json append_suite_history(const nlohmann::json& history, nlohmann::json run, bool& dropped);

struct SuiteReports {
  std::vector<std::filesystem::path> files;  // written
  std::vector<std::string> warnings;         // one line each, for the caller to print
};

// The files write_suite_reports writes into suite.output_dir, in this order: suite.json, history.json,
// index.html, junit.xml.
std::vector<std::filesystem::path> suite_report_files(const Suite& suite);

// <output dir>/.hfbake+suite.lock: the file write_suite_reports locks while it reads history.json and writes
// the reports (docs/output_folders.md). No job's lock has this name (a job name never starts with '+').
std::filesystem::path suite_lock_file(const Suite& suite);

// How long a suite waits for another process's suite reports into the same folder (a few files: seconds at
// most, unless that process is stopped).
inline constexpr std::chrono::seconds kSuiteLockPatience{60};
// The wait write_suite_reports gives the suite lock: kSuiteLockPatience, or the whole seconds of
// HFBAKE_TEST_SUITE_LOCK_WAIT, up to kSuiteLockPatience, when it holds them. A test-only switch
// (docs/development.md), so that a test sees the wait end without waiting a minute; never set in production.
std::chrono::seconds suite_lock_patience();

// What write_suite_reports would refuse only after the suite's jobs have baked: its lock's name taken by
// anything but a file (a link, a folder). The error line (the suite file, /output/dir), or "" when none.
std::string suite_folder_problem(const Suite& suite);

// suite.json (per job: status, outputs, metrics, the comparison with the job's baseline), history.json (the
// last kSuiteHistoryRuns runs), index.html (per job: status, time, reference, the baseline comparison, the
// last runs' results and a link to the report), junit.xml. Written atomically into suite.output_dir, all
// four under suite_lock_file: a suite that finishes while another process writes its reports into the same
// folder waits for it (suite_lock_patience: a minute), then adds its run to the history that process wrote.
// Errors (the lock still held after that, or no lock file of hfbake's at its name): std::runtime_error naming
// the folder, the holder and the wait, nothing written.
SuiteReports write_suite_reports(const Suite& suite, const std::vector<JobOutcome>& outcomes, double seconds);

}  // namespace hfbake
