#!/usr/bin/env python3
"""lsao's tangent strategies against the Embree reference: writes and bakes one job per field
and falloff (hbao, lsao with the receiver tangent, lsao with P3's fixed tangent -0.85; K = 16), then prints
excess_rmse / bias of each against the reference.

    python3 tests/ao/lsao_tangent_jobs.py OUT_DIR [HFBAKE]    (HFBAKE: default build/baker/cli/hfbake)

Fields: the nightly craters, sines, terraces, ridges and rough, a gentler crater field that is not in the
repository (128^2, seed 21), and a 128^2 crop of the lidar DEM ../shared/data/TM1_564_146.tif (made with
gdal_translate -srcwin 400 400 128 128; skipped when the DEM or gdal_translate is absent). Falloffs: smooth
R = 32 (the issue's case) and step R = 8 (the nightly's). 256-sample reference, seed 1.
"""
import json
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def procedural(kind, size=96, **kw):
    return {"procedural": {"kind": kind, "size": [size, size], **kw}, "texel_size": 1.0}


FIELDS = {
    "craters": procedural("craters", seed=9, feature_size=10, amplitude=4),
    "gentle_craters": procedural("craters", 128, seed=21, feature_size=20, amplitude=5),
    "sines": procedural("sines"),
    "terraces": procedural("terraces", seed=5, amplitude=8, step=2.5),
    "ridges": procedural("ridges", seed=4, amplitude=10),
    "rough": procedural("rough", seed=3, angle_deg=70),
}
FALLOFFS = {"smooth32": {"radius": 32, "falloff": "smooth"}, "step8": {"radius": 8, "falloff": "step"}}


def main():
    out = os.path.abspath(sys.argv[1])
    hfbake = os.path.abspath(sys.argv[2] if len(sys.argv) > 2 else os.path.join(ROOT, "build/baker/cli/hfbake"))
    os.makedirs(out, exist_ok=True)
    dem = os.path.join(ROOT, "..", "shared", "data", "TM1_564_146.tif")
    if os.path.exists(dem) and shutil.which("gdal_translate"):
        crop = os.path.join(out, "dem128.tif")
        subprocess.run(["gdal_translate", "-q", "-srcwin", "400", "400", "128", "128", dem, crop], check=True)
        FIELDS["dem"] = {"image": "dem128.tif"}
    print("| job | reference mean | hbao | lsao (receiver tangent) | lsao (fixed -0.85) |")
    print("|---|---|---|---|---|")
    for fname, height in FIELDS.items():
        for cname, falloff in FALLOFFS.items():
            name = f"{fname}_{cname}"
            common = {"directions": 16, **falloff, "layers": ["obscurance"]}
            job = {"version": 1, "name": name, "height": height,
                   "bake": [{"method": "hbao", **common}, {"method": "lsao", **common},
                            {"method": "lsao", **common, "tangent": -0.85}],
                   "reference": {"samples": 256, "seed": 1},
                   "output": {"previews": False, "dir": f"out/{name}"}}
            path = os.path.join(out, name + ".json")
            with open(path, "w") as f:
                json.dump(job, f, indent=1)
            subprocess.run([hfbake, "bake", path, "--quiet"], check=True, cwd=out, stdout=subprocess.DEVNULL)
            with open(os.path.join(out, "out", name, "report.json")) as f:
                methods = json.load(f)["methods"]
            cells = []
            for m in ("hbao", "lsao-1", "lsao-2"):
                o = methods[m]["layers"]["obscurance"]
                cells.append(f"{o['excess_rmse']:.4f} / {o['bias']:+.4f}")
            mean = methods["hbao"]["layers"]["obscurance"]["reference_mean"]
            print(f"| {name} | {mean:.4f} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
