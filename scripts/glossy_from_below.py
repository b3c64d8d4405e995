#!/usr/bin/python3
"""Issue 19, "N + 1 lobes never worse than N": the fit from below (`prt glossy --from-below`) against the plain fit,
from the results scripts/glossy_lobes.py and scripts/glossy_lights.py left in --out (run those first, e.g.
`scripts/glossy_lobes.py --out out/g16 --grid 16 --variants base,below_r3,below_r10,below --lobes 1,2,3` with
`--envs courtyard,sunrise` and `--envs city,forest`, and `scripts/glossy_lights.py --out out/g16 --grid 16 --fit
VARIANT --lobes 1,2,3 --envs courtyard,sunrise`).

For every variant and part (glossy, total): the relative RMSE per map, eye and lobe count, and every case where
N + 1 lobes are above N in the unrounded values (so +0.000 means less than 0.0005 point).

Usage: scripts/glossy_from_below.py [--out out/g16] [--variants base,below_r3,below_r10,below] [--lobes 1,2,3]
       [--envs courtyard,sunrise] [--lights]
"""
import argparse, json, os

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EYES = ("front", "side", "back")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "g16"))
    ap.add_argument("--variants", default="base,below_r3,below_r10,below")
    ap.add_argument("--lobes", default="1,2,3")
    ap.add_argument("--envs", default="courtyard,sunrise")
    ap.add_argument("--lights", action="store_true", help="the lights path (residual negatives kept)")
    opts = ap.parse_args()
    lobes = [int(n) for n in opts.lobes.split(",")]
    envs = opts.envs.split(",")
    results = json.load(open(os.path.join(opts.out, "lights.json" if opts.lights else "lobes.json")))

    def value(variant, env, eye, n, part):
        if opts.lights:
            prefix = "" if variant == "base" else variant + "_"
            return results[f"{prefix}{env}/{eye}/n{n}/lights"][part]
        return results[f"{variant}_n{n}"][f"{env}/{eye}/{part}"]

    print("| variant | part | " + " | ".join(f"{env} {' / '.join(map(str, lobes))} lobes: front \\| side \\| back"
                                             for env in envs) + " | N + 1 worse than N |")
    print("|---|---|" + "---|" * len(envs) + "---|")
    for variant in opts.variants.split(","):
        for part in ("glossy", "total"):
            cells, worse = [], []
            for env in envs:
                groups = []
                for eye in EYES:
                    x = [value(variant, env, eye, n, part) for n in lobes]
                    groups.append(" / ".join(f"{100 * v:.2f}" for v in x))
                    worse += [f"{env[:4]} {eye} {lobes[i - 1]}->{lobes[i]} +{100 * (x[i] - x[i - 1]):.3f}"
                              for i in range(1, len(x)) if x[i] > x[i - 1]]
                cells.append(" \\| ".join(groups))
            cases = len(envs) * len(EYES) * (len(lobes) - 1)
            print(f"| {variant} | {part} | " + " | ".join(cells) +
                  f" | {len(worse)} of {cases}" + (": " + ", ".join(worse) if worse else "") + " |")


if __name__ == "__main__":
    main()
