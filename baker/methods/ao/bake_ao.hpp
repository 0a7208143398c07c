// Entry points of the obscurance family (docs/methods/obscurance.md). Each returns a LayerSet of the field's
// size with the layer names of docs/contract.md ("obscurance", "ao", "bent_normal", ...) from the entry's
// config, as its reader made it (schemas/methods/<method>.schema.json). Their lines of the method table
// (methods/method_table.hpp) below.
#pragma once

#include "core/layers.hpp"
#include "core/run_control.hpp"
#include "field/scene.hpp"
#include "methods/method_table.hpp"

namespace hfbake {

// Brute-force horizon march: K directions x M steps, the exact slab integral of rho between successive
// horizon maxima (cosine or uniform weighting); the truth LSAO is tested against. hbao.cpp
LayerSet bake_hbao(const Scene& scene, const MethodConfig& config, const RunControl& rc);
// Line-sweep ambient obscurance (P3). lsao.cpp
LayerSet bake_lsao(const Scene& scene, const MethodConfig& config, const RunControl& rc);
// Screen-space far-field ambient obscurance mapped to height fields (P4). farfield.cpp
LayerSet bake_farfield(const Scene& scene, const MethodConfig& config, const RunControl& rc);
// Horizon-split ambient occlusion (Dimitrov et al. 2008). hsao.cpp
LayerSet bake_hsao(const Scene& scene, const MethodConfig& config, const RunControl& rc);
// Adaptively layered statistical volumetric obscurance (Hendrickx 2015). vo.cpp
LayerSet bake_vo(const Scene& scene, const MethodConfig& config, const RunControl& rc);

// Their lines of the method table.
MethodInfo hbao_method();
MethodInfo lsao_method();
MethodInfo farfield_method();
MethodInfo hsao_method();
MethodInfo vo_method();

}  // namespace hfbake
