// The comparison metrics on images whose differences are known by construction, the noise-floor
// subtraction, thresholds, baselines, and report.json against its schema.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "core/vec.hpp"
#include "job/schema_validation.hpp"
#include "report/compare.hpp"
#include "report/report_document.hpp"
#include "report/report_html.hpp"

namespace hfbake {
namespace {

Layer mono(const std::string& name, int w, int h, float v) {
  return {name, mono_channels(), std::vector<float>(std::size_t(w) * h, v)};
}

TEST(Compare, ConstantOffset) {
  const int w = 16, h = 8;
  Layer ref = mono("ao", w, h, 0.5f), m = mono("ao", w, h, 0.6f);
  ref.data[3] = 0.8f;  // peak of the reference
  m.data[3] = 0.9f;
  const LayerMetrics r = compare_layer(m, ref, nullptr, w, h, crop_region(w, h, 0));
  EXPECT_NEAR(r.mae, 0.1, 1e-6);
  EXPECT_NEAR(r.rmse, 0.1, 1e-6);
  EXPECT_NEAR(r.bias, 0.1, 1e-6);
  EXPECT_NEAR(r.max, 0.1, 1e-6);
  EXPECT_NEAR(r.p99, 0.1, 1e-6);
  const double ref_mean = (0.5 * (w * h - 1) + 0.8) / (w * h);
  ASSERT_TRUE(r.rel_mae);
  EXPECT_NEAR(*r.rel_mae, 0.1 / ref_mean, 1e-6);
  ASSERT_TRUE(r.psnr);
  EXPECT_NEAR(*r.psnr, 20 * std::log10(0.8 / 0.1), 1e-4);
  EXPECT_EQ(r.noise_rmse, 0);
  EXPECT_NEAR(r.excess_rmse, 0.1, 1e-6);
  EXPECT_EQ(r.values, std::size_t(w * h));
}

TEST(Compare, BentNormalsAreScoredByAngle) {
  // 100 texels: the reference points up; the method is tilted by 1 degree in 98 texels and by 10 and 30
  // degrees in the other two (mean 1.38, p99 10, max 30). A zero vector (nothing escaped) is left out of
  // the angles, not counted as 90 degrees. Lengths do not matter.
  const int w = 10, h = 10;
  Layer ref{"bent_normal", xyz_channels(), std::vector<float>(3 * w * h)};
  Layer m = ref;
  const double deg = kPi / 180;
  for (int t = 0; t < w * h; ++t) {
    ref.data[3 * t + 2] = 1;
    const double a = t == 7 ? 10 * deg : t == 42 ? 30 * deg : 1 * deg;
    m.data[3 * t] = float(2 * std::sin(a));
    m.data[3 * t + 2] = float(2 * std::cos(a));
  }
  LayerMetrics r = compare_layer(m, ref, nullptr, w, h, crop_region(w, h, 0));
  ASSERT_TRUE(r.angle_mean_deg && r.angle_p99_deg && r.angle_max_deg);
  EXPECT_NEAR(*r.angle_mean_deg, (98 * 1 + 10 + 30) / 100.0, 1e-3);
  EXPECT_NEAR(*r.angle_p99_deg, 10, 1e-3);
  EXPECT_NEAR(*r.angle_max_deg, 30, 1e-3);
  m.data[3 * 42] = m.data[3 * 42 + 2] = 0;
  r = compare_layer(m, ref, nullptr, w, h, crop_region(w, h, 0));
  EXPECT_NEAR(*r.angle_max_deg, 10, 1e-3);
  EXPECT_NEAR(*r.angle_mean_deg, (98 * 1 + 10) / 99.0, 1e-3);
  // Scalar layers get no angles; the names list them for thresholds.
  const Layer a = mono("ao", w, h, 0.5f);
  EXPECT_FALSE(compare_layer(a, a, nullptr, w, h, crop_region(w, h, 0)).angle_mean_deg);
  EXPECT_TRUE(metric_value(r, "angle_p99_deg"));
}

TEST(Compare, OutliersMaxAndPercentile) {
  const int w = 10, h = 10;  // 100 values
  Layer ref = mono("ao", w, h, 1.0f), m = mono("ao", w, h, 1.0f);
  m.data[17] = 0.0f;  // one outlier: |diff| = 1
  LayerMetrics r = compare_layer(m, ref, nullptr, w, h, crop_region(w, h, 0));
  EXPECT_NEAR(r.mae, 0.01, 1e-9);
  EXPECT_NEAR(r.rmse, 0.1, 1e-9);
  EXPECT_NEAR(r.bias, -0.01, 1e-9);
  EXPECT_EQ(r.max, 1.0);
  EXPECT_EQ(r.p99, 0.0);  // 99 of 100 values are exact
  m.data[18] = 0.5f;      // a second outlier moves the 99th percentile onto it
  r = compare_layer(m, ref, nullptr, w, h, crop_region(w, h, 0));
  EXPECT_EQ(r.p99, 0.5);
  EXPECT_EQ(r.max, 1.0);
}

TEST(Compare, IdenticalImagesHaveNoPsnrAndZeroReferenceNoRelMae) {
  const int w = 4, h = 4;
  Layer a = mono("ao", w, h, 0.3f);
  LayerMetrics r = compare_layer(a, a, nullptr, w, h, crop_region(w, h, 0));
  EXPECT_EQ(r.rmse, 0);
  EXPECT_FALSE(r.psnr);
  Layer zero = mono("indirect", w, h, 0.0f);
  r = compare_layer(a, zero, nullptr, w, h, crop_region(w, h, 0));
  EXPECT_FALSE(r.rel_mae);
}

TEST(Compare, CropLeavesOutTheBorder) {
  const int w = 12, h = 9;
  Layer ref = mono("ao", w, h, 0.5f), m = mono("ao", w, h, 0.5f);
  for (int x = 0; x < w; ++x) m.data[x] = 0.0f, m.data[(h - 1) * w + x] = 1.0f;
  for (int y = 0; y < h; ++y) m.data[y * w] = 0.2f, m.data[y * w + w - 1] = 0.9f;
  EXPECT_GT(compare_layer(m, ref, nullptr, w, h, crop_region(w, h, 0)).max, 0.4);
  const LayerMetrics r = compare_layer(m, ref, nullptr, w, h, crop_region(w, h, 1));
  EXPECT_EQ(r.max, 0);
  EXPECT_EQ(r.values, std::size_t((w - 2) * (h - 2)));
  EXPECT_THROW(compare_layer(m, ref, nullptr, w, h, crop_region(w, h, 5)), std::invalid_argument);
}

// The reference is truth + Gaussian noise of known standard deviation sigma (and reports sigma as its
// stderr); the method is truth + delta. rmse then holds both errors, and excess_rmse recovers delta.
TEST(Compare, NoiseFloorSubtraction) {
  const int w = 256, h = 256;
  const double sigma = 0.05, delta = 0.02;
  std::mt19937_64 rng(12345);
  std::normal_distribution<double> noise(0.0, sigma);
  Layer truth{"direct", rgb_channels(), {}}, ref = truth, m = truth, se{"direct_stderr", rgb_channels(), {}};
  for (int t = 0; t < w * h * 3; ++t) {
    const double v = 0.3 + 0.4 * double(t % 97) / 97.0;
    ref.data.push_back(float(v + noise(rng)));
    m.data.push_back(float(v + delta));
    se.data.push_back(float(sigma));
  }
  const LayerMetrics r = compare_layer(m, ref, &se, w, h, crop_region(w, h, 0));
  EXPECT_NEAR(r.noise_rmse, sigma, 1e-7);
  EXPECT_NEAR(r.rmse, std::sqrt(delta * delta + sigma * sigma), 5e-4);
  EXPECT_NEAR(r.excess_rmse, delta, 0.03 * delta);  // the sampling error of mean noise^2 is ~0.3 % of sigma^2
  EXPECT_NEAR(r.excess_rmse, std::sqrt(r.rmse * r.rmse - r.noise_rmse * r.noise_rmse), 1e-12);
  // The reference against itself: no error at all, whatever its noise.
  const LayerMetrics exact = compare_layer(ref, ref, &se, w, h, crop_region(w, h, 0));
  EXPECT_EQ(exact.excess_rmse, 0);

  // A single-channel stderr applies to every channel.
  Layer se1{"direct_stderr", mono_channels(), std::vector<float>(std::size_t(w) * h, float(sigma))};
  EXPECT_NEAR(compare_layer(m, ref, &se1, w, h, crop_region(w, h, 0)).noise_rmse, sigma, 1e-7);
}

TEST(Compare, ExcessClampsAtZeroWhenNoiseExceedsError) {
  const int w = 4, h = 4;
  Layer ref = mono("ao", w, h, 0.5f), m = mono("ao", w, h, 0.51f), se = mono("ao_stderr", w, h, 0.1f);
  const LayerMetrics r = compare_layer(m, ref, &se, w, h, crop_region(w, h, 0));
  EXPECT_NEAR(r.rmse, 0.01, 1e-6);
  EXPECT_NEAR(r.noise_rmse, 0.1, 1e-7);
  EXPECT_EQ(r.excess_rmse, 0);
}

TEST(Compare, MismatchedChannelsThrow) {
  Layer a = mono("ao", 2, 2, 1), b{"ao", rgb_channels(), std::vector<float>(12, 1.0f)};
  EXPECT_THROW(compare_layer(a, b, nullptr, 2, 2, crop_region(2, 2, 0)), std::invalid_argument);
}

struct Fixture {
  LayerSet reference, method;
  Fixture() {
    reference.width = method.width = 8;
    reference.height = method.height = 8;
    reference.add("ao", mono_channels()).data.assign(64, 0.5f);
    reference.add("ao_stderr", mono_channels()).data.assign(64, 0.01f);
    reference.add("direct", rgb_channels()).data.assign(192, 1.0f);
    method.add("ao", mono_channels()).data.assign(64, 0.55f);
    method.add("horizon", indexed_channels(4));
    method.add("direct", rgb_channels()).data.assign(192, 1.0f);
  }
};

TEST(Report, ThresholdsPassFailAndTypos) {
  Fixture f;
  f.reference.add("vsky", mono_channels()), f.method.add("vsky", mono_channels());  // zeros: no psnr
  ReportSpec spec;
  spec.hfbake_version = "test";
  spec.job_name = "t";
  spec.thresholds = {{"p1.ao.mae", 0.06},  {"p1.ao.rmse", 0.04}, {"p1.ao.bias", 0.04}, {"p1.ao.psnr", 30},
                     {"p1.aoo.mae", 1.0},  {"p2.ao.mae", 1.0},   {"p1.ao.nope", 1.0},  {"p1.direct.psnr", 1},
                     {"p1.direct.mae", 0}, {"p1.vsky.psnr", 1}};
  const ReportOutcome out =
      build_report(spec, {{"p1", "p1", 1.5, {{"method", "p1"}}, &f.method}}, f.reference);
  // Held: ao.mae (0.05 <= 0.06), direct.mae (0 <= 0), direct.psnr (identical images: infinite). Failed: rmse
  // (0.05 > 0.04), |bias| (0.05 > 0.04), psnr (20 log10(0.5/0.05) = 20 dB < 30), three typos, vsky.psnr
  // (undefined: a zero reference).
  EXPECT_EQ(out.failures.size(), 7u);
  EXPECT_FALSE(out.doc["passed"].get<bool>());
  for (const auto& t : out.doc["thresholds"]) {
    const std::string key = t["key"];
    EXPECT_EQ(t["passed"].get<bool>(),
              key == "p1.ao.mae" || key == "p1.direct.mae" || key == "p1.direct.psnr")
        << key;
    if (key == "p1.direct.psnr") {
      EXPECT_FALSE(t.contains("value")) << t;
    }
    if (key == "p1.vsky.psnr") {
      EXPECT_EQ(t["error"], "metric \"psnr\" is undefined for this layer (a zero reference)") << t;
    }
  }
  EXPECT_NEAR(out.metrics_by_method["p1"]["ao"]["psnr"].get<double>(), 20.0, 1e-4);
  EXPECT_NEAR(out.metrics_by_method["p1"]["ao"]["noise_rmse"].get<double>(), 0.01, 1e-7);
  EXPECT_EQ(out.doc["methods"]["p1"]["not_compared"], nlohmann::json::array({"horizon"}));
  EXPECT_TRUE(validate_against_schema(out.doc, "report.schema.json").empty()) << out.doc.dump(2);
}

// A report as build_report writes it holds no impossible value; an error beyond any two floats' difference,
// an angle beyond 180 degrees or a reference mean beyond float's range is named by its JSON pointer.
TEST(Report, ImpossibleValuesAreNamed) {
  Fixture f;
  ReportSpec spec;
  spec.hfbake_version = "test";
  const nlohmann::json genuine = build_report(spec, {{"p1", "p1", 1.0, {}, &f.method}}, f.reference).doc;
  EXPECT_FALSE(impossible_report_value(genuine)) << genuine.dump(2);
  const std::vector<std::pair<std::string, double>> edits = {{"/methods/p1/layers/ao/rmse", 1e308},
                                                             {"/methods/p1/layers/ao/bias", -7e38},
                                                             {"/methods/p1/layers/ao/angle_max_deg", 181},
                                                             {"/reference/layers/ao/mean", 1e39}};
  for (const auto& [pointer, value] : edits) {
    nlohmann::json doc = genuine;
    doc[nlohmann::json::json_pointer(pointer)] = value;
    const auto found = impossible_report_value(doc);
    ASSERT_TRUE(found) << pointer;
    EXPECT_EQ(found->first, pointer);
  }
  nlohmann::json largest = genuine;
  largest["methods"]["p1"]["layers"]["ao"]["max"] = 2.0 * double(std::numeric_limits<float>::max());
  EXPECT_FALSE(impossible_report_value(largest));
}

TEST(Report, BaselineRegression) {
  Fixture f;
  ReportSpec spec;
  spec.hfbake_version = "test";
  spec.crop = 1;
  const ReportOutcome first = build_report(spec, {{"p1", "p1", 1.0, {}, &f.method}}, f.reference);
  EXPECT_TRUE(first.failures.empty());
  EXPECT_EQ(first.doc["region"]["x1"], 7);
  spec.baseline = first.doc;
  spec.baseline_file = "base.json";
  EXPECT_TRUE(build_report(spec, {{"p1", "p1", 1.0, {}, &f.method}}, f.reference).failures.empty());
  for (float& v : f.method.find("ao")->data) v = 0.6f;  // error doubles
  const ReportOutcome worse = build_report(spec, {{"p1", "p1", 1.0, {}, &f.method}}, f.reference);
  EXPECT_EQ(worse.failures.size(), 3u);  // mae, rmse, excess_rmse
  EXPECT_EQ(worse.doc["baseline"]["regressions"].size(), 3u);
  EXPECT_TRUE(validate_against_schema(worse.doc, "report.schema.json").empty()) << worse.doc.dump(2);
}

TEST(Report, ObscurancesBakedWithOtherSettingsThanTheReferenceAreNotCompared) {
  // The reference computed one obscurance: step falloff, radius 16, cosine-weighted.
  LayerSet reference;
  reference.width = reference.height = 4;
  reference.add("obscurance", mono_channels()).data.assign(16, 0.8f);
  reference.attributes.emplace_back("hfbake:reference_setup", R"({"falloff": "step", "radius": 16})");
  LayerSet method = reference;
  method.attributes.clear();
  method.find("obscurance")->data.assign(16, 0.5f);
  const std::vector<std::pair<EntryReach, bool>> cases = {
      {{"step", 16, true, {}}, true},    {{"step", 32, true, {}}, false},
      {{"smooth", 16, true, {}}, false}, {{"step", 16, false, {}}, false},  // uniform weighting
      {{"none", 0, true, {}}, false},                                       // plain AO
  };
  for (const auto& [reach, comparable] : cases) {
    const std::string what = reach.falloff + " " + std::to_string(reach.radius);
    const ReportOutcome out =
        build_report(ReportSpec{}, {{"hbao", "hbao", 1.0, {{"method", "hbao"}}, &method, reach}}, reference);
    const nlohmann::json& m = out.doc["methods"]["hbao"];
    EXPECT_EQ(m["layers"].contains("obscurance"), comparable) << what;
    EXPECT_EQ(m["not_compared"].size(), comparable ? 0u : 1u) << what;
    if (comparable) {
      EXPECT_NEAR(m["layers"]["obscurance"]["mae"].get<double>(), 0.3, 1e-6);
    }
  }
}

// The reference's bent normal averages ao rays without a distance limit: a bent normal baked with a falloff
// (a radius-limited search) is another quantity, listed under not_compared with the reason; one without a
// falloff is scored, its angles in the report.
TEST(Report, RadiusLimitedBentNormalsAreNotComparedWithTheirReason) {
  LayerSet reference;
  reference.width = reference.height = 4;
  reference.add("bent_normal", xyz_channels()).data.assign(48, 0.0f);
  for (std::size_t t = 0; t < 16; ++t) reference.find("bent_normal")->data[3 * t + 2] = 1;
  LayerSet method = reference;
  const std::vector<std::pair<EntryReach, bool>> cases = {
      {{}, true},  // no falloff
      {{"step", 8, true, {}}, false},
      {{"smooth", 8, true, {}}, false},
  };
  for (const auto& [reach, comparable] : cases) {
    const std::string what = reach.falloff;
    const ReportOutcome out = build_report(ReportSpec{}, {{"m", "m", 1.0, {}, &method, reach}}, reference);
    const nlohmann::json& m = out.doc["methods"]["m"];
    EXPECT_EQ(m["layers"].contains("bent_normal"), comparable) << what;
    if (comparable) {
      EXPECT_NEAR(m["layers"]["bent_normal"]["angle_mean_deg"].get<double>(), 0.0, 1e-6);
    } else {
      EXPECT_EQ(m["not_compared"], nlohmann::json::array({"bent_normal"}));
      EXPECT_NE(m["not_compared_reasons"]["bent_normal"].get<std::string>().find("radius-limited"),
                std::string::npos);
    }
    EXPECT_TRUE(validate_against_schema(out.doc, "report.schema.json").empty()) << out.doc.dump(2);
  }
}

// report.html: the verdict says when nothing was checked; excess_rmse leads the summary; bent-normal angles
// and the reasons for not comparing a layer are on the page.
TEST(Report, HtmlSaysWhatWasCheckedAndShowsAngles) {
  Fixture f;
  f.reference.add("bent_normal", xyz_channels()).data.assign(192, 0.0f);
  f.method.add("bent_normal", xyz_channels()).data.assign(192, 0.0f);
  for (std::size_t t = 0; t < 64; ++t) {
    f.reference.find("bent_normal")->data[3 * t + 2] = 1;
    f.method.find("bent_normal")->data[3 * t + 0] = float(std::sin(0.1));  // 0.1 rad from the reference
    f.method.find("bent_normal")->data[3 * t + 2] = float(std::cos(0.1));
  }
  ReportSpec spec;
  spec.job_name = "t";
  const ReportOutcome none =
      build_report(spec, {{"p1", "p1", 8.39025, {{"method", "p1"}}, &f.method}}, f.reference);
  HtmlInputs in;
  in.report = none.doc;
  HtmlMethod p1;
  p1.stem = p1.method = "p1";
  in.methods = {p1};
  const std::string page = report_html(in);
  EXPECT_NE(page.find("No thresholds set and no baseline: nothing was checked"), std::string::npos);
  EXPECT_EQ(page.find("PASSED"), std::string::npos);
  EXPECT_NE(page.find("<th>layer</th><th>excess_rmse</th><th>rmse</th>"), std::string::npos);
  EXPECT_NE(page.find("<td>8.39</td>"), std::string::npos);                  // seconds rounded for people
  const std::string angle = "<td>p1</td><td>bent_normal</td><td>5.73</td>";  // 0.1 rad
  EXPECT_NE(page.find(angle), std::string::npos) << page.substr(page.find("Directions"), 400);
  EXPECT_NE(page.find("<code>horizon</code>: the reference has no layer of this name"), std::string::npos);

  spec.thresholds = {{"p1.ao.mae", 0.06}};
  in.report = build_report(spec, {{"p1", "p1", 1.0, {{"method", "p1"}}, &f.method}}, f.reference).doc;
  EXPECT_NE(report_html(in).find("PASSED: every threshold held"), std::string::npos);
}

TEST(Report, ReliefLayersAreComparedOnlyWithTheReferencesSettings) {
  // The reference computed relief's quantities for 8 directions, radius 10, compass azimuths.
  LayerSet reference;
  reference.width = reference.height = 4;
  reference.add("svf", mono_channels()).data.assign(16, 0.9f);
  reference.attributes.emplace_back(
      "hfbake:relief_reference",
      R"({"directions": 8, "search_radius": 10.0, "azimuth_convention": "compass"})");
  LayerSet method = reference;
  method.attributes.clear();
  method.find("svf")->data.assign(16, 0.8f);
  auto search = [](const nlohmann::json& s) {
    EntryReach r;
    r.search = s;
    return r;
  };
  const EntryReach same =
      search({{"directions", 8}, {"search_radius", 10.0}, {"azimuth_convention", "compass"}});
  const std::vector<std::pair<EntryReach, bool>> cases = {
      {same, true},
      {search({{"directions", 8}, {"search_radius", 10}, {"azimuth_convention", "compass"}}),
       true},  // an integer radius is the same number
      {search({{"directions", 16}, {"search_radius", 10.0}, {"azimuth_convention", "compass"}}), false},
      {search({{"directions", 8}, {"search_radius", 5.0}, {"azimuth_convention", "compass"}}), false},
      {search({{"directions", 8}, {"search_radius", 10.0}, {"azimuth_convention", "hfbake"}}), false},
      {EntryReach{}, false},  // no search settings
  };
  for (const auto& [reach, comparable] : cases) {
    const ReportOutcome out =
        build_report(ReportSpec{}, {{"relief", "relief", 1.0, {}, &method, reach}}, reference);
    const nlohmann::json& m = out.doc["methods"]["relief"];
    EXPECT_EQ(m["layers"].contains("svf"), comparable) << reach.search.dump();
    if (comparable) {
      EXPECT_NEAR(m["layers"]["svf"]["mae"].get<double>(), 0.1, 1e-6);
    }
  }
  // Without the record (a reference of another hfbake, or none traced): not compared.
  reference.attributes.clear();
  EXPECT_FALSE(build_report(ReportSpec{}, {{"relief", "relief", 1.0, {}, &method, same}}, reference)
                   .doc["methods"]["relief"]["layers"]
                   .contains("svf"));
}

}  // namespace
}  // namespace hfbake
