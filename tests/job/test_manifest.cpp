// Job loading: every kind of bad job gives one line naming the file, the JSON pointer and the rule.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "job/manifest.hpp"

namespace hfbake {
namespace {
namespace fs = std::filesystem;

class Manifest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("hfbake_test_job_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }
  // Loads a job whose text is `text` and returns its error lines.
  std::vector<std::string> errors(const std::string& text) {
    return load_job(write("x.json", text), std::nullopt).errors;
  }
  static std::string minimal(const std::string& extra = "",
                             const std::string& bake = R"([{"method": "p1"}])") {
    return R"({"version": 1, "name": "t", "height": {"procedural": {"kind": "flat", "size": [8, 8]}}, "bake": )" +
           bake + extra + "}";
  }

  fs::path dir_;
};

TEST_F(Manifest, MinimalJobLoadsWithDefaults) {
  const JobLoad r = load_job(write("ok.json", minimal()), std::nullopt);
  ASSERT_TRUE(r.errors.empty()) << r.errors.front();
  ASSERT_TRUE(r.job);
  EXPECT_EQ(r.job->name, "t");
  ASSERT_EQ(r.job->bakes.size(), 1u);
  EXPECT_EQ(r.job->bakes[0].stem, "p1");
  EXPECT_EQ(r.job->output.dir, (dir_ / "out" / "t").lexically_normal());
  EXPECT_FALSE(r.job->output.float_pixels);
}

TEST_F(Manifest, RepeatedMethodGetsIndexedStems) {
  const JobLoad r =
      load_job(write("ok.json", minimal("", R"([{"method": "p1"}, {"method": "hbao"}, {"method": "p1"}])")),
               std::nullopt);
  ASSERT_TRUE(r.job);
  EXPECT_EQ(r.job->bakes[0].stem, "p1-0");
  EXPECT_EQ(r.job->bakes[1].stem, "hbao");
  EXPECT_EQ(r.job->bakes[2].stem, "p1-2");
}

TEST_F(Manifest, MalformedJsonNamesLineAndColumn) {
  const auto e = errors("{\n  \"version\": 1,\n  \"name\": \n}");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_NE(e[0].find("x.json: line 4, column 1: malformed JSON"), std::string::npos) << e[0];
}

TEST_F(Manifest, OutOfRangeDirections) {
  const auto e = errors(minimal("", R"([{"method": "p1", "directions": 0}])"));
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], (dir_ / "x.json").string() + ": /bake/0/directions: must be >= 1");
}

TEST_F(Manifest, WrongType) {
  const auto e = errors(minimal(R"(, "bounces": "two")"));
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], (dir_ / "x.json").string() + ": /bounces: wrong type");
}

TEST_F(Manifest, MissingKey) {
  const auto e = errors(R"({"version": 1, "height": {"procedural": {"kind": "flat"}}, "bake": []})");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], (dir_ / "x.json").string() + ": /: missing required key \"name\"");
}

TEST_F(Manifest, UnknownKeysAreErrorsAtEveryLevel) {
  auto e = errors(minimal(R"(, "bouncess": 2)"));
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], (dir_ / "x.json").string() + ": /bouncess: unknown key");
  e = errors(minimal("", R"([{"method": "p1", "directoins": 8}])"));
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], (dir_ / "x.json").string() + ": /bake/0/directoins: unknown key");
}

TEST_F(Manifest, UnknownMethod) {
  const auto e = errors(minimal("", R"([{"method": "magic"}])"));
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], (dir_ / "x.json").string() +
                      ": /bake/0/method: unknown method \"magic\" (one of \"farfield\", \"hbao\", \"hsao\", "
                      "\"lsao\", \"nlp\", \"p1\", \"p2\", \"vo\")");
}

// Enum errors list the allowed values (issue 14), in the job schema and in a method's own schema.
TEST_F(Manifest, EnumErrorsListTheAllowedValues) {
  auto e = errors(minimal("", R"([{"method": "hbao", "falloff": "gauss"}])"));
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], (dir_ / "x.json").string() +
                      ": /bake/0/falloff: must be one of \"none\", \"step\", \"linear\", \"smooth\", "
                      "\"exponential\", \"rational\"");
  e = errors(minimal("", R"([{"method": "p1", "layers": ["ao", "horizn"]}])"));
  ASSERT_EQ(e.size(), 1u);
  EXPECT_NE(e[0].find("/bake/0/layers/1: must be one of \"ao\", \"vsky\""), std::string::npos) << e[0];
}

// A missing baseline is found before the bake (it used to fail after hours of baking), and the message says
// how to make the first one.
TEST_F(Manifest, MissingBaselineIsFoundBeforeBaking) {
  const auto e = errors(
      R"({"version": 1, "name": "t", "height": {"procedural": {"kind": "fractal", "size": [8, 8]}},
          "bake": [{"method": "p1"}], "reference": {"samples": 4}, "report": {"baseline": "base/report.json"}})");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_NE(e[0].find(": /report/baseline: no such file: "), std::string::npos) << e[0];
  EXPECT_NE(e[0].find("--update-baseline"), std::string::npos) << e[0];
}

TEST_F(Manifest, MissingInputFile) {
  const auto e =
      errors(R"({"version": 1, "name": "t", "height": {"image": "nope.exr"}, "bake": [{"method": "p1"}]})");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_NE(e[0].find(": /height/image: no such file: "), std::string::npos) << e[0];
}

TEST_F(Manifest, EnvironmentNeedsExactlyOneKind) {
  const auto e = errors(minimal(R"(, "environment": {"uniform": 1, "latlong": "a.exr"})"));
  ASSERT_GE(e.size(), 1u);
  EXPECT_NE(e[0].find(": /environment: needs exactly one of"), std::string::npos) << e[0];
}

TEST_F(Manifest, SeveralViolationsAreAllReported) {
  const auto e = errors(minimal(R"(, "bounces": -1, "output": {"pixel_type": "double"})"));
  EXPECT_EQ(e.size(), 2u);
}

TEST_F(Manifest, UnreadableFile) {
  const JobLoad r = load_job(dir_ / "absent.json", std::nullopt);
  ASSERT_EQ(r.errors.size(), 1u);
  EXPECT_NE(r.errors[0].find("absent.json: No such file or directory"), std::string::npos) << r.errors[0];
}

}  // namespace
}  // namespace hfbake
