#!/usr/bin/python3
"""K per map (prt envlight --choose-lights): the chosen configuration against plain order 8, relit on the bunny.

For every map in .cache/data/env: prt envlight --order 5 --max-lights 16 --choose-lights; when lights pay, the
hybrid relight (order-5 interreflected transfer + the chosen lights), else plain order 8 (the fallback); plain
order 8 always; both scored against prt reference (bunny, 3 bounces, albedo 0.8, 8,192 paths, as the results
page's hybrid table). Also the share of the map's power in sources under 5 degrees (the lights' fitted radii), for
the goal's "< 0.5x where a source under 5 degrees holds over 20%". Writes docs/charts/envlight_choice.csv and prints
a markdown table.  Run from the repository root after the build and `make -f Makefile.data`.
"""
import csv
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import envlight_figures as ef  # noqa: E402


def main():
    work = os.path.join(ef.ROOT, "out", "envlight")
    os.makedirs(work, exist_ok=True)
    prt = [os.path.join(ef.ROOT, "build", "prt"), "--log-json"]
    mesh = os.path.join(work, "bunny.glb")
    if not os.path.exists(mesh):
        ef.run(prt + ["meshprep", os.path.join(ef.DATA, "bunny.ply"), "-o", mesh])
    refs = ef.References(prt, mesh, work, 3, "0.8")
    bundles = {}
    for order in (5, 8):
        bundles[order] = os.path.join(work, f"t_o{order}.glb")
        ef.run(prt + ["transfer", mesh, "-o", bundles[order], "--order", str(order), "--mode", "interreflected",
                      "--bounces", "3", "--samples", "1024", "--albedo", "0.8"])
    rows = []
    for env in ef.SHARP + ef.SMOOTH:
        path = os.path.join(ef.DATA, "env", env + ".exr")
        ref = refs.get(env, "--env", path, 8192)
        lights = os.path.join(work, f"choose_{env}.json")
        ef.run(prt + ["envlight", path, "-o", lights, "--order", "5", "--max-lights", "16", "--choose-lights"])
        with open(lights) as f:
            doc = json.load(f)
        choice = doc["choice"]
        plain = os.path.join(work, f"choice_plain8_{env}.npy")
        ef.run(prt + ["relight", bundles[8], "--env", path, "-o", plain])
        p8 = ef.metrics(plain, ref)
        if choice["plain_sh"]:
            chosen = p8
            # What the lights would have given (order 5, the K the errors ranked best), for the record.
            best = min(range(len(choice["errors"])), key=lambda k: choice["errors"][k])
            probe = None
            if best > 0:
                probe_lights = os.path.join(work, f"choice_probe_{env}.json")
                ef.run(prt + ["envlight", path, "-o", probe_lights, "--order", "5", "--max-lights", str(best)])
                out = os.path.join(work, f"choice_probe_{env}.npy")
                ef.run(prt + ["relight", bundles[5], "--env", path, "--lights", probe_lights, "-o", out])
                probe = ef.metrics(out, ref)
        else:
            out = os.path.join(work, f"choice_hybrid_{env}.npy")
            ef.run(prt + ["relight", bundles[5], "--env", path, "--lights", lights, "-o", out])
            chosen, probe, best = ef.metrics(out, ref), None, choice["lights"]
        total = doc["diagnostics"]["environment_power"]
        if choice["plain_sh"] and probe:  # the shares of the lights the fallback declined
            with open(probe_lights) as f:
                doc = json.load(f)
        small = sum(0.2126 * l["power"][0] + 0.7152 * l["power"][1] + 0.0722 * l["power"][2]
                    for l in doc["lights"] if l["angular_radius_degrees"] < 5.0) / total
        rows.append(dict(env=env, lights=choice["lights"], plain_sh=choice["plain_sh"],
                         predicted_ratio=(min(choice["errors"]) / choice["plain_error"]),
                         chosen_rmse=chosen["relative_rmse"], plain8_rmse=p8["relative_rmse"],
                         chosen_nc=chosen["relative_rmse_noise_corrected"],
                         plain8_nc=p8["relative_rmse_noise_corrected"],
                         ratio=chosen["relative_rmse"] / p8["relative_rmse"],
                         ratio_nc=chosen["relative_rmse_noise_corrected"] / p8["relative_rmse_noise_corrected"],
                         negative=chosen["negative_vertex_fraction"], small_source_share=small,
                         probe_k=best if probe else "", probe_ratio=(probe["relative_rmse"] / p8["relative_rmse"]) if probe else "",
                         reference_noise=ref["rms_relative_stderr"]))
        r = rows[-1]
        print(f"{env:10s} K={r['lights']} plain={r['plain_sh']} ratio {r['ratio']:.3f} (nc {r['ratio_nc']:.3f}) "
              f"small-source share {r['small_source_share']:.2f}", flush=True)
    out_dir = os.path.join(ef.ROOT, "docs", "charts")
    with open(os.path.join(out_dir, "envlight_choice.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    pct = lambda x: f"{100 * x:.2f}%"
    print("| map | chosen | predicted ratio | chosen error | plain 8 | ratio (noise-corrected) | small-source share | negative | lights if forced (K, ratio) | ref. noise |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---|---:|")
    for r in rows:
        chosen = "plain order 8 (lights do not pay)" if r["plain_sh"] else f"order 5 + {r['lights']} lights"
        probe = f"{r['probe_k']}, {r['probe_ratio']:.2f}" if r["probe_k"] != "" else ""
        print(f"| {r['env']} | {chosen} | {r['predicted_ratio']:.2f} | {pct(r['chosen_rmse'])} | {pct(r['plain8_rmse'])} | "
              f"{r['ratio']:.2f} ({r['ratio_nc']:.2f}) | {r['small_source_share']:.2f} | {pct(r['negative'])} | {probe} | "
              f"{pct(r['reference_noise'])} |")


if __name__ == "__main__":
    main()
