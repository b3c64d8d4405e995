#!/usr/bin/python3
"""Issue 19, the nested fit's keep criterion: "N + 1 lobes never worse than N" per criterion, from what
scripts/glossy_lobes.py (OUT/lobes.json) and scripts/glossy_lights.py (OUT/lights.json) wrote.

For each variant (a glossy_lobes.py variant with bundles of the --lobes counts; its 1 lobe is base_n1, which every
nested stage 1 is bit for bit, unless it has its own, as the fit from below does) and each map: the glossy part
per lobe count and eye, then the cases where N + 1 lobes are worse than N (glossy part and total, by how many
points), the (vertex, view) problems that kept
stages 2 and 3, and the mean held-out error (grid 16) of the 2- and 3-lobe bundles. --lights: the same with the
lights (glossy_lights.py's "lights" rows, residual negatives kept).

Usage: scripts/glossy_keep.py [--out out/glossy19] --variants nested,nested_pv --envs courtyard,sunrise [--lights]
       [--lobes 1,2,3]
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
    ap.add_argument("--lobes", default="1,2,3", help="lobe counts, ascending (e.g. 1,2,3,4)")
    opts = ap.parse_args()
    lobes = json.load(open(os.path.join(opts.out, "lobes.json")))
    lights = json.load(open(os.path.join(opts.out, "lights.json"))) if opts.lights else {}
    envs = opts.envs.split(",")

    counts = [int(n) for n in opts.lobes.split(",")]

    # A variant's own 1-lobe bundle where it has one (the fit from below), else base_n1 (every nested stage 1).
    def value(variant, n, env, eye, part):
        own = f"{variant}_n{n}" in lobes or n > 1
        if opts.lights:  # glossy_lights.py's keys: no prefix for base
            prefix = "" if variant == "base" or not own else variant + "_"
            return lights.get(f"{prefix}{env}/{eye}/n{n}/lights", {}).get(part)
        return lobes.get(f"{variant}_n{n}" if own else "base_n1", {}).get(f"{env}/{eye}/{part}")

    nested = any(lobes.get(f"{v}_n2", {}).get("nested_kept_stage") for v in opts.variants.split(","))
    names = " / ".join(map(str, counts))
    steps = list(zip(counts, counts[1:]))
    print("| variant | " + " | ".join(f"{env} glossy {names}: front \\| side \\| back" for env in envs) + " | " +
          " | ".join(f"{b} worse than {a} (glossy; total)" for a, b in steps) + " |" +
          (" kept stage 2 / 3 | held-out 2 / 3 |" if nested else ""))
    print("|---" * (len(envs) + len(steps) + (3 if nested else 1)) + "|")
    for variant in opts.variants.split(","):
        cells, worse = [], {}
        for env in envs:
            cells.append(" \\| ".join(" / ".join(f"{100 * value(variant, n, env, eye, 'glossy'):.2f}" for n in counts)
                                      for eye in EYES))
        for part in ("glossy", "total"):
            for a, b in steps:
                worse[(part, b)] = [f"{env[:4]} {eye} +{100 * (value(variant, b, env, eye, part) - value(variant, a, env, eye, part)):.2f}"
                                    for env in envs for eye in EYES
                                    if value(variant, b, env, eye, part) > value(variant, a, env, eye, part)]
        text = lambda n: "; ".join(f"{len(worse[(p, n)])} of {3 * len(envs)}: " + (", ".join(worse[(p, n)]) or "none")
                                   for p in ("glossy", "total"))
        stats = [lobes.get(f"{variant}_n{n}", {}) for n in (2, 3)]
        kept = stats[1].get("nested_kept_stage") or [None, None, None]
        held = " / ".join(f"{100 * (s.get('held_out_mean_relative_error') or 0):.2f}%" for s in stats)
        print(f"| {variant} | " + " | ".join(cells) + " | " + " | ".join(text(b) for _, b in steps) + " |" +
              (f" {kept[1]} / {kept[2]} | {held} |" if nested else ""))

if __name__ == "__main__":
    main()
