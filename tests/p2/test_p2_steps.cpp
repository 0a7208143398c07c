// p2's defaults on stepped hills the repository does not ship (tests/nlp/stepped_fields.hpp: other riser
// heights and tread widths than the nightly terraces, cliffs and sloped risers) against the Embree
// reference: the indirect light's bias stays inside the band docs/methods/p2.md ("Steps") states. Small
// fields and a 128-sample reference: the bias is of means over ~3000 texels (the reference's noise in them
// is about 0.3 %).
#include <gtest/gtest.h>

#include <cstdio>

#include "p2_test_scenes.hpp"
#include "stepped_fields.hpp"

namespace hfbake {
namespace {

TEST(P2Steps, IndirectBiasOnUnseenSteps) {
  // docs/methods/p2.md "Steps": indirect bias -7.3 % to +4.0 % over the family at 160^2 (K = 16 to 64).
  constexpr double kLow = -0.10, kHigh = 0.06;
  for (const steps::Steps s : {steps::Steps{15, 5, 0}, steps::Steps{6, 12, 0}, steps::Steps{3, 6, 3},
                               steps::Steps{2, 24, 0}, steps::Steps{12, 20, 10}}) {
    SCOPED_TRACE(steps::describe(s));
    const Scene scene = steps::make_steps_scene(64, s);
    const LayerSet ref = steps::reference_of(scene, 128);
    for (const int K : {16, 64}) {
      const steps::Score sc = steps::score(bake_p2_defaults(scene, K), ref, 4);
      std::printf("%s, K = %d: indirect bias %+.2f %%, total rel_mae %.2f %% (reference noise %.2f %%)\n",
                  steps::describe(s).c_str(), K, 100 * sc.indirect_bias, 100 * sc.total_rel_mae,
                  100 * sc.total_noise);
      EXPECT_GT(sc.indirect_bias, kLow) << "K = " << K;
      EXPECT_LT(sc.indirect_bias, kHigh) << "K = " << K;
      // The total is within the reference's noise, with room for the cliffs' facets.
      EXPECT_LT(sc.total_rel_mae, 1.8 * sc.total_noise) << "K = " << K;
    }
  }
}

}  // namespace
}  // namespace hfbake
