#!/usr/bin/env python3
"""Writes the example scenes the README and docs/usage.md use, from nothing but this script.

    street.obj          a 30 x 30 m street: ground, three buildings, a lamp pole, a car and an
                        awning on posts; every object its own OBJ shape (one instance each),
                        with UVs in [0, 1] and no overlaps, so shadow atlases take them as they are
    model.glb           glTF 2.0 (binary): a ground tile, a crate mesh used by two nodes (one
                        turned and stacked on the other) and a low wall; TEXCOORD_0 on every mesh
    street_frames.json  four frames for `shadowctl sequence` over street.obj: the car (instance 5)
                        drives along the street while the camera pans

Up is +y, units are metres. Run it from anywhere; `--check` only compares what it would write
with the files there (the docs_examples test does, so the files and this script cannot drift).
"""

import json
import pathlib
import struct
import sys

HERE = pathlib.Path(__file__).resolve().parent

# A box's six faces: corner offsets (-1/+1 per axis), counter-clockwise seen from outside.
FACES = [
    [(-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)],      # +z
    [(1, -1, -1), (-1, -1, -1), (-1, 1, -1), (1, 1, -1)],  # -z
    [(1, -1, 1), (1, -1, -1), (1, 1, -1), (1, 1, 1)],      # +x
    [(-1, -1, -1), (-1, -1, 1), (-1, 1, 1), (-1, 1, -1)],  # -x
    [(-1, 1, 1), (1, 1, 1), (1, 1, -1), (-1, 1, -1)],      # +y
    [(-1, -1, -1), (1, -1, -1), (1, -1, 1), (-1, -1, 1)],  # -y
]


def box(center, size):
    """24 vertices (4 a face), UVs: each face in its own cell of a 3 x 2 grid, with a margin."""
    positions, uvs, tris = [], [], []
    for f, corners in enumerate(FACES):
        u0, v0 = (f % 3) / 3, (f // 3) / 2
        base = len(positions)
        for k, c in enumerate(corners):
            positions.append(tuple(center[a] + c[a] * size[a] / 2 for a in range(3)))
            du, dv = (0, 1, 1, 0)[k], (0, 0, 1, 1)[k]
            uvs.append((u0 + (0.02 + 0.96 * du) / 3, v0 + (0.02 + 0.96 * dv) / 2))
        tris += [(base, base + 1, base + 2), (base, base + 2, base + 3)]
    return positions, uvs, tris


def quad(half):
    """A ground square at y = 0, facing up."""
    p = [(-half, 0, half), (half, 0, half), (half, 0, -half), (-half, 0, -half)]
    return p, [(0, 0), (1, 0), (1, 1), (0, 1)], [(0, 1, 2), (0, 2, 3)]


def merge(*parts):
    """Several parts as one mesh; part i's UVs squeezed into column i of the unit square."""
    positions, uvs, tris = [], [], []
    for i, (p, u, t) in enumerate(parts):
        base = len(positions)
        positions += p
        uvs += [((i + x) / len(parts), y) for x, y in u]
        tris += [(a + base, b + base, c + base) for a, b, c in t]
    return positions, uvs, tris


STREET = [  # name, (center), (size); the ground first
    ("ground", None, None),
    ("building_west", (-8, 4, -5), (5, 8, 6)),
    ("building_east", (7, 3, -6), (6, 6, 5)),
    ("kiosk", (4, 1.25, 5), (2.5, 2.5, 2)),
    ("lamp_pole", (-3, 2.5, 4), (0.25, 5, 0.25)),
    ("car", (-6, 0.75, 2), (4, 1.5, 1.8)),
    ("awning", None, None),
]


def street_obj() -> str:
    lines = ["# street.obj: written by examples/make_examples.py (do not edit by hand)"]
    nv = 0
    for name, center, size in STREET:
        if name == "ground":
            p, u, t = quad(15)
        elif name == "awning":  # a roof on two posts in front of the west building
            p, u, t = merge(box((-8, 3, 0), (5, 0.2, 3)), box((-10.2, 1.45, 1.3), (0.2, 2.9, 0.2)),
                            box((-5.8, 1.45, 1.3), (0.2, 2.9, 0.2)))
        else:
            p, u, t = box(center, size)
        lines.append(f"o {name}")
        lines += [f"v {x:g} {y:g} {z:g}" for x, y, z in p]
        lines += [f"vt {a:.6g} {b:.6g}" for a, b in u]
        lines += [f"f {a + nv + 1}/{a + nv + 1} {b + nv + 1}/{b + nv + 1} {c + nv + 1}/{c + nv + 1}"
                  for a, b, c in t]
        nv += len(p)
    return "\n".join(lines) + "\n"


def street_frames() -> str:
    frames = []
    for i in range(4):
        x = 2.0 * i  # the car's offset from where street.obj puts it
        frames.append({
            "camera": {"eye": {"x": -4 + 2 * i, "y": 10, "z": 24}, "target": {"x": 0, "y": 1, "z": 0},
                       "width": 320, "height": 180},
            "transforms": [{"instance": 5, "transform": {"m": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0,
                                                                 x, 0, 0, 1]}}],
        })
    return json.dumps({"frames": frames}, indent=1) + "\n"


def model_glb() -> bytes:
    meshes = [quad(6), box((0, 0.5, 0), (1, 1, 1)), box((0, 0.75, 0), (6, 1.5, 0.3))]
    nodes = [
        {"name": "ground", "mesh": 0},
        {"name": "crate", "mesh": 1, "translation": [-1, 0, 1]},
        {"name": "crate_on_top", "mesh": 1, "translation": [-1, 1, 1],
         "rotation": [0, 0.3826834, 0, 0.9238795]},  # 45 degrees about y
        {"name": "wall", "mesh": 2, "translation": [0, 0, -3]},
    ]
    blob = bytearray()
    views, accessors, gl_meshes = [], [], []

    def add(data: bytes, target: int) -> int:
        while len(blob) % 4:
            blob.append(0)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data),
                      "target": target})
        blob.extend(data)
        return len(views) - 1

    for p, u, t in meshes:
        pos = add(b"".join(struct.pack("<3f", *v) for v in p), 34962)
        uv = add(b"".join(struct.pack("<2f", *v) for v in u), 34962)
        idx = add(b"".join(struct.pack("<3H", *v) for v in t), 34963)
        lo = [min(v[a] for v in p) for a in range(3)]
        hi = [max(v[a] for v in p) for a in range(3)]
        accessors += [
            {"bufferView": pos, "componentType": 5126, "count": len(p), "type": "VEC3",
             "min": lo, "max": hi},
            {"bufferView": uv, "componentType": 5126, "count": len(u), "type": "VEC2"},
            {"bufferView": idx, "componentType": 5123, "count": 3 * len(t), "type": "SCALAR"},
        ]
        a = len(accessors) - 3
        gl_meshes.append({"primitives": [{"attributes": {"POSITION": a, "TEXCOORD_0": a + 1},
                                          "indices": a + 2}]})
    while len(blob) % 4:
        blob.append(0)
    gltf = {"asset": {"version": "2.0", "generator": "examples/make_examples.py"},
            "scene": 0, "scenes": [{"nodes": list(range(len(nodes)))}], "nodes": nodes,
            "meshes": gl_meshes, "accessors": accessors, "bufferViews": views,
            "buffers": [{"byteLength": len(blob)}]}
    text = json.dumps(gltf, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    body = (struct.pack("<II", len(text), 0x4E4F534A) + text +
            struct.pack("<II", len(blob), 0x004E4942) + bytes(blob))
    return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body


def main() -> int:
    files = {"street.obj": street_obj().encode(), "model.glb": model_glb(),
             "street_frames.json": street_frames().encode()}
    check = "--check" in sys.argv[1:]
    stale = []
    for name, data in files.items():
        path = HERE / name
        if check:
            if not path.is_file() or path.read_bytes() != data:
                stale.append(name)
        else:
            path.write_bytes(data)
    if stale:
        print("examples/make_examples.py would write other bytes to: " + ", ".join(stale))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
