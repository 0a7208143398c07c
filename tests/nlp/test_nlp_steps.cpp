// nlp's defaults on stepped hills the repository does not ship (stepped_fields.hpp: other step heights and
// widths than the nightly terraces, cliffs and sloped risers) against the Embree reference: the indirect
// light's bias stays inside the band docs/methods/nlp.md states, and the total's error falls with m on tall
// steps. Small fields and a 128-sample reference: the bias is of means over ~3000 texels (the reference's
// noise in them is about 0.3 %).
#include <gtest/gtest.h>

#include <cstdio>

#include "stepped_fields.hpp"

namespace hfbake {
namespace {

TEST(NlpSteps, IndirectBiasAndTotalErrorOnUnseenSteps) {
  // docs/methods/nlp.md "Steps": indirect bias -9.1 % to +4.8 % over the family at 160^2 (m = 8 to 64).
  constexpr double kLow = -0.10, kHigh = 0.06;
  for (const steps::Steps s : {steps::Steps{20, 4, 0}, steps::Steps{10, 16, 0}, steps::Steps{4, 4, 2},
                               steps::Steps{1, 4, 0}, steps::Steps{20, 16, 8}}) {
    SCOPED_TRACE(steps::describe(s));
    const Scene scene = steps::make_steps_scene(64, s);
    const LayerSet ref = steps::reference_of(scene, 128);
    steps::Score by_m[3];
    const int ms[3] = {8, 32, 64};
    for (int k = 0; k < 3; ++k) {
      by_m[k] = steps::score(steps::bake_nlp_defaults(scene, ms[k]), ref, 4);
      std::printf("%s, m = %d: indirect bias %+.2f %%, total rel_mae %.2f %% (reference noise %.2f %%)\n",
                  steps::describe(s).c_str(), ms[k], 100 * by_m[k].indirect_bias, 100 * by_m[k].total_rel_mae,
                  100 * by_m[k].total_noise);
      EXPECT_GT(by_m[k].indirect_bias, kLow) << "m = " << ms[k];
      EXPECT_LT(by_m[k].indirect_bias, kHigh) << "m = " << ms[k];
    }
    // More azimuths never make the total worse (beyond the reference's noise in the comparison).
    EXPECT_LE(by_m[2].total_rel_mae, by_m[1].total_rel_mae + 0.002);
    EXPECT_LE(by_m[1].total_rel_mae, by_m[0].total_rel_mae + 0.002);
    // On tall cliffs the error falls with m, well above the reference's noise: 4.6 % at m = 8, 2.5 % at 64.
    if (s.height >= 10 && s.ramp == 0) {
      EXPECT_LT(by_m[2].total_rel_mae, 0.8 * by_m[0].total_rel_mae);
    }
  }
}

}  // namespace
}  // namespace hfbake
