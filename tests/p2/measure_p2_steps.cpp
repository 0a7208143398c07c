// Measurement (not a test): p2's defaults on stepped hills (tests/nlp/stepped_fields.hpp: concentric
// circular terraces of other riser heights, tread widths and ramps) against the Embree reference under a
// uniform sky, one bounce: the indirect bias and the total's rel_mae by K, with the reference's own noise
// beside them. The table of docs/methods/p2.md ("Steps").
//   measure_p2_steps [size=128] [samples=512]
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "p2_test_scenes.hpp"
#include "stepped_fields.hpp"

using namespace hfbake;

int main(int argc, char** argv) {
  const int size = argc > 1 ? std::atoi(argv[1]) : 128;
  const int samples = argc > 2 ? std::atoi(argv[2]) : 512;
  const int ks[] = {16, 32, 64};
  std::printf(
      "| height | width | ramp | indirect / total | indirect bias %% K = 16, 32, 64 | total rel_mae %% K = "
      "16, "
      "32, 64 | reference noise %% |\n|---|---|---|---|---|---|---|\n");
  for (double h : {1.0, 4.0, 10.0, 20.0})
    for (double w : {4.0, 16.0, 64.0})
      for (double ramp : {0.0, 0.5}) {
        const steps::Steps s{h, w, ramp * w};
        const Scene scene = steps::make_steps_scene(size, s);
        const LayerSet ref = steps::reference_of(scene, samples);
        std::vector<steps::Score> sc;
        for (int K : ks) sc.push_back(steps::score(bake_p2_defaults(scene, K), ref, 4));
        std::printf("| %g | %g | %g | %.3f | %+.1f, %+.1f, %+.1f | %.2f, %.2f, %.2f | %.2f |\n", h, w, s.ramp,
                    sc[0].indirect_share, 100 * sc[0].indirect_bias, 100 * sc[1].indirect_bias,
                    100 * sc[2].indirect_bias, 100 * sc[0].total_rel_mae, 100 * sc[1].total_rel_mae,
                    100 * sc[2].total_rel_mae, 100 * sc[0].total_noise);
        std::fflush(stdout);
      }
  return 0;
}
