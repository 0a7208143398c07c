#!/usr/bin/python3
"""How much a south-up copy of a DEM differs from the north-up raster: the triangulated surface is split along
the image's diagonal whatever the orientation (docs/gis.md, Compass terms), so a flipped copy is another
surface. Bakes relief's svf and horizon_deg (compass azimuths) on a window of the DEM and on its copy flipped
north-south with the geotransform to match, and prints the differences (the directions along the image axes,
which the split does not touch, separately).

    /usr/bin/python3 tests/accuracy/orientation_split.py [--hfbake build/baker/cli/hfbake]
        [--dem ../shared/data/TM1_564_146.tif] [--window 200,200,512]

Needs Debian's python3-numpy and python3-gdal. About 20 s on two cores.
"""
import argparse
import json
import os
import subprocess
import tempfile

import numpy as np
from osgeo import gdal

gdal.UseExceptions()


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hfbake", default="build/baker/cli/hfbake")
    ap.add_argument("--dem", default=os.path.join(here, "..", "..", "..", "shared", "data", "TM1_564_146.tif"))
    ap.add_argument("--window", default="200,200,512", help="column, row, side")
    ap.add_argument("--directions", type=int, default=16)
    ap.add_argument("--radius", type=float, default=10)
    a = ap.parse_args()
    c0, r0, n = (int(v) for v in a.window.split(","))
    src = gdal.Open(a.dem)
    z = src.GetRasterBand(1).ReadAsArray(c0, r0, n, n).astype(np.float32)
    g = src.GetGeoTransform()
    x0, y0 = g[0] + c0 * g[1], g[3] + r0 * g[5]
    layers = {}
    with tempfile.TemporaryDirectory() as tmp:
        # North-up as stored; south-up: the rows reversed, row 0 at the southern edge, y growing northwards.
        for name, rows, gt in (("north", z, (x0, g[1], 0, y0, 0, g[5])),
                               ("south", z[::-1], (x0, g[1], 0, y0 + n * g[5], 0, -g[5]))):
            path = os.path.join(tmp, name + ".tif")
            ds = gdal.GetDriverByName("GTiff").Create(path, n, n, 1, gdal.GDT_Float32)
            ds.SetGeoTransform(gt)
            ds.SetProjection(src.GetProjection())
            ds.GetRasterBand(1).WriteArray(rows)
            ds = None
            out = os.path.join(tmp, "out_" + name)
            job = {"version": 1, "name": name, "height": {"image": path},
                   "bake": [{"method": "relief", "directions": a.directions, "search_radius": a.radius,
                             "azimuth_convention": "compass", "layers": ["svf", "horizon_deg"]}],
                   "output": {"dir": out, "pixel_type": "float", "geotiff": True, "previews": False}}
            with open(path + ".json", "w") as f:
                json.dump(job, f)
            subprocess.run([a.hfbake, "bake", path + ".json", "--quiet", "--no-cache"], check=True)
            svf = gdal.Open(os.path.join(out, name + ".relief.svf.tif")).ReadAsArray()
            hor = gdal.Open(os.path.join(out, name + ".relief.horizon_deg.tif")).ReadAsArray()
            if name == "south":  # back to the north-up rows
                svf, hor = svf[::-1], hor[:, ::-1, :]
            layers[name] = (svf, hor)
    d_svf = np.abs(layers["north"][0] - layers["south"][0])
    d_hor = np.abs(layers["north"][1] - layers["south"][1])
    axes = list(range(0, a.directions, a.directions // 4)) if a.directions % 4 == 0 else []
    diagonal = [k for k in range(a.directions) if k not in axes]
    print(f"window {n}² of {os.path.basename(a.dem)}, K = {a.directions}, search_radius {a.radius:g}")
    print(f"svf: median {np.median(d_svf):.4f}, max {d_svf.max():.3f}, "
          f"{100 * (d_svf > 0.005).mean():.1f} % of texels by more than 0.005")
    dh = d_hor[diagonal]
    print(f"horizon_deg, directions off the image axes: median {np.median(dh):.2f}°, "
          f"p99 {np.percentile(dh, 99):.1f}°, max {dh.max():.1f}°, "
          f"{100 * (dh > 2).mean():.1f} % of texel-directions by more than 2°")
    if axes:
        print(f"horizon_deg, directions along the image axes: max {d_hor[axes].max():.3g}°")


if __name__ == "__main__":
    main()
