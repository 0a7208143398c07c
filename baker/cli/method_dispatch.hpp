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

// True when `file` (existing or not) is a name a bake of `job` writes in its output folder, so that writing
// or keeping anything else there would lose it: <name>.<stem>.exr, <name>.<stem>.*.preview.png,
// <name>.<stem>.*.tif, report.json, report.html, textures/<name>.*, a tile task's tiles/<name>+tile-*, and
// the job's locks and owner records (in the folder, in textures/ and in tiles/) and the report lock
// (docs/output_folders.md). Links are resolved first.
bool writes_in_output_folder(const Job& job, const std::filesystem::path& file);

// A resolved entry's config (std::logic_error before resolve_job).
const MethodConfig& entry_config(const BakeEntry& entry);
// Bakes a resolved entry from its config.
LayerSet run_method(const BakeEntry& entry, const Scene& scene, const RunControl& rc);

// The reference's options resolve_job read (std::logic_error before it, or without a reference).
const ReferenceOptions& job_reference_options(const Job& job);

}  // namespace hfbake
