// Measurement (not a test): nlp's defaults on stepped hills (stepped_fields.hpp) against the Embree
// reference, by m: the indirect bias and the total's rel_mae, with the reference's own noise beside them.
// The table of docs/methods/nlp.md ("Steps").
//   measure_nlp_steps [size=128] [samples=512]
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "stepped_fields.hpp"

using namespace hfbake;

int main(int argc, char** argv) {
  const int size = argc > 1 ? std::atoi(argv[1]) : 128;
  const int samples = argc > 2 ? std::atoi(argv[2]) : 512;
  const int ms[] = {8, 16, 32, 64};
  std::printf(
      "| height | width | ramp | indirect / total | indirect bias %% m = 8, 16, 32, 64 | total rel_mae %% "
      "m = 8, 16, 32, 64 | reference noise %% |\n|---|---|---|---|---|---|---|\n");
  for (double h : {1.0, 4.0, 10.0, 20.0})
    for (double w : {4.0, 16.0, 64.0})
      for (double ramp : {0.0, 0.5}) {
        const steps::Steps s{h, w, ramp * w};
        const Scene scene = steps::make_steps_scene(size, s);
        const LayerSet ref = steps::reference_of(scene, samples);
        std::vector<steps::Score> sc;
        for (int m : ms) sc.push_back(steps::score(steps::bake_nlp_defaults(scene, m), ref, 4));
        std::printf("| %g | %g | %g | %.3f | %+.1f, %+.1f, %+.1f, %+.1f | %.2f, %.2f, %.2f, %.2f | %.2f |\n",
                    h, w, s.ramp, sc[0].indirect_share, 100 * sc[0].indirect_bias, 100 * sc[1].indirect_bias,
                    100 * sc[2].indirect_bias, 100 * sc[3].indirect_bias, 100 * sc[0].total_rel_mae,
                    100 * sc[1].total_rel_mae, 100 * sc[2].total_rel_mae, 100 * sc[3].total_rel_mae,
                    100 * sc[0].total_noise);
        std::fflush(stdout);
      }
  return 0;
}
