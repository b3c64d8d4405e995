#!/usr/bin/python3
"""K per map (prt envlight --choose-lights): the chosen configuration against plain order 8, relit on the bunny.

For every map in .cache/data/env (or --maps): prt envlight --order 5 --max-lights 16 --choose-lights, which also
chooses the residual order among 5 and 8 (--residual-orders, default 5,8); when lights pay, the hybrid relight (the
chosen order's interreflected transfer + the chosen lights), else plain order 8 (the fallback); plain order 8 always; both scored against prt reference (bunny, 3 bounces, albedo 0.8, 8,192 paths, as the results
page's hybrid table). Also the share of the map's power in sources under 5 degrees (the lights' fitted radii), for
the goal's "< 0.5x where a source under 5 degrees holds over 20%", and the bytes per vertex each configuration
ships (the transfer bundle's size over its vertices, plus 4 bytes of float32 cone visibility per light, as
--visibility-out writes it). Writes docs/charts/envlight_choice.csv (all eight maps only) and prints a markdown
table.  Run from the repository root after the build and `make -f Makefile.data`.
"""
import argparse
import csv
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import envlight_figures as ef  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--maps", default=",".join(ef.SHARP + ef.SMOOTH), help="comma-separated map names")
    parser.add_argument("--residual-orders", default="5,8", help="passed to prt envlight --residual-orders")
    args = parser.parse_args()
    maps = args.maps.split(",")
    work = os.path.join(ef.ROOT, "out", "envlight")
    os.makedirs(work, exist_ok=True)
    prt = [os.path.join(ef.ROOT, "build", "prt"), "--log-json"]
    mesh = os.path.join(work, "bunny.glb")
    if not os.path.exists(mesh):
        ef.run(prt + ["meshprep", os.path.join(ef.DATA, "bunny.ply"), "-o", mesh])
    refs = ef.References(prt, mesh, work, 3, "0.8")
    bundles = {}
    for order in sorted({5, 8} | {int(o) for o in args.residual_orders.split(",")}):
        bundles[order] = os.path.join(work, f"t_o{order}.glb")
        ef.run(prt + ["transfer", mesh, "-o", bundles[order], "--order", str(order), "--mode", "interreflected",
                      "--bounces", "3", "--samples", "1024", "--albedo", "0.8"])
    rows = []
    vertices = None
    for env in maps:
        path = os.path.join(ef.DATA, "env", env + ".exr")
        ref = refs.get(env, "--env", path, 8192)
        lights = os.path.join(work, f"choose_{env}.json")
        ef.run(prt + ["envlight", path, "-o", lights, "--order", "5", "--max-lights", "16", "--choose-lights",
                      "--residual-orders", args.residual_orders])
        with open(lights) as f:
            doc = json.load(f)
        choice = doc["choice"]
        plain = os.path.join(work, f"choice_plain8_{env}.npy")
        ef.run(prt + ["relight", bundles[8], "--env", path, "-o", plain])
        p8 = ef.metrics(plain, ref)
        if vertices is None:
            import numpy as np
            vertices = np.load(plain).shape[0]
        per_vertex = lambda order, k: os.path.getsize(bundles[order]) / vertices + 4 * k
        order = choice.get("residual_order", 5)
        if choice["plain_sh"]:
            chosen = p8
            # What the lights would have given (the (order, K >= 1) the errors ranked best), for the record.
            tried = choice.get("orders_tried", [5])
            by_order = choice.get("errors_by_order", [choice["errors"]])
            candidates = [(errs[k], o, k) for o, errs in zip(tried, by_order) for k in range(1, len(errs))]
            probe, best = None, 0
            if candidates:
                _, probe_order, best = min(candidates)
                probe_lights = os.path.join(work, f"choice_probe_{env}.json")
                ef.run(prt + ["envlight", path, "-o", probe_lights, "--order", str(probe_order), "--max-lights", str(best)])
                out = os.path.join(work, f"choice_probe_{env}.npy")
                ef.run(prt + ["relight", bundles[probe_order], "--env", path, "--lights", probe_lights, "-o", out])
                probe = ef.metrics(out, ref)
        else:
            out = os.path.join(work, f"choice_hybrid_{env}.npy")
            ef.run(prt + ["relight", bundles[order], "--env", path, "--lights", lights, "-o", out])
            chosen, probe, best = ef.metrics(out, ref), None, choice["lights"]
        total = doc["diagnostics"]["environment_power"]
        if choice["plain_sh"] and probe:  # the shares of the lights the fallback declined
            with open(probe_lights) as f:
                doc = json.load(f)
        small = sum(sum(w * p for w, p in zip(ef.LUMINANCE, l["power"]))
                    for l in doc["lights"] if l["angular_radius_degrees"] < 5.0) / total
        rows.append(dict(env=env, lights=choice["lights"], residual_order=order, plain_sh=choice["plain_sh"],
                         predicted_ratio=(min(choice["errors"][1:] or choice["errors"]) / choice["plain_error"]),
                         chosen_rmse=chosen["relative_rmse"], plain8_rmse=p8["relative_rmse"],
                         chosen_nc=chosen["relative_rmse_noise_corrected"],
                         plain8_nc=p8["relative_rmse_noise_corrected"],
                         ratio=chosen["relative_rmse"] / p8["relative_rmse"],
                         ratio_nc=chosen["relative_rmse_noise_corrected"] / p8["relative_rmse_noise_corrected"],
                         negative=chosen["negative_vertex_fraction"], small_source_share=small,
                         probe_k=best if probe else "", probe_ratio=(probe["relative_rmse"] / p8["relative_rmse"]) if probe else "",
                         bytes_per_vertex=per_vertex(8, 0) if choice["plain_sh"] else per_vertex(order, choice["lights"]),
                         plain8_bytes_per_vertex=per_vertex(8, 0),
                         reference_noise=ref["rms_relative_stderr"]))
        r = rows[-1]
        print(f"{env:10s} order {r['residual_order']} K={r['lights']} plain={r['plain_sh']} ratio {r['ratio']:.3f} (nc {r['ratio_nc']:.3f}) "
              f"small-source share {r['small_source_share']:.2f}", flush=True)
    out_dir = os.path.join(ef.ROOT, "docs", "charts")
    if sorted(maps) == sorted(ef.SHARP + ef.SMOOTH):
        with open(os.path.join(out_dir, "envlight_choice.csv"), "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)
    pct = lambda x: f"{100 * x:.2f}%"
    print("| map | chosen | predicted ratio | chosen error | plain 8 | ratio (noise-corrected) | small-source share | negative | bytes/vertex (plain 8) | lights if forced (K, ratio) | ref. noise |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---|---:|")
    for r in rows:
        chosen = "plain order 8 (lights do not pay)" if r["plain_sh"] else f"order {r['residual_order']} + {r['lights']} lights"
        probe = f"{r['probe_k']}, {r['probe_ratio']:.2f}" if r["probe_k"] != "" else ""
        print(f"| {r['env']} | {chosen} | {r['predicted_ratio']:.2f} | {pct(r['chosen_rmse'])} | {pct(r['plain8_rmse'])} | "
              f"{r['ratio']:.2f} ({r['ratio_nc']:.2f}) | {r['small_source_share']:.2f} | {pct(r['negative'])} | {r['bytes_per_vertex']:.0f} ({r['plain8_bytes_per_vertex']:.0f}) | {probe} | "
              f"{pct(r['reference_noise'])} |")


if __name__ == "__main__":
    main()
