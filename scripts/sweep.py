#!/usr/bin/python3
"""Speed-versus-accuracy sweep: transfer + relight against the path-traced reference.

For one mesh and a set of HDR maps it runs `prt transfer` over orders, sample counts and bounce counts, relights
each result with `prt relight`, scores it with `prt compare` against `prt reference`, and writes
  docs/charts/sweep.csv            one row per (env, order, samples, bounces)
  docs/charts/time_vs_error.png    transfer time against relative RMSE, one curve per (order, bounces)
  docs/charts/error_vs_order.png   relative RMSE against SH order, one curve per HDR map: where truncation and
                                   ringing break the method (sharp suns)
Run from the repository root after the build and `make -f Makefile.data`:  scripts/sweep.py [--quick]
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run(args, capture=False):
    start = time.monotonic()
    result = subprocess.run(args, check=False, stdout=subprocess.PIPE if capture else subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)
    if result.returncode != 0:
        sys.exit(f"sweep: {' '.join(args)} failed ({result.returncode}):\n{result.stderr}")
    return time.monotonic() - start, result.stdout


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--prt", default=os.path.join(ROOT, "build", "prt"))
    parser.add_argument("--mesh", default=os.path.join(ROOT, ".cache", "data", "bunny.ply"))
    parser.add_argument("--envs", default="courtyard,forest,sunset,city,studio")
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "charts"))
    parser.add_argument("--work", default=os.path.join(ROOT, "out", "sweep"))
    parser.add_argument("--reference-samples", type=int, default=4096)
    parser.add_argument("--bounces", type=int, default=3, help="bounces of the reference and of the order sweep")
    parser.add_argument("--quick", action="store_true", help="a small sweep, for checking the script")
    opts = parser.parse_args()

    envs = opts.envs.split(",")
    orders = [3, 5, 8]
    samples = [64, 256, 1024]
    bounces = [0, 1, opts.bounces]
    order_sweep = list(range(1, 11))
    if opts.quick:
        envs, orders, samples, bounces, order_sweep = envs[:2], [3, 5], [64, 256], [0, opts.bounces], [1, 3, 5]
        opts.reference_samples = 512

    os.makedirs(opts.work, exist_ok=True)
    os.makedirs(opts.out, exist_ok=True)
    prt = [opts.prt, "--quiet"]
    mesh = os.path.join(opts.work, "mesh.glb")
    run(prt + ["meshprep", opts.mesh, "-o", mesh])

    rows = []

    def score(env, order, count, bounce):
        bundle = os.path.join(opts.work, f"t_o{order}_s{count}_b{bounce}.glb")
        radiance = os.path.join(opts.work, f"r_{env}_o{order}_s{count}_b{bounce}.npy")
        mode = "interreflected" if bounce > 0 else "shadowed"
        key = (order, count, bounce)
        if key not in transfer_seconds:
            args = ["transfer", mesh, "-o", bundle, "--mode", mode, "--order", str(order), "--samples", str(count)]
            if bounce > 0:
                args += ["--bounces", str(bounce)]
            transfer_seconds[key], _ = run(prt + args)
        relight_seconds, _ = run(prt + ["relight", bundle, "--env", env_path(env), "-o", radiance])
        _, metrics = run(prt + ["compare", radiance, reference[env]], capture=True)
        metrics = json.loads(metrics)
        rows.append(dict(env=env, order=order, samples=count, bounces=bounce,
                         transfer_seconds=round(transfer_seconds[key], 4), relight_seconds=round(relight_seconds, 4),
                         relative_rmse=metrics["relative_rmse"], nrmse=metrics["nrmse"],
                         max_error=metrics["max_error"], mean_luminance_error=metrics["mean_luminance_error"]))
        print(f"{env:10s} order {order:2d} samples {count:5d} bounces {bounce}: "
              f"relative RMSE {metrics['relative_rmse']:.4f}", flush=True)

    def env_path(env):
        return os.path.join(ROOT, ".cache", "data", "env", f"{env}.exr")

    reference = {}
    for env in envs:
        reference[env] = os.path.join(opts.work, f"reference_{env}.npy")
        seconds, _ = run(prt + ["reference", mesh, "--env", env_path(env), "-o", reference[env],
                                "--bounces", str(opts.bounces), "--samples", str(opts.reference_samples)])
        print(f"reference {env}: {seconds:.1f} s", flush=True)

    transfer_seconds = {}
    for env in envs:
        for order in orders:
            for count in samples:
                for bounce in bounces:
                    score(env, order, count, bounce)
        for order in order_sweep:
            if not any(r["env"] == env and r["order"] == order and r["samples"] == samples[-1]
                       and r["bounces"] == opts.bounces for r in rows):
                score(env, order, samples[-1], opts.bounces)

    csv_path = os.path.join(opts.out, "sweep.csv")
    with open(csv_path + ".tmp", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        writer.writeheader()
        writer.writerows(rows)
    os.replace(csv_path + ".tmp", csv_path)
    plot(rows, envs, orders, bounces, samples, opts)


def plot(rows, envs, orders, bounces, samples, opts):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    env = envs[0]
    fig, ax = plt.subplots(figsize=(7, 5))
    for order in orders:
        for bounce in bounces:
            pts = sorted((r["transfer_seconds"], r["relative_rmse"]) for r in rows
                         if r["env"] == env and r["order"] == order and r["bounces"] == bounce and r["samples"] in samples)
            ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", label=f"order {order}, {bounce} bounces")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("transfer time (s)")
    ax.set_ylabel("relative RMSE vs path-traced reference")
    ax.set_title(f"Speed against accuracy ({env}; points: {', '.join(map(str, samples))} samples)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    save(fig, os.path.join(opts.out, "time_vs_error.png"))

    fig, ax = plt.subplots(figsize=(7, 5))
    for env in envs:
        pts = sorted((r["order"], r["relative_rmse"]) for r in rows
                     if r["env"] == env and r["samples"] == samples[-1] and r["bounces"] == opts.bounces)
        ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", label=env)
    ax.set_yscale("log")
    ax.set_xlabel("SH order (bands)")
    ax.set_ylabel("relative RMSE vs path-traced reference")
    ax.set_title(f"Error against SH order ({samples[-1]} samples, {opts.bounces} bounces)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    save(fig, os.path.join(opts.out, "error_vs_order.png"))


def save(fig, path):
    fig.tight_layout()
    fig.savefig(path + ".tmp.png", dpi=110)
    os.replace(path + ".tmp.png", path)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
