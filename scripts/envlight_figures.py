#!/usr/bin/python3
"""Hybrid lighting figures: plain SH PRT against cone lights + SH residual, on the bunny, against the path tracer.

For every HDR map in .cache/data/env (bunny, 3 bounces, albedo 0.8) it runs
  plain:  prt relight at orders 3, 5, 8 of an interreflected transfer;
  hybrid: prt envlight --order L --max-lights K, then prt relight --lights, for L in 3, 5 and K in 1, 2, 4;
  decomposition only: prt reference --lights (the decomposed lighting path-traced exactly) for L = 5, K = 4;
scores each against prt reference (relative RMSE, noise-corrected RMSE, negative-vertex fraction), records
storage (bytes per vertex of the layers each needs) and runtime (the relight kernel and the cone visibility),
then the temporal stability under 1-degree turns (tests/envlight/envlight_temporal) and the failure maps
(synthetic: overcast, more small lights than K, a light at the horizon, a light larger than the cone model).
Writes
  docs/charts/envlight.csv               one row per (map, method, order, lights)
  docs/charts/envlight_temporal.json     the temporal figures per map
  docs/charts/envlight_failures.csv      the failure map
  docs/charts/envlight_figures.md        the tables docs/results.md quotes
  docs/charts/envlight_error_vs_bytes.png
Run from the repository root after the build and `make -f Makefile.data`:  scripts/envlight_figures.py
References are cached in the work directory (out/envlight) under names holding every setting, with the mesh and
map hashes in a sidecar, as scripts/sweep.py does.
"""
import argparse
import csv
import glob
import json
import math
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from prt_commands import DATA, LUMINANCE, ROOT, file_hash, run_logged, stage_seconds  # noqa: E402

SHARP = ["city", "interior", "night", "studio", "sunrise"]  # a small bright source (docs/results.md)
SMOOTH = ["courtyard", "forest", "sunset"]


def run(args):
    return run_logged(args, "envlight_figures")


def metrics(result_path, ref):
    import numpy as np
    a = np.load(result_path).astype(np.float64)
    r = np.load(ref["path"]).astype(np.float64)
    rms_ref = math.sqrt(np.mean(r ** 2))
    mse = np.mean((a - r) ** 2)
    return dict(relative_rmse=math.sqrt(mse) / rms_ref,
                relative_rmse_noise_corrected=math.sqrt(max(0.0, mse - ref["mean_squared_stderr"])) / rms_ref,
                negative_vertex_fraction=float((a < 0).any(axis=1).mean()),
                mean_luminance_bias=float(np.mean(a @ LUMINANCE) / np.mean(r @ LUMINANCE) - 1))


class References:
    def __init__(self, prt, mesh, work, bounces, albedo):
        self.prt, self.mesh, self.work, self.bounces, self.albedo = prt, mesh, work, bounces, albedo
        self.mesh_hash = file_hash(mesh)

    def get(self, name, source_flag, source, samples):
        import numpy as np
        stem = os.path.join(self.work, f"reference_{name}_b{self.bounces}_a{self.albedo}_s{samples}_seed0")
        key = dict(mesh=self.mesh_hash, source=file_hash(source), flag=source_flag, bounces=self.bounces,
                   albedo=self.albedo, samples=samples, seed=0)
        record = None
        if os.path.exists(stem + ".json"):
            with open(stem + ".json") as f:
                record = json.load(f)
            if record.get("key") != key or not os.path.exists(stem + ".npy"):
                record = None
        status = "cached"
        if record is None:
            wall, _, events = run(self.prt + ["reference", self.mesh, source_flag, source, "-o", stem + ".npy",
                                              "--stderr-out", stem + "_se.npy", "--bounces", str(self.bounces),
                                              "--samples", str(samples), "--albedo", self.albedo])
            radiance = np.load(stem + ".npy").astype(np.float64)
            stderr = np.load(stem + "_se.npy").astype(np.float64)
            record = dict(key=key, seconds=stage_seconds(events, wall),
                          mean_relative_stderr=float(stderr.sum() / radiance.sum()),
                          rms_relative_stderr=float(math.sqrt(np.mean(stderr ** 2) / np.mean(radiance ** 2))),
                          mean_squared_stderr=float(np.mean(stderr ** 2)))
            with open(stem + ".json.tmp", "w") as f:
                json.dump(record, f, indent=2)
            os.replace(stem + ".json.tmp", stem + ".json")
            status = f"{record['seconds']:.1f} s"
        record["path"], record["samples"] = stem + ".npy", samples
        print(f"reference {name:24s} {samples:6d} paths: noise {100 * record['rms_relative_stderr']:.3f}% ({status})",
              flush=True)
        return record


def relight_ms(events):
    for event in events:
        msg = event.get("msg", "")
        m = re.search(r"at order \d+ in ([0-9.]+) ms", msg)
        if m:
            return float(m.group(1))
    for event in events:
        if event.get("event") == "relight_stats":
            return 1e3 * float(event["relight_seconds"])
    return float("nan")


def visibility_ms(events):
    for event in events:
        if event.get("event") == "relight_stats":
            return 1e3 * float(event["visibility_seconds"])
    return 0.0


def write_map(path, image):
    import numpy as np
    import OpenImageIO as oiio
    h, w, _ = image.shape
    out = oiio.ImageOutput.create(path)
    out.open(path, oiio.ImageSpec(w, h, 3, "float"))
    out.write_image(np.ascontiguousarray(image, dtype=np.float32))
    out.close()


def directions(w, h):
    import numpy as np
    y, x = np.mgrid[0:h, 0:w]
    theta = math.pi * (y + 0.5) / h
    phi = 2 * math.pi * (x + 0.5) / w - math.pi
    return np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)], axis=-1)


def failure_maps(work):
    """Synthetic 1024x512 maps for the failure map; returns {name: (path, what it tests)}."""
    import numpy as np
    w, h = 1024, 512
    d = directions(w, h)
    sky = 0.6 + 0.4 * np.clip(d[..., 1], 0, 1)  # a bright zenith, darker horizon
    ground = 0.15
    base = np.where(d[..., 1:2] > 0, sky[..., None], ground) * np.ones(3)
    maps = {}

    def disc(centre, radius_deg, radiance):
        c = np.array(centre, float)
        c /= np.linalg.norm(c)
        return (d @ c >= math.cos(math.radians(radius_deg)))[..., None] * np.array(radiance, float)

    maps["overcast"] = (base, "no peak: a smooth sky and ground")
    many = base.copy()
    for k in range(8):
        a = 2 * math.pi * k / 8
        many += disc([math.cos(a), 0.5 + 0.3 * (k % 2), math.sin(a)], 1.5, [300, 300, 300])
    maps["eight_small_lights"] = (many, "8 equal 1.5-degree lights, more than K = 4")
    maps["light_at_horizon"] = (base + disc([1, 0, 0], 2.0, [2000, 1900, 1700]),
                                "a 2-degree sun centred on the horizon")
    lobe = np.exp(40 * (d @ (np.array([0.3, 0.8, 0.2]) / np.linalg.norm([0.3, 0.8, 0.2])) - 1))[..., None]
    maps["broad_lobe"] = (base + 30 * lobe * np.ones(3), "a Gaussian lobe of 15 degrees FWHM: larger and softer "
                                                       "than a cone")
    out = {}
    for name, (image, what) in maps.items():
        path = os.path.join(work, f"failure_{name}.exr")
        if not os.path.exists(path):
            write_map(path, image)
        out[name] = (path, what)
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--prt", default=os.path.join(ROOT, "build", "prt"))
    parser.add_argument("--temporal", default=os.path.join(ROOT, "build", "tests", "envlight", "envlight_temporal"))
    parser.add_argument("--mesh", default=os.path.join(DATA, "bunny.ply"))
    parser.add_argument("--envs", default="", help="comma-separated map names (default: every map)")
    parser.add_argument("--temporal-envs", default="", help="maps of the temporal figure (default: every map)")
    parser.add_argument("--frames", type=int, default=360)
    parser.add_argument("--step", type=float, default=1.0)
    parser.add_argument("--temporal-mode", choices=["coherent", "fresh"], default="coherent",
                        help="coherent: envlight::decomposeCoherent carries lights between frames; fresh: each frame "
                             "decomposed afresh")
    parser.add_argument("--reference-samples", type=int, default=32768)
    parser.add_argument("--decomposed-samples", type=int, default=8192,
                        help="paths of the references of the decomposed lighting")
    parser.add_argument("--transfer-samples", type=int, default=1024)
    parser.add_argument("--work", default=os.path.join(ROOT, "out", "envlight"))
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "charts"))
    parser.add_argument("--skip-temporal", action="store_true")
    parser.add_argument("--skip-failures", action="store_true")
    opts = parser.parse_args()
    os.makedirs(opts.work, exist_ok=True)
    os.makedirs(opts.out, exist_ok=True)
    prt = [opts.prt, "--log-json"]
    available = sorted(os.path.splitext(os.path.basename(p))[0] for p in glob.glob(os.path.join(DATA, "env", "*.exr")))
    envs = opts.envs.split(",") if opts.envs else available
    if not envs:
        sys.exit("envlight_figures: no maps in .cache/data/env; run make -f Makefile.data")
    env_path = lambda e: os.path.join(DATA, "env", e + ".exr")
    albedo, bounces = "0.8", 3

    mesh = os.path.join(opts.work, "bunny.glb")
    if not os.path.exists(mesh):
        run(prt + ["meshprep", opts.mesh, "-o", mesh])
    refs = References(prt, mesh, opts.work, bounces, albedo)

    bundles = {}
    for order in (3, 5, 8):
        bundle = os.path.join(opts.work, f"t_o{order}.glb")
        wall, _, events = run(prt + ["transfer", mesh, "-o", bundle, "--order", str(order), "--mode",
                                     "interreflected", "--bounces", str(bounces), "--samples",
                                     str(opts.transfer_samples), "--albedo", albedo])
        bundles[order] = bundle

    rows = []
    for env in envs:
        ref = refs.get(env, "--env", env_path(env), opts.reference_samples)
        for order in (3, 5, 8):
            out = os.path.join(opts.work, f"plain_{env}_o{order}.npy")
            _, _, events = run(prt + ["relight", bundles[order], "--env", env_path(env), "-o", out])
            rows.append(dict(env=env, method="plain", order=order, max_lights=0, lights=0,
                             bytes_per_vertex=12 * order * order, relight_ms=relight_ms(events), visibility_ms=0.0,
                             envlight_seconds=0.0, reference_noise=ref["rms_relative_stderr"], **metrics(out, ref)))
        for order in (3, 5):
            for k in (1, 2, 4):
                lights = os.path.join(opts.work, f"lights_{env}_o{order}_k{k}.json")
                wall, _, events = run(prt + ["envlight", env_path(env), "-o", lights, "--order", str(order),
                                             "--max-lights", str(k)])
                envlight_seconds = stage_seconds(events, wall)
                with open(lights) as f:
                    doc = json.load(f)
                out = os.path.join(opts.work, f"hybrid_{env}_o{order}_k{k}.npy")
                _, _, events = run(prt + ["relight", bundles[order], "--env", env_path(env), "--lights", lights,
                                          "-o", out])
                row = dict(env=env, method="hybrid", order=order, max_lights=k, lights=len(doc["lights"]),
                           bytes_per_vertex=24 * order * order, relight_ms=relight_ms(events),
                           visibility_ms=visibility_ms(events), envlight_seconds=envlight_seconds,
                           reference_noise=ref["rms_relative_stderr"], **metrics(out, ref))
                row["light_power_fraction"] = doc["diagnostics"]["light_power_fraction"]
                if order == 5 and k == 4:
                    # The decomposed lighting path-traced exactly: the hybrid against it is transfer error alone,
                    # the decomposed reference against the true one is decomposition error alone.
                    dref = refs.get(f"{env}_lights_o5_k4", "--lights", lights, opts.decomposed_samples)
                    row["hybrid_vs_decomposed_reference"] = metrics(out, dref)["relative_rmse_noise_corrected"]
                    row["decomposition_error"] = metrics(dref["path"], ref)["relative_rmse_noise_corrected"]
                rows.append(row)
                print(f"{env:10s} hybrid L={order} K={k}: {row['lights']} lights, rel. RMSE "
                      f"{100 * row['relative_rmse']:.2f}%, negative {100 * row['negative_vertex_fraction']:.2f}%",
                      flush=True)

    fields = ["env", "method", "order", "max_lights", "lights", "relative_rmse", "relative_rmse_noise_corrected",
              "negative_vertex_fraction", "mean_luminance_bias", "bytes_per_vertex", "relight_ms", "visibility_ms",
              "envlight_seconds", "reference_noise", "light_power_fraction", "hybrid_vs_decomposed_reference",
              "decomposition_error"]
    with open(os.path.join(opts.out, "envlight.csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
        writer.writeheader()
        for r in rows:
            writer.writerow(r)

    temporal = {}
    if not opts.skip_temporal:
        for env in (opts.temporal_envs.split(",") if opts.temporal_envs else envs):
            # Cached by map, frames and step (the bundle is rebuilt identically each run: same mesh and seed).
            cached = os.path.join(opts.work, f"temporal_{env}_{opts.temporal_mode}_f{opts.frames}_s{opts.step:g}.json")
            if not os.path.exists(cached):
                _, text, _ = run([opts.temporal, bundles[5], env_path(env), "5", "4", str(opts.frames), str(opts.step),
                                  "64", opts.temporal_mode])
                with open(cached + ".tmp", "w") as f:
                    f.write(text)
                os.replace(cached + ".tmp", cached)
            with open(cached) as f:
                temporal[env] = json.load(f)
            t = temporal[env]
            print(f"temporal {env:10s}: jump {t['largest_direction_jump_degrees']:.3f} deg, count changes "
                  f"{t['light_count_changes']}, change hybrid {100 * t['hybrid_largest_change_rms']:.2f}% plain "
                  f"{100 * t['plain_largest_change_rms']:.2f}%", flush=True)
        with open(os.path.join(opts.out, "envlight_temporal.json"), "w") as f:
            json.dump(temporal, f, indent=1)

    failures = []
    if not opts.skip_failures:
        for name, (path, what) in failure_maps(opts.work).items():
            ref = refs.get(f"failure_{name}", "--env", path, opts.decomposed_samples)
            plain = os.path.join(opts.work, f"plain_failure_{name}.npy")
            run(prt + ["relight", bundles[5], "--env", path, "-o", plain])
            lights = os.path.join(opts.work, f"lights_failure_{name}.json")
            run(prt + ["envlight", path, "-o", lights, "--order", "5", "--max-lights", "4"])
            with open(lights) as f:
                doc = json.load(f)
            hybrid = os.path.join(opts.work, f"hybrid_failure_{name}.npy")
            run(prt + ["relight", bundles[5], "--lights", lights, "-o", hybrid])
            p, h = metrics(plain, ref), metrics(hybrid, ref)
            failures.append(dict(map=name, what=what, lights=len(doc["lights"]),
                                 radii_degrees=" ".join(f"{l['angular_radius_degrees']:.2f}" for l in doc["lights"]),
                                 light_power_fraction=doc["diagnostics"]["light_power_fraction"],
                                 plain_o5=p["relative_rmse"], hybrid_o5_k4=h["relative_rmse"],
                                 plain_negative=p["negative_vertex_fraction"],
                                 hybrid_negative=h["negative_vertex_fraction"], reference_noise=ref["rms_relative_stderr"]))
        with open(os.path.join(opts.out, "envlight_failures.csv"), "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(failures[0].keys()))
            writer.writeheader()
            for r in failures:
                writer.writerow(r)

    write_tables(rows, temporal, failures, opts)
    plot(rows, envs, opts)


def find(rows, env, method, order, k=0):
    for r in rows:
        if r["env"] == env and r["method"] == method and r["order"] == order and r["max_lights"] == k:
            return r
    return None


def write_tables(rows, temporal, failures, opts):
    pct = lambda x: f"{100 * x:.2f}%"
    lines = ["# Hybrid lighting figures (scripts/envlight_figures.py)", "",
             "Relative RMSE against `prt reference` (bunny, 3 bounces, albedo 0.8), negative-vertex fraction in "
             "brackets; hybrid = order L residual + K cone lights.", "",
             "| map | plain 3 | plain 5 | plain 8 | hyb 3/1 | hyb 3/2 | hyb 3/4 | hyb 5/1 | hyb 5/2 | hyb 5/4 | ref. noise |",
             "|---|" + "---:|" * 10]
    envs = sorted({r["env"] for r in rows}, key=lambda e: (e not in SHARP, e))
    for env in envs:
        cells = []
        for method, order, k in [("plain", 3, 0), ("plain", 5, 0), ("plain", 8, 0), ("hybrid", 3, 1), ("hybrid", 3, 2),
                                 ("hybrid", 3, 4), ("hybrid", 5, 1), ("hybrid", 5, 2), ("hybrid", 5, 4)]:
            r = find(rows, env, method, order, k)
            cells.append(f"{pct(r['relative_rmse'])} ({pct(r['negative_vertex_fraction'])})" if r else "")
        noise = find(rows, env, "plain", 3)["reference_noise"]
        lines.append(f"| {env} | " + " | ".join(cells) + f" | {pct(noise)} |")
    lines += ["", "Goal: on maps with a small bright source, order 5 + at most 4 lights under half of plain order 8 "
              "with no negative vertex; on smooth maps never worse than plain at the same order.", "",
              "| map | kind | plain 8 | best hybrid 5/K<=4 | ratio | negative | met |", "|---|---|---:|---:|---:|---:|---|"]
    for env in envs:
        p8 = find(rows, env, "plain", 8)
        hyb = [find(rows, env, "hybrid", 5, k) for k in (1, 2, 4)]
        best = min(hyb, key=lambda r: r["relative_rmse"])
        if env in SHARP:
            met = best["relative_rmse"] < 0.5 * p8["relative_rmse"] and best["negative_vertex_fraction"] == 0
            lines.append(f"| {env} | small source | {pct(p8['relative_rmse'])} | {pct(best['relative_rmse'])} "
                         f"(K={best['max_lights']}) | {best['relative_rmse'] / p8['relative_rmse']:.2f} | "
                         f"{pct(best['negative_vertex_fraction'])} | {'met' if met else 'MISSED'} |")
        else:
            worse = [f"{o}/{k}" for o in (3, 5) for k in (1, 2, 4)
                     if find(rows, env, "hybrid", o, k)["relative_rmse"] > find(rows, env, "plain", o)["relative_rmse"]]
            lines.append(f"| {env} | smooth | {pct(p8['relative_rmse'])} | {pct(best['relative_rmse'])} "
                         f"(K={best['max_lights']}) | {best['relative_rmse'] / p8['relative_rmse']:.2f} | "
                         f"{pct(best['negative_vertex_fraction'])} | "
                         f"{'met' if not worse else 'MISSED: worse than plain at ' + ', '.join(worse)} |")
    lines += ["", "Cost per row: bytes per vertex of the layers it reads; relight kernel time and cone visibility "
              "(Embree, 64 rays per vertex and light: the stand-in for shadow maps), ms, bunny 1,839 vertices.", "",
              "| map | method | L | K | lights found | B/vertex | relight ms | visibility ms | envlight s | "
              "decomposition error | hybrid vs decomposed ref. |", "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['env']} | {r['method']} | {r['order']} | {r['max_lights']} | {r['lights']} | "
                     f"{r['bytes_per_vertex']} | {r['relight_ms']:.3f} | {r['visibility_ms']:.1f} | "
                     f"{r['envlight_seconds']:.2f} | "
                     f"{pct(r['decomposition_error']) if 'decomposition_error' in r else ''} | "
                     f"{pct(r['hybrid_vs_decomposed_reference']) if 'hybrid_vs_decomposed_reference' in r else ''} |")
    if temporal:
        lines += ["", f"Temporal stability, order 5, K = 4, {next(iter(temporal.values()))['frames']} turns of "
                  f"{next(iter(temporal.values()))['step_degrees']} degree about +Y:", "",
                  "| map | light counts seen | count changes | largest direction jump | largest jump against the turn | "
                  "largest frame change, hybrid (RMS / max) | plain (RMS / max) | hybrid largest / median RMS | "
                  "decompose s/frame |",
                  "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
        for env, t in temporal.items():
            counts = sorted(set(t["light_counts"]))
            lines.append(f"| {env} | {counts} | {t['light_count_changes']} | "
                         f"{t['largest_direction_jump_degrees']:.3f} deg | "
                         f"{t['largest_jump_against_the_turn_degrees']:.3f} deg | "
                         f"{pct(t['hybrid_largest_change_rms'])} / {pct(t['hybrid_largest_change_max'])} | "
                         f"{pct(t['plain_largest_change_rms'])} / {pct(t['plain_largest_change_max'])} | "
                         f"{t.get('hybrid_largest_over_median', float('nan')):.2f} | "
                         f"{t['decompose_seconds_per_frame']:.2f} |")
    if failures:
        lines += ["", "Failure map (synthetic 1024x512 maps, order 5, K = 4):", "",
                  "| map | what | lights | radii (deg) | light power fraction | plain 5 | hybrid 5/4 | negative plain / hybrid | ref. noise |",
                  "|---|---|---:|---|---:|---:|---:|---:|---:|"]
        for f in failures:
            lines.append(f"| {f['map']} | {f['what']} | {f['lights']} | {f['radii_degrees']} | "
                         f"{f['light_power_fraction']:.3f} | {pct(f['plain_o5'])} | {pct(f['hybrid_o5_k4'])} | "
                         f"{pct(f['plain_negative'])} / {pct(f['hybrid_negative'])} | {pct(f['reference_noise'])} |")
    with open(os.path.join(opts.out, "envlight_figures.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


def plot(rows, envs, opts):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 5.5))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, env in enumerate(sorted(envs)):
        c = colours[i % len(colours)]
        plain = [find(rows, env, "plain", o) for o in (3, 5, 8)]
        ax.plot([r["bytes_per_vertex"] for r in plain], [r["relative_rmse"] for r in plain], "-o", color=c, ms=4,
                label=f"{env}: plain L=3,5,8")
        hyb = [find(rows, env, "hybrid", o, 4) for o in (3, 5)]
        ax.plot([r["bytes_per_vertex"] for r in hyb], [r["relative_rmse"] for r in hyb], "--s", color=c, ms=5,
                label=f"{env}: hybrid L=3,5, K=4")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("bytes per vertex (float32 layers: plain 12 L^2, hybrid 24 L^2 with the bounce layer)")
    ax.set_ylabel("relative RMSE against the path tracer")
    ax.set_title("Bunny, 3 bounces, albedo 0.8: error against storage")
    ax.legend(fontsize=6.5, ncol=2)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(opts.out, "envlight_error_vs_bytes.png"), dpi=120)


if __name__ == "__main__":
    main()
