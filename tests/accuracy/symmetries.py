#!/usr/bin/python3
"""How far each method's layers move under changes that leave the surface the same: the field transposed or
turned 180 degrees (the triangulation's diagonal maps onto itself and the K directions onto themselves, so the
reference's values move with the texels), and texel size, heights and radius scaled together by 1 + 1e-6
(rounding level). Prints, per method and change, the largest change of a texel and how many texels move by
more than 1e-4, as a markdown table (docs/methods/obscurance.md, "Symmetries").

The field: 96 x 64 texels of rough ground (60 degree median slope at the texel scale) with a dozen
flat-roofed buildings 3-12 texels high; a uniform sky of 1, albedo 0.8, one bounce.

  /usr/bin/python3 tests/accuracy/symmetries.py [--hfbake build/baker/cli/hfbake] [--work /tmp/symmetries]
"""
import argparse
import json
import os
import subprocess

import numpy as np

from exr_io import read_channel, write_exr

METHODS = [("p1", "ao", {"directions": 32, "layers": ["ao"]}),
           ("hbao", "obscurance", {"directions": 16, "radius": 8}),
           ("lsao", "obscurance", {"directions": 16, "radius": 8}),
           ("farfield", "obscurance", {"directions": 16, "radius": 8, "near_field": 4}),
           ("hsao", "obscurance", {"directions": 16, "radius": 8}),
           ("vo", "obscurance", {"radius": 8}),
           ("p2", "indirect", {"directions": 32, "layers": ["indirect"]}),
           ("nlp", "indirect", {"directions": 32, "layers": ["indirect"]})]


def dsm(width=96, height=64, seed=5):
    rng = np.random.default_rng(seed)
    z = np.zeros((height, width))
    for octave in range(5):  # fBm of value noise, its finest octave at the texel scale
        cell = 2 ** (4 - octave)
        coarse = rng.standard_normal((height // cell + 2, width // cell + 2))
        z += np.kron(coarse, np.ones((cell, cell)))[:height, :width] * 0.7 ** octave
    z *= 1.73 / np.median(np.abs(np.diff(z, axis=1)))  # tan 60 degrees between neighbours, in the median
    for _ in range(12):
        w, h = rng.integers(4, 12, 2)
        x, y = rng.integers(0, width - w), rng.integers(0, height - h)
        z[y:y + h, x:x + w] = z[y:y + h, x:x + w].max() + rng.uniform(3, 12)
    return z.astype(np.float32)


def bake(hfbake, work, name, z, scale):
    write_exr(os.path.join(work, name + ".exr"), z)
    entries = []
    for method, _, keys in METHODS:
        e = {"method": method, **keys}
        if "radius" in e:  # world units (near_field is in texels)
            e["radius"] = e["radius"] * scale
        entries.append(e)
    job = {"version": 1, "name": name, "height": {"image": name + ".exr", "texel_size": scale},
           "environment": {"uniform": 1.0}, "surface": {"albedo": 0.8}, "bounces": 1, "bake": entries,
           "output": {"dir": "out_" + name, "pixel_type": "float"}}
    path = os.path.join(work, name + ".json")
    with open(path, "w") as f:
        json.dump(job, f)
    subprocess.run([hfbake, "bake", path, "--quiet", "--overwrite", "--no-cache"], check=True)
    out = os.path.join(work, "out_" + name)
    return {m: read_channel(os.path.join(out, f"{name}.{m}.exr"), layer + (".Y" if layer != "indirect" else ".R"))
            for m, layer, _ in METHODS}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--hfbake", default=os.path.join(os.path.dirname(__file__), "..", "..", "build", "baker",
                                                     "cli", "hfbake"))
    ap.add_argument("--work", default="/tmp/hfbake-symmetries")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    z = dsm()
    f = 1 + 1e-6
    base = bake(a.hfbake, a.work, "base", z, 1.0)
    # Each change's layers mapped back onto the base field's texels.
    changes = [("transposed", bake(a.hfbake, a.work, "transposed", z.T, 1.0), lambda v: v.T),
               ("turned 180°", bake(a.hfbake, a.work, "turned", z[::-1, ::-1], 1.0), lambda v: v[::-1, ::-1]),
               ("scaled by 1 + 1e-6",
                bake(a.hfbake, a.work, "scaled", (z.astype(np.float64) * f).astype(np.float32), f), lambda v: v)]
    print("| method | " + " | ".join(c[0] for c in changes) + " |")
    print("|---|" + "---|" * len(changes))
    for m, layer, _ in METHODS:
        cells = []
        for _, layers, back in changes:
            d = np.abs(back(layers[m]) - base[m])
            cells.append(f"{d.max():.1e} ({int((d > 1e-4).sum())})")
        print(f"| {m} {layer} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
