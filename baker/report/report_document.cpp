#include "report/report_document.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <stdexcept>

namespace hfbake {
namespace {

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// A summary of a reference layer: its mean and noise (the floor no method can be judged below).
nlohmann::json reference_layer_summary(const Layer& layer, const Layer* se, int width, int height,
                                       const CompareRegion& region) {
  const int channels = layer.channel_count();
  double sum = 0, sum_se_sq = 0, max_se = 0;
  for (int y = region.y0; y < region.y1; ++y)
    for (int x = region.x0; x < region.x1; ++x) {
      const std::size_t t = std::size_t(y) * width + x;
      for (int c = 0; c < channels; ++c) {
        sum += layer.data[t * channels + c];
        if (se && se->channel_count() == channels) {
          const double s = se->data[t * channels + c];
          sum_se_sq += s * s;
          max_se = std::max(max_se, s);
        }
      }
    }
  (void)height;
  const double n = double(region.texels()) * channels;
  nlohmann::json j = {{"channels", channels}, {"mean", sum / n}};
  if (se) {
    j["noise_rmse"] = std::sqrt(sum_se_sq / n);
    j["max_stderr"] = max_se;
  }
  return j;
}

// The reference's record of how it was computed (its attribute `key`, a JSON object), or null.
nlohmann::json reference_record(const LayerSet& reference, const char* key) {
  nlohmann::json record;
  for (const auto& [k, value] : reference.attributes)
    if (k == key) record = nlohmann::json::parse(value, nullptr, false);
  return record.is_object() ? record : nlohmann::json();
}

// The reference computes one obscurance (one falloff and radius, cosine-weighted; it records them in its
// "hfbake:reference_setup" attribute). A method's obscurance is a different quantity when it was baked
// with another falloff, radius or weighting, and comparing the two would report a false error.
bool obscurance_comparable(const EntryReach& reach, const LayerSet& reference) {
  const nlohmann::json setup = reference_record(reference, "hfbake:reference_setup");
  if (!setup.contains("falloff")) return true;  // nothing recorded to check against
  if (!reach.cosine_weighted) return false;
  if (reach.falloff != setup["falloff"].get<std::string>()) return false;
  if (reach.falloff == "none") return true;
  const double rr = setup.value("radius", 0.0);
  return std::abs(reach.radius - rr) <= 1e-9 * std::max(1.0, std::abs(rr));
}

// relief's layers (svf, openness_*, horizon_deg) depend on its directions, search radius and azimuth
// convention; the reference computes them for one relief entry and records its settings
// ("hfbake:relief_reference"). Another entry's are a different quantity.
bool search_comparable(const EntryReach& reach, const LayerSet& reference) {
  const nlohmann::json record = reference_record(reference, "hfbake:relief_reference");
  if (record.is_null() || !reach.search.is_object()) return false;
  for (const char* key : {"directions", "search_radius", "azimuth_convention"})
    if (!reach.search.contains(key) || !record.contains(key) || reach.search[key] != record[key])
      return false;
  return true;
}

// A bent normal baked with a falloff (a radius-limited search: the obscurance family's default with a
// radius) averages the directions open within that radius; the reference's bent normal averages its ao
// rays, which have no distance limit. The two are different quantities.
std::string falloff_limit(const EntryReach& reach) {
  if (reach.falloff == "none") return "";
  return "radius-limited (falloff " + reach.falloff + ", radius " + number(reach.radius) +
         "); the reference's bent normal has no distance limit";
}

// Why a method's layer of this kind is not scored against the reference's (empty: it is).
std::string reach_reason(const LayerKind* kind, const EntryReach& reach, const LayerSet& reference) {
  switch (kind ? kind->reach : LayerReach::unlimited) {
    case LayerReach::unlimited:
      return "";
    case LayerReach::falloff:
      return obscurance_comparable(reach, reference)
                 ? ""
                 : "baked with another falloff, radius or weighting than the reference's obscurance";
    case LayerReach::falloff_against_unlimited:
      return falloff_limit(reach);
    case LayerReach::search_radius:
      return search_comparable(reach, reference)
                 ? ""
                 : "baked with other directions, search radius or azimuth convention than the reference's";
  }
  return "";
}

}  // namespace

nlohmann::json metrics_json(const LayerMetrics& m) {
  nlohmann::json j = nlohmann::json::object();
  int count = 0;
  const char* const* names = metric_names(count);
  for (int k = 0; k < count; ++k)
    if (const auto v = metric_value(m, names[k])) j[names[k]] = *v;
  j["reference_mean"] = m.reference_mean;
  j["values"] = m.values;
  return j;
}

std::optional<std::pair<std::string, std::string>> impossible_report_value(const nlohmann::json& report) {
  std::optional<std::pair<std::string, std::string>> found;
  // Each of `keys` present in `object` (at `at`) within [-limit, limit]; the first beyond is `found`.
  auto within = [&](const nlohmann::json& object, const std::string& at,
                    std::initializer_list<const char*> keys, double limit, const std::string& rule) {
    for (const char* key : keys) {
      const auto it = object.find(key);
      if (!found && it != object.end() && it->is_number() && !(std::abs(it->get<double>()) <= limit))
        found.emplace(at + "/" + key, rule);
    }
  };
  const std::string magnitude = "must be at most " + number(kMaxReportMagnitude) +
                                " in magnitude (the largest difference of two floats)";
  if (report.contains("methods") && report["methods"].is_object())
    for (const auto& [stem, method] : report["methods"].items()) {
      if (!method.is_object() || !method.contains("layers") || !method["layers"].is_object()) continue;
      for (const auto& [layer, metrics] : method["layers"].items()) {
        if (!metrics.is_object()) continue;
        const std::string at = "/methods/" + stem + "/layers/" + layer;
        within(metrics, at,
               {"mae", "rmse", "max", "p99", "bias", "noise_rmse", "excess_rmse", "reference_mean"},
               kMaxReportMagnitude, magnitude);
        within(metrics, at, {"angle_mean_deg", "angle_p99_deg", "angle_max_deg"}, 180,
               "must be <= 180 (degrees)");
      }
    }
  const nlohmann::json::json_pointer layers("/reference/layers");
  if (report.contains(layers) && report[layers].is_object())
    for (const auto& [layer, summary] : report[layers].items())
      if (summary.is_object())
        within(summary, "/reference/layers/" + layer, {"mean", "noise_rmse", "max_stderr"},
               kMaxReportMagnitude, magnitude);
  return found;
}

ReportOutcome build_report(const ReportSpec& spec, const std::vector<ReportMethodInput>& methods,
                           const LayerSet& reference) {
  ReportOutcome out;
  const int width = reference.width, height = reference.height;
  const CompareRegion region = crop_region(width, height, spec.crop);
  if (region.x1 <= region.x0 || region.y1 <= region.y0)
    throw std::invalid_argument("report.crop " + std::to_string(spec.crop) + " leaves no texel of the " +
                                std::to_string(width) + "x" + std::to_string(height) + " field");

  nlohmann::json& doc = out.doc;
  doc["hfbake_version"] = spec.hfbake_version;
  doc["job"] = {{"name", spec.job_name}, {"file", spec.job_file}, {"hash", spec.job_hash}};
  if (!spec.job_scene.is_null()) doc["job"]["scene"] = spec.job_scene;
  doc["size"] = {width, height};
  doc["crop"] = spec.crop;
  doc["region"] = {{"x0", region.x0}, {"y0", region.y0}, {"x1", region.x1}, {"y1", region.y1}};

  nlohmann::json ref = {{"seconds", spec.reference_seconds}, {"parameters", spec.reference_parameters}};
  ref["layers"] = nlohmann::json::object();
  for (const Layer& l : reference.layers) {
    if (ends_with(l.name, "_stderr")) continue;
    ref["layers"][l.name] =
        reference_layer_summary(l, reference.find(l.name + "_stderr"), width, height, region);
  }
  doc["reference"] = std::move(ref);

  doc["methods"] = nlohmann::json::object();
  for (const ReportMethodInput& m : methods) {
    nlohmann::json jm = {{"method", m.method},
                         {"seconds", m.seconds},
                         {"parameters", m.parameters.is_object() ? m.parameters : nlohmann::json::object()}};
    jm["layers"] = nlohmann::json::object();
    jm["not_compared"] = nlohmann::json::array();
    jm["not_compared_reasons"] = nlohmann::json::object();
    out.metrics_by_method[m.stem] = nlohmann::json::object();
    if (m.layers) {
      if (m.layers->width != width || m.layers->height != height)
        throw std::invalid_argument("method " + m.stem + " is " + std::to_string(m.layers->width) + "x" +
                                    std::to_string(m.layers->height) + ", the reference " +
                                    std::to_string(width) + "x" + std::to_string(height));
      for (const Layer& l : m.layers->layers) {
        const Layer* r = reference.find(l.name);
        std::string reason;
        if (!r || ends_with(l.name, "_stderr"))
          reason = "the reference has no layer of this name";
        else if (const LayerKind* kind = find_layer_kind(l.name); !kind || kind->score == LayerScore::none)
          reason = "a layer the report does not score";
        else if (r->channel_count() != l.channel_count())
          reason = "the reference's has " + std::to_string(r->channel_count()) + " channels, this " +
                   std::to_string(l.channel_count());
        else
          reason = reach_reason(find_layer_kind(l.name), m.reach, reference);
        if (!reason.empty()) {
          jm["not_compared"].push_back(l.name);
          jm["not_compared_reasons"][l.name] = reason;
          continue;
        }
        const LayerMetrics metrics =
            compare_layer(l, *r, reference.find(l.name + "_stderr"), width, height, region);
        const nlohmann::json mj = metrics_json(metrics);
        jm["layers"][l.name] = mj;
        out.metrics_by_method[m.stem][l.name] = mj;
      }
    }
    doc["methods"][m.stem] = std::move(jm);
  }

  // Thresholds.
  doc["thresholds"] = nlohmann::json::array();
  for (auto& [key, limit_json] : spec.thresholds.items()) {
    const double limit = limit_json.get<double>();
    const auto first = key.find('.'), last = key.rfind('.');
    nlohmann::json t = {{"key", key}, {"limit", limit}};
    std::string problem;
    std::optional<double> value;
    bool identical = false;
    std::string metric;
    if (first == std::string::npos || last == first) {
      problem = "not of the form <method>.<layer>.<metric>";
    } else {
      const std::string stem = key.substr(0, first), layer = key.substr(first + 1, last - first - 1);
      metric = key.substr(last + 1);
      int count = 0;
      const char* const* names = metric_names(count);
      bool known_metric = false;
      for (int k = 0; k < count; ++k) known_metric |= metric == names[k];
      if (!out.metrics_by_method.contains(stem))
        problem = "the job has no bake entry \"" + stem + "\"";
      else if (!out.metrics_by_method[stem].contains(layer))
        problem = "\"" + stem + "\" has no layer \"" + layer + "\" compared with the reference";
      else if (!known_metric)
        problem = "unknown metric \"" + metric + "\"";
      else if (const nlohmann::json& m = out.metrics_by_method[stem][layer]; m.contains(metric))
        value = m[metric].get<double>();
      else if (metric == "psnr" && m.value("rmse", -1.0) == 0.0 && m.contains("rel_mae"))
        identical = true;  // a nonzero reference matched exactly: psnr is infinite, above any minimum
      else
        problem = "metric \"" + metric + "\" is undefined for this layer (a zero reference)";
    }
    if (identical) {
      t["kind"] = "min";
      t["passed"] = true;
    } else if (value) {
      const bool higher_better = metric_is_higher_better(metric);
      const double v = metric == "bias" ? std::abs(*value) : *value;
      const bool pass = higher_better ? v >= limit : v <= limit;
      t["value"] = *value;
      t["kind"] = higher_better ? "min" : "max";
      t["passed"] = pass;
      if (!pass)
        out.failures.push_back(key + " = " + number(v) + (higher_better ? " < " : " > ") + number(limit));
    } else {
      t["passed"] = false;
      t["error"] = problem;
      out.failures.push_back(key + ": " + problem);
    }
    doc["thresholds"].push_back(std::move(t));
  }

  // Baseline.
  if (spec.baseline) {
    nlohmann::json b = {{"file", spec.baseline_file},
                        {"rel_tolerance", kBaselineRelTolerance},
                        {"abs_tolerance", kBaselineAbsTolerance}};
    b["regressions"] = nlohmann::json::array();
    const nlohmann::json& old = *spec.baseline;
    if (!old.is_object() || !old.contains("methods") || !old["methods"].is_object())
      throw std::invalid_argument("the baseline is not a report.json (no \"methods\" object)");
    for (auto& [stem, layers] : out.metrics_by_method.items()) {
      if (!old["methods"].contains(stem)) continue;
      const nlohmann::json& old_layers = old["methods"][stem].value("layers", nlohmann::json::object());
      for (auto& [layer, metrics] : layers.items()) {
        if (!old_layers.contains(layer)) continue;
        for (const char* name : kBaselineMetrics) {
          if (!metrics.contains(name) || !old_layers[layer].contains(name)) continue;
          const double now = metrics[name].get<double>(), was = old_layers[layer][name].get<double>();
          if (now > was * (1 + kBaselineRelTolerance) + kBaselineAbsTolerance) {
            const std::string key = stem + "." + layer + "." + name;
            b["regressions"].push_back({{"key", key}, {"value", now}, {"baseline", was}});
            out.failures.push_back("baseline: " + key + " = " + number(now) + " > " + number(was) + " in " +
                                   spec.baseline_file);
          }
        }
      }
    }
    doc["baseline"] = std::move(b);
  }
  doc["passed"] = out.failures.empty();
  return out;
}

}  // namespace hfbake
