#!/usr/bin/python3
"""Indirect light at the floor of slots and pits a few texels wide: p2 at subdivide 1, 2 and 4, and nlp,
against the Embree reference, as a markdown table (docs/methods/p2.md, "Slots and pits").

Albedo 1, a uniform sky of 1, one bounce, p2 at K = 64, nlp at m = 32, a 512-sample reference. A slot is a
trench w texels wide and D deep through a 48 x 97 field along its columns; a pit is a w x w hole D deep in a
33 x 33 field. The figure is the mean of the floor's centre texels (a slot's centre column over its middle
49 rows; a pit's centre texel, or its centre 2 x 2 when w is even), with the standard error of the
reference's mean.

  /usr/bin/python3 tests/accuracy/slot_floors.py [--hfbake build/baker/cli/hfbake] [--work /tmp/slots]
"""
import argparse
import json
import os
import subprocess

import numpy as np

from exr_io import read_channel, write_exr

CASES = [("slot", 2, 20), ("slot", 3, 10), ("slot", 3, 30), ("slot", 4, 20), ("pit", 3, 10), ("pit", 4, 10)]


def field(kind, w, depth):
    """The heights and the floor texels (rows, columns) whose mean is taken."""
    if kind == "slot":
        z = np.full((97, 48), float(depth), np.float32)
        c = 24 - w // 2
        z[:, c:c + w] = 0.0
        cols = [c + w // 2] if w % 2 else [c + w // 2 - 1, c + w // 2]
        return z, (slice(24, 73), cols)
    z = np.zeros((33, 33), np.float32)
    c = 16 - w // 2
    z[c:c + w, c:c + w] = -float(depth)
    mid = [c + w // 2] if w % 2 else [c + w // 2 - 1, c + w // 2]
    return z, (mid, mid)


def floor_values(layer, where):
    rows, cols = where
    return layer[rows][:, cols] if isinstance(rows, slice) else layer[np.ix_(rows, cols)]


def floor_mean(layer, where):
    return float(np.mean(floor_values(layer, where)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--hfbake", default=os.path.join(os.path.dirname(__file__), "..", "..", "build", "baker",
                                                     "cli", "hfbake"))
    ap.add_argument("--work", default="/tmp/hfbake-slot-floors")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    rows = []
    for kind, w, depth in CASES:
        name = f"{kind}_w{w}_d{depth}"
        z, where = field(kind, w, depth)
        write_exr(os.path.join(a.work, name + ".exr"), z)
        bakes = [{"method": "p2", "directions": 64, "subdivide": [1, 2, 4], "layers": ["indirect"]},
                 {"method": "nlp", "directions": 32, "layers": ["indirect"]}]
        job = {"version": 1, "name": name, "height": {"image": name + ".exr"}, "environment": {"uniform": 1.0},
               "surface": {"albedo": 1.0}, "bounces": 1, "bake": bakes,
               "reference": {"samples": 512, "seed": 1, "layers": ["indirect"]},
               "output": {"dir": "out_" + name, "pixel_type": "float"}}
        path = os.path.join(a.work, name + ".json")
        with open(path, "w") as f:
            json.dump(job, f)
        subprocess.run([a.hfbake, "bake", path, "--quiet", "--overwrite", "--cache", os.path.join(a.work, "cache")],
                       check=True)
        out = os.path.join(a.work, "out_" + name)
        exrs = sorted(f for f in os.listdir(out) if f.endswith(".exr"))
        ref = os.path.join(out, next(f for f in exrs if ".reference." in f))
        r = floor_mean(read_channel(ref, "indirect.R"), where)
        e = floor_values(read_channel(ref, "indirect_stderr.R"), where)
        se = float(np.sqrt(np.sum(e * e)) / e.size)  # the mean's, the texels' estimates independent
        p2 = [floor_mean(read_channel(os.path.join(out, next(f for f in exrs if f".p2{tag}." in f)), "indirect.R"),
                         where) for tag in ("-subdivide1", "-subdivide2", "-subdivide4")]
        nlp = floor_mean(read_channel(os.path.join(out, name + ".nlp.exr"), "indirect.R"), where)
        rows.append((kind, w, depth, r, se, p2, nlp))
    print("| floor of | reference | p2 | p2 subdivide 2 | p2 subdivide 4 | nlp |")
    print("|---|---|---|---|---|---|")
    for kind, w, depth, r, se, p2, nlp in rows:
        print(f"| {kind} {w} wide, {depth} deep | {r:.4f} ± {se:.4f} | " +
              " | ".join(f"{v:.4f} ({v / r:.1f}x)" for v in p2 + [nlp]) + " |")


if __name__ == "__main__":
    main()
