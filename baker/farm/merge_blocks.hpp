// How the merge (and nothing else) combines what shards computed.
#pragma once

#include <vector>

#include "core/layers.hpp"

namespace hfbake {

// Adds a direction block's raw sums into `total`, in block order: the first block is taken as it is
// (`total` empty), later blocks add each layer elementwise in float into the layer of the same name (the
// order MethodInfo::bake does it in, so the bits agree); a layer named "<name>#2f" holds doubles as (hi, lo)
// float pairs and adds them by add_split (core/direction_blocks.hpp); layers whose name contains '@'
// (per-block data such as p1's horizons) are never added, only kept. Attributes: the first block's, and
// those of later blocks under names not yet present (per-block ones such as p2's "<count>@<b>").
void add_direction_block(LayerSet& total, LayerSet&& block);

// Stacks row bands (in order, covering the field's rows) into one LayerSet of `height` rows.
LayerSet stack_row_bands(std::vector<LayerSet>&& bands, int height);

}  // namespace hfbake
