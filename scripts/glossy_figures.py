#!/usr/bin/python3
"""Glossy figures (docs/results.md, "Glossy view-dependent transfer"): PoCL against Ceres on the same problems,
whole-bunny time, error against `prt reference --brdf --eye` for 1-4 lobes at Phong exponents 8, 32, 128 under
courtyard and sunrise, lobe-order flips with and without the coherence terms, the failure map, bytes per vertex,
and a PNG strip (reference, fit, difference x8) for one camera.

Usage: scripts/glossy_figures.py [--out out/glossy] [--grid 8] [--problems 1000] [--samples 256] [--quick]
One command regenerates everything; finished steps are reused from --out unless --force.
"""
import argparse, json, os, subprocess, sys
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PRT = os.path.join(ROOT, "build", "prt")
DATA = os.path.join(ROOT, ".cache", "data")
KS, ALBEDO = 0.5, 0.3
EYES = {"front": (0.0, 5.0, 25.0), "side": (20.0, 12.0, 10.0), "back": (-15.0, 3.0, -18.0)}
ENVS = ("courtyard", "sunrise")


def run(args, out=None, force=False):
    if out and os.path.exists(out) and not force:
        return
    print("+", " ".join(str(a) for a in args), file=sys.stderr, flush=True)
    subprocess.run([PRT] + [str(a) for a in args] + ["--quiet"], check=True)


def compare(a, b):
    text = subprocess.run([PRT, "compare", a, b], check=True, capture_output=True, text=True).stdout
    return json.loads(text)["relative_rmse"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "glossy"))
    ap.add_argument("--grid", type=int, default=8)
    ap.add_argument("--problems", type=int, default=1000)
    ap.add_argument("--samples", type=int, default=256)
    ap.add_argument("--exponents", default="8,32,128")
    ap.add_argument("--lobes", default="1,2,3,4")
    ap.add_argument("--force", action="store_true")
    opts = ap.parse_args()
    os.makedirs(opts.out, exist_ok=True)
    o = lambda name: os.path.join(opts.out, name)
    exponents = [int(e) for e in opts.exponents.split(",")]
    lobe_counts = [int(n) for n in opts.lobes.split(",")]
    results = {"grid": opts.grid, "ks": KS, "albedo": ALBEDO, "eyes": EYES}

    run(["meshprep", os.path.join(DATA, "bunny.ply"), "-o", o("bunny.glb")], o("bunny.glb"))
    bunny = o("bunny.glb")

    # 1. PoCL against Ceres on the same problems, 2 threads each.
    results["solvers"] = {}
    for n in lobe_counts:
        path = o(f"compare_{n}.json")
        run(["glossy", bunny, "--brdf", f"phong:32,{KS}", "--lobes", n, "--grid", opts.grid, "--threads", 2,
             "--compare-solvers", opts.problems, "--stats", path], path, opts.force)
        results["solvers"][n] = json.load(open(path))

    # 2. Fits: every exponent and lobe count, plus the whole bunny at the default 6x16x16 grid, coherence off,
    #    and float32 lobes.
    fits = {}
    for e in exponents:
        for n in lobe_counts:
            name = f"fit_e{e}_n{n}"
            run(["glossy", bunny, "-o", o(name + ".glb"), "--brdf", f"phong:{e},{KS}", "--albedo", ALBEDO,
                 "--lobes", n, "--grid", opts.grid, "--threads", 2, "--stats", o(name + ".json"),
                 "--vertex-stats", o(name + "_vertices.npy")], o(name + ".glb"), opts.force)
            fits[(e, n)] = name
    extra = {
        "default_grid": ["--lobes", 1, "--grid", 16, "--brdf", f"phong:32,{KS}"],
        "no_coherence": ["--lobes", 2, "--grid", opts.grid, "--brdf", f"phong:32,{KS}", "--no-coherence"],
        "float32": ["--lobes", 1, "--grid", opts.grid, "--brdf", f"phong:32,{KS}", "--lobe-type", "float32"],
    }
    for name, args in extra.items():
        run(["glossy", bunny, "-o", o(name + ".glb"), "--albedo", ALBEDO, "--threads", 2, "--stats",
             o(name + ".json")] + args, o(name + ".glb"), opts.force)
    results["fit_stats"] = {f"e{e}_n{n}": json.load(open(o(fits[(e, n)] + ".json"))) for (e, n) in fits}
    results["extra_stats"] = {name: json.load(open(o(name + ".json"))) for name in extra}

    # 3. References and errors: full radiance and the glossy part alone (albedo 0, no bounces) at each eye.
    errors = {}
    for env in ENVS:
        envpath = os.path.join(DATA, "env", env + ".exr")
        for e in exponents:
            for eye_name, eye in EYES.items():
                eye_text = ",".join(str(c) for c in eye)
                for part, albedo in (("full", ALBEDO), ("glossy", 0.0)):
                    ref = o(f"ref_{env}_e{e}_{eye_name}_{part}.npy")
                    run(["reference", bunny, "--env", envpath, "--brdf", f"phong:{e},{KS}", "--albedo", albedo,
                         "--eye", eye_text, "--samples", opts.samples, "--threads", 2, "-o", ref], ref)
                    for n in lobe_counts:
                        fit = o(f"{fits[(e, n)]}_{env}_{eye_name}_{part}.npy")
                        run(["relight", o(fits[(e, n)] + ".glb"), "--env", envpath, "--eye", eye_text, "-o", fit]
                            + (["--glossy-only"] if part == "glossy" else []), fit, opts.force)
                        errors[f"{env}/e{e}/n{n}/{eye_name}/{part}"] = compare(fit, ref)
    results["errors"] = errors
    # Quantisation: float16 against float32 lobes (1 lobe, exponent 32).
    env0 = os.path.join(DATA, "env", "courtyard.exr")
    q = {}
    for name in ("float32", f"fit_e32_n1"):
        path = o(f"quant_{name}.npy")
        run(["relight", o(name + ".glb"), "--env", env0, "--eye", "0,5,25", "--glossy-only", "-o", path], path,
            opts.force)
        q[name] = np.load(path)
    a, b = q["float32"], q["fit_e32_n1"]
    results["float16_vs_float32_relative_rmse"] = float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(a ** 2)))

    # 4. Failure map at exponent 128, 1 lobe, courtyard, front eye: per-vertex glossy error by category.
    results["failure_map"] = failure_map(o, fits, exponents, lobe_counts)
    json.dump(results, open(o("glossy_results.json"), "w"), indent=1, default=str)
    charts(o, results, exponents, lobe_counts)
    strip(o, fits)
    print(json.dumps({k: results[k] for k in ("solvers",)}, indent=1, default=str))


def mesh_of(o):
    """Positions, normals and triangles of the prepared bunny from its glb."""
    import struct
    data = open(o("bunny.glb"), "rb").read()
    length = struct.unpack_from("<I", data, 12)[0]
    gltf = json.loads(data[20:20 + length])
    binary = data[20 + length + 8:]
    def accessor(i):
        acc = gltf["accessors"][i]
        view = gltf["bufferViews"][acc["bufferView"]]
        dtype = {5126: np.float32, 5125: np.uint32, 5123: np.uint16}[acc["componentType"]]
        width = {"SCALAR": 1, "VEC3": 3, "VEC2": 2, "VEC4": 4}[acc["type"]]
        start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
        return np.frombuffer(binary, dtype, acc["count"] * width, start).reshape(acc["count"], width)
    prim = gltf["meshes"][0]["primitives"][0]
    return (accessor(prim["attributes"]["POSITION"]), accessor(prim["attributes"]["NORMAL"]),
            accessor(prim["indices"]).reshape(-1, 3))


def failure_map(o, fits, exponents, lobe_counts):
    positions, normals, _ = mesh_of(o)
    eye = np.array(EYES["front"])
    view = eye - positions
    view /= np.linalg.norm(view, axis=1)[:, None]
    cos_view = np.sum(view * normals, axis=1)
    out = {}
    for e in exponents:
        n = lobe_counts[0]
        ref = np.load(o(f"ref_courtyard_e{e}_front_glossy.npy"))
        fit = np.load(o(f"{fits[(e, n)]}_courtyard_front_glossy.npy"))
        stats = np.load(o(fits[(e, n)] + "_vertices.npy"))
        lum = lambda x: x @ np.array([0.2126, 0.7152, 0.0722])
        err = np.abs(lum(fit) - lum(ref))
        scale = np.sqrt(np.mean(lum(ref) ** 2))
        cats = {
            "all": np.ones(len(err), bool),
            "grazing view (n.wo < 0.25)": (cos_view > 0) & (cos_view < 0.25),
            "frontal view (n.wo > 0.7)": cos_view > 0.7,
            "visibility cuts the hemisphere (visible < 70%)": stats[:, 3] < 0.7,
            "open hemisphere (visible > 95%)": stats[:, 3] > 0.95,
            "worst fit residual > 30% (tiny features, cut lobes)": stats[:, 5] > 0.3,
        }
        out[f"e{e}_n{n}"] = {name: {"vertices": int(mask.sum()),
                                     "relative_rms_error": float(np.sqrt(np.mean(err[mask] ** 2)) / scale)
                                     if mask.any() else None,
                                     "mean_fit_residual": float(np.mean(stats[mask, 4])) if mask.any() else None}
                              for name, mask in cats.items()}
    return out


def charts(o, results, exponents, lobe_counts):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    charts_dir = os.path.join(ROOT, "docs", "charts")
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for env, style in zip(ENVS, ("-", "--")):
        for e in exponents:
            for ax, part in zip(axes, ("full", "glossy")):
                ys = [np.mean([results["errors"][f"{env}/e{e}/n{n}/{eye}/{part}"] for eye in EYES]) for n in lobe_counts]
                xs = [920 * n + 108 for n in lobe_counts] if ax is axes[1] else lobe_counts
                ax.plot(lobe_counts if ax is axes[0] else xs, ys, style, marker="o", label=f"{env}, n={e}")
    axes[0].set_xlabel("lobes per view")
    axes[0].set_ylabel("relative RMSE, view-dependent radiance (mean of 3 eyes)")
    axes[1].set_xlabel("bundle bytes per vertex (float16 lobes + diffuse SH)")
    axes[1].set_ylabel("relative RMSE, glossy part alone")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(charts_dir, "glossy_error.png"), dpi=110)


def render(positions, normals, triangles, values, eye, target, size=(360, 360)):
    """Per-vertex radiance drawn with Gouraud triangles from a pinhole at eye (painter's order, back faces culled)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.tri import Triangulation
    f = np.array(target, float) - eye
    f /= np.linalg.norm(f)
    r = np.cross(f, [0, 1, 0]); r /= np.linalg.norm(r)
    u = np.cross(r, f)
    rel = positions - eye
    depth = rel @ f
    x, y = (rel @ r) / depth, (rel @ u) / depth
    e1 = positions[triangles[:, 1]] - positions[triangles[:, 0]]
    e2 = positions[triangles[:, 2]] - positions[triangles[:, 0]]
    facing = np.sum(np.cross(e1, e2) * (eye - positions[triangles[:, 0]]), axis=1) > 0
    tris = triangles[facing]
    order = np.argsort(-depth[tris].mean(axis=1))
    return x, y, tris[order]


def strip(o, fits):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.tri import Triangulation
    positions, normals, triangles = mesh_of(o)
    eye = np.array(EYES["front"])
    x, y, tris = render(positions, normals, triangles, None, eye, (0, 5, 0))
    ref = np.load(o("ref_courtyard_e32_front_full.npy"))
    fit = np.load(o(f"{fits[(32, 1)]}_courtyard_front_full.npy"))
    lum = lambda v: v @ np.array([0.2126, 0.7152, 0.0722])
    scale = np.percentile(lum(ref), 99)
    panels = [("reference (path traced)", lum(ref) / scale), ("fit: 1 SG + SH order 3", lum(fit) / scale),
              ("|difference| x 8", 8 * np.abs(lum(fit) - lum(ref)) / scale)]
    fig, axes = plt.subplots(1, 3, figsize=(12, 4.4))
    for ax, (title, v) in zip(axes, panels):
        tri = Triangulation(x, y, tris)
        ax.tripcolor(tri, np.clip(v, 0, 1) ** (1 / 2.2), shading="gouraud", cmap="gray", vmin=0, vmax=1)
        ax.set_title(title, fontsize=9)
        ax.set_aspect("equal")
        ax.axis("off")
    fig.suptitle("bunny, Phong n=32 ks=0.5 on albedo 0.3, courtyard, eye (0,5,25)", fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(ROOT, "docs", "charts", "glossy_strip.png"), dpi=110)


if __name__ == "__main__":
    main()
