// Parameter sweeps: "directions": [16, 32, 64] is three runs with stable stems; errors point at the list
// element the user wrote; lists never expand where the method's schema wants an array.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "job/manifest.hpp"
#include "job/parameter_sweep.hpp"

namespace hfbake {
namespace {
namespace fs = std::filesystem;

class Sweep : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("hfbake_test_sweep_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  JobLoad load(const std::string& bake) {
    const fs::path p = dir_ / "j.json";
    std::ofstream(p)
        << R"({"version": 1, "name": "t", "height": {"procedural": {"kind": "flat", "size": [8, 8]}},
        "reference": {"samples": 4}, "bake": )" +
               bake + "}";
    return load_job(p, std::nullopt);
  }

  fs::path dir_;
};

TEST_F(Sweep, ListExpandsIntoOneRunPerValue) {
  const JobLoad r = load(R"([{"method": "p1", "directions": [16, 32, 64], "layers": ["ao"]}])");
  ASSERT_TRUE(r.job) << r.errors.front();
  ASSERT_EQ(r.job->bakes.size(), 3u);
  const int expected[] = {16, 32, 64};
  for (int k = 0; k < 3; ++k) {
    const BakeEntry& e = r.job->bakes[k];
    EXPECT_EQ(e.method, "p1");
    EXPECT_EQ(e.stem, "p1-directions" + std::to_string(expected[k]));
    EXPECT_EQ(e.params["directions"], expected[k]);
    EXPECT_EQ(e.params["layers"], nlohmann::json::array({"ao"}));  // arrays the schema wants stay whole
    EXPECT_EQ(e.sweep_parameter, "directions");
    EXPECT_EQ(e.sweep_value, expected[k]);
    EXPECT_EQ(e.sweep_group, 0);
    EXPECT_EQ(e.pointer, "/bake/0");
  }
  EXPECT_TRUE(r.job->has_reference);  // one reference for the whole job, shared by the runs
  EXPECT_EQ(r.job->doc["bake"].size(), 3u);
}

TEST_F(Sweep, EntriesWithoutListsKeepTheirStems) {
  const JobLoad r = load(R"([{"method": "hbao", "directions": 8}, {"method": "p1", "directions": [4, 8]}])");
  ASSERT_TRUE(r.job) << r.errors.front();
  ASSERT_EQ(r.job->bakes.size(), 3u);
  EXPECT_EQ(r.job->bakes[0].stem, "hbao");
  EXPECT_EQ(r.job->bakes[0].sweep_group, -1);
  EXPECT_EQ(r.job->bakes[1].stem, "p1-directions4");
  EXPECT_EQ(r.job->bakes[2].stem, "p1-directions8");
  EXPECT_EQ(r.job->bakes[2].pointer, "/bake/1");
  EXPECT_EQ(r.job->bakes[2].sweep_group, 1);
}

TEST_F(Sweep, SameMethodTwiceGetsTheEntryIndexToo) {
  const JobLoad r = load(R"([{"method": "p1", "directions": [4, 8]}, {"method": "p1", "directions": 16}])");
  ASSERT_TRUE(r.job) << r.errors.front();
  ASSERT_EQ(r.job->bakes.size(), 3u);
  EXPECT_EQ(r.job->bakes[0].stem, "p1-0-directions4");
  EXPECT_EQ(r.job->bakes[1].stem, "p1-0-directions8");
  EXPECT_EQ(r.job->bakes[2].stem, "p1-1");
}

TEST_F(Sweep, BadValueIsReportedAtItsPlaceInTheList) {
  const JobLoad r = load(R"([{"method": "hbao"}, {"method": "p1", "directions": [16, 0, 64]}])");
  ASSERT_FALSE(r.job);
  ASSERT_EQ(r.errors.size(), 1u);
  EXPECT_NE(r.errors[0].find("j.json: /bake/1/directions/1: "), std::string::npos) << r.errors[0];
}

TEST_F(Sweep, DuplicateValueIsAnErrorAndArrayPropertiesNeverSweep) {
  JobLoad r = load(R"([{"method": "p1", "directions": [16, 16]}])");
  ASSERT_FALSE(r.job);
  EXPECT_NE(r.errors.at(0).find("/bake/0/directions/1: 16 is listed twice in the sweep (first at "
                                "/bake/0/directions/0)"),
            std::string::npos)
      << r.errors[0];
  // 3 and 3.0 are one number: the same bake twice, under two stems.
  r = load(R"([{"method": "hbao", "radius": [2, 3, 3.0]}])");
  ASSERT_FALSE(r.job);
  EXPECT_NE(
      r.errors.at(0).find("/bake/0/radius/2: 3.0 is listed twice in the sweep (first at /bake/0/radius/1)"),
      std::string::npos)
      << r.errors[0];

  // A schema-declared array property is never a sweep: "layers" with numbers is a type error, not a sweep.
  r = load(R"([{"method": "p1", "layers": [1, 2]}])");
  ASSERT_FALSE(r.job);
  EXPECT_NE(r.errors.at(0).find("/bake/0/layers/0"), std::string::npos) << r.errors[0];
}

TEST_F(Sweep, PropertiesDeclaredThroughRefsSweepAndTwoListsAreAnError) {
  // hbao's directions and radius are "$ref"s into obscurance_common.schema.json.
  JobLoad r = load(R"([{"method": "hbao", "radius": [2, 4.5], "falloff": "step"}])");
  ASSERT_TRUE(r.job) << r.errors.front();
  ASSERT_EQ(r.job->bakes.size(), 2u);
  EXPECT_EQ(r.job->bakes[1].stem, "hbao-radius4.5");
  EXPECT_EQ(r.job->bakes[1].params["radius"], 4.5);
  r = load(R"([{"method": "hbao", "radius": [2, 4], "directions": [8, 16]}])");
  ASSERT_FALSE(r.job);
  EXPECT_NE(
      r.errors.at(0).find("/bake/0: sweep one parameter per bake entry (lists given for directions, radius)"),
      std::string::npos)
      << r.errors[0];
}

TEST_F(Sweep, UnknownPropertyListIsNotExpanded) {
  const JobLoad r = load(R"([{"method": "p1", "no_such_key": [1, 2]}])");
  ASSERT_FALSE(r.job);
  ASSERT_EQ(r.errors.size(), 1u);
  EXPECT_NE(r.errors[0].find("/bake/0/no_such_key"), std::string::npos) << r.errors[0];
}

TEST(SweepExpansion, PointersMapBackOntoTheFile) {
  const nlohmann::json doc = {{"bake", {{{"method", "p1"}, {"directions", {4, 8}}}}}};
  const SweepExpansion e = expand_parameter_sweeps(doc);
  EXPECT_TRUE(e.errors.empty());
  ASSERT_EQ(e.doc["bake"].size(), 2u);
  EXPECT_EQ(original_pointer("/bake/1/directions", e.origins), "/bake/0/directions/1");
  EXPECT_EQ(original_pointer("/bake/1/layers/0", e.origins), "/bake/0/layers/0");
  EXPECT_EQ(original_pointer("/bake/1", e.origins), "/bake/0");
  EXPECT_EQ(original_pointer("/name", e.origins), "/name");
  EXPECT_EQ(sweep_stem_suffix("radius", 0.5), "radius0.5");
  EXPECT_EQ(sweep_stem_suffix("directions", 16), "directions16");
}

}  // namespace
}  // namespace hfbake
