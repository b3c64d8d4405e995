#!/usr/bin/python3
"""Regenerates the FIV figures of docs/results.md: builds and runs build/tests/fiv/fiv_figures (minutes; its
brute-force references are cached in .cache/fiv_figures/), then draws docs/charts/fiv_nrmse.png (shadow NRMSE
against grid size and against precompute time, one line per scene and map) and copies the JSON and the shadow
images next to it.

    scripts/fiv_figures.py            # measure and chart
    scripts/fiv_figures.py --from J   # chart an existing fiv_figures.json
"""
import json
import os
import shutil
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
charts = os.path.join(root, "docs", "charts")
work = os.path.join(root, ".cache", "fiv_figures")


def measure():
    os.makedirs(work, exist_ok=True)
    subprocess.run(["cmake", "--build", os.path.join(root, "build"), "-j2", "--target", "fiv_figures"], check=True)
    data = os.path.join(root, ".cache", "data")
    with open(os.path.join(work, "fiv_figures.json"), "w") as out:
        subprocess.run([os.path.join(root, "build", "tests", "fiv", "fiv_figures"), os.path.join(data, "bunny.ply"),
                        os.path.join(data, "env"), work], check=True, stdout=out)
    return os.path.join(work, "fiv_figures.json")


def chart(path):
    with open(path) as f:
        report = json.load(f)
    os.makedirs(charts, exist_ok=True)
    # The defaults: partial "cap", overlap "cap" (equal to "cap+paper" where there is one occluder).
    multi = {(r["scene"], r["map"], r["grid"]) for r in report["results"] if r["mode"] == "cap+cap"}
    rows = [r for r in report["results"] if r["storage"] == "float16" and
            (r["mode"] == "cap+cap" or (r["mode"] == "cap+paper" and (r["scene"], r["map"], r["grid"]) not in multi))]
    lines = {}
    for r in rows:
        lines.setdefault((r["scene"], r["map"]), []).append(r)
    fig, axes = plt.subplots(1, 2, figsize=(15, 5.5))
    scenes = sorted({scene for scene, _ in lines})
    styles = {"courtyard": "-", "sunrise": "--", "constant": ":"}
    for (scene, env), points in sorted(lines.items()):
        if len(points) < 2:
            continue
        points.sort(key=lambda r: r["samples"])
        label = f"{scene}, {env}"
        style = dict(marker="o", label=label, color=f"C{scenes.index(scene)}", linestyle=styles.get(env, "-"))
        axes[0].plot([p["samples"] for p in points], [p["nrmse"] for p in points], **style)
        axes[1].plot([p["visibility_seconds"] for p in points], [p["nrmse"] for p in points], **style)
    for ax, xlabel in zip(axes, ["grid samples (NT x NP x NR)", "precompute (visibility) seconds, 2 threads"]):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(xlabel)
        ax.set_ylabel("shadow NRMSE vs brute force")
        ax.grid(True, which="both", alpha=0.3)
    for seed, label in [(0.023, "seed 32x17x15"), (0.008, "seed 64x33x30")]:
        axes[0].axhline(seed, color="grey", linestyle=":", linewidth=1)
        axes[0].text(axes[0].get_xlim()[0], seed, " " + label, fontsize=7, color="grey", va="bottom")
    axes[1].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.suptitle("FIV shadows of the bunny: error against grid size and precompute time")
    fig.tight_layout()
    fig.savefig(os.path.join(charts, "fiv_nrmse.png"), dpi=110)
    shutil.copy(path, os.path.join(charts, "fiv_figures.json"))
    folder = os.path.dirname(path)
    for name in os.listdir(folder):
        if name.startswith("fiv_shadow_") and name.endswith(".png"):
            shutil.copy(os.path.join(folder, name), os.path.join(charts, name))
    print(os.path.join(charts, "fiv_nrmse.png"))


if __name__ == "__main__":
    if len(sys.argv) > 2 and sys.argv[1] == "--from":
        chart(sys.argv[2])
    else:
        chart(measure())
