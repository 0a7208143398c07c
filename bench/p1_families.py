#!/usr/bin/python3
"""p1's speed across families of terrain: whole-process timings of the same exact bake (ao + vsky, K
directions, a uniform sky) on built-in fields of every hard kind, on rough terrain tilted by a regional
slope, on flat ground (a sea beside land, a city's blocks, a level plane), on planar faces (a tilted plane, bare
and with noise, a V valley), on stairs, on white noise, on low relief far above zero, and on any DEMs given.

    /usr/bin/python3 bench/p1_families.py [--size 1024] [--directions 64] [--reps 3] [--dem FILE.tif ...]
                                          [--out bench/p1_families.md]

Each figure is the median over --reps runs of /usr/bin/time (user + sys CPU seconds, wall seconds); the
families' runs alternate so a drift of the machine's speed reaches all. Throughput is texel-directions
(texels x K) per CPU second. The Markdown table is printed and written to --out. Needs Debian's python3-numpy
and python3-gdal (setup.sh installs them in test mode).
"""
import json
import os
import shutil
import statistics
import tempfile

import numpy as np
from osgeo import gdal

from peers import bench_arguments, has_holes, publish, rough_fbm, timed, write_geotiff

gdal.UseExceptions()

KINDS = ["fractal", "rough", "terraces", "craters", "ridges", "cone", "sines"]


def city(n, seed=3):
    """A DSM of flat-roofed blocks, 8-40 texels a side and 6-40 m tall, on flat ground 300 m up."""
    rng = np.random.default_rng(seed)
    z = np.full((n, n), 300.0)
    for _ in range(n * n // 1750):
        w, h = rng.integers(8, 40, 2)
        x, y = rng.integers(0, n - 40, 2)
        z[y:y + h, x:x + w] = 300.0 + rng.uniform(6.0, 40.0)
    return z


def main():
    ap = bench_arguments(__doc__)
    ap.add_argument("--dem", action="append", default=[], help="a DEM GDAL reads (repeatable)")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "p1_families.md"))
    a = ap.parse_args()
    n, K = a.size, a.directions
    work = tempfile.mkdtemp(prefix="hfbake-families-")
    try:
        fields = [(f"built-in `{k}`", {"procedural": {"kind": k, "size": [n, n], "seed": 7}}, n * n) for k in KINDS]
        yy, xx = np.mgrid[0:n, 0:n].astype(np.float64)
        fbm = rough_fbm(n, seed=5) - 500.0
        for label, z in [
                ("rough fBm (60° texel slopes)", fbm + 500.0),
                ("rough fBm x 0.1 on a 10° tilt", 500.0 + 0.1 * fbm + np.tan(np.radians(10)) * xx),
                ("rough fBm x 0.1 on a 30° tilt", 500.0 + 0.1 * fbm + np.tan(np.radians(30)) * xx),
                ("bare plane, 30°", 500.0 + np.tan(np.radians(30)) * (0.8 * xx + 0.6 * yy)),
                ("a coast: rough fBm, its east half a flat sea", np.where(xx < n // 2, np.maximum(fbm, 0.0), 0.0)),
                ("a city: blocks 6-40 m tall on flat ground", city(n)),
                ("bare plane, level", np.full((n, n), 500.0)),
                ("bare plane, 30°, + noise of 0.1", 500.0 + np.tan(np.radians(30)) * xx +
                 0.1 * np.random.default_rng(9).uniform(-1, 1, (n, n))),
                ("a V valley of 30° faces", 500.0 + np.tan(np.radians(30)) * np.abs(yy - n / 2)),
                ("stairs 3 texels wide, 1 high", 500.0 + np.floor(xx / 3)),
                ("white noise, 1 unit", 500.0 + np.random.default_rng(9).uniform(0, 1, (n, n))),
                ("rough fBm x 0.001, 8000 up", 8000.0 + 0.001 * fbm)]:
            path = os.path.join(work, f"field{len(fields)}.tif")
            write_geotiff(path, z.astype(np.float32))
            fields.append((label, {"image": path}, n * n))
        for dem in a.dem:
            ds = gdal.Open(dem)
            # Holes are filled from their neighbours (docs/gis.md), and the row says so.
            fill = has_holes(dem)
            fields.append((os.path.basename(dem) + (", NoData filled" if fill else ""),
                           dict({"image": os.path.abspath(dem)}, **({"nodata": "fill"} if fill else {})),
                           ds.RasterXSize * ds.RasterYSize))
            ds = None
        cmds = []
        for i, (label, height, texels) in enumerate(fields):
            job = os.path.join(work, f"job{i}.json")
            with open(job, "w") as f:
                json.dump({"version": 1, "name": f"family{i}", "height": height, "environment": {"uniform": 1.0},
                           "bake": [{"method": "p1", "directions": K, "layers": ["ao", "vsky"]}],
                           "output": {"dir": os.path.join(work, f"out{i}"), "previews": False}}, f)
            cmds.append((label, texels, [os.path.abspath(a.hfbake), "bake", job, "--threads", str(a.threads),
                                         "--quiet", "--no-cache", "--overwrite"]))
        runs = {label: [] for label, _, _ in cmds}
        for _ in range(a.reps):
            for label, _, cmd in cmds:
                runs[label].append(timed(cmd))
        lines = [f"p1, ao + vsky, K = {K}, exact, {a.threads} threads; medians of {a.reps} runs.", "",
                 "| field | texels | CPU s | wall s | M texel-directions / CPU s |", "|---|---|---|---|---|"]
        for label, texels, _ in cmds:
            cpu = statistics.median(r[0] for r in runs[label])
            wall = statistics.median(r[1] for r in runs[label])
            lines.append(f"| {label} | {texels} | {cpu:.2f} | {wall:.2f} | {texels * K / cpu / 1e6:.1f} |")
        publish(lines, a.out)
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
