// The method table: one entry per bake method, the one place that says what a method is, what it reads,
// what it writes, what it costs and how its work divides. Dispatch (cli), validate, the memory estimate,
// the reference's choice of quantities and the report all read it.
//
// Adding a method: a folder under baker/methods/ with its CMakeLists.txt (a library hfbake_<folder>), a
// function returning its MethodInfo, one line in method_table.cpp, and schemas/methods/<name>.schema.json.
#pragma once

#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/layers.hpp"
#include "core/run_control.hpp"
#include "field/scene.hpp"
#include "job/params.hpp"

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
  int bounces = 0;  // the job's
};

struct MethodInfo {
  const char* name = "";
  const char* summary = "";  // one line
  // Reads and checks every parameter of a bake entry (every method-level rule: validate runs it), leaving
  // the resolved parameters, "layers" included, in the reader. Throws InputError naming file and pointer.
  void (*read)(Params& params, const MethodContext& context) = nullptr;
  // Bakes the entry as written (the method reads it again with its own reader).
  LayerSet (*bake)(const Scene& scene, const nlohmann::json& params, const RunControl& rc) = nullptr;
  // Bytes held at the method's peak besides its output layers (4 bytes per texel and channel), from the
  // resolved parameters and the field's shape: its per-texel arrays and its sweeps' line buffers. What
  // the memory estimate adds for it (cli/scene_loader.hpp); docs/large-fields.md says how close it is.
  double (*working_bytes)(const nlohmann::json& resolved, const MethodContext& context) = nullptr;
  // What a user lowers to make the method fit a memory budget, for the refusal message ("its directions
  // (...)").
  const char* memory_knob = "a smaller field";
  WorkDivision division = WorkDivision::directions;
  const char* division_note = "";  // how, and why not otherwise
  // The farm (baker/farm) for a method that divides by directions: bake_block gives the raw sums of
  // direction block `block` (core/direction_blocks.hpp, of the entry's K) as float layers; the merge adds
  // same-named layers in block order (the first block's taken as they are; a name containing '@' is never
  // added, only kept) and finish_blocks turns them into what `bake` returns -- bit-identical to it, because
  // bake sums the same blocks the same way. Null: the method runs whole (in shard 0).
  LayerSet (*bake_block)(const Scene& scene, const nlohmann::json& params, int block,
                         const RunControl& rc) = nullptr;
  LayerSet (*finish_blocks)(const Scene& scene, const nlohmann::json& params, LayerSet&& sums,
                            const RunControl& rc) = nullptr;
  // The farm for a method whose work runs in successive stages, each needing the previous one's result of
  // the whole field (p2: stage 0 its direct light, stage b its bounce b): stages(resolved) says how many;
  // bake_stage computes stage `stage` from the previous stage's state (empty for stage 0) and returns the
  // state after it, as float layers (the shard file's); finish_stages turns the last state into what `bake`
  // returns -- bit-identical to it, because bake runs the same stages in order. Null: not staged.
  int (*stages)(const nlohmann::json& resolved) = nullptr;
  LayerSet (*bake_stage)(const Scene& scene, const nlohmann::json& params, int stage, LayerSet&& previous,
                         const RunControl& rc) = nullptr;
  LayerSet (*finish_stages)(const Scene& scene, const nlohmann::json& params, LayerSet&& last,
                            const RunControl& rc) = nullptr;
  // A stage divided by direction blocks (every stage of p2; core/direction_blocks.hpp of the entry's K):
  // stage_blocks(resolved, stage) says how many (0: the stage runs whole through bake_stage);
  // bake_stage_block gives block `block`'s raw sums from the state before the stage (the previous stage's,
  // whole) as float layers, added by the farm like bake_block's (farm/merge_blocks.cpp add_direction_block);
  // finish_stage_blocks turns the state before the stage and the blocks' total into the state after it:
  // what bake_stage returns, bit-identical, because bake sums the same blocks the same way.
  int (*stage_blocks)(const nlohmann::json& resolved, int stage) = nullptr;
  LayerSet (*bake_stage_block)(const Scene& scene, const nlohmann::json& params, int stage, int block,
                               LayerSet&& previous, const RunControl& rc) = nullptr;
  LayerSet (*finish_stage_blocks)(const Scene& scene, const nlohmann::json& params, int stage,
                                  LayerSet&& previous, LayerSet&& sums, const RunControl& rc) = nullptr;
  // What the method reads from the Scene besides the heights and the lighting. The job loader builds
  // Scene::normals (12 bytes per texel) and Scene::surface.albedo (12 bytes per texel from an image, a
  // constant held once) only when a method of the job or the reference reads them; a method that does not
  // must not touch them (they may be empty).
  bool reads_normals = true;
  bool reads_albedo = true;
  // Obscurance family: its falloff and radius define the quantity the reference's "obscurance" estimates.
  bool falloff_defines_obscurance = false;
};

// Every method, in the order docs/methods/README.md lists them.
std::span<const MethodInfo> method_table();
// nullptr when no method has that name.
const MethodInfo* find_method(std::string_view name);
// "p1", "p2", ... for messages.
std::vector<std::string> method_names();

// The resolved parameters of one bake entry (method included), after every check. Throws InputError with
// `file` and `pointer` (e.g. "/bake/2") for an unknown method or a parameter it refuses.
nlohmann::json resolve_method_params(const nlohmann::json& entry, const MethodContext& context,
                                     const std::string& file, const std::string& pointer);

// Channels an output layer has (horizon and horizon_distance: one per direction; sh_*: 16 per colour).
int layer_channel_count(const std::string& layer, const nlohmann::json& resolved);

}  // namespace hfbake
