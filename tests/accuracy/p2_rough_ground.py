#!/usr/bin/python3
"""p2's bounce on ground rough at the texel scale against the Embree reference: a family of fields (white
noise; DSMs of blocks, cone trees and per-texel noise) under a uniform sky, an emission map rising with the
heights, and the built-in sky with suns at 20, 35 and 60 degrees. Prints the Markdown table of
docs/methods/p2.md (bias of the field mean, excess rmse over the reference's own noise, the mean).

    /usr/bin/python3 tests/accuracy/p2_rough_ground.py [--hfbake build/baker/cli/hfbake] [--samples 256]
                                                      [--subdivided | --subdivided-only] [--method nlp]

--subdivided adds the second table of p2.md: p2 with "subdivide" 1, 2 and 4 on the white-noise field (the
field baked subdivided on its triangulation, read at its own texels). About 2 minutes on two cores (about 1
more with --subdivided). --method nlp prints the same table for nlp (its defaults, the same fields, lights and
reference: the figures of docs/methods/nlp.md). Needs Debian's python3-numpy and python3-gdal.
"""
import argparse
import json
import os
import subprocess
import tempfile

import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "bench"))
from peers import write_geotiff as write_raster  # noqa: E402  (square metre pixels, a projected CRS)


def smooth_noise(n, cell, rng):
    """Value noise of lattice `cell` texels, smoothstep-interpolated."""
    g = rng.standard_normal((n // cell + 3, n // cell + 3))
    t = np.arange(n) / cell
    i = np.floor(t).astype(int)
    f = t - i
    f = f * f * (3 - 2 * f)
    a, b = (1 - f), f
    return (g[i][:, i] * a[:, None] * a[None, :] + g[i + 1][:, i] * b[:, None] * a[None, :] +
            g[i][:, i + 1] * a[:, None] * b[None, :] + g[i + 1][:, i + 1] * b[:, None] * b[None, :])


def dsm(n, seed):
    """Blocks 3-15 units high, cone trees of 60-degree flanks and 1.8 units of per-texel noise."""
    rng = np.random.default_rng(seed)
    z = 3 * smooth_noise(n, 32, rng)
    for _ in range(40 * n * n // 128 ** 2 + 1):
        w, h = rng.integers(4, 16, 2)
        x, y = rng.integers(0, n - 4, 2)
        z[y:y + h, x:x + w] = np.maximum(z[y:y + h, x:x + w], z[y:y + h, x:x + w].mean() + rng.uniform(3, 15))
    yy, xx = np.mgrid[0:n, 0:n]
    for _ in range(60 * n * n // 128 ** 2 + 1):
        cx, cy = rng.uniform(0, n, 2)
        r = rng.uniform(1.5, 4)
        d = np.hypot(xx - cx, yy - cy)
        z = np.maximum(z, z.mean() + (r - d) * np.tan(np.radians(60)) * (d < r) - 100 * (d >= r))
    return (z + 1.8 * rng.standard_normal((n, n))).astype(np.float32)


def subdivided_rows(hfbake, samples, tmp):
    """p2 with "subdivide": 1, 2 and 4 on the white-noise field: bias of the field mean against the reference
    (of the field itself), the border ring cropped, as the first table."""
    z = (np.random.default_rng(2).standard_normal((48, 48)) * 1.8).astype(np.float32)
    heights, em = os.path.join(tmp, "s.tif"), os.path.join(tmp, "se.tif")
    write_raster(heights, z)
    write_raster(em, ((z - z.min()) / (z.max() - z.min())).astype(np.float32))
    lines = ["| light | `subdivide` | `indirect_b1` bias | `indirect_b2` bias |", "|---|---|---|---|"]
    for lname, env, emission in (("emission rising with height", {"uniform": 0.0}, True),
                                 ("sky, sun at 35°", {"sky": {"sun": {"elevation_deg": 35, "azimuth_deg": 135}}},
                                  False)):
        for s in (1, 2, 4):
            out = os.path.join(tmp, f"sub{s}_{int(emission)}")
            surface = {"albedo": 0.5}
            if emission:
                surface["emission"] = {"image": em}
            job = {"version": 1, "name": "sub", "height": {"image": heights}, "surface": surface,
                   "environment": env, "bounces": 2,
                   "bake": [{"method": "p2", "directions": 64, "subdivide": s,
                             "layers": ["indirect_b1", "indirect_b2"]}],
                   "reference": {"samples": samples, "seed": 1, "layers": ["indirect_b1", "indirect_b2"]},
                   "report": {"crop": 4}, "output": {"dir": out, "pixel_type": "float", "previews": False}}
            path = out + ".json"
            with open(path, "w") as f:
                json.dump(job, f)
            subprocess.run([hfbake, "bake", path, "--quiet", "--no-cache"], check=True)
            with open(os.path.join(out, "report.json")) as f:
                layers = json.load(f)["methods"]["p2"]["layers"]
            cells = [f"{100 * layers[l]['bias'] / layers[l]['reference_mean']:+.1f} %"
                     for l in ("indirect_b1", "indirect_b2")]
            lines.append(f"| {lname} | {s} | {cells[0]} | {cells[1]} |")
            print(lines[-1], flush=True)
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hfbake", default="build/baker/cli/hfbake")
    ap.add_argument("--samples", type=int, default=256)
    ap.add_argument("--subdivided", action="store_true",
                    help='also p2 with "subdivide" 1, 2 and 4 on the white-noise field')
    ap.add_argument("--subdivided-only", action="store_true", help="only the table of --subdivided")
    ap.add_argument("--method", choices=("p2", "nlp"), default="p2", help="the method of the first table")
    a = ap.parse_args()
    if a.subdivided_only:
        with tempfile.TemporaryDirectory() as tmp:
            print("\n".join(subdivided_rows(a.hfbake, a.samples, tmp)))
        return
    fields = [("white noise 1.8 units a texel, 48²",
               (np.random.default_rng(2).standard_normal((48, 48)) * 1.8).astype(np.float32)),
              ("rough DSM, 96²", dsm(96, 8)), ("rough DSM, 64²", dsm(64, 3))]
    lights = [("uniform sky", {"uniform": 1.0}, None),
              ("emission rising with height", {"uniform": 0.0}, "emission"),
              ("sky, sun at 35°", {"sky": {"sun": {"elevation_deg": 35, "azimuth_deg": 135}}}, None),
              ("sky, sun at 20°", {"sky": {"sun": {"elevation_deg": 20, "azimuth_deg": 135}}}, None),
              ("sky, sun at 60°", {"sky": {"sun": {"elevation_deg": 60, "azimuth_deg": 135}}}, None)]
    # p2 at K = 64, each bounce; nlp (its defaults) has no layer per bounce: its indirect light of both.
    entry = ({"method": "p2", "directions": 64, "layers": ["indirect_b1", "indirect_b2"]} if a.method == "p2"
             else {"method": "nlp", "layers": ["indirect"]})
    scored = entry["layers"]
    lines = (["| field | light | `indirect_b1`: bias, excess rmse of mean | `indirect_b2` |", "|---|---|---|---|"]
             if a.method == "p2" else
             ["| field | light | `indirect` (two bounces): bias, excess rmse of mean |", "|---|---|---|"])
    with tempfile.TemporaryDirectory() as tmp:
        for fi, (fname, z) in enumerate(fields):
            heights = os.path.join(tmp, f"f{fi}.tif")
            write_raster(heights, z)
            emission = os.path.join(tmp, f"e{fi}.tif")
            write_raster(emission, ((z - z.min()) / (z.max() - z.min())).astype(np.float32))
            for li, (lname, env, em) in enumerate(lights):
                surface = {"albedo": 0.5}
                if em:
                    surface["emission"] = {"image": emission}
                job = {"version": 1, "name": f"r{fi}_{li}", "height": {"image": heights}, "surface": surface,
                       "environment": env, "bounces": 2,
                       "bake": [entry],
                       "reference": {"samples": a.samples, "seed": 1, "layers": scored},
                       "report": {"crop": 4}, "output": {"dir": os.path.join(tmp, f"out{fi}_{li}"),
                                                          "pixel_type": "float", "previews": False}}
                path = os.path.join(tmp, f"r{fi}_{li}.json")
                with open(path, "w") as f:
                    json.dump(job, f)
                subprocess.run([a.hfbake, "bake", path, "--quiet", "--no-cache"], check=True)
                with open(os.path.join(tmp, f"out{fi}_{li}", "report.json")) as f:
                    layers = json.load(f)["methods"][a.method]["layers"]
                cells = []
                for layer in scored:
                    v = layers[layer]
                    cells.append(f"{100 * v['bias'] / v['reference_mean']:+.1f} %, {v['excess_rmse']:.4f} of "
                                 f"{v['reference_mean']:.3f}")
                lines.append(f"| {fname} | {lname} | " + " | ".join(cells) + " |")
                print(lines[-1], flush=True)
    print("\n".join(lines))
    if a.subdivided:
        with tempfile.TemporaryDirectory() as tmp:
            print("\n".join(subdivided_rows(a.hfbake, a.samples, tmp)))


if __name__ == "__main__":
    main()
