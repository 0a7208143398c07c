#!/usr/bin/python3
"""hfbake beside its peers: whole-process timings of p1's speed bakes and, when GRASS GIS is installed
(Debian grass-core), r.horizon on the same field with the same number of directions, measured in one run. A --dem with NoData holes is baked with "nodata": "fill"
(the table says so); r.horizon skips its NULL cells.

    /usr/bin/python3 bench/peers.py [--size 1024] [--directions 64] [--reps 3] [--grass-reps 1]
                                    [--dem FILE.tif] [--out bench/peers.md]

The field is rough fBm at the texel scale (1 m texels, a projected CRS) written as a GeoTIFF both programs
read, or --dem. Each figure is the median over --reps runs of /usr/bin/time (user + sys CPU seconds, wall
seconds, peak resident memory); the runs of hfbake and r.horizon alternate so a drift of the machine's speed
reaches both. r.horizon (GRASS 8.2) runs on one thread, with its default search distance (the whole
region) and sampling step; hfbake's figures are its exact horizons unless a tolerance is given: ao and vsky,
those with the horizon layer, and the horizon layer alone (what r.horizon computes), its EXR compressed by
default (PIZ) and uncompressed. Throughput is texel-directions (texels x K) per CPU second. The Markdown table
is printed and written to --out. Needs Debian's python3-numpy and python3-gdal (setup.sh installs them in test mode).
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile

import numpy as np
from osgeo import gdal, osr

gdal.UseExceptions()


def rough_fbm(size, seed=11, slope_deg=60.0, gain=0.7, largest=64):
    """Value-noise fBm from `largest` texels down to one, scaled so that the median forward difference is
    tan(slope_deg): terrain rough at the texel scale, like a lidar DSM."""
    rng = np.random.default_rng(seed)
    z = np.zeros((size, size))
    amp, cell = 1.0, largest
    while cell >= 1:
        n = size // cell + 2
        lattice = rng.uniform(-1, 1, (n, n))
        t = np.arange(size) / cell
        i0 = np.floor(t).astype(int)
        f = t - i0
        rows = lattice[i0] * (1 - f)[:, None] + lattice[i0 + 1] * f[:, None]
        z += amp * (rows[:, i0] * (1 - f)[None, :] + rows[:, i0 + 1] * f[None, :])
        amp *= gain
        cell //= 2
    med = np.median(np.abs(np.diff(z, axis=1)))
    return (z * np.tan(np.radians(slope_deg)) / med + 500.0).astype(np.float32)


def write_geotiff(path, z, pixel=1.0):
    """z as a float32 GeoTIFF of square pixels `pixel` metres wide in UTM 33N."""
    drv = gdal.GetDriverByName("GTiff")
    ds = drv.Create(path, z.shape[1], z.shape[0], 1, gdal.GDT_Float32)
    ds.SetGeoTransform((500000.0, pixel, 0.0, 5100000.0 + pixel * z.shape[0], 0.0, -pixel))
    srs = osr.SpatialReference()
    srs.ImportFromEPSG(32633)
    ds.SetProjection(srs.ExportToWkt())
    ds.GetRasterBand(1).WriteArray(z)
    ds = None


def timed(cmd, env=None):
    """user + sys CPU seconds, wall seconds and peak RSS (MiB) of one whole process."""
    fmt = "%U %S %e %M"
    with tempfile.NamedTemporaryFile("r", suffix=".time") as tf:
        r = subprocess.run(["/usr/bin/time", "-f", fmt, "-o", tf.name] + cmd, env=env,
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if r.returncode != 0:
            sys.exit(f"peers: {' '.join(cmd)} failed ({r.returncode}): {r.stderr.strip()[-400:]}")
        u, s, e, m = tf.read().split()[-4:]
    return float(u) + float(s), float(e), float(m) / 1024.0


def publish(lines, path):
    """Prints the Markdown lines and writes them to path."""
    text = "\n".join(lines) + "\n"
    print(text)
    with open(path, "w") as f:
        f.write(text)


def has_holes(path):
    """Whether the DEM's first band has NoData or non-finite texels."""
    ds = gdal.Open(path)
    band = ds.GetRasterBand(1)
    z = band.ReadAsArray().astype(np.float64)
    nodata = band.GetNoDataValue()
    return bool((~np.isfinite(z)).any() or (nodata is not None and (z == nodata).any()))


def hfbake_job(path, dem, out_dir, K, layers, tolerance, compression=None, fill=False):
    entry = {"method": "p1", "directions": K, "layers": layers}
    if tolerance is not None:
        entry["horizon_tolerance"] = tolerance
    output = {"dir": out_dir, "previews": False}
    if compression:
        output["compression"] = compression
    job = {"version": 1, "name": os.path.splitext(os.path.basename(path))[0],
           "height": dict({"image": dem}, **({"nodata": "fill"} if fill else {})), "environment": {"uniform": 1.0}, "bake": [entry], "output": output}
    with open(path, "w") as f:
        json.dump(job, f, indent=2)


def bench_arguments(doc):
    """The arguments every p1 speed script takes: the binary, the field's size, K, repetitions, threads."""
    ap = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    ap.add_argument("--hfbake", default=os.path.join(os.path.dirname(__file__), "..", "build", "baker", "cli",
                                                     "hfbake"))
    ap.add_argument("--size", type=int, default=1024)
    ap.add_argument("--directions", type=int, default=64)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    return ap


def main():
    ap = bench_arguments(__doc__)
    ap.add_argument("--grass-reps", type=int, default=1, help="r.horizon takes minutes a run")
    ap.add_argument("--tolerance", type=float, action="append",
                    help="p1 horizon_tolerance values to time besides the default (repeatable)")
    ap.add_argument("--dem", help="a GeoTIFF DEM instead of the rough field")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "peers.md"))
    a = ap.parse_args()
    K = a.directions
    work = tempfile.mkdtemp(prefix="hfbake-peers-")
    try:
        if a.dem:
            dem = os.path.abspath(a.dem)
            ds = gdal.Open(dem)
            texels, field = ds.RasterXSize * ds.RasterYSize, os.path.basename(dem)
            ds = None
            # hfbake refuses holes unless told to fill them from their neighbours (docs/gis.md); r.horizon
            # skips its NULL cells.
            fill = has_holes(dem)
            if fill:
                field += ", its NoData holes filled by hfbake (\"nodata\": \"fill\")"
        else:
            dem = os.path.join(work, "rough.tif")
            write_geotiff(dem, rough_fbm(a.size))
            fill = False
            texels, field = a.size * a.size, f"rough fBm {a.size}² (60° median texel slope)"
        # The horizon layer alone is what r.horizon computes; its EXR (64 half channels) is written with the
        # default PIZ compression and, in the last row, uncompressed (r.horizon's own maps are compressed).
        bakes = [("p1 ao + vsky", ["ao", "vsky"], None, None),
                 ("p1 ao + vsky + horizon", ["ao", "vsky", "horizon"], None, None),
                 ("p1 horizon", ["horizon"], None, None)]
        for tol in a.tolerance or []:
            bakes.append((f"p1 ao + vsky + horizon, tolerance {tol:g}", ["ao", "vsky", "horizon"], tol, None))
        bakes.append(("p1 horizon, EXR uncompressed", ["horizon"], None, "none"))
        cmds = []
        for i, (label, layers, tol, compression) in enumerate(bakes):
            job = os.path.join(work, f"bake{i}.json")
            hfbake_job(job, dem, os.path.join(work, f"out{i}"), K, layers, tol, compression, fill)
            cmds.append((label, [os.path.abspath(a.hfbake), "bake", job, "--threads", str(a.threads), "--quiet",
                                 "--no-cache"]))
        grass = shutil.which("grass")
        grass_cmd = None
        if grass:
            loc = os.path.join(work, "grassdb", "loc")
            subprocess.run([grass, "-c", dem, "-e", loc], check=True, capture_output=True)
            subprocess.run([grass, os.path.join(loc, "PERMANENT"), "--exec", "r.in.gdal", "-o", f"input={dem}",
                            "output=dem"], check=True, capture_output=True)
            subprocess.run([grass, os.path.join(loc, "PERMANENT"), "--exec", "g.region", "raster=dem"], check=True,
                           capture_output=True)
            grass_cmd = [grass, os.path.join(loc, "PERMANENT"), "--exec", "r.horizon", "--overwrite",
                         "elevation=dem", f"step={360.0 / K!r}", "output=hor"]
        results = {label: [] for label, _ in cmds}
        grass_runs = []
        for rep in range(max(a.reps, a.grass_reps)):
            for label, cmd in cmds:
                if rep < a.reps:
                    results[label].append(timed(cmd))
            if grass_cmd and rep < a.grass_reps:
                grass_runs.append(timed(grass_cmd))

        def med(runs, i):
            return statistics.median(r[i] for r in runs)

        rows = []
        g_cpu = med(grass_runs, 0) if grass_runs else None
        for label, _ in cmds:
            runs = results[label]
            cpu = med(runs, 0)
            rows.append((label, cpu, med(runs, 1), med(runs, 2), texels * K / cpu / 1e6,
                         f"{g_cpu / cpu:.1f}x" if g_cpu else "—"))
        if grass_runs:
            rows.append((f"GRASS r.horizon ({K} maps)", g_cpu, med(grass_runs, 1), med(grass_runs, 2),
                         texels * K / g_cpu / 1e6, "1.0x"))
        lines = [f"Field: {field}, {texels} texels, K = {K}, {a.threads} threads; medians of {a.reps} runs "
                 f"(r.horizon: {a.grass_reps}).", "",
                 "| bake | CPU s | wall s | peak MiB | M texel-directions / CPU s | r.horizon CPU / this CPU |",
                 "|---|---|---|---|---|---|"]
        for r in rows:
            lines.append(f"| {r[0]} | {r[1]:.2f} | {r[2]:.2f} | {r[3]:.0f} | {r[4]:.2f} | {r[5]} |")
        if not grass:
            lines.append("")
            lines.append("GRASS GIS is not installed (Debian grass-core): r.horizon was not run.")
        publish(lines, a.out)
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
