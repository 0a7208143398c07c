#include "cli/suite.hpp"

#include <glob.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <set>
#include <sstream>

#include "cli/version.hpp"
#include "core/error.hpp"
#include "core/safe_file.hpp"
#include "job/manifest.hpp"
#include "job/schema_validation.hpp"
#include "report/report_html.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

void write_atomically(const fs::path& file, const std::string& text) {
  try {
    write_file_atomically(file, text);
  } catch (const std::system_error& e) {
    throw InputError(file.string(), "", "cannot write file: " + e.code().message());
  }
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

std::string index_html(const Suite& suite, const std::vector<JobOutcome>& outcomes, double seconds) {
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>hfbake suite "
    << html_escape(suite.name) << "</title>\n<style>body{font-family:sans-serif;margin:2em}"
    << "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:4px 8px;text-align:left}"
    << ".ok{color:#070}.bad{color:#b00;font-weight:bold}</style></head><body>\n";
  h << "<h1>Suite " << html_escape(suite.name) << "</h1>\n<p>hfbake " << hfbake_version() << ", "
    << outcomes.size() << " jobs, " << seconds_text(seconds) << " s</p>\n";
  h << "<table><tr><th>job</th><th>status</th><th>time "
       "(s)</th><th>reference</th><th>report</th><th>errors</th>"
    << "</tr>\n";
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
    h << "</td><td>";
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

  Suite suite;
  suite.file = file;
  suite.name = doc["suite"].get<std::string>();
  const fs::path base = fs::absolute(file).parent_path();
  suite.output_dir = (doc.contains("output") && doc["output"].contains("dir"))
                         ? base / doc["output"]["dir"].get<std::string>()
                         : base / "out" / suite.name;
  suite.output_dir = suite.output_dir.lexically_normal();
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
        if (!skipped.count(p) && seen.insert(p).second) suite.jobs.push_back(p);
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

std::vector<fs::path> write_suite_reports(const Suite& suite, const std::vector<JobOutcome>& outcomes,
                                          double seconds) {
  fs::create_directories(suite.output_dir);
  nlohmann::json doc = {{"suite", suite.name}, {"hfbake_version", hfbake_version()}, {"seconds", seconds}};
  doc["jobs"] = nlohmann::json::array();
  for (const JobOutcome& o : outcomes) {
    nlohmann::json j = {{"file", o.file},       {"name", o.name},     {"status", job_status_name(o.status)},
                        {"seconds", o.seconds}, {"errors", o.errors}, {"methods", o.methods}};
    j["outputs"] = nlohmann::json::array();
    for (const fs::path& p : o.outputs) j["outputs"].push_back(p.string());
    doc["jobs"].push_back(std::move(j));
  }
  doc["skipped"] = suite.skipped;
  const std::vector<fs::path> files = {suite.output_dir / "suite.json", suite.output_dir / "index.html",
                                       suite.output_dir / "junit.xml"};
  write_atomically(files[0], doc.dump(2) + "\n");
  write_atomically(files[1], index_html(suite, outcomes, seconds));
  write_atomically(files[2], junit_xml(suite, outcomes, seconds));
  return files;
}

}  // namespace hfbake
