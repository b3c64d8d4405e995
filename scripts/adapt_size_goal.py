#!/usr/bin/python3
"""Issue 20's size goal for adaptive order: order 8 adapted under courtyard (its own map as the prior) in <= 1/3 of
full order 8's bytes at <= 1.1x full order 8's error against the path tracer.

The set-up of scripts/adapt_figures.py (the bunny, `prt transfer --order 8 --samples 1024 --mode interreflected
--bounces 3 --albedo 0.8`, `prt reference --bounces 3 --albedo 0.8 --samples 16384 --seed 0`, cached in WORK), then
`prt adapt --max-error E --sh courtyard.json` in every storage format (float, half, u16 and u8 per-band codes with
per-vertex or per-cluster scales) over a grid of bounds E. Each bundle is relit under courtyard (`prt relight`) and
scored against the reference (relative RMSE as `prt compare`); bytes are the transfer layers' bytes as
`prt adapt --log-json` reports them, over full order 8's (768 per vertex). The error is also given with the
reference's own noise taken out, sqrt(rmse^2 - se^2) / sqrt(mean r^2 - se^2) (se: its per-value standard error).
Prints one row per (format, E) as JSON lines and the smallest bytes ratio within 1.1x, and writes
docs/charts/adapt_size_goal.csv.

Run from the repository root after the build and `make -f Makefile.data`:  scripts/adapt_size_goal.py
"""
import argparse
import csv
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from prt_commands import DATA, ROOT, run_logged  # noqa: E402


def run(args):
    """Runs a prt command; returns the JSON events of its --log-json stderr."""
    return run_logged(args, "adapt_size_goal")[2]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--prt", default=os.path.join(ROOT, "build", "prt"))
    parser.add_argument("--work", default=os.path.join(ROOT, "out", "adapt_goal"))
    parser.add_argument("--env", default="courtyard")
    parser.add_argument("--reference-samples", type=int, default=16384)
    parser.add_argument("--max-errors", default="0.0025,0.005,0.0075,0.01,0.015,0.02")
    parser.add_argument("--formats", default="float,half,u16:per-vertex,u16:per-cluster,u8:per-vertex,u8:per-cluster")
    parser.add_argument("--clusters", type=int, default=64)
    parser.add_argument("--extra", default="", help="more prt adapt flags, space-separated, for every row")
    opts = parser.parse_args()
    os.makedirs(opts.work, exist_ok=True)
    prt = [opts.prt, "--quiet", "--log-json"]
    env = os.path.join(DATA, "env", opts.env + ".exr")
    w = opts.work
    mesh, full, sh = f"{w}/bunny_mesh.glb", f"{w}/bunny_full8.glb", f"{w}/sh_{opts.env}.json"
    if not os.path.exists(full):
        run(prt + ["meshprep", os.path.join(DATA, "bunny.ply"), "-o", mesh])
        run(prt + ["transfer", mesh, "-o", full, "--order", "8", "--samples", "1024", "--mode", "interreflected",
                   "--bounces", "3", "--albedo", "0.8"])
    if not os.path.exists(sh):
        run(prt + ["envsh", env, "--order", "8", "-o", sh])
    ref, se = f"{w}/reference_{opts.env}_s{opts.reference_samples}.npy", f"{w}/reference_{opts.env}_se.npy"
    if not os.path.exists(ref):
        run(prt + ["reference", mesh, "--env", env, "-o", ref, "--stderr-out", se, "--bounces", "3", "--samples",
                   str(opts.reference_samples), "--albedo", "0.8,0.8,0.8", "--seed", "0"])
    r, s = np.load(ref).astype(np.float64), np.load(se).astype(np.float64)

    def scores(bundle, name):
        path = f"{w}/{name}.npy"
        run(prt + ["relight", bundle, "--env", env, "-o", path])
        a = np.load(path).astype(np.float64)
        raw = float(np.sqrt(np.mean((a - r) ** 2) / np.mean(r ** 2)))
        corrected = float(np.sqrt(max(np.mean((a - r) ** 2) - np.mean(s ** 2), 0) / (np.mean(r ** 2) - np.mean(s ** 2))))
        return raw, corrected

    full_raw, full_corrected = scores(full, "full8")
    print(json.dumps({"full_order_8": {"rel_vs_reference": full_raw, "noise_corrected": full_corrected,
                                       "reference_noise": float(np.sqrt(np.mean(s ** 2) / np.mean(r ** 2)))}}))
    rows = []
    for fmt in opts.formats.split(","):
        name, _, scales = fmt.partition(":")
        for E in [float(x) for x in opts.max_errors.split(",")]:
            out = f"{w}/adapt_{name}_{scales or 'none'}_{E}.glb"
            extra = ["--max-error", str(E), "--sh", sh, "--format", name] + (opts.extra.split() if opts.extra else [])
            if scales:
                extra += ["--scales", scales, "--clusters", str(opts.clusters)]
            events = run(prt + ["adapt", full, "-o", out] + extra)
            stats = next(e for e in events if e.get("event") == "adapt_stats")
            raw, corrected = scores(out, "adapt")
            row = dict(format=fmt, max_error=E, mean_order=stats["mean_order"],
                       bytes_ratio=stats["layer_bytes"] / stats["full_layer_bytes"],
                       bytes_per_vertex=stats["layer_bytes"] / stats["vertices"], rel_vs_full=stats["relative_rmse"],
                       rel_vs_reference=raw, error_ratio=raw / full_raw, noise_corrected_ratio=corrected / full_corrected)
            rows.append(row)
            print(json.dumps(row), flush=True)
    ok = [x for x in rows if x["error_ratio"] <= 1.1]
    best = min(ok, key=lambda x: x["bytes_ratio"]) if ok else None
    print(json.dumps({"smallest_within_1.1x": best}))
    path = os.path.join(ROOT, "docs", "charts", "adapt_size_goal.csv")
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        writer.writeheader()
        writer.writerows(rows)


if __name__ == "__main__":
    main()
