#!/usr/bin/python3
"""Issue 19, item 2: cone lights through the glossy path, measured against the exact direct-light oracle
(`prt reference --brute-force --brdf phong:N,KS --eye ...` over the original map: every texel, Embree visibility,
no noise).

The setting of scripts/glossy_lobes.py (bunny decimated to 800 triangles = 402 vertices, Phong n = 32, ks = 0.5,
albedo 0.5, no bounces, 6x8x8 grid, eyes front / side / back) under courtyard, sunrise, city and interior. The lights
are `prt envlight ENV --order 6` (the glossy bundle's diffuse order; at most 4 lights). For each map, eye and lobe
count: relative RMSE of the total and of the glossy part alone (relight --glossy-only against oracle(brdf) -
oracle(diffuse)), without lights (the plain lobes) and with them (residual negatives kept, and clamped), the
diffuse part alone, and the negative outputs.

Usage: scripts/glossy_lights.py [--out out/glossy19] [--lobes 1,2] [--envs courtyard,sunrise,city,interior]
       [--decomposed sunrise]   (also the oracle of the decomposed lighting, `prt reference --lights`)
       [--strip]   the sunrise strips of docs/strips/ (glossy_lights_sunrise.png, glossy_plain_sunrise.png)
Steps already done are reused from --out (shared with scripts/glossy_lobes.py). Writes OUT/lights.json.
"""
import argparse, json, os, sys
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import glossy_lobes as gl  # noqa: E402  (run, rmse, EYES, the fit settings)

VARIANTS = {"plain": [], "lights": ["keep"], "lights_clamp": ["clamp"]}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=os.path.join(gl.ROOT, "out", "glossy19"))
    ap.add_argument("--triangles", type=int, default=800)
    ap.add_argument("--grid", type=int, default=8)
    ap.add_argument("--lobes", default="1")
    ap.add_argument("--envs", default="courtyard,sunrise,city,interior")
    ap.add_argument("--solver", default="pocl")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--light-samples", type=int, default=64)
    ap.add_argument("--fit", default="base", help="the glossy_lobes.py variant whose bundles are relit (e.g. nested)")
    ap.add_argument("--decomposed", default="", help="maps whose decomposed lighting also gets the oracle")
    ap.add_argument("--strip", action="store_true", help="only the sunrise strips (after a run with sunrise)")
    opts = ap.parse_args()
    os.makedirs(opts.out, exist_ok=True)
    o = lambda name: os.path.join(opts.out, name)
    threads = ["--threads", opts.threads]
    run = gl.run
    mesh = o(f"bunny{opts.triangles}.glb")
    run(["meshprep", os.path.join(gl.DATA, "bunny.ply"), "--decimate-to", opts.triangles, "-o", mesh], mesh)
    env_path = lambda env: os.path.join(gl.DATA, "env", env + ".exr")
    eye_text = lambda eye: ",".join(map(str, gl.EYES[eye]))
    brdf = f"phong:{gl.EXPONENT},{gl.KS}"
    envs = opts.envs.split(",")
    if opts.strip:
        return strips(opts, o, mesh, env_path, brdf)

    def oracle(env, lights=None):
        """(total, glossy part, diffuse part) per eye of the brute-force sum over the map (or the decomposition)."""
        tag = env if lights is None else env + "_decomposed"
        source = ["--env", env_path(env)] if lights is None else ["--lights", lights, "--lights-width", 1024]
        diffuse = o(f"oracle_{tag}_diffuse.npy")
        run(["reference", mesh, *source, "--brute-force", "--albedo", gl.ALBEDO, *threads, "-o", diffuse], diffuse)
        out = {}
        for eye in gl.EYES:
            total = o(f"oracle_{tag}_{eye}.npy")
            run(["reference", mesh, *source, "--brute-force", "--brdf", brdf, "--albedo", gl.ALBEDO, "--eye",
                 eye_text(eye), *threads, "-o", total], total)
            out[eye] = (np.load(total), np.load(total) - np.load(diffuse), np.load(diffuse))
        return out

    results = {}
    fit = "" if opts.fit == "base" else opts.fit + "_"  # prefix of the relights and result keys
    for env in envs:
        lights = o(f"lights_{env}_o6.json")
        run(["envlight", env_path(env), "--order", 6, "-o", lights], lights)
        doc = json.load(open(lights))
        results[f"{env}/lights"] = {"count": len(doc["lights"]),
                                    "radii_deg": [float(np.degrees(l["angular_radius"])) for l in doc["lights"]]}
        exact = oracle(env)
        decomposed = oracle(env, lights) if env in opts.decomposed.split(",") else None
        for n in map(int, opts.lobes.split(",")):
            bundle = o(f"{opts.fit}_n{n}.glb")
            run(["glossy", mesh, "-o", bundle, "--brdf", brdf, "--albedo", gl.ALBEDO, "--lobes", n, "--grid", opts.grid,
                 "--solver", opts.solver, *threads, "--stats", o(f"{opts.fit}_n{n}.json")] + gl.VARIANTS[opts.fit][0],
                bundle)
            for variant, negatives in VARIANTS.items():
                for eye in gl.EYES:
                    row = {}
                    parts = {}
                    for part in ("total", "glossy"):
                        tag = "" if opts.light_samples == 64 or not negatives else f"_s{opts.light_samples}"
                        path = o(f"{fit}{variant}{tag}_n{n}_{env}_{eye}_{part}.npy")
                        extra = ([] if not negatives else
                                 ["--lights", lights, "--light-samples", opts.light_samples, "--residual-negatives",
                                  negatives[0]])
                        run(["relight", bundle, "--env", env_path(env), "--eye", eye_text(eye), "-o", path] + extra +
                            (["--glossy-only"] if part == "glossy" else []), path)
                        parts[part] = np.load(path)
                    total, glossy, diffuse = exact[eye]
                    row["total"] = gl.rmse(parts["total"], total)
                    row["glossy"] = gl.rmse(parts["glossy"], glossy)
                    row["diffuse"] = gl.rmse(parts["total"] - parts["glossy"], diffuse)
                    row["negative_vertices"] = int(np.sum(np.any(parts["total"] < 0, axis=1)))
                    row["negative_glossy_vertices"] = int(np.sum(np.any(parts["glossy"] < 0, axis=1)))
                    row["min_total"] = float(parts["total"].min())
                    # The worst vertex of the glossy part (luminance-free: the largest channel error) and its oracle.
                    worst = np.unravel_index(np.argmax(np.abs(parts["glossy"] - glossy)), glossy.shape)
                    row["worst_glossy"] = [float(parts["glossy"][worst]), float(glossy[worst]), int(worst[0])]
                    if decomposed:
                        d_total, d_glossy, _ = decomposed[eye]
                        row["decomposed_oracle_vs_exact_total"] = gl.rmse(d_total, total)
                        row["decomposed_oracle_vs_exact_glossy"] = gl.rmse(d_glossy, glossy)
                        row["total_vs_decomposed_oracle"] = gl.rmse(parts["total"], d_total)
                    key = f"{fit}{env}/{eye}/n{n}/{variant}" + ("" if opts.light_samples == 64 or not negatives
                                                           else f"/s{opts.light_samples}")
                    results[key] = row
    old = json.load(open(o("lights.json"))) if os.path.exists(o("lights.json")) else {}
    json.dump({**old, **results}, open(o("lights.json"), "w"), indent=1)

    print("relative RMSE against the exact oracle: total / glossy part / diffuse part; negative vertices")
    print("| map | eye | lobes | plain | lights | lights, clamped |")
    print("|---|---|---|---|---|---|")
    for env in envs:
        for n in map(int, opts.lobes.split(",")):
            for eye in gl.EYES:
                cells = []
                for variant in VARIANTS:
                    r = results[f"{fit}{env}/{eye}/n{n}/{variant}" + ("" if opts.light_samples == 64 or variant == "plain"
                                                                   else f"/s{opts.light_samples}")]
                    cells.append(f"{100 * r['total']:.1f} / {100 * r['glossy']:.1f} / {100 * r['diffuse']:.1f}; "
                                 f"{r['negative_vertices']}")
                print(f"| {env} | {eye} | {n} | " + " | ".join(cells) + " |")
    for env in envs:
        print(env, results[f"{env}/lights"])


def strips(opts, o, mesh, env_path, brdf):
    """Item 5: result | exact reference | error under sunrise, from a camera 45 degrees round from the sun (which
    sits 8 degrees above the horizon), 12 degrees up, 24 units from the bunny, so the sun's highlights are in view.
    The brute-force oracle is per vertex (it has no image mode: a pixel would cost a map's worth of rays), so the
    reference is the oracle toward the camera's eye drawn per vertex (`prt render --vertex-radiance`), and the result
    is `prt relight --eye` of the same eye drawn the same way; also the per-pixel `prt render --lights`."""
    import math
    run = gl.run
    az, el, r = math.radians(144 - 45), math.radians(12), 24.0
    eye = (r * math.cos(el) * math.sin(az), 4.8 + r * math.sin(el), r * math.cos(el) * math.cos(az))
    eye_text = ",".join(f"{x:.3f}" for x in eye)
    camera = eye_text + ",0,4.8,0,0,1,0,28"
    env, lights, bundle = env_path("sunrise"), o("lights_sunrise_o6.json"), o("base_n1.glb")
    ref = o("strip_ref.npy")
    run(["reference", mesh, "--env", env, "--brute-force", "--brdf", brdf, "--albedo", gl.ALBEDO, "--eye", eye_text,
         "--threads", opts.threads, "-o", ref], ref)
    run(["relight", bundle, "--env", env, "--lights", lights, "--eye", eye_text, "-o", o("strip_lights.npy")])
    run(["relight", bundle, "--env", env, "--eye", eye_text, "-o", o("strip_plain.npy")])
    for name in ("ref", "lights", "plain"):
        run(["render", mesh, "--vertex-radiance", o(f"strip_{name}.npy"), "--camera", camera, "--size", "320,240",
             "-o", o(f"strip_{name}.exr")])
    run(["render", bundle, "--env", env, "--lights", lights, "--camera", camera, "--size", "320,240", "-o",
         o("strip_pixel.exr")])
    docs = os.path.join(gl.ROOT, "docs", "strips")
    for name, target in (("lights", "glossy_lights_sunrise"), ("plain", "glossy_plain_sunrise"), ("pixel", None)):
        strip = os.path.join(docs, target + ".png") if target else o("strip_pixel_strip.png")
        run(["compare", "--image", o(f"strip_{name}.exr"), o("strip_ref.exr"), "-o", o(f"strip_{name}_diff.png"),
             "--strip", strip, "--exposure", -1.5, "--metrics", o(f"strip_{name}.json")])
        m = json.load(open(o(f"strip_{name}.json")))
        print(f"{name}: camera {camera}: relative RMSE {100 * m['relative_rmse']:.2f}%, mean relative luminance "
              f"error {100 * m['mean_relative_luminance_error']:.2f}%, p95 {100 * m['p95_relative_luminance_error']:.2f}%")


if __name__ == "__main__":
    main()
