#!/usr/bin/python3
"""Issue 19, item 3: why more lobes relight worse, measured against the exact direct-light oracle
(`prt reference --brute-force --brdf phong:N,KS --eye ...`: every map texel, Embree visibility, no noise).

The bunny decimated to --triangles (a vertex subset of the shared 2-core machine's budget), Phong n = 32,
ks = 0.5, albedo 0.5, no bounces, three eyes outside the bounding sphere, courtyard and sunrise. For each variant
(a set of `prt glossy` / `prt relight` flags) and lobe count: relative RMSE of the glossy part alone (relight
--glossy-only against oracle(albedo 0.5, brdf) - oracle(albedo 0.5, diffuse)) and of the total.

Usage: scripts/glossy_lobes.py [--out out/glossy19] [--variants base,nocoh,...] [--lobes 1,2,3]
Prints one table per variant; writes OUT/lobes.json. Steps already done are reused from --out.
"""
import argparse, json, os, subprocess, sys
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PRT = os.environ.get("PRT_BIN", os.path.join(ROOT, "build", "prt"))  # PRT_BIN: another build
DATA = os.path.join(ROOT, ".cache", "data")
EXPONENT, KS, ALBEDO = 32, 0.5, 0.5
EYES = {"front": (0.0, 5.0, 25.0), "side": (20.0, 12.0, 10.0), "back": (-15.0, 3.0, -18.0)}
ENVS = ("courtyard", "sunrise")
TRAINING = ("city", "forest", "interior", "night", "studio", "sunset")  # the maps a criterion may be trained on
TRAINING_LIGHTING = ",".join(os.path.join(DATA, "env", m + ".exr") for m in TRAINING)
# name: (prt glossy flags, the variant whose bundles it relights (None: its own), relight environment)
VARIANTS = {
    "base": ([], None, {}),                              # the defaults (coherence pass, greedy start)
    "nocoh": (["--no-coherence"], None, {}),             # without the coherence terms
    "grid16": (["--grid", 16], None, {}),                # the finer kernel grid
    "warm": (["--warm-start"], None, {}),                # N lobes started from the N-1 fit
    "warm_nocoh": (["--warm-start", "--no-coherence"], None, {}),
    # Nested: each lobe count from the previous plus one lobe, kept per (vertex, view) only where it lowers the
    # error on held-out directions (docs/glossy.md, "More lobes were worse").
    "nested": (["--nested"], None, {}),
    "nested_nocoh": (["--nested", "--no-coherence"], None, {}),
    # Keep criteria of the nested fit: per vertex (all views or none) and with a relative margin m on the held-out
    # error (docs/glossy.md, "The keep criterion").
    "nested_pv": (["--nested", "--nested-per-vertex"], None, {}),
    "nested_m05": (["--nested", "--nested-margin", 0.05], None, {}),
    "nested_m10": (["--nested", "--nested-margin", 0.1], None, {}),
    "nested_m20": (["--nested", "--nested-margin", 0.2], None, {}),
    "nested_pv_m05": (["--nested", "--nested-per-vertex", "--nested-margin", 0.05], None, {}),
    "nested_pv_m10": (["--nested", "--nested-per-vertex", "--nested-margin", 0.1], None, {}),
    # The largest held-out residual (the worst direction of a small source) in place of the L2 held-out error.
    "nested_max": (["--nested", "--nested-max"], None, {}),
    "nested_pv_max": (["--nested", "--nested-per-vertex", "--nested-max"], None, {}),
    # Lighting-aware: the relit held-out error under the six training maps (never courtyard or sunrise), 8 turns each.
    "nested_lit": (["--nested", "--nested-lighting", TRAINING_LIGHTING], None, {}),
    "nested_pv_lit": (["--nested", "--nested-per-vertex", "--nested-lighting", TRAINING_LIGHTING], None, {}),
    # From below: lobe k fitted alone on what lobes < k leave, an overshoot weighted 1 + rho (docs/glossy.md,
    # "Fit from below").
    "below": (["--from-below", "--overshoot", 100], None, {}),
    "below_r1": (["--from-below", "--overshoot", 1], None, {}),
    "below_r3": (["--from-below", "--overshoot", 3], None, {}),
    "below_r10": (["--from-below"], None, {}),  # the default rho, 10
    "below_r1000": (["--from-below", "--overshoot", 1000], None, {}),
    # The same bundles relit without blending lobe parameters across the 3 views around the eye: the radiance of
    # each view's own lobes, blended (radiance), or the nearest view's alone (nearest).
    "base_radiance": ([], "base", {"PRT_GLOSSY_BLEND": "radiance"}),
    "base_nearest": ([], "base", {"PRT_GLOSSY_BLEND": "nearest"}),
    "nocoh_radiance": (["--no-coherence"], "nocoh", {"PRT_GLOSSY_BLEND": "radiance"}),
}

def run(args, out=None, force=False, env=None, prt=None):
    if out and os.path.exists(out) and not force:
        return
    print("+", " ".join(str(a) for a in args), file=sys.stderr, flush=True)
    subprocess.run([prt or PRT] + [str(a) for a in args] + ["--quiet"], check=True, env={**os.environ, **(env or {})})


def rmse(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b ** 2)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "glossy19"))
    ap.add_argument("--triangles", type=int, default=800)
    ap.add_argument("--grid", type=int, default=8)
    ap.add_argument("--lobes", default="1,2,3")
    ap.add_argument("--variants", default="base,nocoh")
    ap.add_argument("--solver", default="pocl")
    ap.add_argument("--envs", default=",".join(ENVS), help="maps (e.g. city,forest: training maps of a criterion)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--diffuse-orders", default="", help="e.g. 2,3,4,5,6,8: the diffuse part's error per SH order")
    ap.add_argument("--diffuse-samples", type=int, default=1024)
    ap.add_argument("--prt", default=None, help="the prt binary that relights (default build/prt), e.g. another "
                    "branch's build, to compare runtimes on the same fits")
    ap.add_argument("--tag", default="", help="prefix of the relight outputs and result keys (with --prt)")
    opts = ap.parse_args()
    os.makedirs(opts.out, exist_ok=True)
    o = lambda name: os.path.join(opts.out, name)
    threads = ["--threads", opts.threads]
    mesh = o(f"bunny{opts.triangles}.glb")
    run(["meshprep", os.path.join(DATA, "bunny.ply"), "--decimate-to", opts.triangles, "-o", mesh], mesh)
    env_path = lambda env: os.path.join(DATA, "env", env + ".exr")
    eye_text = lambda eye: ",".join(map(str, EYES[eye]))

    # The oracle: the diffuse direct sum once per map, the glossy one per (map, eye); glossy part = difference.
    envs = opts.envs.split(",")
    oracle = {}
    for env in envs:
        diffuse = o(f"oracle_{env}_diffuse.npy")
        run(["reference", mesh, "--env", env_path(env), "--brute-force", "--albedo", ALBEDO, *threads, "-o", diffuse],
            diffuse)
        for eye in EYES:
            total = o(f"oracle_{env}_{eye}.npy")
            run(["reference", mesh, "--env", env_path(env), "--brute-force", "--brdf", f"phong:{EXPONENT},{KS}",
                 "--albedo", ALBEDO, "--eye", eye_text(eye), *threads, "-o", total], total)
            oracle[(env, eye)] = (np.load(total), np.load(total) - np.load(diffuse))

    if opts.diffuse_orders:
        diffuse_orders(opts, o, mesh, env_path, eye_text, oracle)
        return
    results = {}
    for variant in opts.variants.split(","):
        glossy_flags, source, relight_env = VARIANTS[variant]
        for n in map(int, opts.lobes.split(",")):
            name = f"{opts.tag}{variant}_n{n}"
            fit_name = f"{source or variant}_n{n}"
            bundle = o(fit_name + ".glb")
            run(["glossy", mesh, "-o", bundle, "--brdf", f"phong:{EXPONENT},{KS}", "--albedo", ALBEDO, "--lobes", n,
                 "--grid", opts.grid, "--solver", opts.solver, *threads, "--stats", o(fit_name + ".json")] +
                glossy_flags, bundle)
            stats = json.load(open(o(fit_name + ".json")))
            row = {"fit_seconds": stats.get("fit_seconds"), "mean_relative_error": stats.get("mean_relative_error"),
                   "view_flips": stats.get("view_flips"), "view_pairs": stats.get("view_pairs"),
                   "nested_kept_stage": stats.get("nested_kept_stage"),
                   "held_out_mean_relative_error": stats.get("held_out_mean_relative_error")}
            for env in envs:
                for eye in EYES:
                    for part in ("total", "glossy"):
                        path = o(f"{name}_{env}_{eye}_{part}.npy")
                        run(["relight", bundle, "--env", env_path(env), "--eye", eye_text(eye), "-o", path] +
                            (["--glossy-only"] if part == "glossy" else []), path, env=relight_env, prt=opts.prt)
                        ref = oracle[(env, eye)][0 if part == "total" else 1]
                        row[f"{env}/{eye}/{part}"] = rmse(np.load(path), ref)
            results[name] = row
    merged = json.load(open(o("lobes.json"))) if os.path.exists(o("lobes.json")) else {}
    for name, row in results.items():  # per row, so runs over other --envs keep their cells
        merged[name] = {**merged.get(name, {}), **row}
    json.dump(merged, open(o("lobes.json"), "w"), indent=1)
    for variant in opts.variants.split(","):
        print(f"\n{variant}: glossy part / total, relative RMSE against the oracle")
        print("| env | eye | " + " | ".join(f"{n} lobes" for n in opts.lobes.split(",")) + " |")
        for env in envs:
            for eye in EYES:
                cells = [f"{100 * results[f'{opts.tag}{variant}_n{n}'][f'{env}/{eye}/glossy']:.2f}% / "
                         f"{100 * results[f'{opts.tag}{variant}_n{n}'][f'{env}/{eye}/total']:.2f}%"
                         for n in opts.lobes.split(",")]
                print(f"| {env} | {eye} | " + " | ".join(cells) + " |")
        fits = [f"{100 * results[f'{opts.tag}{variant}_n{n}']['mean_relative_error']:.1f}%" for n in opts.lobes.split(",")]
        print("fit residual (grid): " + ", ".join(fits))
        kept = [str(results[f'{opts.tag}{variant}_n{n}'].get('nested_kept_stage')) for n in opts.lobes.split(",")]
        held = [f"{100 * (results[f'{opts.tag}{variant}_n{n}'].get('held_out_mean_relative_error') or 0):.2f}%"
                for n in opts.lobes.split(",")]
        print("kept per stage: " + ", ".join(kept) + "; held-out (grid 16) mean: " + ", ".join(held))


def diffuse_orders(opts, o, mesh, env_path, eye_text, oracle):
    """Item 7: the diffuse part's error against the diffuse oracle per SH order (shadowed transfer, the glossy
    stage's computeTransfer), and the total with the 1-lobe glossy part of the base fit (if it is there)."""
    out = {}
    for order in map(int, opts.diffuse_orders.split(",")):
        bundle = o(f"transfer_o{order}_s{opts.diffuse_samples}.glb")
        run(["transfer", mesh, "--mode", "shadowed", "--order", order, "--samples", opts.diffuse_samples,
             "--albedo", ALBEDO, "--threads", opts.threads, "-o", bundle], bundle)
        for env in ENVS:
            path = bundle.replace(".glb", f"_{env}.npy")
            run(["relight", bundle, "--env", env_path(env), "-o", path], path)
            diffuse = np.load(path)
            ref = np.load(o(f"oracle_{env}_diffuse.npy"))
            out[f"o{order}/{env}/diffuse"] = rmse(diffuse, ref)
            for eye in EYES:
                glossy = o(f"base_n1_{env}_{eye}_glossy.npy")
                if os.path.exists(glossy):
                    out[f"o{order}/{env}/{eye}/total"] = rmse(diffuse + np.load(glossy), oracle[(env, eye)][0])
    json.dump(out, open(o(f"diffuse_orders_s{opts.diffuse_samples}.json"), "w"), indent=1)
    print("| order | " + " | ".join(f"{env} diffuse | {env} total (1 lobe, mean of eyes)" for env in ENVS) + " |")
    for order in map(int, opts.diffuse_orders.split(",")):
        cells = []
        for env in ENVS:
            totals = [out.get(f"o{order}/{env}/{eye}/total") for eye in EYES]
            mean = np.mean(totals) if None not in totals else float("nan")
            cells.append(f"{100 * out[f'o{order}/{env}/diffuse']:.2f}% | {100 * mean:.2f}%")
        print(f"| {order} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
