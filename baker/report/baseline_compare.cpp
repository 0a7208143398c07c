#include "report/baseline_compare.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <stdexcept>

#include "report/compare.hpp"
#include "report/report_document.hpp"

namespace hfbake {
namespace {

const nlohmann::json& methods_of(const nlohmann::json& doc, const char* which) {
  if (!doc.is_object() || !doc.contains("methods") || !doc["methods"].is_object())
    throw std::invalid_argument(std::string(which) + " is not a report.json (no \"methods\" object)");
  for (auto& [stem, m] : doc["methods"].items())
    if (!m.is_object() || !m.contains("layers") || !m["layers"].is_object())
      throw std::invalid_argument(std::string(which) + ": /methods/" + stem + " has no \"layers\" object");
  return doc["methods"];
}

// A metric: absent, or null (a value JSON cannot hold), is none; any other type is not a report hfbake
// writes (a damaged baseline whose metric would otherwise pass for new).
std::optional<double> number_at(const nlohmann::json& obj, const std::string& key) {
  if (!obj.is_object() || !obj.contains(key) || obj[key].is_null()) return std::nullopt;
  if (!obj[key].is_number())
    throw std::invalid_argument("not a report.json as hfbake writes it: \"" + key + "\" is " +
                                std::string(obj[key].type_name()) + ", not a number");
  return obj[key].get<double>();
}

bool known_metric(const std::string& name) {
  int count = 0;
  const char* const* names = metric_names(count);
  for (int i = 0; i < count; ++i)
    if (name == names[i]) return true;
  return name == "seconds";
}

// A JSON value as it would be written in a job file; an absent one as "(not set)".
std::string show(const std::optional<nlohmann::json>& v) {
  return v ? v->dump() : "(not set)";
}

// Every key (objects recursed, joined by '.') where `a` and `b` differ; arrays and scalars compared whole.
void diff_values(const std::string& prefix, const nlohmann::json* a, const nlohmann::json* b,
                 std::vector<ParameterChange>& out) {
  if (a && b && *a == *b) return;
  if (a && b && a->is_object() && b->is_object()) {
    std::set<std::string> keys;
    for (auto& [k, v] : a->items()) keys.insert(k);
    for (auto& [k, v] : b->items()) keys.insert(k);
    for (const std::string& k : keys)
      diff_values(prefix.empty() ? k : prefix + "." + k, a->contains(k) ? &(*a)[k] : nullptr,
                  b->contains(k) ? &(*b)[k] : nullptr, out);
    return;
  }
  ParameterChange c;
  c.key = prefix;
  if (a) c.now = *a;
  if (b) c.was = *b;
  out.push_back(std::move(c));
}

const nlohmann::json* at(const nlohmann::json& doc, const char* pointer) {
  const nlohmann::json::json_pointer p(pointer);
  return doc.is_object() && doc.contains(p) ? &doc.at(p) : nullptr;
}

std::string fmt(std::optional<double> v) {
  if (!v) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.5g", *v);
  return buf;
}

}  // namespace

BaselineOptions BaselineOptions::defaults() {
  BaselineOptions o;
  for (const char* m : kBaselineMetrics) o.checked[m] = {kBaselineRelTolerance, kBaselineAbsTolerance};
  return o;
}

std::string parse_tolerance(const std::string& text, BaselineOptions& options) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    return "expected METRIC=REL or METRIC=REL,ABS, got \"" + text + "\"";
  const std::string metric = text.substr(0, eq), values = text.substr(eq + 1);
  if (!known_metric(metric)) return "unknown metric \"" + metric + "\"";
  MetricTolerance t;
  const auto comma = values.find(',');
  try {
    std::size_t used = 0;
    const std::string rel = values.substr(0, comma);
    t.rel = std::stod(rel, &used);
    if (used != rel.size()) throw std::invalid_argument(rel);
    if (comma != std::string::npos) {
      const std::string abs = values.substr(comma + 1);
      t.abs = std::stod(abs, &used);
      if (used != abs.size()) throw std::invalid_argument(abs);
    }
  } catch (const std::exception&) {
    return "\"" + text + "\": tolerances must be numbers";
  }
  if (!(t.rel >= 0) || !(t.abs >= 0) || !std::isfinite(t.rel) || !std::isfinite(t.abs))
    return "\"" + text + "\": tolerances must be finite and >= 0";
  options.checked[metric] = t;
  return "";
}

const char* metric_change_name(MetricChange c) {
  switch (c) {
    case MetricChange::same:
      return "same";
    case MetricChange::improved:
      return "improved";
    case MetricChange::regressed:
      return "REGRESSED";
    case MetricChange::missing:
      return "MISSING";
    case MetricChange::added:
      return "new";
    case MetricChange::info:
      return "info";
  }
  return "?";
}

std::vector<std::string> job_differences(const nlohmann::json& now, const nlohmann::json& baseline) {
  std::vector<std::string> out;
  // A difference of one recorded value (both sides must record it): "<what> <baseline> (new: <now>)".
  auto whole = [&](const char* pointer, const std::string& what) {
    const nlohmann::json *a = at(now, pointer), *b = at(baseline, pointer);
    if (a && b && *a != *b) out.push_back(what + " " + b->dump() + " (new: " + a->dump() + ")");
  };
  // Key by key: "<what>.<key> <baseline> (new: <now>)". both_record: only keys both sides record (older
  // reports hold the reference's parameters as written, newer ones resolved: a default that only one side
  // spells out is not a difference).
  auto keys = [&](const char* pointer, const std::string& what, bool both_record) {
    const nlohmann::json *a = at(now, pointer), *b = at(baseline, pointer);
    if (!a || !b) return;
    std::vector<ParameterChange> changes;
    diff_values("", a, b, changes);
    for (const ParameterChange& c : changes)
      if (!both_record || (c.now && c.was))
        out.push_back(what + (c.key.empty() ? "" : "." + c.key) + " " + show(c.was) +
                      " (new: " + show(c.now) + ")");
  };
  whole("/job/name", "job name");
  whole("/size", "field size");
  whole("/crop", "crop");
  keys("/reference/parameters", "reference", true);
  const std::size_t before_scene = out.size();
  keys("/job/scene", "scene", false);
  if (out.size() == before_scene) {
    const nlohmann::json *a = at(now, "/job/scene_hash"), *b = at(baseline, "/job/scene_hash");
    if (a && b && *a != *b)
      out.push_back("the scene's input files differ (scene hash " + b->get<std::string>() +
                    ", new: " + a->get<std::string>() + ")");
  }
  return out;
}

std::vector<ParameterChange> parameter_changes(const nlohmann::json& now, const nlohmann::json& baseline) {
  std::vector<ParameterChange> out;
  const nlohmann::json *a = at(now, "/methods"), *b = at(baseline, "/methods");
  if (!a || !b || !a->is_object() || !b->is_object()) return out;
  const nlohmann::json none = nlohmann::json::object();
  for (auto& [stem, m] : a->items()) {
    if (!b->contains(stem) || !m.is_object() || !(*b)[stem].is_object()) continue;
    const nlohmann::json& old = (*b)[stem];
    const nlohmann::json& pa = m.contains("parameters") ? m["parameters"] : none;
    const nlohmann::json& pb = old.contains("parameters") ? old["parameters"] : none;
    diff_values(stem, &pa, &pb, out);
    // The bake entry as written names its method; a report without it still records the method per stem.
    if (!pa.contains("method") && !pb.contains("method"))
      diff_values(stem + ".method", m.contains("method") ? &m["method"] : nullptr,
                  old.contains("method") ? &old["method"] : nullptr, out);
  }
  std::sort(out.begin(), out.end(),
            [](const ParameterChange& x, const ParameterChange& y) { return x.key < y.key; });
  return out;
}

std::string another_job_message(const std::vector<std::string>& differences) {
  std::string s = "a report of another job:";
  for (std::size_t i = 0; i < differences.size(); ++i) s += (i ? "; " : " ") + differences[i];
  return s;
}

namespace {

BaselineComparison compare_documents(const nlohmann::json& now, const nlohmann::json& baseline,
                                     const BaselineOptions& options) {
  const nlohmann::json& new_methods = methods_of(now, "the new report");
  const nlohmann::json& old_methods = methods_of(baseline, "the baseline");
  BaselineComparison c;
  c.job_differences = job_differences(now, baseline);
  c.parameter_changes = parameter_changes(now, baseline);

  auto classify = [&](MetricRow& r) {
    const auto it = options.checked.find(r.metric);
    r.checked = it != options.checked.end();
    if (r.checked) r.tolerance = it->second;
    if (!r.was) {
      r.change = MetricChange::added;
    } else if (!r.now) {
      r.change = r.checked ? MetricChange::missing : MetricChange::info;
    } else if (!r.checked) {
      r.change = MetricChange::info;
    } else {
      const double margin = std::max(r.tolerance.abs, r.tolerance.rel * std::abs(*r.was));
      const double worse = metric_is_higher_better(r.metric) ? *r.was - *r.now : *r.now - *r.was;
      r.change = worse > margin ? MetricChange::regressed
                                : (-worse > margin ? MetricChange::improved : MetricChange::same);
    }
    switch (r.change) {
      case MetricChange::regressed:
        ++c.regressed;
        break;
      case MetricChange::improved:
        ++c.improved;
        break;
      case MetricChange::missing:
        ++c.missing;
        break;
      case MetricChange::added:  // counted as the table shows them: checked metrics and a new method's time
        c.added += r.checked || r.metric == "seconds";
        break;
      default:
        break;
    }
    c.rows.push_back(std::move(r));
  };

  // Every (stem, layer) of either document, in sorted order (nlohmann objects are key-sorted).
  std::set<std::string> stems;
  for (auto& [stem, m] : new_methods.items()) stems.insert(stem);
  for (auto& [stem, m] : old_methods.items()) stems.insert(stem);
  const nlohmann::json none = nlohmann::json::object();
  int count = 0;
  const char* const* names = metric_names(count);
  for (const std::string& stem : stems) {
    const nlohmann::json& nm = new_methods.contains(stem) ? new_methods[stem] : none;
    const nlohmann::json& om = old_methods.contains(stem) ? old_methods[stem] : none;
    {
      MetricRow r;
      r.stem = stem, r.metric = "seconds", r.now = number_at(nm, "seconds"), r.was = number_at(om, "seconds");
      if (r.now || r.was) classify(r);
    }
    std::set<std::string> layers;
    const nlohmann::json new_layers = nm.value("layers", none), old_layers = om.value("layers", none);
    for (auto& [layer, v] : new_layers.items()) layers.insert(layer);
    for (auto& [layer, v] : old_layers.items()) layers.insert(layer);
    for (const std::string& layer : layers) {
      const nlohmann::json& nl =
          nm.contains("layers") && nm["layers"].contains(layer) ? nm["layers"][layer] : none;
      const nlohmann::json& ol =
          om.contains("layers") && om["layers"].contains(layer) ? om["layers"][layer] : none;
      for (int i = 0; i < count; ++i) {
        MetricRow r;
        r.stem = stem, r.layer = layer, r.metric = names[i];
        r.now = number_at(nl, names[i]), r.was = number_at(ol, names[i]);
        // psnr is absent when the images are identical: a new zero error is not a lost metric.
        if (!r.now && r.was && r.metric == "psnr" && number_at(nl, "rmse") == 0.0) r.now = INFINITY;
        if (r.now || r.was) classify(r);
      }
    }
  }
  return c;
}

}  // namespace

BaselineComparison compare_to_baseline(const nlohmann::json& now, const nlohmann::json& baseline,
                                       const BaselineOptions& options) {
  // A report.json whose values have other types than hfbake writes (a hand-edited or damaged file) is not a
  // report: one line from `compare`, never an uncaught exception.
  try {
    return compare_documents(now, baseline, options);
  } catch (const nlohmann::json::exception& e) {
    std::string what = e.what();  // "[json.exception.type_error.302] type must be string, but is number"
    if (const auto b = what.find("] "); b != std::string::npos) what = what.substr(b + 2);
    throw std::invalid_argument("not a report.json as hfbake writes it: " + what);
  }
}

std::string comparison_table(const BaselineComparison& c, bool all) {
  std::string out;
  char line[512];
  if (!c.parameter_changes.empty()) {
    out += "  parameters changed since the baseline:\n";
    for (const ParameterChange& p : c.parameter_changes)
      out += "    " + p.key + ": " + show(p.was) + " -> " + show(p.now) + "\n";
  }
  std::snprintf(line, sizeof line, "  %-44s %12s %12s %9s  %s\n", "metric", "baseline", "new", "change", "");
  out += line;
  int shown = 0;
  for (const MetricRow& r : c.rows) {
    const bool notable = r.change == MetricChange::regressed || r.change == MetricChange::missing ||
                         r.change == MetricChange::improved || r.change == MetricChange::added;
    if (!notable && !(all && r.checked)) continue;
    if (r.change == MetricChange::added && r.metric != "seconds" && !r.checked && !all) continue;
    // The change in percent of the baseline's magnitude: "-" where that is no finite number (a baseline of
    // 0, or a ratio beyond double's range), in powers of ten from 10^5 %.
    std::string change = "-";
    if (r.now && r.was && *r.was != 0) {
      const double percent = 100.0 * ((*r.now - *r.was) / std::abs(*r.was));
      if (std::isfinite(percent)) {
        char buf[32];
        std::snprintf(buf, sizeof buf, std::abs(percent) < 1e5 ? "%+.1f%%" : "%+.2g%%", percent);
        change = buf;
      }
    }
    std::snprintf(line, sizeof line, "  %-44s %12s %12s %9s  %s\n",
                  (r.layer.empty() ? r.stem + "." + r.metric : r.key()).c_str(), fmt(r.was).c_str(),
                  fmt(r.now).c_str(), change.c_str(), metric_change_name(r.change));
    out += line;
    ++shown;
  }
  if (shown == 0) out += "  (no checked metric changed beyond its tolerance)\n";
  std::snprintf(line, sizeof line, "%s%s: %d regressed, %d missing, %d improved, %d new\n",
                c.label.empty() ? "" : (c.label + ": ").c_str(), c.regression() ? "REGRESSION" : "ok",
                c.regressed, c.missing, c.improved, c.added);
  out += line;
  return out;
}

nlohmann::json comparison_json(const BaselineComparison& c) {
  nlohmann::json j = {{"regressed", c.regressed},
                      {"missing", c.missing},
                      {"improved", c.improved},
                      {"new", c.added},
                      {"regression", c.regression()}};
  if (!c.label.empty()) j["label"] = c.label;
  j["job_differences"] = c.job_differences;
  j["parameter_changes"] = nlohmann::json::array();
  for (const ParameterChange& p : c.parameter_changes) {
    nlohmann::json pc = {{"key", p.key}};
    if (p.now) pc["value"] = *p.now;
    if (p.was) pc["baseline"] = *p.was;
    j["parameter_changes"].push_back(std::move(pc));
  }
  j["rows"] = nlohmann::json::array();
  for (const MetricRow& r : c.rows) {
    nlohmann::json row = {{"key", r.layer.empty() ? r.stem + "." + r.metric : r.key()},
                          {"change", metric_change_name(r.change)},
                          {"checked", r.checked}};
    if (r.now && std::isfinite(*r.now)) row["value"] = *r.now;
    if (r.was) row["baseline"] = *r.was;
    if (r.checked) row["tolerance"] = {{"rel", r.tolerance.rel}, {"abs", r.tolerance.abs}};
    j["rows"].push_back(std::move(row));
  }
  return j;
}

}  // namespace hfbake
