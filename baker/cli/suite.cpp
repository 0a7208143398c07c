#include "cli/suite.hpp"

#include <glob.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "cli/version.hpp"
#include "core/error.hpp"
#include "core/safe_file.hpp"
#include "job/manifest.hpp"
#include "job/schema_validation.hpp"
#include "report/report_html.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

// What stands at a suite report's name that a report may not replace: "" when nothing or a file (or a link,
// replaced by the rename).
std::string report_name_problem(const fs::path& report) {
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(report, ec);
  if (!fs::exists(st) || fs::is_regular_file(st) || fs::is_symlink(st)) return "";
  return std::string(fs::is_directory(st) ? "a folder" : "no regular file") +
         " stands where the suite writes this report: remove it or give the suite another output folder";
}

std::string junit_xml(const Suite& suite, const std::vector<JobOutcome>& outcomes, double seconds) {
  int failures = 0, errors = 0;
  for (const JobOutcome& o : outcomes) {
    failures += o.status == JobStatus::threshold_failed;
    errors +=
        o.status == JobStatus::failed || o.status == JobStatus::invalid || o.status == JobStatus::cancelled;
  }
  std::ostringstream x;
  x << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  x << "<testsuites name=\"hfbake\" tests=\"" << outcomes.size() << "\" failures=\"" << failures
    << "\" errors=\"" << errors << "\" time=\"" << seconds << "\">\n";
  x << "  <testsuite name=\"" << html_escape(suite.name) << "\" tests=\"" << outcomes.size()
    << "\" failures=\"" << failures << "\" errors=\"" << errors << "\" time=\"" << seconds << "\">\n";
  for (const JobOutcome& o : outcomes) {
    const std::string name = o.name.empty() ? fs::path(o.file).stem().string() : o.name;
    x << "    <testcase classname=\"" << html_escape(suite.name) << "\" name=\"" << html_escape(name)
      << "\" time=\"" << o.seconds << "\">\n";
    std::string text;
    for (const std::string& e : o.errors) text += e + "\n";
    if (o.status == JobStatus::threshold_failed)
      x << "      <failure message=\"accuracy regressed\">" << html_escape(text) << "</failure>\n";
    else if (o.status != JobStatus::ok)
      x << "      <error message=\"" << job_status_name(o.status) << "\">" << html_escape(text)
        << "</error>\n";
    x << "    </testcase>\n";
  }
  x << "  </testsuite>\n</testsuites>\n";
  return x.str();
}

// A job's key in history.json: its file's path from the suite's folder without the extension ("a",
// "night/cliff"): unique within the suite, whatever the jobs' stems or names.
std::string job_key(const Suite& suite, const JobOutcome& o) {
  const fs::path file = fs::absolute(o.file).lexically_normal();
  fs::path p = file.lexically_relative(fs::absolute(suite.file).parent_path().lexically_normal());
  if (p.empty() || *p.begin() == "..") p = file.filename();
  return p.replace_extension().generic_string();
}

// A metric for people: four significant digits.
std::string metric_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

// The comparison with the job's baseline, for a table cell.
std::string baseline_cell(const nlohmann::json& b) {
  if (b.is_null()) return "&ndash;";
  const nlohmann::json& regressions = b["regressions"];
  const std::string file = html_escape(b.value("file", ""));
  if (regressions.empty()) return "<span class=\"ok\">held</span> against " + file;
  std::ostringstream c;
  c << "<span class=\"bad\">" << regressions.size() << " regressed</span> against " << file;
  std::size_t shown = 0;
  for (const nlohmann::json& r : regressions) {
    if (++shown > 5) {
      c << "<br>and " << regressions.size() - 5 << " more (report.json: /baseline)";
      break;
    }
    c << "<br>" << html_escape(r.value("key", "")) << ": " << html_escape(metric_text(r.value("value", 0.0)))
      << " (baseline " << html_escape(metric_text(r.value("baseline", 0.0))) << ")";
  }
  return c.str();
}

// The job's result in each run of `history`, oldest first: its status, the run's time and the job's seconds
// in the tooltip; a dot where the job was not in that run.
std::string history_cell(const nlohmann::json& history, const std::string& key) {
  std::ostringstream c;
  for (const nlohmann::json& run : history["runs"]) {
    const std::string when = html_escape(run.value("finished", ""));
    if (!run["jobs"].contains(key)) {
      c << "<span title=\"" << when << ": not in this run\">&middot;</span> ";
      continue;
    }
    const nlohmann::json& j = run["jobs"][key];
    const std::string status = j.value("status", "");
    c << "<span class=\"" << (status == "ok" ? "ok" : "bad") << "\" title=\"" << when << ", "
      << seconds_text(j.value("seconds", 0.0)) << " s";
    if (j.contains("baseline_regressions"))
      c << ", " << j["baseline_regressions"].get<int>() << " baseline regressions";
    c << "\">" << html_escape(status) << "</span> ";
  }
  return c.str();
}

std::string index_html(const Suite& suite, const std::vector<JobOutcome>& outcomes, double seconds,
                       const nlohmann::json& history) {
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>hfbake suite "
    << html_escape(suite.name) << "</title>\n<style>body{font-family:sans-serif;margin:2em}"
    << "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:4px 8px;text-align:left}"
    << ".ok{color:#070}.bad{color:#b00;font-weight:bold}</style></head><body>\n";
  h << "<h1>Suite " << html_escape(suite.name) << "</h1>\n<p>hfbake " << hfbake_version() << ", "
    << outcomes.size() << " jobs, " << seconds_text(seconds) << " s</p>\n";
  h << "<table><tr><th>job</th><th>status</th><th>time (s)</th><th>reference</th><th>baseline</th><th>last "
    << history["runs"].size() << " runs (oldest first)</th><th>report</th><th>errors</th></tr>\n";
  for (const JobOutcome& o : outcomes) {
    const bool ok = o.status == JobStatus::ok;
    std::string report;
    for (const fs::path& p : o.outputs)
      if (p.filename() == "report.html" || (report.empty() && p.filename() == "report.json"))
        report = fs::relative(p, suite.output_dir).string();
    h << "<tr><td>" << html_escape(o.name.empty() ? o.file : o.name) << "</td><td class=\""
      << (ok ? "ok" : "bad") << "\">" << job_status_name(o.status) << "</td><td>" << seconds_text(o.seconds)
      << "</td><td>";
    if (o.methods.contains("reference")) {  // computed, or from the reference cache (cli/reference_cache.hpp)
      const nlohmann::json& r = o.methods["reference"];
      h << seconds_text(r.value("seconds", 0.0)) << " s";
      if (r.value("cache", "") == "hit")
        h << " (cache hit, " << seconds_text(r.value("cache_saved_seconds", 0.0)) << " s saved)";
    }
    h << "</td><td>" << baseline_cell(o.baseline) << "</td><td>" << history_cell(history, job_key(suite, o))
      << "</td><td>";
    if (!report.empty()) h << "<a href=\"" << html_escape(report) << "\">" << html_escape(report) << "</a>";
    h << "</td><td>";
    for (const std::string& e : o.errors) h << html_escape(e) << "<br>";
    h << "</td></tr>\n";
  }
  h << "</table>\n</body></html>\n";
  return h.str();
}

// Whether `file` reads as a suite (a JSON object with "suite"); unreadable files are left to the job loader.
bool is_suite_file(const fs::path& file) {
  try {
    const nlohmann::json doc = read_json_file(file);
    return doc.is_object() && doc.contains("suite");
  } catch (const InputError&) {
    return false;
  }
}

}  // namespace

std::optional<Suite> load_suite(const fs::path& file, std::vector<std::string>& errors) {
  nlohmann::json doc;
  try {
    doc = read_json_file(file);  // bounded: a regular file under the size limit
  } catch (const InputError&) {
    return std::nullopt;  // not a readable suite: load_job reports what is wrong with the file
  }
  if (!doc.is_object() || !doc.contains("suite")) return std::nullopt;

  const std::size_t errors_before = errors.size();
  for (const SchemaViolation& v : validate_against_schema(doc, "suite.schema.json"))
    errors.push_back(file.string() + ": " + (v.pointer.empty() ? "/" : v.pointer) + ": " + v.message);
  if (errors.size() != errors_before) return std::nullopt;
  // Every path the suite names (its output folder, the jobs' files or globs, the files they need) is refused
  // when it holds a NUL (nul_in_path).
  std::vector<std::pair<std::string, std::string>> paths;
  if (doc.contains("output") && doc["output"].contains("dir"))
    paths.emplace_back("/output/dir", doc["output"]["dir"].get<std::string>());
  for (std::size_t i = 0; i < doc["jobs"].size(); ++i) {
    const nlohmann::json& entry = doc["jobs"][i];
    const std::string at = "/jobs/" + std::to_string(i);
    if (!entry.is_object()) {
      paths.emplace_back(at, entry.get<std::string>());
      continue;
    }
    paths.emplace_back(at + "/job", entry["job"].get<std::string>());
    for (std::size_t k = 0; k < entry["needs"].size(); ++k)
      paths.emplace_back(at + "/needs/" + std::to_string(k), entry["needs"][k].get<std::string>());
  }
  for (const auto& [ptr, path] : paths)
    if (const std::string why = nul_in_path(path); !why.empty())
      errors.push_back(printable(file.string() + ": " + ptr + ": " + why));
  if (errors.size() != errors_before) return std::nullopt;

  Suite suite;
  suite.file = file;
  suite.name = doc["suite"].get<std::string>();
  const fs::path base = fs::absolute(file).parent_path();
  suite.output_dir = (doc.contains("output") && doc["output"].contains("dir"))
                         ? base / doc["output"]["dir"].get<std::string>()
                         : base / "out" / suite.name;
  suite.output_dir = suite.output_dir.lexically_normal();
  // The suite's reports replace files of theirs (a link there is replaced, not followed): anything else
  // at one of their names (a folder) is refused here, before any job bakes.
  for (const fs::path& report : suite_report_files(suite))
    if (const std::string why = report_name_problem(report); !why.empty())
      errors.push_back(printable(file.string() + ": " + report.string() + ": " + why));
  std::set<fs::path> seen;
  std::set<fs::path> skipped;  // jobs whose "needs" are missing, even when another entry lists them too
  for (const nlohmann::json& entry : doc["jobs"])
    if (entry.is_object())
      for (const nlohmann::json& need : entry["needs"])
        if (!fs::exists(base / need.get<std::string>())) {
          const std::string pattern = (base / entry["job"].get<std::string>()).string();
          glob_t g{};
          if (glob(pattern.c_str(), 0, nullptr, &g) == 0)
            for (std::size_t k = 0; k < g.gl_pathc; ++k)
              if (skipped.insert(fs::path(g.gl_pathv[k]).lexically_normal()).second)
                suite.skipped.push_back(fs::path(g.gl_pathv[k]).lexically_normal().string() + ": skipped: " +
                                        (base / need.get<std::string>()).lexically_normal().string() +
                                        " is not on this machine");
          globfree(&g);
          break;
        }
  for (std::size_t i = 0; i < doc["jobs"].size(); ++i) {
    const nlohmann::json& entry = doc["jobs"][i];
    const std::string pattern =
        (base / (entry.is_object() ? entry["job"] : entry).get<std::string>()).string();
    glob_t g{};
    const int rc = glob(pattern.c_str(), 0, nullptr, &g);
    if (rc != 0) {
      errors.push_back(file.string() + ": /jobs/" + std::to_string(i) + ": no file matches " + pattern);
    } else {
      for (std::size_t k = 0; k < g.gl_pathc; ++k) {  // glob sorts its matches
        const fs::path p = fs::path(g.gl_pathv[k]).lexically_normal();
        if (is_suite_file(p)) {  // itself, or another suite: a suite holds jobs
          errors.push_back(file.string() + ": /jobs/" + std::to_string(i) + ": " + p.string() +
                           " is a suite, not a job (a suite lists jobs only)");
          continue;
        }
        // A job bakes into <suite folder>/<its file's stem>/: a stem that is a suite report's name (or its
        // lock's) would put a folder where the suite writes that file.
        const std::vector<fs::path> reports = suite_report_files(suite);
        const bool report_name = p.stem() == suite_lock_file(suite).filename() ||
                                 std::any_of(reports.begin(), reports.end(),
                                             [&](const fs::path& r) { return r.filename() == p.stem(); });
        if (report_name) {
          errors.push_back(file.string() + ": /jobs/" + std::to_string(i) + ": " + p.string() +
                           " would bake into the folder " + (suite.output_dir / p.stem()).string() +
                           ", where the suite writes its " + p.stem().string() +
                           ": give the job file another name");
          continue;
        }
        // Listed twice (a file and a glob, or a link to it): once. Compared as the files they resolve to.
        std::error_code ec;
        const fs::path real = fs::weakly_canonical(p, ec);
        if (!skipped.count(p) && seen.insert(ec ? p : real).second) suite.jobs.push_back(p);
      }
    }
    globfree(&g);
  }
  if (errors.size() != errors_before) return std::nullopt;
  if (suite.jobs.empty()) {
    errors.push_back(file.string() + ": /jobs: every job is skipped (" + suite.skipped.front() + ")");
    return std::nullopt;
  }
  return suite;
}

CallJobs call_jobs(const std::vector<fs::path>& files, const std::optional<fs::path>& out) {
  CallJobs call;
  std::size_t plain = 0;  // job files given as such
  for (const fs::path& file : files) {
    const std::size_t errors_before = call.errors.size();
    if (std::optional<Suite> suite = load_suite(file, call.errors)) {
      if (out) suite->output_dir = fs::absolute(*out / suite->name);
      if (const std::string problem = suite_folder_problem(*suite); !problem.empty()) {
        call.errors.push_back(problem);  // nothing of the suite runs
        continue;
      }
      for (const fs::path& job : suite->jobs)
        call.jobs.push_back({job, suite->output_dir / job.stem(), int(call.suites.size()),
                             out ? "--out" : "/output/dir of suite " + suite->file.string()});
      call.suites.push_back(std::move(*suite));
    } else if (call.errors.size() == errors_before) {  // not a suite: a job
      call.jobs.push_back({file, std::nullopt, -1});
      ++plain;
    }
  }
  // With --out and several job files, each gets a folder of its own under DIR.
  for (CallJob& job : call.jobs)
    if (job.suite < 0 && out) job.out = plain > 1 ? *out / job.file.stem() : *out;
  return call;
}

nlohmann::json suite_history_run(const Suite& suite, const std::vector<JobOutcome>& outcomes, double seconds,
                                 const std::string& finished) {
  nlohmann::json run = {{"finished", finished}, {"hfbake_version", hfbake_version()}, {"seconds", seconds}};
  run["jobs"] = nlohmann::json::object();
  for (const JobOutcome& o : outcomes) {
    nlohmann::json j = {{"status", job_status_name(o.status)}, {"seconds", o.seconds}};
    if (!o.baseline.is_null()) j["baseline_regressions"] = o.baseline["regressions"].size();
    run["jobs"][job_key(suite, o)] = std::move(j);
  }
  return run;
}

nlohmann::json append_suite_history(const nlohmann::json& history, nlohmann::json run, bool& dropped) {
  auto is_run = [](const nlohmann::json& r) {
    if (!r.is_object() || !r.contains("finished") || !r["finished"].is_string() || !r.contains("jobs") ||
        !r["jobs"].is_object())
      return false;
    for (const auto& [key, j] : r["jobs"].items())
      if (!j.is_object() || !j.contains("status") || !j["status"].is_string() ||
          (j.contains("seconds") && !j["seconds"].is_number()) ||
          (j.contains("baseline_regressions") && !j["baseline_regressions"].is_number_integer()))
        return false;
    return true;
  };
  dropped = !(history.is_object() && history.contains("runs") && history["runs"].is_array() &&
              std::all_of(history["runs"].begin(), history["runs"].end(), is_run));
  nlohmann::json runs = dropped ? nlohmann::json::array() : history["runs"];
  runs.push_back(std::move(run));
  if (runs.size() > kSuiteHistoryRuns) runs.erase(runs.begin(), runs.end() - kSuiteHistoryRuns);
  return {{"runs", std::move(runs)}};
}

std::chrono::seconds suite_lock_patience() {
  const char* v = std::getenv("HFBAKE_TEST_SUITE_LOCK_WAIT");
  if (!v || !*v || std::strlen(v) > 2 || std::strspn(v, "0123456789") != std::strlen(v))
    return kSuiteLockPatience;
  return std::min(std::chrono::seconds(std::atoi(v)), kSuiteLockPatience);
}

fs::path suite_lock_file(const Suite& suite) {
  return suite.output_dir / ".hfbake+suite.lock";
}

std::string suite_folder_problem(const Suite& suite) {
  // The folder, or the nearest of its parents that exists, must be a folder this process can write into (a
  // file at its name failed the reports after every job had baked).
  std::error_code ec;
  for (fs::path p = suite.output_dir; !p.empty(); p = p.parent_path()) {
    const fs::file_status st = fs::status(p, ec);
    if (fs::exists(st)) {
      if (!fs::is_directory(st))
        return suite.file.string() + ": /output/dir: " + p.string() + " is not a folder";
      if (access(p.c_str(), W_OK | X_OK) != 0)
        return suite.file.string() + ": /output/dir: cannot write into " + p.string() + ": " +
               std::strerror(errno);
      break;
    }
    if (p == p.parent_path()) break;
  }
  const std::string problem = lock_name_problem(suite_lock_file(suite));
  return problem.empty() ? "" : suite.file.string() + ": /output/dir: " + problem;
}

std::vector<fs::path> suite_report_files(const Suite& suite) {
  return {suite.output_dir / "suite.json", suite.output_dir / "history.json", suite.output_dir / "index.html",
          suite.output_dir / "junit.xml"};
}

SuiteReports write_suite_reports(const Suite& suite, const std::vector<JobOutcome>& outcomes,
                                 double seconds) {
  fs::create_directories(suite.output_dir);
  nlohmann::json doc = {{"suite", suite.name}, {"hfbake_version", hfbake_version()}, {"seconds", seconds}};
  doc["jobs"] = nlohmann::json::array();
  for (const JobOutcome& o : outcomes) {
    nlohmann::json j = {{"file", o.file},       {"name", o.name},     {"status", job_status_name(o.status)},
                        {"seconds", o.seconds}, {"errors", o.errors}, {"methods", o.methods}};
    if (!o.baseline.is_null()) j["baseline"] = o.baseline;
    j["outputs"] = nlohmann::json::array();
    for (const fs::path& p : o.outputs) j["outputs"].push_back(p.string());
    doc["jobs"].push_back(std::move(j));
  }
  doc["skipped"] = suite.skipped;

  // history.json is read, extended and replaced: one suite at a time per folder, so that suites finishing
  // together each add their run, and the four reports are each one suite's.
  const fs::path lock_file = suite_lock_file(suite);
  const std::chrono::seconds patience = suite_lock_patience();
  const FolderLock lock(lock_file, patience);
  if (!lock.held())
    throw std::runtime_error(
        lock.problem().empty() ? lock.holder_words() + " has been writing suite reports into " +
                                     suite.output_dir.string() + " for " + std::to_string(patience.count()) +
                                     " s: wait for it to finish, then bake the suite again"
                               : not_a_lock_file(lock_file, lock.problem()));
  SuiteReports written;
  written.files = suite_report_files(suite);
  const fs::path history_file = written.files[1];
  nlohmann::json previous = {{"runs", nlohmann::json::array()}};
  bool dropped = false;
  if (fs::exists(history_file)) {
    try {
      previous = read_json_file(history_file);
    } catch (const InputError&) {
      previous = nullptr;  // dropped below, with a warning
    }
  }
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char finished[32];
  std::strftime(finished, sizeof finished, "%Y-%m-%dT%H:%M:%SZ", &utc);
  const nlohmann::json history =
      append_suite_history(previous, suite_history_run(suite, outcomes, seconds, finished), dropped);
  if (dropped)
    written.warnings.push_back(history_file.string() +
                               ": not a suite history (history.json); starting it afresh with this run");

  // The four reports are one run's: each written whole beside its name first, then all moved into place,
  // so a write that fails (a full disk, a folder planted since the check) leaves the previous run's four.
  const std::string texts[4] = {doc.dump(2) + "\n", history.dump(2) + "\n",
                                index_html(suite, outcomes, seconds, history),
                                junit_xml(suite, outcomes, seconds)};
  std::vector<std::unique_ptr<TempFile>> staged;
  for (int k = 0; k < 4; ++k) {
    const fs::path& file = written.files[std::size_t(k)];
    if (const std::string why = report_name_problem(file); !why.empty())
      throw InputError(file.string(), "", why);
    try {
      staged.push_back(std::make_unique<TempFile>(file));
      if (!staged.back()->write(texts[k]))
        throw std::system_error(errno ? errno : EIO, std::generic_category());
    } catch (const std::system_error& e) {
      throw InputError(file.string(), "", "cannot write the report: " + e.code().message());
    }
  }
  for (std::size_t k = 0; k < staged.size(); ++k) {
    try {
      staged[k]->commit();
    } catch (const std::system_error& e) {
      throw InputError(written.files[k].string(), "",
                       "cannot move the report into place: " + e.code().message());
    }
  }
  return written;
}

}  // namespace hfbake
