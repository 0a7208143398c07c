// Maps a bake entry's "method" onto the method's entry point.
#pragma once

#include "core/layers.hpp"
#include "core/run_control.hpp"
#include "field/scene.hpp"
#include "job/manifest.hpp"

namespace hfbake {

LayerSet run_method(const BakeEntry& entry, const Scene& scene, const RunControl& rc);
LayerSet run_reference(const Job& job, const Scene& scene, const RunControl& rc);

}  // namespace hfbake
