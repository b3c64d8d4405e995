#!/usr/bin/python3
"""Speed-versus-accuracy sweep: transfer + relight against the path-traced reference.

For one mesh and the HDR maps in .cache/data/env it runs `prt transfer` over SH orders, sample counts and bounce
counts, relights each result with `prt relight`, scores it with `prt compare` against `prt reference` (same albedo,
same bounce count), and writes
  docs/charts/sweep.csv            one row per (env, order, samples, bounces)
  docs/charts/figures.md           the figures table: relative RMSE per figure map at orders 3, 5, 8
  docs/charts/time_vs_error.png    transfer time against relative RMSE, one curve per (order, bounces), one panel
                                   per figure map (courtyard, forest, sunset)
  docs/charts/error_vs_order.png   relative RMSE against SH order, one curve per HDR map (bounces and samples
                                   fixed), with the knee where the error stops falling fast marked; a second panel
                                   shows SH truncation alone (each order against a high-order relight of the same
                                   transfer samples): where truncation and ringing break the method (sharp suns)

Run from the repository root after the build and `make -f Makefile.data`:  scripts/sweep.py
(`--quick` is a small sweep for checking the script; it writes to WORK/quick, not docs/charts.)

The references are the expensive part. They are cached in the work directory (out/sweep by default) under a name
that holds every setting, with a JSON sidecar that records the hashes of the mesh and the map: a rerun only
recomputes the transfers, relights and charts (a few minutes). Transfer times are the stage's own wall-clock time
as `prt --log-json` reports it (process start-up excluded), the minimum over --repeats runs.
"""
import argparse
import csv
import glob
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from prt_commands import DATA, ROOT, file_hash, run_logged, stage_seconds  # noqa: E402

# The maps the figure names; they get the grid sweep and the higher-sample references.
FIGURE_ENVS = ["courtyard", "forest", "sunset"]


def run(args):
    return run_logged(args, "sweep")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--prt", default=os.path.join(ROOT, "build", "prt"))
    parser.add_argument("--mesh", default=os.path.join(DATA, "bunny.ply"))
    parser.add_argument("--envs", default="",
                        help="comma-separated map names for the order sweep (default: every .cache/data/env/*.exr)")
    parser.add_argument("--figure-envs", default=",".join(FIGURE_ENVS),
                        help="maps of the time/error grid and the figures table (default: %(default)s)")
    parser.add_argument("--out", default=None, help="charts and CSV (default: docs/charts)")
    parser.add_argument("--work", default=os.path.join(ROOT, "out", "sweep"), help="intermediate files and cache")
    parser.add_argument("--albedo", type=float, default=0.8, help="grey albedo of transfer and reference")
    parser.add_argument("--bounces", type=int, default=3, help="bounces of the references and of the order sweep")
    parser.add_argument("--reference-samples", type=int, default=262144,
                        help="paths per vertex of the figure maps' references (default: %(default)s)")
    parser.add_argument("--other-reference-samples", type=int, default=65536,
                        help="paths per vertex of the other maps' references, whose errors are larger")
    parser.add_argument("--order-sweep-samples", type=int, default=16384, help="transfer samples of the order sweep")
    parser.add_argument("--max-order", type=int, default=12, help="the order sweep runs 1..this")
    parser.add_argument("--truncation-order", type=int, default=24,
                        help="high-order relight that the truncation-only curves are measured against")
    parser.add_argument("--repeats", type=int, default=2, help="transfer runs per setting; the fastest counts")
    parser.add_argument("--quick", action="store_true", help="a small sweep, for checking the script")
    parser.add_argument("--plot-only", action="store_true", help="redraw the charts from OUT/sweep.csv")
    opts = parser.parse_args()

    available = sorted(os.path.splitext(os.path.basename(p))[0] for p in glob.glob(os.path.join(DATA, "env", "*.exr")))
    envs = opts.envs.split(",") if opts.envs else available
    figure_envs = [e for e in opts.figure_envs.split(",") if e]
    for env in set(envs) | set(figure_envs):
        if not os.path.exists(env_path(env)):
            sys.exit(f"sweep: no map {env_path(env)} (have: {', '.join(available)}); run make -f Makefile.data")
    envs = figure_envs + [e for e in envs if e not in figure_envs]

    orders = [3, 5, 8]
    samples = [16, 64, 256, 1024, 4096, 16384]
    bounces = [0, 1, opts.bounces]
    order_sweep = list(range(1, opts.max_order + 1))
    if opts.quick:
        envs, figure_envs = envs[:2], figure_envs[:1]
        orders, samples, bounces, order_sweep = [3, 5], [64, 256], [0, opts.bounces], [1, 3, 5]
        opts.reference_samples = opts.other_reference_samples = 1024
        opts.order_sweep_samples, opts.truncation_order, opts.repeats = 256, 8, 1
        opts.work = os.path.join(opts.work, "quick")
    if opts.out is None:
        opts.out = opts.work if opts.quick else os.path.join(ROOT, "docs", "charts")
    albedo = f"{opts.albedo:g}"
    if opts.plot_only:
        with open(os.path.join(opts.out, "sweep.csv")) as f:
            table = [{k: (v if k in ("env", "truncation_relative_rmse") and v == "" or k == "env" else float(v))
                      for k, v in r.items()} for r in csv.DictReader(f)]
        envs = [e for e in envs if any(r["env"] == e for r in table)]
        write_figures(table, figure_envs, orders, samples, opts)
        plot(table, envs, figure_envs, orders, bounces, samples, order_sweep, opts)
        return

    sweep_start = time.monotonic()
    os.makedirs(opts.work, exist_ok=True)
    os.makedirs(opts.out, exist_ok=True)
    prt = [opts.prt, "--quiet", "--log-json"]
    mesh = os.path.join(opts.work, "mesh.glb")
    run(prt + ["meshprep", opts.mesh, "-o", mesh])
    mesh_hash = file_hash(mesh)

    import numpy as np

    # References, cached by every setting that changes them.
    reference = {}
    for env in envs:
        count = opts.reference_samples if env in figure_envs else opts.other_reference_samples
        stem = os.path.join(opts.work, f"reference_{env}_b{opts.bounces}_a{albedo}_s{count}_seed0")
        record_path = stem + ".json"
        key = dict(mesh=mesh_hash, env=file_hash(env_path(env)), bounces=opts.bounces, albedo=albedo,
                   samples=count, seed=0)
        record = None
        if os.path.exists(record_path):
            with open(record_path) as f:
                record = json.load(f)
            if record.get("key") != key or not os.path.exists(stem + ".npy") or not os.path.exists(stem + "_se.npy"):
                record = None
        if record is None:
            wall, _, events = run(prt + ["reference", mesh, "--env", env_path(env), "-o", stem + ".npy",
                                         "--stderr-out", stem + "_se.npy", "--bounces", str(opts.bounces),
                                         "--samples", str(count), "--albedo", ",".join([albedo] * 3)])
            radiance, stderr = np.load(stem + ".npy").astype(np.float64), np.load(stem + "_se.npy").astype(np.float64)
            record = dict(key=key, seconds=stage_seconds(events, wall),
                          # what `prt reference` logs: mean standard error over mean radiance
                          mean_relative_stderr=float(stderr.sum() / radiance.sum()),
                          # the same noise in relative-RMSE terms: the floor a perfect result would score
                          rms_relative_stderr=float(np.sqrt(np.mean(stderr ** 2) / np.mean(radiance ** 2))),
                          mean_squared_stderr=float(np.mean(stderr ** 2)))
            with open(record_path + ".tmp", "w") as f:
                json.dump(record, f, indent=2)
            os.replace(record_path + ".tmp", record_path)
            status = f"{record['seconds']:.1f} s"
        else:
            status = "cached"
        record["path"], record["samples"] = stem + ".npy", count
        reference[env] = record
        print(f"reference {env:10s} {count:7d} samples: standard error {100 * record['mean_relative_stderr']:.3f}% "
              f"of mean radiance ({status})", flush=True)

    transfers = {}  # (order, samples, bounces) -> (bundle, stage seconds, process CPU seconds)

    def transfer(order, count, bounce):
        key = (order, count, bounce)
        if key in transfers:
            return transfers[key]
        bundle = os.path.join(opts.work, f"t_o{order}_s{count}_b{bounce}.glb")
        args = ["transfer", mesh, "-o", bundle, "--order", str(order), "--samples", str(count), "--albedo", albedo]
        args += ["--mode", "interreflected", "--bounces", str(bounce)] if bounce > 0 else ["--mode", "shadowed"]
        best, best_cpu = float("inf"), float("inf")
        for _ in range(max(1, opts.repeats)):
            before = os.times()
            wall, _, events = run(prt + args)
            after = os.times()
            best = min(best, stage_seconds(events, wall))
            best_cpu = min(best_cpu, (after.children_user - before.children_user)
                           + (after.children_system - before.children_system))
        transfers[key] = (bundle, best, best_cpu)
        return transfers[key]

    rows = {}

    def relight(bundle, env, name):
        radiance = os.path.join(opts.work, f"{name}.npy")
        wall, _, events = run(prt + ["relight", bundle, "--env", env_path(env), "-o", radiance])
        return radiance, stage_seconds(events, wall)

    def compare(result, ref):
        _, text, _ = run([opts.prt, "--quiet", "compare", result, ref])
        return json.loads(text)

    def score(env, order, count, bounce):
        if (env, order, count, bounce) in rows:
            return rows[(env, order, count, bounce)]
        bundle, seconds, cpu = transfer(order, count, bounce)
        radiance, relight_seconds = relight(bundle, env, f"r_{env}_o{order}_s{count}_b{bounce}")
        ref = reference[env]
        metrics = compare(radiance, ref["path"])
        # Reference noise adds in quadrature to the error: E[rmse^2] = error^2 + mean(stderr^2).
        reference_rms = metrics["rmse"] / metrics["relative_rmse"] if metrics["relative_rmse"] else float("nan")
        corrected = np.sqrt(max(metrics["rmse"] ** 2 - ref["mean_squared_stderr"], 0.0)) / reference_rms
        row = dict(env=env, order=order, samples=count, bounces=bounce, albedo=albedo,
                   transfer_seconds=round(seconds, 4), transfer_cpu_seconds=round(cpu, 3),
                   relight_seconds=round(relight_seconds, 4),
                   relative_rmse=metrics["relative_rmse"], relative_rmse_noise_corrected=float(corrected),
                   rmse=metrics["rmse"], nrmse=metrics["nrmse"], max_abs_error=metrics["max_abs_error"],
                   mean_abs_luminance_error=metrics["mean_abs_luminance_error"],
                   mean_luminance_bias=metrics["mean_luminance_bias"],
                   # vertices with a negative relit channel: SH ringing of a bright, small light
                   negative_vertex_fraction=float((np.load(radiance) < 0).any(axis=1).mean()),
                   truncation_relative_rmse="",
                   reference_bounces=opts.bounces, reference_samples=ref["samples"],
                   reference_mean_relative_stderr=ref["mean_relative_stderr"],
                   reference_rms_relative_stderr=ref["rms_relative_stderr"],
                   reference_seconds=round(ref["seconds"], 2))
        rows[(env, order, count, bounce)] = row
        print(f"{env:10s} order {order:2d} samples {count:5d} bounces {bounce}: relative RMSE "
              f"{metrics['relative_rmse']:.4f} (noise-corrected {corrected:.4f}), transfer {seconds:.3f} s", flush=True)
        return row

    for env in figure_envs:
        for order in orders:
            for count in samples:
                for bounce in bounces:
                    score(env, order, count, bounce)

    # Order sweep, plus SH truncation alone: each order against a high-order relight of the same samples, which
    # leaves out Monte Carlo noise (transfer and reference) and any model difference from the path tracer.
    high_bundle, _, _ = transfer(opts.truncation_order, opts.order_sweep_samples, opts.bounces)
    for env in envs:
        high, _ = relight(high_bundle, env, f"r_{env}_o{opts.truncation_order}_s{opts.order_sweep_samples}"
                                            f"_b{opts.bounces}")
        for order in order_sweep:
            row = score(env, order, opts.order_sweep_samples, opts.bounces)
            radiance = os.path.join(opts.work, f"r_{env}_o{order}_s{opts.order_sweep_samples}_b{opts.bounces}.npy")
            row["truncation_relative_rmse"] = compare(radiance, high)["relative_rmse"]

    table = sorted(rows.values(), key=lambda r: (envs.index(r["env"]), r["order"], r["samples"], r["bounces"]))
    csv_path = os.path.join(opts.out, "sweep.csv")
    with open(csv_path + ".tmp", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(table[0].keys()))
        writer.writeheader()
        writer.writerows(table)
    os.replace(csv_path + ".tmp", csv_path)
    print(f"wrote {csv_path}")
    write_figures(table, figure_envs, orders, samples, opts)
    plot(table, envs, figure_envs, orders, bounces, samples, order_sweep, opts)
    print(f"sweep: {time.monotonic() - sweep_start:.0f} s in all")


def write_figures(rows, figure_envs, orders, samples, opts):
    """docs/charts/figures.md: the issue's figure, relative RMSE per figure map and order at full bounces."""
    counts = [n for n in (1024, samples[-1]) if n in samples]
    get = {(r["env"], r["order"], r["samples"], r["bounces"]): r for r in rows}
    head = "| map | order |" + "".join(f" rel. RMSE, {n} samples | transfer s, {n} samples |" for n in counts)
    lines = [f"Bunny, {opts.bounces} bounces, albedo {opts.albedo:g}, against `prt reference` ({opts.bounces} "
             "bounces, same albedo). Written by scripts/sweep.py from sweep.csv.", "", head,
             "|---|---|" + "---:|---:|" * len(counts)]
    for env in figure_envs:
        for order in orders:
            cells = []
            for n in counts:
                r = get.get((env, order, n, opts.bounces))
                cells += [f"{r['relative_rmse']:.4f}", f"{r['transfer_seconds']:.3f}"] if r else ["", ""]
            lines.append(f"| {env} | {order} | " + " | ".join(cells) + " |")
    lines += ["", "| map | reference paths per vertex | mean standard error / mean radiance | "
              "RMS standard error / RMS radiance | reference seconds |", "|---|---:|---:|---:|---:|"]
    for env in figure_envs:
        r = next(r for r in rows if r["env"] == env)
        lines.append(f"| {env} | {int(r['reference_samples'])} | {100 * r['reference_mean_relative_stderr']:.3f}% | "
                     f"{100 * r['reference_rms_relative_stderr']:.3f}% | {r['reference_seconds']:.0f} |")
    path = os.path.join(opts.out, "figures.md")
    with open(path + ".tmp", "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(path + ".tmp", path)
    print(f"wrote {path}")


def env_path(env):
    return os.path.join(DATA, "env", f"{env}.exr")


def knee_order(points):
    """Where the error stops falling fast: the first odd order L (from 3 on) at which two more bands, L+2, no
    longer halve the error. Only odd orders count: a diffuse cosine lobe has no odd bands above 1, so an even
    order (4, 6, ...) gains little over the odd order below it."""
    error = dict(points)
    for order in sorted(error):
        if order >= 3 and order % 2 == 1 and order + 2 in error and error[order + 2] > 0.5 * error[order]:
            return order, error[order]
    return points[-1]


def decay_exponent(points, first=5):
    """The slope p of log(error) against log(order) over orders >= first: error ~ L^p."""
    import numpy as np
    pts = [(o, e) for o, e in points if o >= first and e > 0]
    if len(pts) < 2:
        return float("nan")
    return float(np.polyfit(np.log([p[0] for p in pts]), np.log([p[1] for p in pts]), 1)[0])


def plot(rows, envs, figure_envs, orders, bounces, samples, order_sweep, opts):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    styles = {0: ":", 1: "--"}
    markers = {0: "s", 1: "^"}

    # Time against error, one panel per figure map.
    fig, axes = plt.subplots(1, len(figure_envs), figsize=(5.2 * len(figure_envs), 5.2), sharey=True, squeeze=False)
    for ax, env in zip(axes[0], figure_envs):
        for i, order in enumerate(orders):
            for bounce in bounces:
                pts = sorted((r["transfer_seconds"], r["relative_rmse"], r["samples"]) for r in rows
                             if r["env"] == env and r["order"] == order and r["bounces"] == bounce
                             and r["samples"] in samples)
                ax.plot([p[0] for p in pts], [p[1] for p in pts], color=colours[i], ls=styles.get(bounce, "-"),
                        marker=markers.get(bounce, "o"), ms=4, label=f"order {order}, {bounce} bounces")
                if bounce == bounces[-1] and i == len(orders) - 1:
                    for x, y, n in pts:
                        ax.annotate(str(int(n)), (x, y), textcoords="offset points", xytext=(0, 6), fontsize=7,
                                    ha="center", color=colours[i])
        ref = next(r for r in rows if r["env"] == env)
        ax.axhline(ref["reference_rms_relative_stderr"], color="grey", lw=1, ls="-.",
                   label=f"reference noise ({int(ref['reference_samples'])} paths)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("transfer time (s, wall clock, 2 threads)")
        ax.set_title(f"bunny under {env}")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].set_ylabel(f"relative RMSE of relit radiance\nvs path-traced reference ({opts.bounces} bounces)")
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(bounces) + 1, fontsize=8, frameon=False)
    fig.suptitle(f"Speed against accuracy. Along each curve the transfer samples per vertex are "
                 f"{', '.join(map(str, samples))} (labelled on order {orders[-1]}); albedo {opts.albedo:g}",
                 fontsize=10)
    fig.tight_layout(rect=(0, 0.1, 1, 1))
    save(fig, os.path.join(opts.out, "time_vs_error.png"), layout=False)

    # Error against order, one curve per map; right panel: truncation alone.
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(13, 7))
    count = opts.order_sweep_samples
    for i, env in enumerate(envs):
        colour = colours[i % len(colours)]
        sel = sorted((r for r in rows if r["env"] == env and r["samples"] == count and r["bounces"] == opts.bounces
                      and r["order"] in order_sweep), key=lambda r: r["order"])
        pts = [(r["order"], r["relative_rmse"]) for r in sel]
        noise = sel[0]["reference_rms_relative_stderr"]
        negative = max([r["negative_vertex_fraction"] for r in sel if r["order"] >= 3] or [0.0])
        label = f"{env}: error ~ $L^{{{decay_exponent(pts):.1f}}}$ from L = 5; ref. noise {100 * noise:.2f}%"
        if negative > 0.005:
            label += f"; ringing: up to {100 * negative:.0f}% of vertices relit < 0 at L >= 3"
        ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", ms=4, color=colour, label=label)
        order, error = knee_order(pts)
        ax.plot([order], [error], marker="o", ms=13, mfc="none", mec=colour, mew=1.5)
        trunc = [(r["order"], r["truncation_relative_rmse"]) for r in sel if r["truncation_relative_rmse"] != ""]
        bx.plot([p[0] for p in trunc], [p[1] for p in trunc], marker="o", ms=4, color=colour, label=env)
    ax.plot([], [], marker="o", ms=13, mfc="none", mec="k", ls="none",
            label="knee: from here two more bands\nno longer halve the error")
    for a in (ax, bx):
        a.set_yscale("log")
        a.set_xlabel("SH order L (bands; L² coefficients)")
        a.set_xticks(order_sweep)
        a.grid(True, which="both", alpha=0.3)
    ax.set_ylabel("relative RMSE of relit radiance")
    ax.set_title(f"Against the path-traced reference\n({count} transfer samples, {opts.bounces} bounces, "
                 f"albedo {opts.albedo:g})", fontsize=10)
    bx.set_ylabel(f"relative RMSE against the order-{opts.truncation_order} relight")
    bx.set_title(f"SH truncation alone: order L against order {opts.truncation_order}\n(same transfer samples "
                 "and bounces; no Monte Carlo noise)", fontsize=10)
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=2, fontsize=8, frameon=False)
    fig.suptitle("bunny: error against SH order for each HDR map (colours shared by both panels)", fontsize=11)
    fig.tight_layout(rect=(0, 0.17, 1, 1))
    save(fig, os.path.join(opts.out, "error_vs_order.png"), layout=False)


def save(fig, path, layout=True):
    if layout:
        fig.tight_layout()
    fig.savefig(path + ".tmp.png", dpi=110)
    os.replace(path + ".tmp.png", path)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
