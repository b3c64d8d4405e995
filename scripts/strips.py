#!/usr/bin/python3
"""Comparison strips for docs/: the Stanford bunny relit by `prt render` (shadowed per-vertex transfer) against
`prt reference --image` (path-traced, the same camera and albedo) under each of the eight HDR maps.

usage: scripts/strips.py [--prt build/prt] [--data .cache/data] [--work .cache/strips] [--size 160,120]
                         [--order 6] [--samples 512]

Writes docs/strips/MAP.png (result | reference | relative luminance error), docs/strips/MAP.diff.png (the error
picture with its legend) and docs/strips/strips.json (each map's `prt compare --image` metrics). One command
regenerates all of it; the reference images are cached in --work by their parameters."""
import argparse
import json
import struct
import subprocess
from pathlib import Path

MAPS = ["city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset"]


def bounds(glb):
    """POSITION min/max of a bundle's mesh, from the GLB's JSON chunk."""
    data = Path(glb).read_bytes()
    length = struct.unpack_from("<I", data, 12)[0]
    gltf = json.loads(data[20:20 + length])
    accessor = gltf["accessors"][gltf["meshes"][0]["primitives"][0]["attributes"]["POSITION"]]
    return accessor["min"], accessor["max"]


def run(*args):
    subprocess.run([str(a) for a in args], check=True)


def main():
    root = Path(__file__).resolve().parent.parent
    parser = argparse.ArgumentParser()
    parser.add_argument("--prt", default=root / "build/prt")
    parser.add_argument("--data", default=root / ".cache/data")
    parser.add_argument("--work", default=root / ".cache/strips")
    parser.add_argument("--size", default="160,120")
    parser.add_argument("--order", type=int, default=6)
    parser.add_argument("--samples", type=int, default=512)
    args = parser.parse_args()
    prt, data, work = Path(args.prt), Path(args.data), Path(args.work)
    out = root / "docs/strips"
    work.mkdir(parents=True, exist_ok=True)
    out.mkdir(parents=True, exist_ok=True)
    albedo = "0.8"

    mesh = work / "bunny.glb"
    bundle = work / f"bunny.shadowed.o{args.order}.glb"
    if not mesh.exists():
        run(prt, "--quiet", "meshprep", data / "bunny.ply", "-o", mesh)
    if not bundle.exists():
        run(prt, "--quiet", "transfer", mesh, "--mode", "shadowed", "--order", args.order, "--samples", 1024,
            "--albedo", albedo, "--seed", 1, "-o", bundle)
    lo, hi = bounds(mesh)
    centre = [(a + b) / 2 for a, b in zip(lo, hi)]
    extent = max(b - a for a, b in zip(lo, hi))
    eye = [centre[0] + 0.35 * extent, centre[1] + 0.3 * extent, centre[2] + 1.9 * extent]
    camera = ",".join(f"{v:.6g}" for v in eye + centre + [0, 1, 0, 35])

    table = {"camera": camera, "size": args.size, "order": args.order, "transfer": "shadowed, 1024 samples",
             "reference": f"bounces 0, {args.samples} samples per pixel", "albedo": float(albedo), "maps": {}}
    for name in MAPS:
        env = data / "env" / f"{name}.exr"
        reference = work / f"reference.{name}.{args.size.replace(',', 'x')}.s{args.samples}.exr"
        if not reference.exists():
            run(prt, "--quiet", "reference", mesh, "--env", env, "--image", args.size, "--camera", camera,
                "--samples", args.samples, "--albedo", albedo, "--seed", 1, "-o", reference)
        render = work / f"render.{name}.exr"
        run(prt, "--quiet", "render", bundle, "--env", env, "--camera", camera, "--size", args.size, "-o", render)
        metrics = work / f"{name}.json"
        subprocess.run([str(prt), "--quiet", "compare", "--image", str(render), str(reference), "-o",
                        str(out / f"{name}.diff.png"), "--strip", str(out / f"{name}.png"), "--metrics", str(metrics)],
                       check=True, stdout=subprocess.DEVNULL)
        m = json.loads(metrics.read_text())
        table["maps"][name] = {k: m[k] for k in ("count", "relative_rmse", "mean_relative_luminance_error",
                                                  "p95_relative_luminance_error", "mean_luminance_bias")}
        print(f"{name}: relative RMSE {100 * m['relative_rmse']:.1f}%, mean relative luminance error "
              f"{100 * m['mean_relative_luminance_error']:.1f}% over {m['count']} pixels")
    (out / "strips.json").write_text(json.dumps(table, indent=2) + "\n")


if __name__ == "__main__":
    main()
