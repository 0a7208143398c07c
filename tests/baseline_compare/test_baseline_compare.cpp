// Baseline comparison on hand-made report.json documents: each rule of the comparison (improved, regressed,
// within tolerance, missing metric / layer / method, new method, psnr higher-is-better, custom
// tolerances) is checked against numbers worked out by hand.
#include <gtest/gtest.h>

#include <functional>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "report/baseline_compare.hpp"

namespace hfbake {
namespace {

nlohmann::json metrics(double mae, double rmse, double excess, std::optional<double> psnr = 30.0) {
  nlohmann::json m = {
      {"mae", mae},  {"rmse", rmse},        {"excess_rmse", excess}, {"max", 0.5},    {"p99", 0.2},
      {"bias", 0.0}, {"noise_rmse", 0.001}, {"reference_mean", 0.7}, {"values", 100}, {"rel_mae", mae / 0.7}};
  if (psnr) m["psnr"] = *psnr;
  return m;
}

nlohmann::json report(const nlohmann::json& methods) {
  return {{"hfbake_version", "test"}, {"methods", methods}};
}

nlohmann::json method(const nlohmann::json& layers, double seconds = 1.0) {
  return {{"method", "p1"},
          {"seconds", seconds},
          {"parameters", nlohmann::json::object()},
          {"layers", layers},
          {"not_compared", nlohmann::json::array()}};
}

const MetricRow& row(const BaselineComparison& c, const std::string& key) {
  for (const MetricRow& r : c.rows)
    if ((r.layer.empty() ? r.stem + "." + r.metric : r.key()) == key) return r;
  throw std::runtime_error("no row " + key);
}

const nlohmann::json kBase = report({{"p1", method({{"ao", metrics(0.010, 0.020, 0.015)}})}});

TEST(BaselineCompare, IdenticalReportsAreSame) {
  const BaselineComparison c = compare_to_baseline(kBase, kBase, BaselineOptions::defaults());
  EXPECT_FALSE(c.regression());
  EXPECT_EQ(c.regressed + c.missing + c.improved + c.added, 0);
  EXPECT_EQ(row(c, "p1.ao.rmse").change, MetricChange::same);
  EXPECT_TRUE(row(c, "p1.ao.rmse").checked);
  EXPECT_EQ(row(c, "p1.ao.max").change, MetricChange::info);  // not checked by default
  EXPECT_EQ(row(c, "p1.seconds").change, MetricChange::info);
}

TEST(BaselineCompare, RegressionBeyondToleranceOnly) {
  // Default tolerance: 5 % relative or 1e-5 absolute, whichever is larger. rmse 0.020 -> limit 0.021.
  auto with_rmse = [](double rmse) {
    return report({{"p1", method({{"ao", metrics(0.010, rmse, 0.015)}})}});
  };
  BaselineComparison c = compare_to_baseline(with_rmse(0.0209), kBase, BaselineOptions::defaults());
  EXPECT_EQ(row(c, "p1.ao.rmse").change, MetricChange::same);
  EXPECT_FALSE(c.regression());
  c = compare_to_baseline(with_rmse(0.0211), kBase, BaselineOptions::defaults());
  EXPECT_EQ(row(c, "p1.ao.rmse").change, MetricChange::regressed);
  EXPECT_TRUE(c.regression());
  EXPECT_EQ(c.regressed, 1);
  EXPECT_NE(comparison_table(c, false).find("p1.ao.rmse"), std::string::npos);
  EXPECT_NE(comparison_table(c, false).find("REGRESSED"), std::string::npos);
  // Improvement is symmetric: 0.0189 is more than 5 % better.
  c = compare_to_baseline(with_rmse(0.0189), kBase, BaselineOptions::defaults());
  EXPECT_EQ(row(c, "p1.ao.rmse").change, MetricChange::improved);
  EXPECT_EQ(c.improved, 1);
  EXPECT_FALSE(c.regression());
}

TEST(BaselineCompare, AbsoluteToleranceProtectsTinyErrors) {
  const nlohmann::json base = report({{"p1", method({{"ao", metrics(1e-7, 2e-7, 1e-7)}})}});
  const nlohmann::json now =
      report({{"p1", method({{"ao", metrics(5e-6, 8e-6, 6e-6)}})}});  // 40x, but < 1e-5
  EXPECT_FALSE(compare_to_baseline(now, base, BaselineOptions::defaults()).regression());
}

TEST(BaselineCompare, MissingMetricLayerAndMethodRegress) {
  nlohmann::json now = kBase;
  now["methods"]["p1"]["layers"]["ao"].erase("excess_rmse");
  BaselineComparison c = compare_to_baseline(now, kBase, BaselineOptions::defaults());
  EXPECT_EQ(row(c, "p1.ao.excess_rmse").change, MetricChange::missing);
  EXPECT_EQ(c.missing, 1);
  EXPECT_TRUE(c.regression());

  // An unchecked metric that disappears is information, not a regression.
  now = kBase;
  now["methods"]["p1"]["layers"]["ao"].erase("max");
  c = compare_to_baseline(now, kBase, BaselineOptions::defaults());
  EXPECT_EQ(row(c, "p1.ao.max").change, MetricChange::info);
  EXPECT_FALSE(c.regression());

  const nlohmann::json two =
      report({{"p1", method({{"ao", metrics(0.01, 0.02, 0.015)}, {"direct", metrics(0.01, 0.02, 0.015)}})},
              {"hbao", method({{"ao", metrics(0.01, 0.02, 0.015)}})}});
  c = compare_to_baseline(kBase, two, BaselineOptions::defaults());
  EXPECT_EQ(row(c, "p1.direct.rmse").change, MetricChange::missing);
  EXPECT_EQ(row(c, "hbao.ao.mae").change, MetricChange::missing);
  EXPECT_EQ(c.missing, 6);  // 3 checked metrics x (p1.direct, hbao.ao)
  EXPECT_NE(comparison_table(c, false).find("hbao.ao.mae"), std::string::npos);
}

TEST(BaselineCompare, NewMethodIsListedNotARegression) {
  nlohmann::json now = kBase;
  now["methods"]["lsao"] = method({{"obscurance", metrics(0.03, 0.04, 0.035)}}, 2.0);
  const BaselineComparison c = compare_to_baseline(now, kBase, BaselineOptions::defaults());
  EXPECT_FALSE(c.regression());
  EXPECT_EQ(row(c, "lsao.obscurance.rmse").change, MetricChange::added);
  EXPECT_EQ(c.added, 4);  // 3 checked metrics and the method's seconds, each a row of the table
  EXPECT_NE(comparison_table(c, false).find("lsao.obscurance.rmse"), std::string::npos);
  EXPECT_NE(comparison_table(c, false).find("lsao.seconds"), std::string::npos);
}

TEST(BaselineCompare, PsnrIsHigherBetter) {
  BaselineOptions o = BaselineOptions::defaults();
  ASSERT_EQ(parse_tolerance("psnr=0,0.5", o), "");  // 0.5 dB
  auto with_psnr = [](double p) {
    return report({{"p1", method({{"ao", metrics(0.010, 0.020, 0.015, p)}})}});
  };
  EXPECT_EQ(row(compare_to_baseline(with_psnr(29.6), kBase, o), "p1.ao.psnr").change, MetricChange::same);
  EXPECT_EQ(row(compare_to_baseline(with_psnr(29.4), kBase, o), "p1.ao.psnr").change,
            MetricChange::regressed);
  EXPECT_EQ(row(compare_to_baseline(with_psnr(30.6), kBase, o), "p1.ao.psnr").change, MetricChange::improved);
  // psnr disappears when the error becomes zero: that is not a lost metric.
  nlohmann::json exact = report({{"p1", method({{"ao", metrics(0, 0, 0, std::nullopt)}})}});
  const BaselineComparison c = compare_to_baseline(exact, kBase, o);
  EXPECT_EQ(row(c, "p1.ao.psnr").change, MetricChange::improved);
  EXPECT_FALSE(c.regression());
}

// The change column is a finite percentage or "-": never inf or nan, whatever the two values.
TEST(BaselineCompare, TheChangeIsAFinitePercentageOrNone) {
  const std::vector<std::tuple<double, double, std::string>> cases = {
      {0.1, 1e308, "-100.0%"},  // 100 * (0.1 - 1e308) overflows before the division
      {1e300, 0.1, "+1e+303%"}, {1e308, 0.1, "-"},      {0.1, 1e-320, "-"},
      {-1e308, 1e308, "-"},     {0.03, 0.02, "+50.0%"}, {0.1, 0.0, "-"}};
  for (const auto& [now, was, change] : cases) {
    SCOPED_TRACE(std::to_string(now) + " from " + std::to_string(was));
    auto with_bias = [](double bias) {
      nlohmann::json m = metrics(0.010, 0.020, 0.015);
      m["bias"] = bias;
      return report({{"p1", method({{"ao", m}})}});
    };
    BaselineOptions options = BaselineOptions::defaults();
    ASSERT_EQ(parse_tolerance("bias=0.05", options), "");
    const std::string table =
        comparison_table(compare_to_baseline(with_bias(now), with_bias(was), options), true);
    const std::size_t at = table.find("p1.ao.bias");
    ASSERT_NE(at, std::string::npos) << table;
    const std::string line = table.substr(at, table.find('\n', at) - at);
    std::istringstream fields(line);
    std::string key, baseline, value, shown;
    fields >> key >> baseline >> value >> shown;
    EXPECT_EQ(shown, change) << line;
    EXPECT_EQ(table.find("inf"), std::string::npos) << table;
    EXPECT_EQ(table.find("nan"), std::string::npos) << table;
  }
}

TEST(BaselineCompare, CustomTolerancesAndTheirErrors) {
  BaselineOptions o = BaselineOptions::defaults();
  EXPECT_EQ(parse_tolerance("max=0.1", o), "");
  EXPECT_EQ(o.checked["max"].rel, 0.1);
  EXPECT_EQ(o.checked["max"].abs, 0.0);
  EXPECT_EQ(parse_tolerance("rmse=0.5,0.01", o), "");
  EXPECT_EQ(o.checked["rmse"].abs, 0.01);
  EXPECT_NE(parse_tolerance("rsme=0.1", o), "");
  EXPECT_NE(parse_tolerance("max", o), "");
  EXPECT_NE(parse_tolerance("max=abc", o), "");
  EXPECT_NE(parse_tolerance("max=-1", o), "");
  EXPECT_NE(parse_tolerance("max=0.1,2x", o), "");

  nlohmann::json now = kBase;
  now["methods"]["p1"]["layers"]["ao"]["max"] = 0.56;    // +12 %: beyond 10 %
  now["methods"]["p1"]["layers"]["ao"]["rmse"] = 0.029;  // +45 %: within 50 %
  const BaselineComparison c = compare_to_baseline(now, kBase, o);
  EXPECT_EQ(row(c, "p1.ao.max").change, MetricChange::regressed);
  EXPECT_EQ(row(c, "p1.ao.rmse").change, MetricChange::same);
  EXPECT_EQ(c.regressed, 1);
  const nlohmann::json j = comparison_json(c);
  EXPECT_TRUE(j["regression"].get<bool>());
  EXPECT_EQ(j["regressed"], 1);
}

TEST(BaselineCompare, TimingCanBeChecked) {
  BaselineOptions o = BaselineOptions::defaults();
  ASSERT_EQ(parse_tolerance("seconds=1.0", o), "");  // fail when twice as slow
  nlohmann::json now = kBase;
  now["methods"]["p1"]["seconds"] = 2.5;
  EXPECT_EQ(row(compare_to_baseline(now, kBase, o), "p1.seconds").change, MetricChange::regressed);
  now["methods"]["p1"]["seconds"] = 1.9;
  EXPECT_EQ(row(compare_to_baseline(now, kBase, o), "p1.seconds").change, MetricChange::same);
}

TEST(BaselineCompare, NotAReportIsAnError) {
  EXPECT_THROW(compare_to_baseline(nlohmann::json::object(), kBase, BaselineOptions::defaults()),
               std::invalid_argument);
  EXPECT_THROW(compare_to_baseline(kBase, report({{"p1", {{"seconds", 1}}}}), BaselineOptions::defaults()),
               std::invalid_argument);
}

// A report with what identifies its job, as hfbake writes it.
nlohmann::json identified(const nlohmann::json& methods) {
  nlohmann::json r = report(methods);
  r["job"] = {{"name", "cliff"},
              {"file", "jobs/cliff.json"},
              {"hash", "0123456789abcdef"},
              {"scene",
               {{"height", {{"image", "fnv1a:00000000000000aa"}, {"texel_size", 1.0}}},
                {"environment", {{"uniform", 1.0}}},
                {"bounces", 1}}}};
  r["size"] = {64, 32};
  r["crop"] = 0;
  r["reference"] = {{"seconds", 3.0}, {"parameters", {{"samples", 256}, {"seed", 1}}}};
  return r;
}

TEST(BaselineJob, TheSameJobHasNoDifferences) {
  const nlohmann::json a = identified({{"p1", method({{"ao", metrics(0.01, 0.02, 0.015)}})}});
  nlohmann::json b = a;
  // What does not identify the job: the file it was run from, the job hash (it covers the method
  // parameters), metrics, timings.
  b["job"]["file"] = "elsewhere/cliff.json";
  b["job"]["hash"] = "fedcba9876543210";
  b["methods"]["p1"]["layers"]["ao"]["rmse"] = 0.5;
  b["reference"]["seconds"] = 99.0;
  EXPECT_TRUE(job_differences(a, b).empty());
  EXPECT_TRUE(compare_to_baseline(a, b, BaselineOptions::defaults()).job_differences.empty());
}

TEST(BaselineJob, EachIdentifyingPartIsADifference) {
  const nlohmann::json base = identified({{"p1", method({{"ao", metrics(0.01, 0.02, 0.015)}})}});
  auto differences = [&](const std::function<void(nlohmann::json&)>& change) {
    nlohmann::json now = base;
    change(now);
    return job_differences(now, base);
  };
  using V = std::vector<std::string>;
  EXPECT_EQ(differences([](nlohmann::json& r) { r["job"]["name"] = "dune"; }),
            V{"job name \"cliff\" (new: \"dune\")"});
  EXPECT_EQ(differences([](nlohmann::json& r) {
              r["size"] = {64, 64};
            }),
            V{"field size [64,32] (new: [64,64])"});
  EXPECT_EQ(differences([](nlohmann::json& r) { r["crop"] = 4; }), V{"crop 0 (new: 4)"});
  EXPECT_EQ(differences([](nlohmann::json& r) { r["reference"]["parameters"]["samples"] = 1024; }),
            V{"reference.samples 256 (new: 1024)"});
  // A key only one side records is a default spelled out (older reports hold the reference's parameters
  // as written, newer ones resolved): not a difference.
  EXPECT_EQ(differences([](nlohmann::json& r) { r["reference"]["parameters"]["replicates"] = 8; }), V{});
  // The height image's bytes changed (its hash stands in for the path).
  EXPECT_EQ(
      differences([](nlohmann::json& r) { r["job"]["scene"]["height"]["image"] = "fnv1a:00000000000000bb"; }),
      V{"scene.height.image \"fnv1a:00000000000000aa\" (new: \"fnv1a:00000000000000bb\")"});
  EXPECT_EQ(differences([](nlohmann::json& r) { r["job"]["scene"].erase("bounces"); }),
            V{"scene.bounces 1 (new: (not set))"});
  // Several at once: each is named.
  EXPECT_EQ(differences([](nlohmann::json& r) {
              r["job"]["name"] = "dune";
              r["job"]["scene"]["environment"]["uniform"] = 2.0;
            }).size(),
            2u);
  // A document that does not record a part (a report from before /job/scene) is not refused for it.
  EXPECT_TRUE(differences([](nlohmann::json& r) { r["job"].erase("scene"); }).empty());
}

TEST(BaselineJob, MessageIsOneLine) {
  const std::string m = another_job_message({"job name \"a\" (new: \"b\")", "crop 0 (new: 4)"});
  EXPECT_EQ(m, "a report of another job: job name \"a\" (new: \"b\"); crop 0 (new: 4)");
}

TEST(BaselineJob, ParameterChangesOfTheStemsBothHave) {
  nlohmann::json base = identified({{"p1", method({{"ao", metrics(0.01, 0.02, 0.015)}})},
                                    {"lsao", method({{"obscurance", metrics(0.01, 0.02, 0.015)}})}});
  base["methods"]["p1"]["parameters"] = {{"method", "p1"}, {"directions", 32}, {"layers", {"ao"}}};
  base["methods"]["lsao"]["parameters"] = {
      {"method", "lsao"}, {"radius", 8}, {"falloff", {{"kind", "step"}}}};
  nlohmann::json now = base;
  now["methods"]["p1"]["parameters"]["directions"] = 64;
  now["methods"]["p1"]["parameters"]["layers"] = {"ao", "vsky"};
  now["methods"]["p1"]["parameters"]["near_radius"] = 4;
  now["methods"]["lsao"]["parameters"].erase("radius");
  now["methods"]["lsao"]["parameters"]["falloff"]["kind"] = "smooth";
  now["methods"]["hbao"] =
      method(nlohmann::json::object());  // new stem: listed as new metrics, not as parameter changes
  const std::vector<ParameterChange> c = parameter_changes(now, base);
  ASSERT_EQ(c.size(), 5u);
  EXPECT_EQ(c[0].key, "lsao.falloff.kind");
  EXPECT_EQ(*c[0].was, "step");
  EXPECT_EQ(*c[0].now, "smooth");
  EXPECT_EQ(c[1].key, "lsao.radius");
  EXPECT_EQ(*c[1].was, 8);
  EXPECT_FALSE(c[1].now);
  EXPECT_EQ(c[2].key, "p1.directions");
  EXPECT_EQ(c[3].key, "p1.layers");  // arrays compare whole
  EXPECT_EQ(*c[3].now, nlohmann::json({"ao", "vsky"}));
  EXPECT_EQ(c[4].key, "p1.near_radius");
  EXPECT_FALSE(c[4].was);
  EXPECT_EQ(*c[4].now, 4);
  // A stem whose method changed says so.
  nlohmann::json swapped = base;
  swapped["methods"]["p1"]["method"] = "p2";
  swapped["methods"]["p1"]["parameters"]["method"] = "p2";
  const std::vector<ParameterChange> s = parameter_changes(swapped, base);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].key, "p1.method");
  EXPECT_EQ(*s[0].now, "p2");
  // Shown in the table and the JSON.
  const BaselineComparison cmp = compare_to_baseline(now, base, BaselineOptions::defaults());
  const std::string table = comparison_table(cmp, false);
  EXPECT_NE(table.find("p1.directions: 32 -> 64"), std::string::npos) << table;
  EXPECT_NE(table.find("lsao.radius: 8 -> (not set)"), std::string::npos) << table;
  const nlohmann::json j = comparison_json(cmp);
  ASSERT_EQ(j["parameter_changes"].size(), 5u);
  EXPECT_EQ(j["parameter_changes"][2],
            (nlohmann::json{{"key", "p1.directions"}, {"value", 64}, {"baseline", 32}}));
  EXPECT_EQ(j["parameter_changes"][1], (nlohmann::json{{"key", "lsao.radius"}, {"baseline", 8}}));
}

}  // namespace
}  // namespace hfbake
