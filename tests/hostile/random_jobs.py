#!/usr/bin/env python3
"""Random valid jobs in combinations the examples never use, each baked under a time limit.

Fields of every procedural kind at odd and thin sizes, clamp or repeat, lights at any azimuth and elevation,
every method with parameters drawn across their schema ranges, 0-3 bounces. A job that validate refuses is
counted, not an error; a bake that crashes, hangs (TIMEOUT seconds), exits other than 0/1 after validate
accepted it (a non-finite output is one: the bake refuses to write it) is a finding: its job file is kept in OUT/findings/.

  tests/hostile/random_jobs.py --hfbake build/baker/cli/hfbake --out /tmp/rj --count 200 [--seed 1]
"""
import argparse
import json
import math
import os
import random
import shutil
import subprocess
import sys

KINDS = ["fractal", "sines", "blocks", "bricks", "terraces", "craters", "ridges", "rough", "flat", "pit", "cone",
         "trench", "slope"]
FALLOFFS = ["none", "step", "linear", "smooth", "exponential", "rational"]


def rand_dir(r):
    el = r.uniform(-0.2, 1.0) if r.random() < 0.9 else r.choice([0.0, 1.0])
    az = r.uniform(-math.pi, math.pi) if r.random() < 0.7 else math.atan2(r.randint(-5, 5), r.randint(-5, 5) or 1)
    return [math.cos(az) * math.cos(el), math.sin(az) * math.cos(el), math.sin(el)]


def method(r, name):
    m = {"method": name}
    if name == "p1":
        m["directions"] = r.choice([1, 2, 3, 5, 7, 8, 12, 17, 32, 37])
        m["layers"] = r.sample(["ao", "vsky", "direct", "horizon", "horizon_distance", "bent_normal"],
                               r.randint(1, 6))
        if r.random() < 0.3:
            m["near_radius"] = r.choice([1, 1.5, 3, 7, 20])
        if r.random() < 0.3:
            m["normal_bins"] = r.choice([0, 3, 7, 15])
    elif name == "p2":
        m["directions"] = r.choice([1, 3, 4, 8, 13, 16])
        if r.random() < 0.3:
            m["supersampling"] = r.choice([1, 2, 3, 5])
        if r.random() < 0.3:
            m["near_radius"] = r.choice([0, 1, 2.5, 6])
        if r.random() < 0.2:
            m["senders"] = "texels"
        if r.random() < 0.2:
            m["visibility"] = "naive"
    elif name == "nlp":
        m["directions"] = r.choice([3, 4, 7, 8, 16])
        if r.random() < 0.3:
            m["levels_per_octave"] = r.choice([1, 2, 4])
        if r.random() < 0.3:
            m["indirect_cosine"] = r.choice(["sh", "exact"])
    elif name == "relief":
        m["directions"] = r.choice([1, 4, 9, 16])
        m["search_radius"] = r.choice([0.5, 1, 3, 10, 100])
    elif name == "sun":
        minutes = r.choice([30, 120, 1440])
        day = r.randint(1, 28)
        m["latitude"] = r.choice([r.uniform(-89.9, 89.9), 0.0, 66.6, -89.9])
        m["longitude"] = r.uniform(-180, 180)
        m["start"] = f"2026-{r.randint(1, 12):02d}-{day:02d}T{r.randint(0, 21):02d}:00"
        end_h = int(m["start"][11:13]) * 60 + minutes
        m["end"] = f"2026-{m['start'][5:7]}-{day + end_h // 1440:02d}T{(end_h % 1440) // 60:02d}:{end_h % 60:02d}"
        m["utc_offset"] = r.choice([-5, 0, 2, 5.5])
        m["step_minutes"] = r.choice([10, 15, 30])
        m["layers"] = r.sample(["irradiation", "beam", "sky", "sun_hours"], r.randint(1, 4))
        if r.random() < 0.3:
            m["directions"] = r.choice([1, 3, 16])
    else:
        m["radius"] = r.choice([0.3, 1, 2.5, 4, 8, 13, 40])
        if name != "vo":
            m["directions"] = r.choice([1, 2, 3, 4, 7, 8, 16])
        if name in ("hbao", "lsao", "farfield"):
            m["falloff"] = r.choice(FALLOFFS)
        if name == "hsao":
            m["falloff"] = r.choice(["step", "linear", "smooth"])
        if name == "farfield" and r.random() < 0.5:
            m["near_field"] = r.choice([0, 1, 3, 12])
        if name == "hbao" and r.random() < 0.3:
            m["surface"] = "triangles"
        if name == "vo" and r.random() < 0.3:
            m["depth_layers"] = r.choice([1, 2, 4, 8])
    return m


def job(r, i):
    w = r.choice([2, 3, 5, 17, 31, 33, 48, 64, 80]) if r.random() < 0.8 else r.choice([1, 2, 3])
    h = r.choice([2, 3, 5, 17, 31, 33, 48, 64, 80]) if r.random() < 0.8 else r.choice([200, 400])
    if r.random() < 0.5:
        w, h = h, w
    j = {"version": 1, "name": f"r{i}",
         "height": {"procedural": {"kind": r.choice(KINDS), "size": [w, h], "seed": r.randint(0, 99)},
                    "texel_size": r.choice([0.1, 0.5, 1, 2, 30]),
                    "wrap": r.choice(["clamp", "clamp", "repeat"])},
         "surface": {"albedo": r.choice([0, 0.3, 0.9, [0.2, 0.5, 0.8]])},
         "bounces": r.choice([0, 0, 1, 2, 3]),
         "bake": [method(r, n) for n in r.sample(["p1", "p2", "nlp", "hbao", "lsao", "hsao", "farfield", "vo",
                                                  "relief"], r.randint(1, 4))],
         "output": {"dir": "out", "previews": r.random() < 0.3}}
    if r.random() < 0.5:
        j["height"]["height_scale"] = r.choice([0.01, 0.5, 3, 20])
    if r.random() < 0.6:
        j["lights"] = [{"directional": {"direction": rand_dir(r), "irradiance": r.choice([1, 5]),
                                        "angular_diameter_deg": r.choice([0, 0.53, 5])}}
                       for _ in range(r.randint(1, 3))]
    env = r.choice(["uniform", "sky", "none"])
    if env == "uniform":
        j["environment"] = {"uniform": [r.random(), r.random(), r.random()]}
    elif env == "sky":
        j["environment"] = {"sky": {"sun": {"elevation_deg": r.uniform(-5, 90), "azimuth_deg": r.uniform(0, 360)}}}
    if r.random() < 0.3:
        j["reference"] = {"samples": r.choice([4, 16]), "seed": r.randint(1, 9)}
    # sun from a generator of its own, so the rest of every job is what the same seed always made
    rs = random.Random(f"sun {i} {r.getstate()[1][:4]}")
    if rs.random() < 0.25:
        j["bake"].append(method(rs, "sun"))
    return j


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--hfbake", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--count", type=int, default=100)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=120)
    a = ap.parse_args()
    r = random.Random(a.seed)
    os.makedirs(os.path.join(a.out, "findings"), exist_ok=True)
    counts = {"baked": 0, "refused": 0, "findings": 0}
    for i in range(a.count):
        j = job(r, i)
        d = os.path.join(a.out, f"job{i}")
        os.makedirs(d, exist_ok=True)
        path = os.path.join(d, "job.json")
        with open(path, "w") as f:
            json.dump(j, f, indent=1)
        v = subprocess.run([a.hfbake, "validate", path], capture_output=True, text=True)
        w, h = j["height"]["procedural"]["size"]
        if v.returncode == 2 and "to bake" in v.stderr and w * h <= 1 << 20:
            # A memory refusal of a field this small is an estimate gone wrong (farfield at K = 2 once asked
            # 17 billion GiB for 3x48).
            counts["findings"] += 1
            shutil.copy(path, os.path.join(a.out, "findings", f"job{i}.json"))
            print(f"finding: job{i}: validate refused a {w}x{h} field for memory: {v.stderr.strip()[:300]}")
            continue
        if v.returncode == 2:
            counts["refused"] += 1
            shutil.rmtree(d)
            continue
        try:
            p = subprocess.run(["nice", a.hfbake, "bake", path, "--quiet", "--threads", "2"],
                               capture_output=True, text=True, timeout=a.timeout)
            rc, err = p.returncode, p.stderr.strip()
        except subprocess.TimeoutExpired:
            subprocess.run(["pkill", "-9", "-f", path])
            rc, err = "timeout", ""
        if rc in (0, 1) and v.returncode == 0:
            counts["baked"] += 1
            shutil.rmtree(d)
            continue
        counts["findings"] += 1
        shutil.copy(path, os.path.join(a.out, "findings", f"job{i}.json"))
        print(f"finding: job{i}: validate {v.returncode}, bake {rc}: {err[:300]}", flush=True)
    print(json.dumps(counts))
    return 1 if counts["findings"] else 0


if __name__ == "__main__":
    sys.exit(main())
