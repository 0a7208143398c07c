#!/usr/bin/python3
"""Bakes every job under jobs/examples/ (and jobs/demo.json) as a user would from a fresh clone, and checks what
each example promises: exit 0, a report.json where the job has a reference, the engine textures of the game
example, GeoTIFFs with a CRS from the GIS example.

    tests/examples/bake_examples.py --hfbake build/baker/cli/hfbake --out /tmp/examples
"""
import argparse
import glob
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hfbake", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--gdalinfo", default="gdalinfo")
    args = parser.parse_args()
    jobs = sorted(glob.glob(os.path.join(ROOT, "jobs", "examples", "*.json"))) + [os.path.join(ROOT, "jobs", "demo.json")]
    failures = []
    cmd = [args.hfbake, "bake", *jobs, "--out", args.out, "--no-cache", "--quiet",
           "--summary", os.path.join(args.out, "summary.json")]
    print(" ".join(cmd), flush=True)
    rc = subprocess.call(cmd)
    if rc != 0:
        failures.append(f"hfbake bake exited {rc}")
    for job in jobs:
        with open(job) as f:
            doc = json.load(f)
        out = os.path.join(args.out, os.path.splitext(os.path.basename(job))[0])
        name = doc["name"]
        if "reference" in doc and not os.path.exists(os.path.join(out, "report.json")):
            failures.append(f"{job}: no report.json in {out}")
        for entry in doc.get("bake", []):
            stem = entry["method"]
            if sum(e["method"] == stem for e in doc["bake"]) == 1 and not isinstance(entry.get("directions"), list):
                if not os.path.exists(os.path.join(out, f"{name}.{stem}.exr")):
                    failures.append(f"{job}: no {name}.{stem}.exr in {out}")
        for t in doc.get("output", {}).get("textures", []):
            if not glob.glob(os.path.join(out, "textures", f"{name}.*")):
                failures.append(f"{job}: no textures in {out}/textures")
        if doc.get("output", {}).get("geotiff"):
            tifs = sorted(glob.glob(os.path.join(out, f"{name}.*.tif")))
            if not tifs:
                failures.append(f"{job}: no GeoTIFF in {out}")
            for tif in tifs:
                info = subprocess.run([args.gdalinfo, tif], capture_output=True, text=True).stdout
                if "Coordinate System is:" not in info or 'ID["EPSG"' not in info:
                    failures.append(f"{tif}: no CRS")
    for f in failures:
        print("FAILED: " + f, file=sys.stderr)
    print(f"{len(jobs)} example jobs baked, {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
