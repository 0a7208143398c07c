#include "cli/compare_command.hpp"

#include <unistd.h>

#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli/report_writer.hpp"
#include "core/error.hpp"
#include "core/safe_file.hpp"
#include "job/manifest.hpp"
#include "report/baseline_compare.hpp"

namespace hfbake {
namespace fs = std::filesystem;

namespace {

void copy_atomically(const fs::path& from, const fs::path& to) {
  if (to.has_parent_path()) fs::create_directories(to.parent_path());
  std::string why;
  const int fd = open_regular_file(from, why);
  if (fd < 0) throw std::runtime_error(from.string() + ": " + why);
  std::string bytes;
  char buf[1 << 16];
  for (ssize_t n; (n = read(fd, buf, sizeof buf)) > 0;) bytes.append(buf, std::size_t(n));
  close(fd);
  write_file_atomically(to, bytes);
}

// Every report.json under `dir`, by path relative to it. A bake's staging folders (.hfbake-staging-*: what a
// running, killed or crashed bake had not committed) are not outputs and are not entered.
std::map<std::string, fs::path> reports_under(const fs::path& dir) {
  std::map<std::string, fs::path> found;
  for (auto it = fs::recursive_directory_iterator(dir); it != fs::recursive_directory_iterator(); ++it) {
    if (it->is_directory() && it->path().filename().string().rfind(".hfbake-staging-", 0) == 0) {
      it.disable_recursion_pending();
      continue;
    }
    if (it->path().filename() != "report.json") continue;
    // Keyed by where it is, not by where a link leads (fs::relative would resolve it): a baseline's link
    // is compared and replaced as the report of its own folder.
    std::error_code ec;
    if (!fs::is_regular_file(it->path(), ec))
      throw InputError(it->path().string(), "",
                       "is not a regular file (a folder, a device or a broken link)");
    found[it->path().lexically_relative(dir).string()] = it->path();
  }
  return found;
}

}  // namespace

CompareResult compare_reports(const CompareOptions& o) {
  BaselineOptions rule = BaselineOptions::defaults();
  for (const std::string& t : o.tolerances) {
    const std::string problem = parse_tolerance(t, rule);
    if (!problem.empty()) throw InputError("command line", "--tolerance", problem);
  }
  std::error_code ec;
  if (!fs::exists(o.now, ec)) throw InputError(o.now.string(), "", "no such file or folder");
  const bool folders = fs::is_directory(o.now);
  if (!fs::exists(o.baseline, ec) && !o.update_baseline)
    throw InputError(
        o.baseline.string(), "",
        "no such baseline (create it deliberately with hfbake compare NEW BASELINE --update-baseline)");
  if (fs::exists(o.baseline, ec) && fs::is_directory(o.baseline) != folders)
    throw InputError(o.baseline.string(), "",
                     folders ? "is not a folder (NEW is one)" : "is a folder (NEW is a file)");

  // Pairs (label, new file, baseline file); a missing side is an empty path.
  std::vector<std::tuple<std::string, fs::path, fs::path>> pairs;
  if (folders) {
    const auto now = reports_under(o.now);
    const auto old = fs::exists(o.baseline) ? reports_under(o.baseline) : std::map<std::string, fs::path>{};
    if (now.empty()) throw InputError(o.now.string(), "", "no report.json under this folder");
    for (const auto& [rel, p] : now) pairs.emplace_back(rel, p, old.count(rel) ? old.at(rel) : fs::path());
    for (const auto& [rel, p] : old)
      if (!now.count(rel)) pairs.emplace_back(rel, fs::path(), p);
  } else {
    pairs.emplace_back("", o.now, fs::exists(o.baseline) ? o.baseline : fs::path());
  }

  // --json never replaces a report this comparison reads or a baseline it updates, and is checked before
  // anything is compared.
  if (o.json) {
    const fs::path& json = *o.json;
    if (const std::string why = named_output_problem(json); !why.empty())
      throw InputError(json.string(), "--json", why);
    const fs::path at = fs::weakly_canonical(fs::absolute(json), ec);
    auto is = [&](const fs::path& f) {
      std::error_code e;
      return !f.empty() &&
             (fs::weakly_canonical(fs::absolute(f), e) == at || (fs::equivalent(json, f, e) && !e));
    };
    for (const auto& [label, now_file, old_file] : pairs) {
      for (const fs::path& f : {now_file, old_file})
        if (is(f))
          throw InputError(
              json.string(), "--json",
              "is " + f.string() + ", which this comparison reads: give the output another name");
      if (o.update_baseline && is(folders ? o.baseline / label : o.baseline))
        throw InputError(json.string(), "--json",
                         "is where --update-baseline writes the baseline: give the output another name");
    }
  }

  CompareResult r;
  for (const auto& [label, now_file, old_file] : pairs) {
    if (now_file.empty()) {  // a whole report went missing
      r.regression = true;
      r.text += label + ": MISSING (in the baseline, not in " + o.now.string() + ")\n";
      r.comparisons.push_back({{"label", label}, {"regression", true}, {"missing_report", true}});
      continue;
    }
    if (old_file.empty()) {
      r.text += label + (label.empty() ? "" : ": ") + "new report (no baseline yet)\n";
      r.comparisons.push_back({{"label", label}, {"regression", false}, {"new_report", true}});
      continue;
    }
    BaselineComparison c;
    try {
      c = compare_to_baseline(read_report_file(now_file), read_report_file(old_file), rule);
    } catch (const std::invalid_argument& e) {
      throw InputError(now_file.string() + " vs " + old_file.string(), "", e.what());
    }
    c.label = label;
    if (!c.job_differences.empty()) {
      const std::string why = another_job_message(c.job_differences);
      if (!o.allow_different_job) {
        r.refusals.push_back(old_file.string() + ": " + why + " (compare anyway with --allow-different-job)");
        continue;
      }
      r.text += "note: " + old_file.string() + ": " + why + " (allowed by --allow-different-job)\n";
    }
    r.regression = r.regression || c.regression();
    r.text += comparison_table(c, o.all);
    r.comparisons.push_back(comparison_json(c));
  }
  if (!r.refusals.empty()) return r;  // neither --json nor --update-baseline: the comparison did not happen
  if (o.json) {
    // Atomic like every output: a reader never sees half of it, and a link at the name is replaced.
    try {
      write_named_output(
          *o.json,
          nlohmann::json{{"regression", r.regression}, {"comparisons", r.comparisons}}.dump(2) + "\n");
    } catch (const std::system_error& e) {
      throw InputError(o.json->string(), "--json", "cannot write file: " + e.code().message());
    }
  }
  if (o.update_baseline) {
    for (const auto& [label, now_file, old_file] : pairs) {
      if (now_file.empty()) {
        fs::remove(old_file);
      } else {
        copy_atomically(now_file, folders ? o.baseline / label : o.baseline);
      }
    }
    r.text += "baseline updated: " + o.baseline.string() + "\n";
    r.baseline_updated = true;
  }
  return r;
}

int run_compare(const CompareOptions& o) {
  try {
    const CompareResult r = compare_reports(o);
    if (!o.quiet) std::printf("%s", r.text.c_str());
    for (const std::string& line : r.refusals) std::fprintf(stderr, "hfbake: error: %s\n", line.c_str());
    if (!r.refusals.empty()) return 2;
    if (r.baseline_updated) return 0;
    return r.regression ? 1 : 0;
  } catch (const InputError& e) {
    std::fprintf(stderr, "hfbake: error: %s\n", e.line().c_str());
    return 2;
  } catch (const fs::filesystem_error& e) {
    std::fprintf(stderr, "hfbake: error: %s\n", e.what());
    return 2;
  }
}

}  // namespace hfbake
