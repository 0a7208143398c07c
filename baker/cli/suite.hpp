// Suites: a JSON file listing jobs (paths or globs) that run together, e.g. a nightly accuracy run.
// A file given to `hfbake bake` is a suite when it has a "suite" key (schema: schemas/suite.schema.json).
#pragma once

#include <filesystem>
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

// suite.json (per job: status, outputs, metrics), index.html linking every report, junit.xml.
// Written atomically into suite.output_dir; returns the paths written.
std::vector<std::filesystem::path> write_suite_reports(const Suite& suite,
                                                       const std::vector<JobOutcome>& outcomes,
                                                       double seconds);

}  // namespace hfbake
