#!/usr/bin/python3
"""relief's far field against its exact march on one DEM: whole-process CPU time and the error of svf and of
the horizon angle, beside the bound each far-field bake certifies (docs/gis.md, Far field).

    /usr/bin/python3 bench/relief_far_field.py [--dem ../shared/data/TM1_564_146.tif] [--radius 2000]
        [--directions 16] [--far 100:8,200:8,100:16,200:16] [--reps 3] [--threads 2] [--out FILE.md]

--radius and the far fields' beyond (D) are in texels; --far lists D:C pairs (C: the cell in texels). Each
repetition bakes the exact job, then each far-field job, as whole processes timed by /usr/bin/time, so a
drift of the machine's speed reaches all of them; a far field's speed-up is the median over repetitions of
the exact bake's CPU seconds (user + sys) over its own in the same repetition. The errors compare the far
field's GeoTIFFs with the exact bake's, texel by texel (svf) and texel-direction by texel-direction
(horizon_deg). Without --dem's file, a 4096^2 fractal GeoTIFF (1 m texels) is written and used. Prints the
Markdown table and writes it to --out. Needs Debian's python3-numpy and python3-gdal.
"""
import argparse
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile

import numpy as np
from osgeo import gdal, osr

from peers import has_holes

gdal.UseExceptions()

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def fractal(path, size=4096, seed=3):
    """fBm by spectral synthesis (beta = 2.4), 1 m texels, 200 m of relief, in a projected CRS."""
    rng = np.random.default_rng(seed)
    kx = np.fft.fftfreq(size)[None, :]
    ky = np.fft.fftfreq(size)[:, None]
    k = np.hypot(kx, ky)
    k[0, 0] = 1
    spectrum = (rng.normal(size=(size, size)) + 1j * rng.normal(size=(size, size))) * k ** -1.2
    spectrum[0, 0] = 0
    z = np.real(np.fft.ifft2(spectrum))
    z = (z - z.min()) / (z.max() - z.min()) * 200
    ds = gdal.GetDriverByName("GTiff").Create(path, size, size, 1, gdal.GDT_Float32)
    ds.SetGeoTransform([500000, 1, 0, 5000000, 0, -1])
    srs = osr.SpatialReference()
    srs.ImportFromEPSG(32633)
    ds.SetProjection(srs.ExportToWkt())
    ds.GetRasterBand(1).WriteArray(z.astype(np.float32))
    ds = None


def bands(path):
    ds = gdal.Open(path)
    return ds.ReadAsArray().astype(np.float64), ds.GetMetadata()


def timed(cmd):
    """(CPU seconds = user + sys, wall seconds, peak RSS MiB) of one whole process."""
    r = subprocess.run(["/usr/bin/time", "-f", "%U %S %e %M"] + cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(" ".join(cmd) + " failed:\n" + r.stderr)
    user, sys_s, wall, rss = r.stderr.strip().splitlines()[-1].split()
    return float(user) + float(sys_s), float(wall), float(rss) / 1024


def add_common_args(ap, directions, far):
    """The options both far-field scripts take."""
    ap.add_argument("--hfbake", default=os.path.join(ROOT, "build", "baker", "cli", "hfbake"))
    ap.add_argument("--dem", default=os.path.join(ROOT, "..", "shared", "data", "TM1_564_146.tif"))
    ap.add_argument("--directions", type=int, default=directions)
    ap.add_argument("--far", default=far)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default="")


def dem_or_fractal(path, work, size):
    """(the DEM's absolute path, its texel) or, without its file, a size^2 fractal written into `work`."""
    dem = os.path.abspath(path)
    if not os.path.exists(dem):
        print("%s is absent: a %d^2 fractal instead" % (dem, size), file=sys.stderr)
        dem = os.path.join(work, "fractal%d.tif" % size)
        fractal(dem, size=size)
    return dem, gdal.Open(dem).GetGeoTransform()[1]


def finish(heading, rows, out, work):
    """Prints the heading and the Markdown table of `rows`, writes the table to `out` (when given) and removes
    the work folder."""
    table = "\n".join(rows)
    print(heading + "\n")
    print(table)
    if out:
        with open(out, "w") as f:
            f.write(table + "\n")
    shutil.rmtree(work)


def far_field_jobs(dem, work, far, make_entry):
    """The exact run and one per D:C pair of `far` (texels), each a job file baking make_entry(far) (far: None
    or (D, C)) on `dem` into its own folder of `work`: ([(name, far)], {name: job file})."""
    fars = [tuple(int(x) for x in p.split(":")) for p in far.split(",")]
    runs = [("exact", None)] + [("D%d_C%d" % (d, c), (d, c)) for d, c in fars]
    # A DEM's NoData holes are filled from their neighbours (docs/gis.md), the same in every run.
    height = dict({"image": dem}, **({"nodata": "fill"} if has_holes(dem) else {}))
    jobs = {}
    for name, f in runs:
        job = {"version": 1, "name": name, "height": height, "bake": [make_entry(f)],
               "output": {"dir": os.path.join(work, name), "geotiff": True}}
        jobs[name] = os.path.join(work, name + ".json")
        with open(jobs[name], "w") as out:
            json.dump(job, out)
    return runs, jobs


def time_runs(hfbake, runs, jobs, reps, threads):
    """Each repetition bakes every run in order as a whole process: {name: [(CPU s, wall s, peak MiB)]}."""
    timings = {name: [] for name, _ in runs}
    for rep in range(reps):
        for name, _ in runs:
            t = timed([hfbake, "bake", "--quiet", "--no-cache", "--overwrite", "--threads", str(threads),
                       jobs[name]])
            timings[name].append(t)
            print("rep %d %s: %.1f s CPU, %.1f s wall" % (rep, name, t[0], t[1]), file=sys.stderr)
    return timings


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common_args(ap, 16, "100:8,200:8,100:16,200:16")
    ap.add_argument("--radius", type=float, default=2000)
    a = ap.parse_args()

    work = tempfile.mkdtemp(prefix="hfbake_relief_far_field_")
    dem, texel = dem_or_fractal(a.dem, work, 4096)
    def entry(far):
        e = {"method": "relief", "directions": a.directions, "search_radius": a.radius * texel,
             "layers": ["svf", "horizon_deg"]}
        if far:
            e["far_field"] = {"beyond": far[0] * texel, "cell": far[1]}
        return e

    runs, jobs = far_field_jobs(dem, work, a.far, entry)
    timings = time_runs(a.hfbake, runs, jobs, a.reps, a.threads)
    cpu = {name: [t[0] for t in ts] for name, ts in timings.items()}
    rss = {name: [t[2] for t in ts] for name, ts in timings.items()}

    def layer(name, what):
        return bands(os.path.join(work, name, "%s.relief.%s.tif" % (name, what)))

    svf_e, _ = layer("exact", "svf")
    hor_e, _ = layer("exact", "horizon_deg")
    rows = []
    rows.append("| run | CPU s (median) | exact / run (median of pairs) | peak RSS MiB | svf error max / mean "
                "| horizon error max / mean (deg) | certified bound: tan (svf) / deg |")
    rows.append("|---|---|---|---|---|---|---|")
    for name, far in runs:
        ratio = statistics.median(e / r for e, r in zip(cpu["exact"], cpu[name]))
        med = statistics.median(cpu[name])
        mem = statistics.median(rss[name])
        if far is None:
            rows.append("| exact march | %.0f | 1 | %.0f | — | — | — |" % (med, mem))
            continue
        svf, meta = layer(name, "svf")
        hor, _ = layer(name, "horizon_deg")
        ds, dh = np.abs(svf - svf_e), np.abs(hor - hor_e)
        bound = float(meta["HFBAKE_RELIEF_FAR_FIELD_BOUND"])
        rows.append("| D = %d, C = %d | %.0f | %.2f | %.0f | %.4f / %.5f | %.2f / %.3f | %.3f / %.2f |" % (
            far[0], far[1], med, ratio, mem, ds.max(), ds.mean(), dh.max(), dh.mean(), bound,
            math.degrees(math.atan(bound))))
    finish("%s: %dx%d, K = %d, search_radius %g texels, %d repetitions, --threads %d" % (
        os.path.basename(dem), svf_e.shape[1], svf_e.shape[0], a.directions, a.radius, a.reps, a.threads),
        rows, a.out, work)


if __name__ == "__main__":
    main()
