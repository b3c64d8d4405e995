#!/usr/bin/python3
"""Issue 19, the nested fit's keep criterion: "N + 1 lobes never worse than N" per criterion, from what
scripts/glossy_lobes.py (OUT/lobes.json) and scripts/glossy_lights.py (OUT/lights.json) wrote.

For each variant (a glossy_lobes.py variant with 2- and 3-lobe bundles; 1 lobe is base_n1, which every nested
stage 1 is bit for bit) and each map: the glossy part at 1 / 2 / 3 lobes per eye, then the cases where 2 lobes are
worse than 1 and 3 worse than 2 (glossy part and total, by how many points), the (vertex, view) problems that kept
stages 2 and 3, and the mean held-out error (grid 16) of the 2- and 3-lobe bundles. --lights: the same with the
lights (glossy_lights.py's "lights" rows, residual negatives kept).

Usage: scripts/glossy_keep.py [--out out/glossy19] --variants nested,nested_pv --envs courtyard,sunrise [--lights]
"""
import argparse, json, os

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EYES = ("front", "side", "back")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "glossy19"))
    ap.add_argument("--variants", default="nested")
    ap.add_argument("--envs", default="courtyard,sunrise")
    ap.add_argument("--lights", action="store_true")
    opts = ap.parse_args()
    lobes = json.load(open(os.path.join(opts.out, "lobes.json")))
    lights = json.load(open(os.path.join(opts.out, "lights.json"))) if opts.lights else {}
    envs = opts.envs.split(",")

    def value(variant, n, env, eye, part):
        if opts.lights:
            key = f"{env}/{eye}/n1/lights" if n == 1 else f"{variant}_{env}/{eye}/n{n}/lights"
            return lights.get(key, {}).get(part)
        return lobes.get("base_n1" if n == 1 else f"{variant}_n{n}", {}).get(f"{env}/{eye}/{part}")

    print("| variant | " + " | ".join(f"{env} glossy 1 / 2 / 3: front \\| side \\| back" for env in envs) +
          " | 2 worse than 1 (glossy; total) | 3 worse than 2 (glossy; total) | kept stage 2 / 3 | held-out 2 / 3 |")
    print("|---" * (len(envs) + 5) + "|")
    for variant in opts.variants.split(","):
        cells, worse = [], {}
        for env in envs:
            cells.append(" \\| ".join(" / ".join(f"{100 * value(variant, n, env, eye, 'glossy'):.2f}" for n in (1, 2, 3))
                                      for eye in EYES))
        for part in ("glossy", "total"):
            for n in (2, 3):
                worse[(part, n)] = [f"{env[:4]} {eye} +{100 * (value(variant, n, env, eye, part) - value(variant, n - 1, env, eye, part)):.2f}"
                                    for env in envs for eye in EYES
                                    if value(variant, n, env, eye, part) > value(variant, n - 1, env, eye, part)]
        text = lambda n: "; ".join(f"{len(worse[(p, n)])} of {3 * len(envs)}: " + (", ".join(worse[(p, n)]) or "none")
                                   for p in ("glossy", "total"))
        stats = [lobes.get(f"{variant}_n{n}", {}) for n in (2, 3)]
        kept = stats[1].get("nested_kept_stage") or [None, None, None]
        held = " / ".join(f"{100 * (s.get('held_out_mean_relative_error') or 0):.2f}%" for s in stats)
        print(f"| {variant} | " + " | ".join(cells) + f" | {text(2)} | {text(3)} | {kept[1]} / {kept[2]} | {held} |")


if __name__ == "__main__":
    main()
