// The CLI entry of method "p1" (see p1.hpp for what it computes).
#pragma once

#include "core/layers.hpp"
#include "core/run_control.hpp"
#include "field/scene.hpp"
#include "methods/method_table.hpp"

namespace hfbake {

// Layers: ao, vsky, direct (default), horizon, horizon_distance, bent_normal (on request via "layers").
LayerSet bake_p1(const Scene& scene, const MethodConfig& config, const RunControl& rc);

// p1's line of the method table.
MethodInfo p1_method();

}  // namespace hfbake
