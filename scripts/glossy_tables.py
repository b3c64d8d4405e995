#!/usr/bin/python3
"""Markdown tables for docs/results.md from out/glossy/glossy_results.json (written by glossy_figures.py)."""
import json, os, sys
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
r = json.load(open(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "out", "glossy", "glossy_results.json")))
print("| lobes | problems | PoCL ms/fit | Ceres ms/fit | speed ratio | PoCL cost | Ceres cost | within 1% of Ceres | iterations PoCL / Ceres |")
print("|---|---|---|---|---|---|---|---|---|")
import glob
folder = os.path.dirname(sys.argv[1]) if len(sys.argv) > 1 else os.path.join(ROOT, "out", "glossy")
solvers = {json.load(open(f))["lobes"]: json.load(open(f)) for f in glob.glob(os.path.join(folder, "compare_*.json"))}
for n, s in sorted(solvers.items()):
    print(f"| {n} | {s['problems']} | {s['pocl_ms_per_fit']:.3f} | {s['ceres_ms_per_fit']:.3f} | {s['speed_ratio']:.1f}x | "
          f"{s['pocl_cost']:.4g} | {s['ceres_cost']:.4g} | {100 * s['share_within_1pct']:.1f}% | "
          f"{s['pocl_mean_iterations']:.1f} / {s['ceres_mean_iterations']:.1f} |")
print()
envs = sorted({k.split("/")[0] for k in r["errors"]})
exps = sorted({int(k.split("/")[1][1:]) for k in r["errors"]})
lobes = sorted({int(k.split("/")[2][1:]) for k in r["errors"]})
eyes = sorted({k.split("/")[3] for k in r["errors"]})
for part in ("full", "glossy"):
    print(f"Relative RMSE against `prt reference`, {'view-dependent radiance (diffuse + glossy)' if part == 'full' else 'glossy part alone'}, mean over eyes {', '.join(eyes)}:")
    print()
    print("| env | exponent | " + " | ".join(f"{n} lobe{'s' if n > 1 else ''}" for n in lobes) + " |")
    print("|---|---|" + "---|" * len(lobes))
    for env in envs:
        for e in exps:
            vals = [np.mean([r["errors"][f"{env}/e{e}/n{n}/{eye}/{part}"] for eye in eyes]) for n in lobes]
            print(f"| {env} | {e} | " + " | ".join(f"{100 * v:.1f}%" for v in vals) + " |")
    print()
print("| fit (bunny, 1839 vertices) | problems | fit s | tabulate s | whole stage s | peak MiB | mean fit residual | view flips | vertex flips |")
print("|---|---|---|---|---|---|---|---|---|")
for name, s in list(r["fit_stats"].items()) + list(r["extra_stats"].items()):
    vf = f"{s['view_flips']}/{s['view_pairs']}" if s.get("view_pairs") else "-"
    xf = f"{s['vertex_flips']}/{s['vertex_pairs']}" if s.get("vertex_pairs") else "-"
    print(f"| {name} (grid {s.get('grid')}, {'coherence' if s.get('coherence') else 'no coherence'}) | {s['problems']} | "
          f"{s['fit_seconds']:.1f} | {s['tabulate_seconds']:.1f} | {s['seconds']:.1f} | {s['peak_memory_bytes'] / 2**20:.0f} | "
          f"{100 * s['mean_relative_error']:.1f}% | {vf} | {xf} |")
print()
print("Failure map (glossy part, courtyard, front eye, per-vertex luminance error RMS over the reference's RMS):")
print()
for key, cats in r["failure_map"].items():
    print(f"| {key} | vertices | relative RMS error | mean fit residual |")
    print("|---|---|---|---|")
    for name, c in cats.items():
        err = "-" if c["relative_rms_error"] is None else f"{100 * c['relative_rms_error']:.1f}%"
        res = "-" if c["mean_fit_residual"] is None else f"{100 * c['mean_fit_residual']:.1f}%"
        print(f"| {name} | {c['vertices']} | {err} | {res} |")
    print()
print(f"float16 against float32 lobes (1 lobe, n=32, glossy part, courtyard, front eye): relative RMSE "
      f"{100 * r['float16_vs_float32_relative_rmse']:.3f}%")
