#!/usr/bin/python3
"""The seed's per-frame scheme (multi-level filtering, seed 004 Algorithm 2) against `prt adapt`'s offline orders.

Per frame and vertex the seed evaluates bands 0..2, then adds band l = 3, 4, ... while the band's contribution
|D_l| (largest over RGB) is at least T, stopping after the first band below T. T is t times the frame's RMS
full-order radiance. The ROI-refinement BFS passes of the seed are left out (they only add bands). Frames: the map
turned about +Y in 2-degree steps over 60 degrees (`prt envsh --rotate-y`), so the scheme's choice of bands changes
with the lighting while the offline orders do not.

Measured here in numpy on the bunny's order-8 transfer (out/adapt/bunny_full8.glb from scripts/adapt_figures.py):
  - coefficients evaluated per vertex (mean over frames): the work proxy; the seed's runtime also pays a test per
    band, and cannot use the compact storage: it reads full-order rows;
  - relative RMSE against full order (mean over frames);
  - flicker: the fraction of vertices whose band count changes between consecutive frames, and the largest
    frame-to-frame radiance change in excess of full order's own change, over the RMS radiance.
The offline adaptive bundle (out/adapt/bunny_adaptive_0.01.glb) is scored the same way. Writes
docs/charts/adapt_perframe.md.
"""
import json
import os
import struct
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
WORK = os.path.join(ROOT, "out", "adapt")
PRT = os.path.join(ROOT, "build", "prt")


def layers(path):
    data = open(path, "rb").read()
    json_length = struct.unpack_from("<I", data, 12)[0]
    gltf = json.loads(data[20:20 + json_length])
    buffer = data[28 + json_length:28 + json_length + gltf["buffers"][0]["byteLength"]]
    dtypes = {"float32": "<f4", "float16": "<f2", "uint8": "u1", "uint16": "<u2", "uint32": "<u4"}
    out = {}
    for layer in gltf["extensions"]["PRT_bundle"]["layers"]:
        if "bufferView" in layer:
            view = gltf["bufferViews"][layer["bufferView"]]
            out[layer["name"]] = np.frombuffer(buffer, dtypes[layer.get("componentType", "float32")],
                                               int(np.prod(layer["shape"])), view.get("byteOffset", 0)).reshape(layer["shape"])
    return out


def main():
    env = sys.argv[1] if len(sys.argv) > 1 else "courtyard"
    full = layers(os.path.join(WORK, "bunny_full8.glb"))["transfer"].astype(np.float64)  # [V, 64, 3]
    V = full.shape[0]
    adaptive_layers = layers(os.path.join(WORK, "bunny_adaptive_0.01.glb"))
    offsets = adaptive_layers["transfer_offsets"].astype(np.int64)
    ragged = adaptive_layers["transfer_ragged"].astype(np.float64)
    adaptive = np.zeros_like(full)
    for v in range(V):
        adaptive[v, :offsets[v + 1] - offsets[v]] = ragged[offsets[v]:offsets[v + 1]]
    frames = []
    for angle in range(0, 62, 2):
        path = os.path.join(WORK, f"sh_{env}_rot{angle}.json")
        if not os.path.exists(path):
            subprocess.run([PRT, "--quiet", "envsh", os.path.join(ROOT, ".cache", "data", "env", env + ".exr"),
                            "--order", "8", "--rotate-y", str(angle), "-o", path], check=True)
        frames.append(np.array(json.load(open(path))["coefficients"], dtype=np.float64))
    band = np.array([int(np.sqrt(j)) for j in range(64)])
    lines = [f"## The seed's per-frame scheme against offline adaptive order (bunny, {env} turned 0-60 degrees in 2-degree steps)", "",
             "| scheme | coefficients evaluated per vertex | rel. RMSE vs full order 8 (mean over frames) | vertices changing band count per frame | largest excess frame-to-frame change / RMS |",
             "|---|---:|---:|---:|---:|"]

    def score(name, radiance_of):
        rel, counts, changes, excess = [], [], [], []
        previous = None
        for L in frames:
            f = np.einsum("vjc,jc->vc", full, L)
            a, n = radiance_of(L, f)
            rel.append(np.sqrt(np.mean((a - f) ** 2) / np.mean(f ** 2)))
            counts.append(n.mean())
            if previous is not None:
                pa, pf, pn = previous
                changes.append(np.mean(n != pn))
                excess.append(np.max(np.abs((a - pa) - (f - pf))) / np.sqrt(np.mean(f ** 2)))
            previous = (a, f, n)
        lines.append(f"| {name} | {np.mean(counts):.1f} | {np.mean(rel):.4f} | {100 * np.mean(changes):.2f}% | {np.max(excess):.4f} |")

    for t in [0.001, 0.003, 0.01, 0.03]:
        def per_frame(L, f, t=t):
            contributions = np.einsum("vjc,jc->vjc", full, L)
            per_band = np.stack([contributions[:, band == l].sum(axis=1) for l in range(8)], axis=1)  # [V, 8, 3]
            threshold = t * np.sqrt(np.mean(f ** 2))
            levels = np.full(V, 8)
            for v in range(V):
                for l in range(3, 8):
                    if np.max(np.abs(per_band[v, l])) < threshold:
                        levels[v] = l + 1
                        break
            keep = np.arange(8)[None, :] < levels[:, None]
            return (per_band * keep[:, :, None]).sum(axis=1), levels ** 2
        score(f"per-frame, T = {t} x RMS", per_frame)
    offline_counts = (offsets[1:] - offsets[:-1])
    score("offline adaptive (prt adapt --max-error 0.01, eight-map prior)",
          lambda L, f: (np.einsum("vjc,jc->vc", adaptive, L), offline_counts))
    score("full order 8", lambda L, f: (f, np.full(V, 64)))
    text = "\n".join(lines) + "\n"
    open(os.path.join(ROOT, "docs", "charts", "adapt_perframe.md"), "w").write(text)
    print(text)


if __name__ == "__main__":
    main()
