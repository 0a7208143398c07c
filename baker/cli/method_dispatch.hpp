// Between a loaded job and the method table: the checks every method and the reference run before any
// bake starts (validate runs the same), and the dispatch of a bake entry to its method.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/layers.hpp"
#include "core/run_control.hpp"
#include "field/scene.hpp"
#include "job/manifest.hpp"
#include "methods/method_table.hpp"
#include "reference/bake_reference.hpp"

namespace hfbake {

// What a method's reader may know of a job before its heights are loaded: the field's shape (probed from
// the procedural spec or the image header) and the job's bounces.
MethodContext job_method_context(const Job& job);

// Reads every bake entry's parameters and the reference's with their full checks, once: each entry's
// method reader fills BakeEntry::config, the reference's reader (given those configs) Job::reference_options.
// Returns every problem as one line "<file>: <JSON pointer>: <what>" (empty: the job is good to bake).
std::vector<std::string> resolve_job(Job& job);

// Which names writes_in_output_folder counts. `kept`: every name hfbake keeps for the job in its output
// folder, whatever the job's output options (what an input or a summary must never be). `moved`: the names a
// bake of the job as it stands moves an output or owner record to (what a folder must not take: rename(2)
// cannot replace it), needing the resolved job (resolve_job's layers, plan_textures).
enum class OutputNames { kept, moved };

// True when `file` (existing or not) is a name a bake of `job` writes in its output folder, so that writing
// or keeping anything else there would lose it: <name>.<stem>.exr, <name>.<stem>.*.preview.png,
// <name>.<stem>.*.tif, report.json, report.html, textures/<name>.*, a tile task's tiles/<name>+tile-*, a
// shard task's shards/<name>.*.hfshard, and the job's locks and owner records (in the folder, in textures/,
// tiles/ and shards/) and the report lock
// (docs/output_folders.md). Links are resolved first. With OutputNames::moved, only the files the bake moves
// into place: previews, GeoTIFFs, textures and the report as the job asks for them, the owner records, no
// lock.
bool writes_in_output_folder(const Job& job, const std::filesystem::path& file,
                             OutputNames names = OutputNames::kept);

// A resolved entry's config (std::logic_error before resolve_job).
const MethodConfig& entry_config(const BakeEntry& entry);
// Bakes a resolved entry from its config.
LayerSet run_method(const BakeEntry& entry, const Scene& scene, const RunControl& rc);

// The reference's options resolve_job read (std::logic_error before it, or without a reference).
const ReferenceOptions& job_reference_options(const Job& job);

}  // namespace hfbake
