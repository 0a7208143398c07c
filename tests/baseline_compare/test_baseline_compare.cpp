// Baseline comparison on hand-made report.json documents: each rule of the comparison (improved, regressed,
// within tolerance, missing metric / layer / method, new method, psnr higher-is-better, custom
// tolerances) is checked against numbers worked out by hand.
#include <gtest/gtest.h>

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
  EXPECT_EQ(c.added, 3);
  EXPECT_NE(comparison_table(c, false).find("lsao.obscurance.rmse"), std::string::npos);
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

}  // namespace
}  // namespace hfbake
