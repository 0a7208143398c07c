#!/usr/bin/python3
"""p1's far field against its exact search on one DEM: whole-process CPU time and the errors of ao, vsky and
the horizons, beside the bound each far-field bake certifies (docs/methods/p1.md, Far field).

    /usr/bin/python3 bench/p1_far_field.py [--dem ../shared/data/TM1_564_146.tif] [--directions 64]
        [--far 100:8,200:8,400:16] [--reps 3] [--threads 2] [--out FILE.md]

--far lists D:C pairs (D: the far field's beyond, C: its cell, both in texels). Each repetition bakes the
exact job, then each far-field job, as whole processes timed by /usr/bin/time; a far field's cost is the
median over repetitions of its CPU seconds (user + sys) over the exact bake's in the same repetition. The
errors compare the far field's GeoTIFFs with the exact bake's texel by texel (ao, vsky) and texel-direction
by texel-direction (horizon: the sine of the elevation). Without --dem's file, a 2048^2 fractal GeoTIFF
(1 m texels) is written and used. Prints the Markdown table and writes it to --out. Needs Debian's
python3-numpy and python3-gdal.
"""
import argparse
import math
import os
import statistics
import sys
import tempfile

import numpy as np
from osgeo import gdal

gdal.UseExceptions()

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
from relief_far_field import (add_common_args, bands, dem_or_fractal, far_field_jobs, finish,  # noqa: E402
                              time_runs)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common_args(ap, 64, "100:8,200:8,400:16")
    a = ap.parse_args()

    work = tempfile.mkdtemp(prefix="hfbake_p1_far_field_")
    dem, texel = dem_or_fractal(a.dem, work, 2048)
    def entry(far):
        e = {"method": "p1", "directions": a.directions, "layers": ["ao", "vsky", "horizon"]}
        if far:
            e["far_field"] = {"beyond": far[0] * texel, "cell": far[1]}
        return e

    runs, jobs = far_field_jobs(dem, work, a.far, entry)
    cpu = {name: [t[0] for t in ts] for name, ts in time_runs(a.hfbake, runs, jobs, a.reps, a.threads).items()}

    def layer(name, what):
        return bands(os.path.join(work, name, "%s.p1.%s.tif" % (name, what)))

    ao_e, _ = layer("exact", "ao")
    vs_e, _ = layer("exact", "vsky")
    hz_e, _ = layer("exact", "horizon")
    rows = ["| run | CPU s (median) | run / exact (median of pairs) | ao error max / mean | vsky error max / mean "
            "| horizon error (sin) max / mean / share raised | certified bound: tan / deg |",
            "|---|---|---|---|---|---|---|"]
    for name, far in runs:
        med = statistics.median(cpu[name])
        if far is None:
            rows.append("| exact search | %.1f | 1 | — | — | — | — |" % med)
            continue
        ratio = statistics.median(r / e for e, r in zip(cpu["exact"], cpu[name]))
        ao, meta = layer(name, "ao")
        vs, _ = layer(name, "vsky")
        hz, _ = layer(name, "horizon")
        da, dv, dh = np.abs(ao - ao_e), np.abs(vs - vs_e), hz - hz_e
        bound = float(meta["HFBAKE_P1_FAR_FIELD_BOUND"])
        rows.append("| D = %d, C = %d | %.1f | %.2f | %.4f / %.5f | %.4f / %.5f | %.4f / %.5f / %.1f %% | %.3f / %.2f |"
                    % (far[0], far[1], med, ratio, da.max(), da.mean(), dv.max(), dv.mean(), dh.max(),
                       np.abs(dh).mean(), 100.0 * np.mean(dh > 1e-5), bound, math.degrees(math.atan(bound))))
    finish("%s: %dx%d, K = %d, %d repetitions, --threads %d" % (
        os.path.basename(dem), ao_e.shape[1], ao_e.shape[0], a.directions, a.reps, a.threads), rows, a.out, work)


if __name__ == "__main__":
    main()
