// The layer table (core/layers.hpp) is the one place that says what a layer name means: a layer added
// through it reaches the EXR writer, the output checks, the memory estimate, the reference's plan and the
// report with no other change. And what the report needs of an entry to judge its radius-limited layers
// comes from the entry's typed config (entry_reach), its defaults those of the method's reader.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include "cli/method_dispatch.hpp"
#include "cli/outputs.hpp"
#include "cli/report_writer.hpp"
#include "cli/scene_loader.hpp"
#include "io/exr_output.hpp"
#include "reference/bake_reference.hpp"
#include "reference/relief_reference.hpp"
#include "report/report_document.hpp"

namespace hfbake {
namespace {

namespace fs = std::filesystem;

bool has(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

Job resolved_job(const nlohmann::json& bake, int size) {
  const nlohmann::json doc = {
      {"version", 1},
      {"name", "table"},
      {"height",
       {{"procedural", {{"kind", "fractal"}, {"size", {size, size}}, {"seed", 2}, {"amplitude", 4}}}}},
      {"bake", bake},
      {"output", {{"dir", fs::temp_directory_path().string()}}}};
  JobLoad load = load_job_document(doc, "table.json", std::nullopt);
  if (!load.job) throw std::runtime_error(load.errors.empty() ? "no job" : load.errors[0]);
  Job job = std::move(*load.job);
  const std::vector<std::string> problems = resolve_job(job);
  if (!problems.empty()) throw std::runtime_error(problems[0]);
  return job;
}

TEST(LayerTable, AToyLayerAddedThroughTheTableReachesEveryReader) {
  // One line: K channels, scored by value against a path-traced reference layer of the same falloff, a
  // fraction of the sky.
  const ExtraLayerKind toy({"toy", false, LayerChannels::per_direction, 0, LayerScore::values,
                            LayerTrace::path_traced, LayerReach::falloff, LayerValues::fraction});
  ASSERT_NE(find_layer_kind("toy"), nullptr);
  EXPECT_EQ(layer_channel_count("toy", 12), 12);

  // The EXR writer: a per-direction layer is compressed as the horizons are.
  LayerSet set;
  set.width = 4;
  set.height = 3;
  set.add("ao", mono_channels());
  EXPECT_EQ(default_exr_compression(set), "zip");
  set.add("toy", indexed_channels(12));
  EXPECT_EQ(default_exr_compression(set), "piz");

  // The output checks: a fraction of the sky may not reach 2.
  check_layers_finite("m", set);
  set.find("toy")->data[7] = 2.0f;
  EXPECT_THROW(check_layers_finite("m", set), std::runtime_error);

  // The memory estimate: an entry that also writes the toy layer holds its K floats a texel.
  const int n = 256;
  Job job = resolved_job({{{"method", "hbao"}, {"directions", 12}, {"radius", 4}}}, n);
  const std::size_t without = estimate_peak_bytes(job, {n, n});
  MethodConfig config = entry_config(job.bakes[0]);
  config.layers.push_back("toy");
  job.bakes[0].config = std::make_shared<const MethodConfig>(config);
  const std::size_t with = estimate_peak_bytes(job, {n, n});
  EXPECT_GE(double(with) - double(without), 4.0 * 12 * n * n);

  // The reference's plan: it traces the toy layer for an entry that writes it, when the entry has the falloff
  // the toy layer's reach needs.
  MethodContext context;
  context.field.width = context.field.height = n;
  EXPECT_TRUE(has(reference_layer_names(0), "toy"));
  EXPECT_TRUE(
      has(read_reference_options(nlohmann::json::object(), {&config}, context, "table.json").layers, "toy"));
  MethodConfig plain = config;
  plain.obscurance.reset();
  EXPECT_FALSE(
      has(read_reference_options(nlohmann::json::object(), {&plain}, context, "table.json").layers, "toy"));

  // The report: scored against the reference's toy layer when the falloffs agree, else not compared.
  LayerSet reference;
  reference.width = reference.height = 4;
  reference.add("toy", indexed_channels(2)).data.assign(32, 0.5f);
  reference.attributes.emplace_back("hfbake:reference_setup", R"({"falloff": "step", "radius": 4})");
  LayerSet method = reference;
  method.attributes.clear();
  method.find("toy")->data.assign(32, 0.25f);
  const ReportOutcome same =
      build_report(ReportSpec{}, {{"m", "hbao", 1.0, {}, &method, entry_reach(config)}}, reference);
  EXPECT_NEAR(same.doc["methods"]["m"]["layers"]["toy"]["mae"].get<double>(), 0.25, 1e-9);
  const ReportOutcome other =
      build_report(ReportSpec{}, {{"m", "hbao", 1.0, {}, &method, entry_reach(plain)}}, reference);
  EXPECT_EQ(other.doc["methods"]["m"]["not_compared"], nlohmann::json::array({"toy"}));
}

TEST(LayerTable, TheTableNamesEveryLayerTheReferenceTraces) {
  for (const std::string& name : reference_layer_names(3)) {
    const LayerKind* kind = find_layer_kind(name);
    ASSERT_NE(kind, nullptr) << name;
    EXPECT_EQ(kind->trace, LayerTrace::path_traced) << name;
  }
  EXPECT_EQ(find_layer_kind("indirect_b0"), nullptr);
  EXPECT_EQ(find_layer_kind("indirect_b"), nullptr);
  EXPECT_EQ(layer_channel_count("indirect_b12", 0), 3);
  EXPECT_EQ(layer_channel_count("horizon_distance", 40), 40);
  EXPECT_EQ(layer_channel_count("sh_visibility", 40), 16);
  EXPECT_TRUE(is_direction_layer("bent_normal"));
  EXPECT_FALSE(is_direction_layer("direct"));
}

// The report judges an entry's radius-limited layers by what its reader made of it: the falloff rule of
// methods/ao/falloff.hpp (step with a radius, none without), the weighting, relief's search.
TEST(LayerTable, AnEntrysReachComesFromItsConfig) {
  const Job job =
      resolved_job({{{"method", "hbao"}, {"directions", 4}, {"radius", 16}},
                    {{"method", "hbao"}, {"directions", 4}},
                    {{"method", "hbao"}, {"directions", 4}, {"radius", 16}, {"weighting", "uniform"}},
                    {{"method", "lsao"}, {"directions", 4}, {"radius", 8}, {"falloff", "smooth"}},
                    {{"method", "p1"}, {"directions", 4}},
                    {{"method", "relief"}, {"directions", 8}, {"search_radius", 10}}},
                   24);
  const EntryReach step = entry_reach(entry_config(job.bakes[0]));
  EXPECT_EQ(step.falloff, "step");
  EXPECT_EQ(step.radius, 16.0);
  EXPECT_TRUE(step.cosine_weighted);
  EXPECT_EQ(entry_reach(entry_config(job.bakes[1])).falloff, "none");
  EXPECT_FALSE(entry_reach(entry_config(job.bakes[2])).cosine_weighted);
  EXPECT_EQ(entry_reach(entry_config(job.bakes[3])).falloff, "smooth");
  EXPECT_EQ(entry_reach(entry_config(job.bakes[4])).falloff, "none");
  EXPECT_TRUE(entry_reach(entry_config(job.bakes[4])).search.is_null());
  EXPECT_EQ(entry_reach(entry_config(job.bakes[5])).search,
            relief_reference_record(ReliefReferenceSettings{8, 10.0, false, GridAxes{}}));
}

}  // namespace
}  // namespace hfbake
