// Between a loaded job and the method table: the checks every method and the reference run before any
// bake starts (validate runs the same), and the dispatch of a bake entry to its method.
#pragma once

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

// Reads every bake entry's parameters and the reference's with their full checks, filling
// BakeEntry::resolved and Job::reference_resolved. Returns every problem as one line
// "<file>: <JSON pointer>: <what>" (empty: the job is good to bake).
std::vector<std::string> resolve_job(Job& job);

LayerSet run_method(const BakeEntry& entry, const Scene& scene, const RunControl& rc);

// The reference's options for a loaded scene (the same reader resolve_job ran).
ReferenceOptions job_reference_options(const Job& job, const Scene& scene);

}  // namespace hfbake
