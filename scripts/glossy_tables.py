#!/usr/bin/python3
"""Markdown tables for docs/results.md from out/glossy/glossy_results.json (written by glossy_figures.py)."""
import json, os, sys
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "out", "glossy", "glossy_results.json")
r = json.load(open(path))
folder = os.path.dirname(path)

print("| lobes | problems | PoCL ms/fit | Ceres ms/fit | speed ratio | PoCL cost | Ceres cost | within 1% of Ceres | iterations PoCL / Ceres |")
print("|---|---|---|---|---|---|---|---|---|")
for n, s in sorted(r["solvers"].items()):
    print(f"| {n} | {s['problems']} | {s['pocl_ms_per_fit']:.3f} | {s['ceres_ms_per_fit']:.3f} | {s['speed_ratio']:.1f}x | "
          f"{s['pocl_cost']:.4g} | {s['ceres_cost']:.4g} | {100 * s['share_within_1pct']:.1f}% | "
          f"{s['pocl_mean_iterations']:.1f} / {s['ceres_mean_iterations']:.1f} |")
print()

envs = sorted({k.split("/")[0] for k in r["errors"]})
exps = sorted({int(k.split("/")[1][1:]) for k in r["errors"]})
lobes = sorted({int(k.split("/")[2][1:]) for k in r["errors"]})
eyes = list(r["eyes"])
for part in ("full", "glossy"):
    what = "view-dependent radiance (diffuse SH + glossy)" if part == "full" else "glossy part alone"
    print(f"Relative RMSE against `prt reference`, {what}, mean over the eyes {', '.join(eyes)} "
          f"(reference noise: its standard error's RMS over its RMS):")
    print()
    print("| env | exponent | " + " | ".join(f"{n} lobe{'s' if n > 1 else ''}" for n in lobes) + " | reference noise |")
    print("|---|---|" + "---|" * (len(lobes) + 1))
    for env in envs:
        for e in exps:
            vals = [np.mean([r["errors"][f"{env}/e{e}/n{n}/{eye}/{part}"] for eye in eyes]) for n in lobes]
            noise = np.mean([r["reference_noise"][f"{env}/e{e}/{eye}/{part}"] for eye in eyes])
            print(f"| {env} | {e} | " + " | ".join(f"{100 * v:.1f}%" for v in vals) + f" | {100 * noise:.1f}% |")
    print()

print("Per eye, glossy part alone, courtyard:")
print()
print("| exponent | eye | " + " | ".join(f"{n} lobes" for n in lobes) + " |")
print("|---|---|" + "---|" * len(lobes))
for e in exps:
    for eye in eyes:
        print(f"| {e} | {eye} | " + " | ".join(f"{100 * r['errors'][f'courtyard/e{e}/n{n}/{eye}/glossy']:.1f}%" for n in lobes) + " |")
print()

def flips(s, kind):
    return f"{s[kind + '_flips']}/{s[kind + '_pairs']} ({100 * s[kind + '_flips'] / s[kind + '_pairs']:.1f}%)" if s.get(kind + "_pairs") else "-"

print("| fit (bunny, 1839 vertices, grid 6x8x8) | problems | fit s | whole stage s | peak MiB | mean fit residual | view flips | vertex flips | bytes/vertex |")
print("|---|---|---|---|---|---|---|---|---|")
for name, s in r["fit_stats"].items():
    print(f"| {name} | {s['problems']} | {s['fit_seconds']:.1f} | {s['seconds']:.1f} | {s['peak_memory_bytes'] / 2**20:.0f} | "
          f"{100 * s['mean_relative_error']:.1f}% | {flips(s, 'view')} | {flips(s, 'vertex')} | "
          f"{s['lobe_layer_bytes_per_vertex'] + 108:.0f} |")
print()

print("Coherence weights (beta = gamma = delta = w; 2 lobes, Phong n = 32; glossy error: courtyard, mean over the eyes):")
print()
print("| w | mean fit residual | view flips | vertex flips | glossy relative RMSE | fit s |")
print("|---|---|---|---|---|---|")
for w in sorted(r["weight_stats"], key=float):
    s = r["weight_stats"][w]
    label = "0 (--no-coherence)" if float(w) == 0 else w
    print(f"| {label} | {100 * s['mean_relative_error']:.2f}% | {flips(s, 'view')} | {flips(s, 'vertex')} | "
          f"{100 * r['weight_errors'][w]:.2f}% | {s['fit_seconds']:.1f} |")
print()

print("Failure map (glossy part, courtyard, front eye; per-vertex luminance error RMS over the reference's RMS on "
      "the vertices facing the eye):")
print()
keys = list(r["failure_map"])
cats = list(r["failure_map"][keys[0]])
print("| category | vertices | " + " | ".join(keys) + " |")
print("|---|---|" + "---|" * len(keys))
for c in cats:
    cells = []
    for k in keys:
        v = r["failure_map"][k][c]
        cells.append("-" if v["relative_rms_error"] is None else f"{100 * v['relative_rms_error']:.1f}% (fit {100 * v['mean_fit_residual']:.0f}%)")
    print(f"| {c} | {r['failure_map'][keys[0]][c]['vertices']} | " + " | ".join(cells) + " |")
print()

print("Quantisation (1 lobe, n = 32, glossy part, courtyard):")
print()
print("| eye | float16 against float32 | float32 against reference | float16 against reference |")
print("|---|---|---|---|")
for eye, q in r["quantisation"].items():
    print(f"| {eye} | {100 * q['float16_vs_float32']:.3f}% | {100 * q['float32_vs_reference']:.2f}% | {100 * q['float16_vs_reference']:.2f}% |")
strip = os.path.join(folder, "strip_metrics.json")
if os.path.exists(strip):
    print()
    print(f"Strip: relative RMSE over the bunny's pixels {100 * json.load(open(strip))['image_relative_rmse']:.1f}%")
if "indirect" in r:
    print()
    print("Indirect glossy (1 lobe, n = 32, diffuse 1 bounce; full radiance against a 1-bounce reference, courtyard):")
    print()
    eyes_i = [k for k in next(iter(r["indirect"].values())) if k != "fit_seconds"]
    print("| glossy part | " + " | ".join(eyes_i) + " | stage s |")
    print("|---|" + "---|" * (len(eyes_i) + 1))
    for label, v in r["indirect"].items():
        print(f"| {label} | " + " | ".join(f"{100 * v[e]:.2f}%" for e in eyes_i) + f" | {v['fit_seconds']:.1f} |")
