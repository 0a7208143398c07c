// p1_working_bytes on repeat fields too large for the lane search's tiling (lane_horizons.hpp, lane_tiles)
// against the bytes compute_p1 holds there, counted here from its design: the strip search sums one direction
// block (core/direction_blocks.hpp: min(K, 8) blocks, the largest of ceil(K / blocks) directions) at a time,
// each through its own sweep whose line buffers hold FarHorizonWorker's two floats ([dz, run]) for every
// texel and direction of the block; the block's sums (4 bytes a texel for ao, 12 for bent_normal) lie beside
// the total, which is the layers; with horizon layers, the block's horizon planes (4 bytes a texel per
// direction of the block) wait to be placed. What is left is per-thread scratch (the lines' workers, a tile's
// gather), bounded here by 5 MiB a thread (lines of up to twice 4800 samples).
#include <gtest/gtest.h>

#include <algorithm>

#include "core/threads.hpp"
#include "field/triangulation.hpp"
#include "methods/p1/lane_horizons.hpp"
#include "methods/p1/p1.hpp"

namespace hfbake {
namespace {

TEST(P1WorkingBytes, RepeatFieldsHoldOneDirectionBlocksStripsAndSums) {
  struct Shape {
    int width, height;
  };
  const double per_thread = 5.0 * (1 << 20);
  const double slack = per_thread * double(worker_threads()) + double(1 << 20);
  for (const Shape s : {Shape{4800, 800}, Shape{800, 4800}, Shape{4700, 600}})
    for (const int K : {1, 4, 8, 12, 16, 24, 64})
      for (const int layers : {0, 1, 2}) {  // ao; ao and bent_normal; ao and horizon
        FieldShape shape;
        shape.width = s.width, shape.height = s.height;
        shape.wrap = Wrap::repeat;
        ASSERT_FALSE(p1::lane_tiles(s.width, s.height, shape.wrap, 1)) << s.width << "x" << s.height;
        P1Params p;
        p.directions = K;
        p.ao = true;
        p.vsky = p.direct = false;
        p.bent_normal = layers == 1;
        p.horizon = layers == 2;
        const double N = double(s.width) * double(s.height);
        const int blocks = std::min(K, 8), largest = (K + blocks - 1) / blocks;
        const double sums = 4.0 + (p.bent_normal ? 12.0 : 0.0);
        const double expected =
            (blocks > 1 ? sums : 0.0) * N + 2.0 * 4.0 * largest * N + (p.horizon ? 4.0 * largest * N : 0.0);
        const double got = p1_working_bytes(shape, p, /*uniform_environment=*/true);
        EXPECT_GE(got, expected) << s.width << "x" << s.height << " K " << K << " layers " << layers;
        EXPECT_LE(got, expected + slack) << s.width << "x" << s.height << " K " << K << " layers " << layers;
      }
}

// P2's corner facets (direct_facets, field/triangulation.hpp) are no layer a caller counts: while the
// directions are summed (the peak), each facet's RGB float sum is held in the total and in the block's sums
// and, for the lane search (clamp fields, and repeat ones whose tiling it takes), each facet's normal (12
// bytes): 3 x 12 bytes a texel and facet there, 2 x 12 on repeat fields the strip search takes, beside
// what direct alone holds.
TEST(P1WorkingBytes, P2sCornerFacetsAreHeldBesideTheLayers) {
  struct Case {
    Wrap wrap;
    int width, height;
  };
  for (const Case c :
       {Case{Wrap::clamp, 1024, 768}, Case{Wrap::repeat, 1024, 768}, Case{Wrap::repeat, 8192, 3072}}) {
    const Wrap wrap = c.wrap;
    FieldShape shape;
    shape.width = c.width, shape.height = c.height;
    shape.wrap = wrap;
    const bool lanes = p1::lane_tiles(c.width, c.height, wrap, 1);
    EXPECT_EQ(lanes, c.width == 1024) << c.width;
    P1Params p;
    p.directions = 16;
    p.ao = p.vsky = false;
    p.direct = true;
    p.lights = false;
    P1Params facets = p;
    facets.facet_direct = true;
    const double N = double(c.width) * double(c.height);
    const double held = (lanes ? 3 : 2) * 12.0 * kCornerFacets * N;
    EXPECT_DOUBLE_EQ(p1_working_bytes(shape, facets, false) - p1_working_bytes(shape, p, false), held)
        << (wrap == Wrap::clamp ? "clamp " : "repeat ") << c.width;
  }
}

}  // namespace
}  // namespace hfbake
