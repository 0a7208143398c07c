// The method table: one entry per bake method, the one place that says what a method is, what it reads,
// what it writes, what it costs and how its work divides. Dispatch (cli), validate, the memory estimate,
// the reference's choice of quantities and the report all read it.
//
// Adding a method: a folder under baker/methods/ with its CMakeLists.txt (a library hfbake_<folder>), its
// typed config and a reader returning it, a function returning its MethodInfo, one line in
// method_table.cpp, and schemas/methods/<name>.schema.json.
#pragma once

#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <typeinfo>
#include <vector>

#include "core/layers.hpp"
#include "core/run_control.hpp"
#include "field/scene.hpp"
#include "job/params.hpp"
#include "methods/ao/falloff.hpp"

namespace hfbake {

// How a method's work can be split across machines (the farm issue builds on it).
enum class WorkDivision {
  directions,      // partial sums over disjoint sets of azimuths, merged by adding in a fixed order
  bounce_stages,   // by directions within a bounce; each bounce a stage needing the previous one whole
  texel_tiles,     // texel tiles with a halo of the method's reach
  receiver_tiles,  // receiver tiles, each against the whole field's geometry (the reference)
};

// What a method's parameter reader may know before the heights are loaded.
struct MethodContext {
  FieldShape field;
  bool curvature = false;           // the job's Earth curvature is on (Scene::curvature > 0)
  int bounces = 0;                  // the job's
  bool uniform_environment = true;  // no sky, latlong, cubemap or cross (io/load_environment.cpp)
  double environment_bytes = 0;     // the world lat-long a copy of the scene holds (EnvironmentBytes::world)
  bool placed = false;  // a CRS places the field on the Earth (Georeference::has_site: a site and north)
};
// Whether a job document's environment is uniform (the rule of io/load_environment.cpp).
inline bool job_environment_uniform(const nlohmann::json& doc) {
  if (!doc.contains("environment") || !doc["environment"].is_object()) return true;
  for (const char* key : {"sky", "latlong", "cubemap", "cross"})
    if (doc["environment"].contains(key)) return false;
  return true;
}

struct MethodInfo;

// One bake entry's parameters, read once by its method's reader (resolve_method) and kept for the whole
// bake (BakeEntry::config): the method's own typed config, handed to every entry point of its MethodInfo,
// and what the rest of hfbake asks of any entry (its layers, its directions, its obscurance falloff).
struct MethodConfig {
  const MethodInfo* method = nullptr;
  std::vector<std::string> layers;  // what it writes, in the job's order
  int directions = 0;               // K: its per-direction layers' channels and its direction blocks; 0: none
  // The falloff and radius the entry writes (an obscurance-family entry with "falloff" or "radius"): what
  // the reference's obscurance estimates when the reference gives none of its own.
  std::optional<Falloff> obscurance;
  // How its obscurance weights directions: by the cosine (docs/contract.md) or uniformly (HBAO's).
  bool cosine_weighted = true;
  // Every value the reader read, defaults included, "method" and "layers" too: the record written to the
  // EXR metadata and report.json (never read back).
  nlohmann::json resolved;

  // Whether the config is a C (the config type of one method).
  template <class C>
  bool holds() const {
    return type_ != nullptr && *type_ == typeid(C);
  }
  // The method's config as its reader made it (C must be that type).
  template <class C>
  const C& get() const {
    if (!holds<C>()) throw std::logic_error("MethodConfig::get: not the type of this entry's config");
    return *static_cast<const C*>(value_.get());
  }
  template <class C>
  void set(C config) {
    value_ = std::make_shared<const C>(std::move(config));
    type_ = &typeid(C);
  }

 private:
  std::shared_ptr<const void> value_;
  const std::type_info* type_ = nullptr;
};

// A reader's result: `config` as the entry's typed value, with its directions.
template <class C>
MethodConfig method_config(C config, int directions = 0) {
  MethodConfig c;
  c.set(std::move(config));
  c.directions = directions;
  return c;
}

struct MethodInfo {
  const char* name = "";
  const char* summary = "";  // one line
  // Reads and checks every parameter of a bake entry (every method-level rule: validate runs it) through
  // `params` (layers through Params::layers), once, and returns the typed config (method_config) with its
  // directions and, for the obscurance family, the falloff it writes. Throws InputError naming file and
  // pointer.
  MethodConfig (*read)(Params& params, const MethodContext& context) = nullptr;
  // Bakes the entry from its config.
  LayerSet (*bake)(const Scene& scene, const MethodConfig& config, const RunControl& rc) = nullptr;
  // Bytes held at the method's peak besides its output layers (4 bytes per texel and channel), from the
  // config and the field's shape: its per-texel arrays and its sweeps' line buffers. What the memory
  // estimate adds for it (cli/scene_loader.hpp); docs/large-fields.md says how close it is.
  double (*working_bytes)(const MethodConfig& config, const MethodContext& context) = nullptr;
  // What a user lowers to make the method fit a memory budget, for the refusal message ("its directions
  // (...)").
  const char* memory_knob = "a smaller field";
  WorkDivision division = WorkDivision::directions;
  // How far from a texel, in world units, the bake reads heights (a march's length, a search radius): a
  // tile whose halo covers it bakes the whole bake's texels (farm/tile_plan.hpp, cli/tile_command.hpp).
  // Null: unbounded (the whole field), so the method is not baked in tiles.
  double (*reach)(const MethodConfig& config) = nullptr;
  // The cell side, in texels, of the coarse copy of the whole field (field/coarse_heights.hpp) the bake
  // walks beyond its reach (relief's far field); 0 or null: none. A tiled bake builds that copy once from
  // the whole raster and hands it to every tile (Scene::window).
  int (*far_cell)(const MethodConfig& config) = nullptr;
  const char* division_note = "";  // how, and why not otherwise
  // The farm (baker/farm) for a method that divides by directions: bake_block gives the raw sums of
  // direction block `block` (core/direction_blocks.hpp, of the config's directions) as float layers; the
  // merge adds same-named layers in block order (the first block's taken as they are; a name containing
  // '@' is never added, only kept) and finish_blocks turns them into what `bake` returns -- bit-identical
  // to it, because bake sums the same blocks the same way. Null: the method runs whole (in shard 0).
  LayerSet (*bake_block)(const Scene& scene, const MethodConfig& config, int block,
                         const RunControl& rc) = nullptr;
  LayerSet (*finish_blocks)(const Scene& scene, const MethodConfig& config, LayerSet&& sums,
                            const RunControl& rc) = nullptr;
  // The farm for a method whose work runs in successive stages, each needing the previous one's result of
  // the whole field (p2: stage 0 its direct light, stage b its bounce b): stages(config) says how many;
  // bake_stage computes stage `stage` from the previous stage's state (empty for stage 0) and returns the
  // state after it, as float layers (the shard file's); finish_stages turns the last state into what `bake`
  // returns -- bit-identical to it, because bake runs the same stages in order. Null: not staged.
  int (*stages)(const MethodConfig& config) = nullptr;
  LayerSet (*bake_stage)(const Scene& scene, const MethodConfig& config, int stage, LayerSet&& previous,
                         const RunControl& rc) = nullptr;
  LayerSet (*finish_stages)(const Scene& scene, const MethodConfig& config, LayerSet&& last,
                            const RunControl& rc) = nullptr;
  // A stage divided by direction blocks (every stage of p2; core/direction_blocks.hpp of the config's
  // directions): stage_blocks(config, stage) says how many (0: the stage runs whole through bake_stage);
  // bake_stage_block gives block `block`'s raw sums from the state before the stage (the previous stage's,
  // whole) as float layers, added by the farm like bake_block's (farm/merge_blocks.cpp add_direction_block);
  // finish_stage_blocks turns the state before the stage and the blocks' total into the state after it:
  // what bake_stage returns, bit-identical, because bake sums the same blocks the same way.
  int (*stage_blocks)(const MethodConfig& config, int stage) = nullptr;
  LayerSet (*bake_stage_block)(const Scene& scene, const MethodConfig& config, int stage, int block,
                               LayerSet&& previous, const RunControl& rc) = nullptr;
  LayerSet (*finish_stage_blocks)(const Scene& scene, const MethodConfig& config, int stage,
                                  LayerSet&& previous, LayerSet&& sums, const RunControl& rc) = nullptr;
  // What the method reads from the Scene besides the heights and the lighting. The job loader builds
  // Scene::normals (12 bytes per texel) and Scene::surface.albedo (12 bytes per texel from an image, a
  // constant held once) only when a method of the job or the reference reads them; a method that does not
  // must not touch them (they may be empty).
  bool reads_normals = true;
  bool reads_albedo = true;
  // Whether the method bakes rectangular texels (FieldShape::dx() != dy(): a geographic raster in its
  // local frame) and lowers its casters by the Earth's curvature (Scene::curvature). resolve_method refuses
  // an entry of a method without them on such a field, or with curvature on.
  bool rectangular_texels = false;
  bool applies_curvature = false;
};

// Every method, in the order docs/methods/README.md lists them.
std::span<const MethodInfo> method_table();
// nullptr when no method has that name.
const MethodInfo* find_method(std::string_view name);
// "p1", "p2", ... for messages.
std::vector<std::string> method_names();

// Runs the reader of the entry's method once, after every check: the entry's config. Throws InputError with
// `file` and `pointer` (e.g. "/bake/2") for an unknown method or a parameter it refuses.
MethodConfig resolve_method(const nlohmann::json& entry, const MethodContext& context,
                            const std::string& file, const std::string& pointer);
// The same for method `name` from a bare parameter object (code and tests that hold one; "method" may be
// absent), and its bake with the scene's shape and bounces as the context.
MethodConfig read_method_config(std::string_view name, const nlohmann::json& params,
                                const MethodContext& context);
LayerSet bake_method(std::string_view name, const Scene& scene, const nlohmann::json& params,
                     const RunControl& rc);
// The context a loaded scene gives a reader: its shape and bounces.
MethodContext scene_method_context(const Scene& scene);

}  // namespace hfbake
