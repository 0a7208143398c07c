#!/usr/bin/env python3
"""The obscurance cost/accuracy table of a frontier or budget job (tests/accuracy/obscurance_*.json).

    hfbake bake tests/accuracy/obscurance_frontier.json --threads 2 --summary S.json
    python3 tests/ao/frontier_table.py out/obscurance_frontier/report.json S.json

Per run: the swept parameters, obscurance excess_rmse / bias / rmse against the reference, wall seconds and
process CPU seconds (from the bake summary), and texels per second at 2 threads computed from the CPU
seconds (texels / (cpu / 2): what 2 threads of an otherwise idle machine deliver; the wall time of a loaded
machine measures the other users too).
"""
import json
import sys


def find_cpu(summary, stem):
    """cpu_seconds of a run in the bake summary (searched anywhere, the layout is the CLI's)."""
    if isinstance(summary, dict):
        for k, v in summary.items():
            if k == stem and isinstance(v, dict) and "cpu_seconds" in v:
                return v["cpu_seconds"]
            r = find_cpu(v, stem)
            if r is not None:
                return r
    elif isinstance(summary, list):
        for v in summary:
            r = find_cpu(v, stem)
            if r is not None:
                return r
    return None


def main():
    report = json.load(open(sys.argv[1]))
    summary = json.load(open(sys.argv[2])) if len(sys.argv) > 2 else {}
    size = report.get("size", [0, 0])
    texels = size[0] * size[1] if isinstance(size, list) else 0
    ref = report.get("reference", {})
    print("job %s, %s texels; reference: %s" % (report.get("job"), size, json.dumps(ref)[:300]))
    print("| run | parameters | excess_rmse | bias | rmse | wall s | CPU s | Mtexel/s (2 thr, from CPU) |")
    print("|---|---|---|---|---|---|---|---|")
    for stem, m in report["methods"].items():
        ob = m.get("layers", {}).get("obscurance")
        if ob is None:
            continue
        p = {k: v for k, v in m.get("parameters", {}).items()
             if k not in ("method", "layers", "radius", "falloff")}
        cpu = find_cpu(summary, stem)
        rate = "%.2f" % (texels / (cpu / 2) / 1e6) if cpu and texels else "-"
        print("| %s | %s | %.4f | %+.4f | %.4f | %.1f | %s | %s |" % (
            stem, json.dumps(p, separators=(",", ":")), ob["excess_rmse"], ob["bias"], ob["rmse"],
            m.get("seconds", 0), "%.1f" % cpu if cpu else "-", rate))


if __name__ == "__main__":
    main()
