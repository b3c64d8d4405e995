#!/usr/bin/python3
"""Writes a glTF scene of many instances of one mesh, for the instancing figures (docs/results.md).

    scripts/instanced_scene.py MESH.glb COUNT OUT.glb

MESH.glb is a bundle or plain .glb whose meshes[0] is the mesh (e.g. `prt meshprep bunny.ply`). The scene holds
COUNT nodes placing that mesh on a square grid (spacing 1.25 x its largest extent, each copy turned by a
different angle about +Y so that no two see the same occlusion), over a floor quad (mesh 1). Only meshes[0]'s
accessors are kept; the PRT_bundle extension is dropped.
"""
import json
import math
import struct
import sys


def read_glb(path):
    data = open(path, "rb").read()
    magic, _, _ = struct.unpack_from("<4sII", data, 0)
    if magic != b"glTF":
        raise SystemExit(f"{path}: not a glTF binary")
    json_length = struct.unpack_from("<I", data, 12)[0]
    gltf = json.loads(data[20:20 + json_length])
    binary_length = struct.unpack_from("<I", data, 20 + json_length)[0]
    return gltf, data[28 + json_length:28 + json_length + binary_length]


def main():
    if len(sys.argv) != 4:
        raise SystemExit(__doc__)
    source, binary = read_glb(sys.argv[1])
    count = int(sys.argv[2])
    if not 1 <= count <= 1_000_000:
        raise SystemExit("COUNT must lie in 1..1000000")
    primitive = source["meshes"][0]["primitives"][0]
    out = bytearray()
    views, accessors = [], []

    def copy_accessor(index):
        accessor = dict(source["accessors"][index])
        view = source["bufferViews"][accessor["bufferView"]]
        start = view.get("byteOffset", 0) + accessor.get("byteOffset", 0)
        size = {5126: 4, 5125: 4, 5123: 2, 5121: 1}[accessor["componentType"]]
        width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[accessor["type"]]
        length = accessor["count"] * size * width
        while len(out) % 4:
            out.append(0)
        views.append({"buffer": 0, "byteOffset": len(out), "byteLength": length})
        out.extend(binary[start:start + length])
        accessor["bufferView"] = len(views) - 1
        accessor.pop("byteOffset", None)
        accessors.append(accessor)
        return len(accessors) - 1

    attributes = {name: copy_accessor(index) for name, index in primitive["attributes"].items()
                  if name in ("POSITION", "NORMAL")}
    indices = copy_accessor(primitive["indices"])
    lo = accessors[attributes["POSITION"]]["min"]
    hi = accessors[attributes["POSITION"]]["max"]
    extent = max(h - l for h, l in zip(hi, lo))
    spacing = 1.25 * extent
    side = math.ceil(math.sqrt(count))

    def add_floats(values, kind):
        while len(out) % 4:
            out.append(0)
        views.append({"buffer": 0, "byteOffset": len(out), "byteLength": 4 * len(values)})
        out.extend(struct.pack(f"<{len(values)}f", *values))
        accessor = {"bufferView": len(views) - 1, "componentType": 5126, "type": kind, "count": len(values) // 3}
        accessors.append(accessor)
        return len(accessors) - 1

    half = 0.5 * side * spacing + extent
    y = lo[1]
    floor_positions = [-half, y, -half, half, y, -half, half, y, half, -half, y, half]
    position = add_floats(floor_positions, "VEC3")
    accessors[position]["min"] = [-half, y, -half]
    accessors[position]["max"] = [half, y, half]
    floor_normals = add_floats([0, 1, 0] * 4, "VEC3")
    while len(out) % 4:
        out.append(0)
    views.append({"buffer": 0, "byteOffset": len(out), "byteLength": 24})
    out.extend(struct.pack("<6I", 0, 2, 1, 0, 3, 2))
    accessors.append({"bufferView": len(views) - 1, "componentType": 5125, "type": "SCALAR", "count": 6})
    floor_indices = len(accessors) - 1

    nodes = [{"name": "floor", "mesh": 1}]
    centre = [0.5 * (h + l) for h, l in zip(hi, lo)]
    for k in range(count):
        row, column = divmod(k, side)
        angle = 2.0 * math.pi * ((k * 0.6180339887) % 1.0)
        x = (column - 0.5 * (side - 1)) * spacing - centre[0]
        z = (row - 0.5 * (side - 1)) * spacing - centre[2]
        nodes.append({"name": f"copy {k}", "mesh": 0, "translation": [x, 0.0, z],
                      "rotation": [0.0, math.sin(0.5 * angle), 0.0, math.cos(0.5 * angle)]})
    while len(out) % 4:
        out.append(0)
    gltf = {
        "asset": {"version": "2.0", "generator": "prt scripts/instanced_scene.py"},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": [{"name": "copy", "primitives": [{"attributes": attributes, "indices": indices, "material": 0}]},
                   {"name": "floor", "primitives": [{"attributes": {"POSITION": position, "NORMAL": floor_normals},
                                                     "indices": floor_indices, "material": 0}]}],
        "materials": [{"name": "grey", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0],
                                                                "metallicFactor": 0.0}}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(out)}],
    }
    text = json.dumps(gltf, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    total = 12 + 8 + len(text) + 8 + len(out)
    with open(sys.argv[3] + ".tmp", "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, total))
        f.write(struct.pack("<I4s", len(text), b"JSON") + text)
        f.write(struct.pack("<I4s", len(out), b"BIN\0") + bytes(out))
    import os
    os.replace(sys.argv[3] + ".tmp", sys.argv[3])
    print(f"{sys.argv[3]}: {count} instances of {accessors[indices]['count'] // 3} triangles "
          f"({count * accessors[indices]['count'] // 3} in all) over a floor")


if __name__ == "__main__":
    main()
