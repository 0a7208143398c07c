#!/usr/bin/env python3
"""Writes the jobs behind the accuracy table of docs/methods/nlp.md: nlp alone on each nightly field (and a
128^2 crop of the lidar DEM of ../shared/data when gdal_translate and the file are there), in the nightly
setting (sky + sun, albedo 0.5, 256-sample reference) and in a uniform one (uniform sky (0.6, 0.7, 1.0), albedo
0.6, 512-sample reference), 4-texel border cropped; two entries, the paper-shading preset of baker/methods/nlp/README.md
("previous") and the defaults, each at m = 8, 16, 32, 64.

  python3 tests/nlp/nlp_defaults_jobs.py OUT_DIR
  for j in OUT_DIR/*.json; do build/baker/cli/hfbake bake $j --cache OUT_DIR/cache; done
  # report.json, per stem nlp-0-directions32 (previous) / nlp-1-directions32 (defaults): layers.total.rel_mae,
  # layers.indirect.bias / layers.indirect.reference_mean
"""
import json
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
FIELDS = os.path.join(HERE, "..", "nightly", "fields")
DEM = os.path.join(HERE, "..", "..", "..", "shared", "data", "TM1_564_146.tif")
PREVIOUS = {"senders": "texels", "indirect_cosine": "sh", "direct_cosine": "sh", "visibility_horizon": "bspline",
            "near_spacing": 0}
NAMES = ["terraces", "blocks", "bricks", "sines", "trench", "craters", "ridges", "rough", "fractal", "slope"]


def main():
    out = os.path.abspath(sys.argv[1])
    os.makedirs(out, exist_ok=True)
    fields = {n: json.load(open(os.path.join(FIELDS, n + ".json"))) for n in NAMES}
    if os.path.exists(DEM) and shutil.which("gdal_translate"):
        crop = os.path.join(out, "dem128.tif")
        subprocess.run(["gdal_translate", "-q", "-srcwin", "400", "400", "128", "128", DEM, crop], check=True)
        dem = dict(fields["craters"])
        dem["height"] = {"image": crop}
        fields["dem"] = dem
    for name, job in fields.items():
        for setting in ["nightly", "uniform"]:
            j = {k: v for k, v in job.items() if k not in ("description", "bake", "report", "output")}
            j["name"] = f"{name}_{setting}"
            if setting == "uniform":
                j["environment"] = {"uniform": [0.6, 0.7, 1.0]}
                j["surface"] = {"albedo": 0.6}
                j["reference"] = {"samples": 512, "seed": 1}
            layers = ["direct", "indirect", "total"]
            j["bake"] = [dict({"method": "nlp", "directions": [8, 16, 32, 64], "layers": layers}, **PREVIOUS),
                         {"method": "nlp", "directions": [8, 16, 32, 64], "layers": layers}]
            j["report"] = {"crop": 4}
            j["output"] = {"dir": os.path.join(out, j["name"]), "previews": False}
            with open(os.path.join(out, j["name"] + ".json"), "w") as f:
                json.dump(j, f, indent=1)


if __name__ == "__main__":
    main()
