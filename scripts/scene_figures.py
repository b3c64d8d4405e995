#!/usr/bin/python3
"""Figures of real assets (docs/results.md, "Real assets"): a textured multi-material scene relit by prt against
`prt reference` with the same materials, per vertex and per image, at SH orders 3, 5 and 8, and a strip.

usage: scripts/scene_figures.py [--prt build/prt] [--data .cache/data] [--work .cache/scene_figures]
                                [--asset assets/OBJ/spider.obj] [--env courtyard] [--size 200,150]
                                [--samples 1024] [--reference-samples 4096] [--bounces 2]

Writes docs/strips/scene.png (result | reference | error), docs/strips/scene.diff.png, the same for the lightmap
bake (docs/strips/scene.bake.png) and docs/charts/scene_figures.json, with the references' own noise. Every step is a prt command; the reference is cached in --work."""
import argparse
import json
import struct
import subprocess
from pathlib import Path


def run(*args):
    subprocess.run([str(a) for a in args], check=True)


def scene_bounds(glb):
    """World bounds of the flattened scene: the positions `prt relight --positions` writes."""
    import numpy as np
    positions = np.load(glb)
    return positions.min(axis=0), positions.max(axis=0)


def main():
    root = Path(__file__).resolve().parent.parent
    parser = argparse.ArgumentParser()
    parser.add_argument("--prt", default=root / "build/prt")
    parser.add_argument("--data", default=root / ".cache/data")
    parser.add_argument("--work", default=root / ".cache/scene_figures")
    parser.add_argument("--asset", default="assets/OBJ/spider.obj")
    parser.add_argument("--env", default="courtyard")
    parser.add_argument("--size", default="200,150")
    parser.add_argument("--samples", type=int, default=1024)
    parser.add_argument("--reference-samples", type=int, default=4096)
    parser.add_argument("--bounces", type=int, default=2)
    args = parser.parse_args()
    prt, data, work = Path(args.prt), Path(args.data), Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    (root / "docs/strips").mkdir(parents=True, exist_ok=True)
    (root / "docs/charts").mkdir(parents=True, exist_ok=True)
    env = data / "env" / f"{args.env}.exr"

    prepared = work / "scene.glb"
    run(prt, "--quiet", "meshprep", data / args.asset, "-o", prepared, "--report", work / "meshprep.json")
    reference = work / f"reference.b{args.bounces}.s{args.reference_samples}.npy"
    reference_error = work / f"reference.b{args.bounces}.s{args.reference_samples}.stderr.npy"
    if not reference.exists():
        run(prt, "--quiet", "reference", prepared, "--env", env, "--bounces", args.bounces, "--samples",
            args.reference_samples, "--seed", 1, "-o", reference, "--stderr-out", reference_error)
    figures = {"asset": args.asset, "env": args.env, "transfer": f"interreflected, {args.bounces} bounces, "
               f"{args.samples} samples", "reference": f"{args.bounces} bounces, {args.reference_samples} paths",
               "orders": {}}
    positions = work / "positions.npy"
    for order in (3, 5, 8):
        bundle = work / f"transfer.o{order}.glb"
        run(prt, "--quiet", "transfer", prepared, "--mode", "interreflected", "--bounces", args.bounces, "--order",
            order, "--samples", args.samples, "--seed", 1, "-o", bundle)
        relit = work / f"relight.o{order}.npy"
        run(prt, "--quiet", "relight", bundle, "--env", env, "-o", relit, "--positions", positions)
        metrics = json.loads(subprocess.run([str(prt), "--quiet", "compare", str(relit), str(reference)], check=True,
                                            capture_output=True, text=True).stdout)
        figures["orders"][order] = {"vertex": metrics}
        print(f"order {order}: per vertex relative RMSE {100 * metrics['relative_rmse']:.2f}%")

    lo, hi = scene_bounds(positions)
    centre = [(a + b) / 2 for a, b in zip(lo, hi)]
    extent = max(b - a for a, b in zip(lo, hi))
    eye = [centre[0] + 0.6 * extent, centre[1] + 0.55 * extent, centre[2] + 1.1 * extent]
    camera = ",".join(f"{v:.6g}" for v in eye + centre + [0, 1, 0, 40])
    figures["camera"] = camera
    # The image reference is the mean of two half-sample runs (seeds 1 and 2), so that its own noise is measured:
    # the RMS of their difference / 2 is the noise of the mean.
    import OpenImageIO as oiio
    import numpy as np
    halves = []
    for seed in (1, 2):
        half = work / f"reference.image.{args.size.replace(',', 'x')}.seed{seed}.exr"
        if not half.exists():
            run(prt, "--quiet", "reference", prepared, "--env", env, "--bounces", args.bounces, "--samples",
                args.reference_samples // 8, "--seed", seed, "--image", args.size, "--camera", camera, "-o", half)
        halves.append(oiio.ImageBuf(str(half)).get_pixels(oiio.FLOAT))
    reference_image = work / f"reference.image.{args.size.replace(',', 'x')}.exr"
    mean = (halves[0] + halves[1]) / 2
    out_buf = oiio.ImageBuf(oiio.ImageSpec(mean.shape[1], mean.shape[0], mean.shape[2], oiio.FLOAT))
    out_buf.set_pixels(oiio.ROI(), mean)
    out_buf.write(str(reference_image))
    vertex_reference = np.load(reference)
    vertex_noise = np.load(reference_error)
    figures["reference_vertex_noise_relative_rms"] = float(np.sqrt(np.mean(vertex_noise ** 2)) /
                                                           np.sqrt(np.mean(vertex_reference ** 2)))
    for order in (3, 5, 8):
        render = work / f"render.o{order}.exr"
        run(prt, "--quiet", "render", work / f"transfer.o{order}.glb", "--env", env, "--camera", camera, "--size",
            args.size, "-o", render)
        out = root / "docs/strips" / ("scene" if order == 8 else f"scene.o{order}")
        metrics_file = work / f"image.o{order}.json"
        subprocess.run([str(prt), "--quiet", "compare", "--image", str(render), str(reference_image), "-o",
                        f"{out}.diff.png", "--strip", f"{out}.png", "--metrics", str(metrics_file)], check=True,
                       stdout=subprocess.DEVNULL)
        metrics = json.loads(metrics_file.read_text())
        figures["orders"][order]["image"] = metrics
        print(f"order {order}: per image relative RMSE {100 * metrics['relative_rmse']:.2f}%")
    # The reference's noise over the pixels the compare counts (the render's coverage).
    covered = oiio.ImageBuf(str(work / "render.o8.exr")).get_pixels(oiio.FLOAT)[..., 3] > 0.5
    noise = np.sqrt(np.mean(((halves[0] - halves[1])[covered][:, :3] / 2) ** 2))
    level = np.sqrt(np.mean(mean[covered][:, :3] ** 2))
    figures["reference_image_noise_relative_rms"] = float(noise / level)
    print(f"image reference: {args.reference_samples // 4} paths per pixel, noise {100 * noise / level:.2f}% (relative RMS)")
    # The lightmap: one atlas over the whole asset at order 5, rendered per texel times the base colour per pixel.
    bake = work / "bake.o5.glb"
    run(prt, "--quiet", "bake", prepared, "-o", bake, "--resolution", 1024, "--order", 5, "--samples", 256,
        "--bounces", args.bounces, "--seed", 1)
    render = work / "render.bake.o5.exr"
    run(prt, "--quiet", "render", bake, "--texels", "--env", env, "--camera", camera, "--size", args.size, "-o", render)
    out = root / "docs/strips" / "scene.bake"
    metrics_file = work / "image.bake.o5.json"
    subprocess.run([str(prt), "--quiet", "compare", "--image", str(render), str(reference_image), "-o",
                    f"{out}.diff.png", "--strip", f"{out}.png", "--metrics", str(metrics_file)], check=True,
                   stdout=subprocess.DEVNULL)
    figures["bake"] = {"order": 5, "resolution": 1024, "samples": 256,
                       "image": json.loads(metrics_file.read_text())}
    print(f"bake order 5: per image relative RMSE {100 * figures['bake']['image']['relative_rmse']:.2f}%")
    (root / "docs/charts/scene_figures.json").write_text(json.dumps(figures, indent=1) + "\n")


if __name__ == "__main__":
    main()
