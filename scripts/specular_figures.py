#!/usr/bin/python3
"""Specular figures (docs/results.md, "Specular through SH triple products"): relative RMSE of the glossy part
(and of diffuse + glossy) against `prt reference --brdf phong:N,0.5 --eye` at Phong exponents 8, 32, 128 under
courtyard and sunrise, against the SH order of the visibility and lighting, with cost: bytes per vertex, precompute
seconds, relight milliseconds per frame, bands used. A second series keeps the visibility at order L but projects
the lighting to order 16 and keeps 16 bands of the product (beyond seed 004, which truncates everything to L).

Same bunny, eyes, KS = 0.5, ALBEDO = 0.3 and 256-path references as scripts/glossy_figures.py: references are read
from its cache (out/glossy) when there, else made here with the same command, so the numbers sit in one table.

Usage: scripts/specular_figures.py [--out out/specular] [--glossy-out out/glossy] [--orders 3,4,5,6,7,8,10,12]
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
HIGH_LIGHT_ORDER = 16
MAX_LIGHT_ORDER = 32  # sh::kMaxOrder; only at visibility order MAX_SERIES_ORDER (its tensor takes seconds to build)
MAX_SERIES_ORDER = 8


def run(args, out=None, force=False, capture=False):
    if out and os.path.exists(out) and not force and not capture:
        return None
    print("+", " ".join(str(a) for a in args), file=sys.stderr, flush=True)
    if not capture:
        subprocess.run([PRT] + [str(a) for a in args] + ["--quiet"], check=True)
        return None
    done = subprocess.run([PRT] + [str(a) for a in args] + ["--log-json"], check=True, capture_output=True, text=True)
    return [json.loads(line) for line in done.stderr.splitlines() if line.startswith("{")]


def relative_rmse(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b ** 2)))


def env_path(env):
    return os.path.join(DATA, "env", env + ".exr")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "specular"))
    ap.add_argument("--glossy-out", default=os.path.join(ROOT, "out", "glossy"))
    ap.add_argument("--orders", default="3,4,5,6,7,8,10,12")
    ap.add_argument("--exponents", default="8,32,128")
    ap.add_argument("--samples", type=int, default=1024, help="visibility rays per vertex")
    ap.add_argument("--reference-samples", type=int, default=256)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--force", action="store_true")
    opts = ap.parse_args()
    os.makedirs(opts.out, exist_ok=True)
    o = lambda name: os.path.join(opts.out, name)
    orders = [int(x) for x in opts.orders.split(",")]
    exponents = [int(x) for x in opts.exponents.split(",")]

    bunny = os.path.join(opts.glossy_out, "bunny.glb")
    if not os.path.exists(bunny):
        bunny = o("bunny.glb")
        run(["meshprep", os.path.join(DATA, "bunny.ply"), "-o", bunny], bunny)
    # The diffuse part as the glossy sweep has it: order 3 shadowed, 1024 rays, albedo 0.3.
    run(["transfer", bunny, "-o", o("transfer.glb"), "--order", 3, "--samples", 1024, "--albedo", ALBEDO,
         "--threads", opts.threads], o("transfer.glb"))

    results = {"ks": KS, "albedo": ALBEDO, "eyes": EYES, "samples": opts.samples, "orders": orders,
               "reference_samples": opts.reference_samples, "stage": {}, "errors": {}, "noise": {}, "relight": {}}
    for L in orders:
        name = o(f"vis_o{L}.glb")
        run(["specular", o("transfer.glb"), "-o", name, "--order", L, "--samples", opts.samples, "--threads",
             opts.threads, "--stats", o(f"vis_o{L}.json")], name)
        results["stage"][L] = json.load(open(o(f"vis_o{L}.json")))

    def reference(env, e, eye_name, part):
        for folder in (opts.glossy_out, opts.out):
            ref = os.path.join(folder, f"ref_{env}_e{e}_{eye_name}_{part}.npy")
            if os.path.exists(ref) and os.path.exists(ref.replace(".npy", "_se.npy")):
                return np.load(ref), np.load(ref.replace(".npy", "_se.npy"))
        run(["reference", bunny, "--env", env_path(env), "--brdf", f"phong:{e},{KS}",
             "--albedo", ALBEDO if part == "full" else 0.0, "--eye", ",".join(map(str, EYES[eye_name])),
             "--samples", opts.reference_samples, "--threads", opts.threads, "-o", ref,
             "--stderr-out", ref.replace(".npy", "_se.npy")], ref)
        return np.load(ref), np.load(ref.replace(".npy", "_se.npy"))

    def relit(series, L, env, e, eye_name, part):
        path = o(f"{series}_o{L}_{env}_e{e}_{eye_name}_{part}.npy")
        stats_path = path.replace(".npy", ".json")
        if not (os.path.exists(path) and os.path.exists(stats_path)) or opts.force:
            top = {"high": HIGH_LIGHT_ORDER, "max": MAX_LIGHT_ORDER}.get(series)
            extra = ["--light-order", top, "--product-bands", top] if top else []
            events = run(["relight", o(f"vis_o{L}.glb"), "--env", env_path(env), "--brdf", f"phong:{e},{KS}",
                          "--eye", ",".join(map(str, EYES[eye_name])), "-o", path] + extra +
                         (["--glossy-only"] if part == "glossy" else []), capture=True)
            stats = next(ev for ev in events if ev.get("event") == "specular_relight_stats")
            json.dump(stats, open(stats_path, "w"))
        return np.load(path), json.load(open(stats_path))

    for env in ENVS:
        for e in exponents:
            for eye_name in EYES:
                for part in ("glossy", "full"):
                    ref, se = reference(env, e, eye_name, part)
                    results["noise"][f"{env}/e{e}/{eye_name}/{part}"] = float(
                        np.sqrt(np.mean(se ** 2)) / np.sqrt(np.mean(ref ** 2)))
                    for series in ("base", "high", "max"):
                        for L in orders:
                            if part == "full" and series != "base" or series == "max" and L != MAX_SERIES_ORDER:
                                continue
                            value, stats = relit(series, L, env, e, eye_name, part)
                            key = f"{series}/{env}/e{e}/o{L}/{eye_name}/{part}"
                            results["errors"][key] = relative_rmse(value, ref)
                            results["relight"][key] = stats
    results["failure"] = failure(o, bunny, orders, exponents, reference, relit)
    json.dump(results, open(o("specular_results.json"), "w"), indent=1, default=str)
    sg = os.path.join(opts.glossy_out, "glossy_results.json")
    results["gaussian_lobe"] = json.load(open(sg))["errors"] if os.path.exists(sg) else {}
    tables(results, orders, exponents)
    chart(results, orders, exponents)


def failure(o, bunny, orders, exponents, reference, relit):
    """Glossy error by the vertex's cosine-weighted visible share (O_00 / (sqrt(pi) / 2)), front eye, courtyard."""
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    from glossy_figures import mesh_of
    positions, normals, _ = mesh_of(bunny)
    view = np.array(EYES["front"]) - positions
    view /= np.linalg.norm(view, axis=1)[:, None]
    facing = np.sum(view * normals, axis=1) > 0
    out = {}
    for L in (orders[0], 8, orders[-1]):
        if L not in orders:
            continue
        share = visible_share(o(f"vis_o{L}.glb"), len(positions), L)
        for e in exponents:
            ref = reference("courtyard", e, "front", "glossy")[0]
            for series in ("base", "high"):
                fit = relit(series, L, "courtyard", e, "front", "glossy")[0]
                err = np.sqrt(np.sum((fit - ref) ** 2, axis=1))
                scale = np.sqrt(np.mean(np.sum(ref[facing] ** 2, axis=1)))
                cats = {"facing the eye": facing, "open (share > 0.95)": facing & (share > 0.95),
                        "occluded (share < 0.7)": facing & (share < 0.7)}
                out[f"{series}/o{L}/e{e}"] = {k: {"vertices": int(m.sum()),
                                                  "relative_rms_error": float(np.sqrt(np.mean(err[m] ** 2)) / scale)}
                                              for k, m in cats.items()}
    return out


def visible_share(path, vertices, order):
    """Column 0 of the specular_visibility layer over sqrt(pi) / 2: the cosine-weighted share of the unoccluded sky."""
    import struct
    data = open(path, "rb").read()
    length = struct.unpack_from("<I", data, 12)[0]
    gltf = json.loads(data[20:20 + length])
    binary = data[20 + length + 8:]
    layer = next(l for l in gltf["extensions"]["PRT_bundle"]["layers"] if l["name"] == "specular_visibility")
    view = gltf["bufferViews"][layer["bufferView"]]
    values = np.frombuffer(binary, np.float32, vertices * order * order, view.get("byteOffset", 0))
    return values.reshape(vertices, order * order)[:, 0] / (np.sqrt(np.pi) / 2)


def tables(results, orders, exponents):
    eyes = list(EYES)
    pct = lambda x: f"{100 * x:.1f}%"
    mean = lambda key: float(np.mean([results["errors"][key.format(eye=eye)] for eye in eyes]))
    noise = lambda env, e, part: float(np.mean([results["noise"][f"{env}/e{e}/{eye}/{part}"] for eye in eyes]))
    for series, part, title in (("base", "glossy", "glossy part alone, lighting and product at order L (seed 004)"),
                                ("high", "glossy", f"glossy part alone, visibility at order L, lighting and product at order {HIGH_LIGHT_ORDER}"),
                                ("base", "full", "diffuse SH (order 3) + specular at order L")):
        print(f"\nRelative RMSE against `prt reference`, {title}, mean over the eyes front, side, back:\n")
        print("| env | exponent | " + " | ".join(f"L = {L}" for L in orders) + " | reference noise |")
        print("|---|---|" + "---|" * (len(orders) + 1))
        for env in ENVS:
            for e in exponents:
                cells = [pct(mean(f"{series}/{env}/e{e}/o{L}/{{eye}}/{part}")) for L in orders]
                print(f"| {env} | {e} | " + " | ".join(cells) + f" | {pct(noise(env, e, part))} |")
    print("\nCost (bunny, 1,839 vertices; relight on 2 shared cores, mean over the 18 glossy relights of each cell):\n")
    print("| L | bytes/vertex | precompute s | bands used n=" + "/".join(map(str, exponents)) +
          " | light product ms | shading ms | lighting projection ms | light product ms, lighting order 16 | shading ms, lighting order 16 |")
    print("|---|---|---|---|---|---|---|---|---|")
    for L in orders:
        stage = results["stage"][L] if L in results["stage"] else results["stage"][str(L)]
        def stat(series, field):
            values = [s[field] for k, s in results["relight"].items() if k.startswith(f"{series}/") and f"/o{L}/" in k
                      and k.endswith("/glossy")]
            return float(np.mean(values))
        bands = "/".join(str(results["relight"][f"base/courtyard/e{e}/o{L}/front/glossy"]["bands"]) for e in exponents)
        print(f"| {L} | {stage['bytes_per_vertex']} | {stage['visibility_seconds']:.2f} | {bands} | "
              f"{1e3 * stat('base', 'product_seconds'):.3f} | {1e3 * stat('base', 'shade_seconds'):.2f} | "
              f"{1e3 * stat('base', 'project_seconds'):.1f} | {1e3 * stat('high', 'product_seconds'):.3f} | "
              f"{1e3 * stat('high', 'shade_seconds'):.2f} |")
    for e in exponents:
        top = [s for k, s in results["relight"].items() if k.startswith("max/") and f"/e{e}/" in k]
        if top:
            print(f"\nn = {e}, lighting order {MAX_LIGHT_ORDER} asked at L = {MAX_SERIES_ORDER}: {top[0]['bands']} bands, lighting "
                  f"order {top[0]['light_order']} used, tensor {top[0]['tensor_entries']} entries built in "
                  f"{np.mean([s['tensor_seconds'] for s in top]):.2f} s (once), lighting projection "
                  f"{1e3 * np.mean([s['project_seconds'] for s in top]):.0f} ms, light product "
                  f"{1e3 * np.mean([s['product_seconds'] for s in top]):.1f} ms, shading "
                  f"{1e3 * np.mean([s['shade_seconds'] for s in top]):.1f} ms")
    L = MAX_SERIES_ORDER
    print(f"\nGlossy part alone at visibility order L = {L} (256 bytes per vertex) against one Gaussian lobe per view "
          "(1,028 bytes per vertex, the glossy table above), mean over the eyes:\n")
    print(f"| env | exponent | lighting order {L} (seed 004) | lighting order {HIGH_LIGHT_ORDER} | lighting order {MAX_LIGHT_ORDER} | 1 SG lobe | reference noise |")
    print("|---|---|---|---|---|---|---|")
    for env in ENVS:
        for e in exponents:
            cells = [pct(mean(f"{series}/{env}/e{e}/o{L}/{{eye}}/glossy")) for series in ("base", "high", "max")]
            lobe = [results["gaussian_lobe"].get(f"{env}/e{e}/n1/{eye}/glossy") for eye in eyes]
            cells.append(pct(float(np.mean(lobe))) if all(x is not None for x in lobe) else "-")
            print(f"| {env} | {e} | " + " | ".join(cells) + f" | {pct(noise(env, e, 'glossy'))} |")
    print("\nWhere it fails (courtyard, front eye, glossy part; error RMS over the category / reference RMS over facing vertices):\n")
    print("| series | L | exponent | facing the eye | open (share > 0.95) | occluded (share < 0.7) |")
    print("|---|---|---|---|---|---|")
    for key, cats in sorted(results["failure"].items(), key=lambda kv: (int(kv[0].split("/")[1][1:]), kv[0].split("/")[0], int(kv[0].split("/")[2][1:]))):
        series, L, e = key.split("/")
        cells = [f"{pct(c['relative_rms_error'])} ({c['vertices']})" for c in cats.values()]
        print(f"| {series} | {L[1:]} | {e[1:]} | " + " | ".join(cells) + " |")


def chart(results, orders, exponents):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    eyes = list(EYES)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
    colours = dict(zip(exponents, ("tab:blue", "tab:orange", "tab:green", "tab:red")))
    for ax, env in zip(axes, ENVS):
        for e in exponents:
            for series, style in (("base", "-"), ("high", "--")):
                ys = [100 * np.mean([results["errors"][f"{series}/{env}/e{e}/o{L}/{eye}/glossy"] for eye in eyes])
                      for L in orders]
                label = f"n={e}, lighting order L" if series == "base" else f"n={e}, lighting order {HIGH_LIGHT_ORDER}"
                ax.plot(orders, ys, style, marker="o", color=colours[e], label=label)
            top = [results["errors"].get(f"max/{env}/e{e}/o{MAX_SERIES_ORDER}/{eye}/glossy") for eye in eyes]
            if all(x is not None for x in top):
                ax.plot([MAX_SERIES_ORDER], [100 * np.mean(top)], "*", ms=11, color=colours[e],
                        label=f"n={e}, lighting order {MAX_LIGHT_ORDER}" if env == ENVS[0] else None)
            floor = 100 * np.mean([results["noise"][f"{env}/e{e}/{eye}/glossy"] for eye in eyes])
            ax.axhline(floor, color=colours[e], lw=0.6, ls=":")
        ax.set_title(f"{env}: glossy part alone (dotted: reference noise)", fontsize=9)
        ax.set_xlabel("visibility SH order L  (bytes per vertex 4 L^2: " +
                      ", ".join(f"{L}: {4 * L * L}" for L in orders[::2]) + ")", fontsize=8)
        ax.set_xticks(orders)
        ax.grid(alpha=0.3)
        ax.set_yscale("log")
    axes[0].set_ylabel("relative RMSE, % (mean over 3 eyes)")
    axes[0].legend(fontsize=7)
    fig.suptitle("bunny, Phong ks=0.5, specular through SH triple products against prt reference (direct light)",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(ROOT, "docs", "charts", "specular_error.png"), dpi=110)


if __name__ == "__main__":
    main()
