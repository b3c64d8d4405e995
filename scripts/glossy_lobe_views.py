#!/usr/bin/python3
"""Issue 19, item 3, step 1: the lobe count with the runtime's view blend taken out.

Views are world-space directions toward a distant viewer (docs/glossy.md, "What is computed"), so an eye far away
exactly along one of the 92 views makes every vertex's view direction that view: the runtime then evaluates that
one view's fitted lobes (blend weights 1, 0, 0; the turn is the identity), and the exact oracle
(`prt reference --brute-force --brdf ...`) sums the same kernel the lobes were fitted to, over every map texel. Any
error left is the fit's (plus the prefiltered lookup's). An eye far away along the centroid of a view triangle
gives the opposite extreme: the blend of three views with weights 1/3 and the largest turn.

Eyes: for each of the three eyes of glossy_lobes.py (front, side, back), the view nearest its direction from the
bunny (vfront, vside, vback) and the centroid of the view triangle around that view whose centroid is nearest it
(cfront, cside, cback), each at DISTANCE from the origin. Relights the bundles that glossy_lobes.py fitted
(OUT/VARIANT_nN.glb, fitting them first if they are missing) and scores them as glossy_lobes.py does.

Usage: scripts/glossy_lobe_views.py [--out out/glossy19] [--variants base] [--lobes 1,2,3]
Writes OUT/lobe_views.json.
"""
import argparse, itertools, json, os, sys
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import glossy_lobes as gl

DISTANCE = 1.0e5
CENTRE = np.array([0.0, 4.8, 0.0])  # about the bunny's bounding-sphere centre (the strips' camera target)


def view_set():
    """The 92 views and 180 triangles as lib/glossy/views.cpp builds them (frequency-3 geodesic icosahedron)."""
    t = (1.0 + 5 ** 0.5) / 2.0
    corners = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t],
                        [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], float)
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
             (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    index, dirs, tris = {}, [], []

    def point(face, w):
        key = tuple(sorted((face[c], w[c]) for c in range(3) if w[c] > 0))
        if key not in index:
            d = sum(weight * corners[c] for c, weight in key)
            index[key] = len(dirs)
            # float32 as the bundle stores them
            dirs.append((d / np.linalg.norm(d)).astype(np.float32))
        return index[key]

    for c in range(12):
        point((c, c, c), (3, 0, 0))
    for face in faces:
        p = lambda i, j: point(face, (i, j, 3 - i - j))
        for i in range(3):
            for j in range(3 - i):
                tris.append((p(i + 1, j), p(i, j + 1), p(i, j)))
                if i + j < 2:
                    tris.append((p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)))
    return np.array(dirs, np.float64), tris


def eyes():
    dirs, tris = view_set()
    assert len(dirs) == 92 and len(tris) == 180
    out = {}
    for name, eye in gl.EYES.items():
        d = np.array(eye) - CENTRE
        d /= np.linalg.norm(d)
        v = int(np.argmax(dirs @ d))
        out["v" + name] = (dirs[v] * DISTANCE, f"view {v}")
        best = None
        for tri in tris:
            if v not in tri:
                continue
            c = dirs[list(tri)].sum(0)
            c /= np.linalg.norm(c)
            if best is None or c @ d > best[0]:
                best = (c @ d, c, tri)
        out["c" + name] = (best[1] * DISTANCE, f"centroid of views {best[2]}")
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=os.path.join(gl.ROOT, "out", "glossy19"))
    ap.add_argument("--triangles", type=int, default=800)
    ap.add_argument("--grid", type=int, default=8)
    ap.add_argument("--lobes", default="1,2,3")
    ap.add_argument("--variants", default="base")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--eyes", default="", help="comma-separated subset of the eyes (default all)")
    opts = ap.parse_args()
    o = lambda name: os.path.join(opts.out, name)
    mesh = o(f"bunny{opts.triangles}.glb")
    threads = ["--threads", opts.threads]
    env_path = lambda env: os.path.join(gl.DATA, "env", env + ".exr")
    all_eyes = eyes()
    names = opts.eyes.split(",") if opts.eyes else list(all_eyes)
    oracle = {}
    for env in gl.ENVS:
        diffuse = o(f"oracle_{env}_diffuse.npy")
        gl.run(["reference", mesh, "--env", env_path(env), "--brute-force", "--albedo", gl.ALBEDO, *threads, "-o",
                diffuse], diffuse)
        for eye in names:
            text = ",".join(f"{x:.6f}" for x in all_eyes[eye][0])
            total = o(f"oracle_{env}_{eye}.npy")
            gl.run(["reference", mesh, "--env", env_path(env), "--brute-force", "--brdf",
                    f"phong:{gl.EXPONENT},{gl.KS}", "--albedo", gl.ALBEDO, "--eye", text, *threads, "-o", total], total)
            oracle[(env, eye)] = (np.load(total), np.load(total) - np.load(diffuse))
    path = o("lobe_views.json")
    results = json.load(open(path)) if os.path.exists(path) else {}
    for variant, n in itertools.product(opts.variants.split(","), map(int, opts.lobes.split(","))):
        glossy_flags, source, relight_env = gl.VARIANTS[variant]
        bundle = o(f"{source or variant}_n{n}.glb")
        gl.run(["glossy", mesh, "-o", bundle, "--brdf", f"phong:{gl.EXPONENT},{gl.KS}", "--albedo", gl.ALBEDO,
                "--lobes", n, "--grid", opts.grid, *threads, "--stats", bundle.replace(".glb", ".json")] + glossy_flags,
               bundle)
        row = results.get(f"{variant}_n{n}", {})
        for env, eye, part in itertools.product(gl.ENVS, names, ("total", "glossy")):
            text = ",".join(f"{x:.6f}" for x in all_eyes[eye][0])
            out = o(f"{variant}_n{n}_{env}_{eye}_{part}.npy")
            gl.run(["relight", bundle, "--env", env_path(env), "--eye", text, "-o", out] +
                   (["--glossy-only"] if part == "glossy" else []), out, env=relight_env)
            row[f"{env}/{eye}/{part}"] = gl.rmse(np.load(out), oracle[(env, eye)][0 if part == "total" else 1])
        results[f"{variant}_n{n}"] = row
    json.dump(results, open(path, "w"), indent=1)
    for variant in opts.variants.split(","):
        print(f"\n{variant}: glossy part / total, relative RMSE against the oracle, eyes at {DISTANCE:g}")
        print("| env | eye | " + " | ".join(f"{n} lobes" for n in opts.lobes.split(",")) + " |")
        for env, eye in itertools.product(gl.ENVS, names):
            cells = [f"{100 * results[f'{variant}_n{n}'][f'{env}/{eye}/glossy']:.2f}% / "
                     f"{100 * results[f'{variant}_n{n}'][f'{env}/{eye}/total']:.2f}%" for n in opts.lobes.split(",")]
            print(f"| {env} | {eye} ({all_eyes[eye][1]}) | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
