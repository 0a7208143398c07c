#!/usr/bin/env python3
"""Accuracy of every method on a set of jobs, as a markdown table, for one hfbake binary or two (before/after).

Bakes each job with each binary into OUT/<label>/<job name> (sharing one reference cache, so the Embree
reference is traced once) and reads the report.json files: per method.layer and job, excess_rmse and the
bias relative to the reference mean (bent normals and horizons: the mean angle error in degrees).

  tests/nightly/accuracy_table.py --hfbake build/baker/cli/hfbake [--vs OLD_HFBAKE] --out /tmp/acc \
      tests/nightly/fields/{fractal,blocks,terraces,craters,ridges,rough,dem}.json

A column per job, named after its file: dem.json is the lidar DEM (a 160^2 window of
../shared/data/TM1_564_146.tif read through tests/nightly/data/dem_400_300_160.vrt); without that folder the
job cannot load and its column is left out with a note.
"""
import argparse
import json
import os
import subprocess
import sys

LAYERS = ["p1.ao", "p1.vsky", "p1.direct", "p1.horizon", "p1.bent_normal", "p2.direct", "p2.indirect",
          "p2.total", "nlp.direct", "nlp.indirect", "nlp.total", "nlp.sh_visibility", "nlp.sh_irradiance",
          "hbao.obscurance", "lsao.obscurance", "hsao.obscurance", "farfield.obscurance", "vo.obscurance",
          "relief.svf", "relief.openness_positive", "relief.openness_negative"]


def bake(hfbake, job, out, cache, threads):
    cmd = ["nice", hfbake, "bake", job, "--out", out, "--cache", cache, "--quiet"]
    if threads:
        cmd += ["--threads", str(threads)]
    rc = subprocess.run(cmd).returncode
    if rc == 2 and os.path.basename(job) == "dem.json":  # bad input: ../shared/data is not there
        print(f"accuracy_table: {job} cannot load (is ../shared/data there?): no dem column", file=sys.stderr)
        return None
    if rc not in (0, 1):  # 1: a threshold failed, the report is still written
        sys.exit(f"accuracy_table: {' '.join(cmd)} exited {rc}")
    with open(os.path.join(out, "report.json")) as f:
        return json.load(f)


def cell(report, key):
    method, layer = key.split(".")
    m = report.get("methods", {}).get(method)
    if not m or layer not in m.get("layers", {}):
        return None
    s = m["layers"][layer]
    if "angle_mean_deg" in s:
        return f"{s['angle_mean_deg']:.2f} deg"
    mean = s.get("reference_mean") or 0
    bias = 100 * s["bias"] / mean if mean else float("nan")
    return f"{s['excess_rmse']:.4f} / {bias:+.1f} %"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--hfbake", required=True)
    ap.add_argument("--vs", help="a second binary (before): cells read 'before -> after'")
    ap.add_argument("--vs-jobs", help="folder with the before versions of the job files (same names), for jobs"
                    " whose keys the old binary does not know (e.g. git show OLD:jobs/... into it)")
    ap.add_argument("--out", required=True)
    ap.add_argument("--cache", help="reference cache (default OUT/cache)")
    ap.add_argument("--threads", type=int)
    ap.add_argument("jobs", nargs="+")
    a = ap.parse_args()
    cache = a.cache or os.path.join(a.out, "cache")
    binaries = [("after", a.hfbake)] + ([("before", a.vs)] if a.vs else [])
    reports = {}
    for job in a.jobs:
        name = os.path.splitext(os.path.basename(job))[0]
        for label, exe in binaries:
            path = os.path.join(a.vs_jobs, os.path.basename(job)) if label == "before" and a.vs_jobs else job
            reports[(name, label)] = bake(exe, path, os.path.join(a.out, label, name), cache, a.threads)
    names = [os.path.splitext(os.path.basename(j))[0] for j in a.jobs]
    names = [n for n in names if all(reports[(n, label)] is not None for label, _ in binaries)]
    print("excess_rmse / bias (% of the reference mean); bent normals and horizons: mean angle error"
          + ("; cells: before -> after" if a.vs else ""))
    print()
    print("| method.layer | " + " | ".join(names) + " |")
    print("|---|" + "---|" * len(names))
    for key in LAYERS:
        row = []
        for n in names:
            after = cell(reports[(n, "after")], key)
            before = cell(reports[(n, "before")], key) if a.vs else None
            if after is None and before is None:
                row.append("")
            elif a.vs:
                row.append(f"{before or '-'} -> {after or '-'}")
            else:
                row.append(after)
        if any(row):
            print(f"| {key} | " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
