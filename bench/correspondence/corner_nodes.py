#!/usr/bin/env python3
"""Where do the patch corners of two charts of ONE surface part?

usage: corner_nodes.py DISSECTION_DIR [--nodes]

For a dissection of two tessellations of one surface (a mesh and its own re-tessellation, or one
smooth surface tessellated twice: bench/correspondence.sh's self-* and gen-v0 rows), the two
charts' corners of every node of the union quinary tree are compared as `qs-metro --correspondence`
compares the leaves' corners: mesh 1's corner against the image of mesh 0's corner on mesh 1,
taken as its closest point of mesh 1 (what a "surface" map does between vertices; for gen-v0,
whose truth is a sphere map, this is within the two tessellations' chord error), in % of mesh 1's
bounding-box diagonal. A node's corner k is corner 0 of its
child k down to a leaf (children S{0,1,5,4}, S{1,2,6,5}, S{2,3,7,6}, S{3,0,4,7}, S{4,5,6,7}), so
every node's corners are chart vertices. Per split node: `outer` = mean distance of its 4 corners
(what its parents handed down), `inner` = mean distance of the 4 split points it made (the corners
of its child 4), `made` = inner - outer. Printed per depth and per stretch band (the node's
largest L2 stretch over the two meshes), and with --nodes per node.
"""
import json
import struct
import sys
from collections import defaultdict

import numpy as np


def read_chart(path):
    """Positions (#V x 3) and faces (#F x 3) of a qs chart file (binary PLY, version 2)."""
    with open(path, "rb") as f:
        header = b""
        while not header.endswith(b"end_header\n"):
            header += f.readline()
        nv = nf = None
        for line in header.decode("ascii").splitlines():
            if line.startswith("element vertex"):
                nv = int(line.split()[2])
            if line.startswith("element face"):
                nf = int(line.split()[2])
        xyz = np.frombuffer(f.read(24 * nv), dtype="<f8").reshape(nv, 3)
        rec = np.dtype([("n", "u1"), ("v", "<i4", 3), ("m", "u1"), ("uv", "<f8", 6), ("patch", "<i4"), ("rgb", "u1", 3)])
        faces = np.frombuffer(f.read(rec.itemsize * nf), dtype=rec)
        if not (np.all(faces["n"] == 3) and np.all(faces["m"] == 6)):
            raise SystemExit(f"{path}: not a qs chart (version 2) face list")
    return xyz, faces["v"].astype(np.int64)


def closest_points(p, a, b, c):
    """Closest point to p on each triangle (a[i], b[i], c[i]) (Ericson, Real-Time Collision
    Detection 5.1.5), vectorized over the triangles."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = ap @ ab.T if ab.ndim == 1 else np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    bp = p - b
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    cp = p - c
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    denom = va + vb + vc
    denom = np.where(np.abs(denom) > 1e-300, denom, 1e-300)
    v = vb / denom
    w = vc / denom
    out = a + ab * v[:, None] + ac * w[:, None]  # inside the face
    with np.errstate(divide="ignore", invalid="ignore"):
        # edge regions
        t = np.clip(d1 / (d1 - d3), 0, 1)
        m = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
        out[m] = (a + ab * t[:, None])[m]
        t = np.clip(d2 / (d2 - d6), 0, 1)
        m = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
        out[m] = (a + ac * t[:, None])[m]
        t = np.clip((d4 - d3) / ((d4 - d3) + (d5 - d6)), 0, 1)
        m = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
        out[m] = (b + (c - b) * t[:, None])[m]
    # vertex regions
    m = (d1 <= 0) & (d2 <= 0)
    out[m] = a[m]
    m = (d3 >= 0) & (d4 <= d3)
    out[m] = b[m]
    m = (d6 >= 0) & (d5 <= d6)
    out[m] = c[m]
    return out


def closest_on(xyz, faces, p):
    """The closest point of the mesh (xyz, faces) to p (brute force)."""
    q = closest_points(p, xyz[faces[:, 0]], xyz[faces[:, 1]], xyz[faces[:, 2]])
    return q[np.argmin(np.einsum("ij,ij->i", q - p, q - p))]


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        return 1
    folder = sys.argv[1]
    doc = json.load(open(f"{folder}/dissection.json"))
    meshes = doc["meshes"]
    if len(meshes) != 2:
        print(f"{folder}: {len(meshes)} meshes; expected two tessellations of one surface", file=sys.stderr)
        return 2
    charts = [read_chart(f"{folder}/{m['chart']}") for m in meshes]
    pos = [c[0] for c in charts]
    image = {}  # mesh 0's corner -> its image on mesh 1 (the closest point, as the surface map has it)
    corners = [{p["name"]: p["corners"] for p in m["patches"]} for m in meshes]
    diag = float(np.linalg.norm(pos[1].max(axis=0) - pos[1].min(axis=0)))
    nodes = {n["name"]: n for n in doc["tree"]}
    stretch = {name: max(m["node_stretch"].get(name, 0.0) for m in meshes) for name in nodes}

    def corner(i, name, k):
        if name in corners[i]:
            return corners[i][name][k]
        return corner(i, f"{name}.{k}", 0)

    def dist(name, k):
        a = corner(0, name, k)
        if a not in image:
            image[a] = closest_on(charts[1][0], charts[1][1], pos[0][a])
        return 100 * float(np.linalg.norm(pos[1][corner(1, name, k)] - image[a])) / diag

    rows = []
    for name, n in nodes.items():
        if not n.get("split") or f"{name}.4" not in nodes:
            continue
        outer = [dist(name, k) for k in range(4)]
        inner = [dist(f"{name}.4", k) for k in range(4)]
        rows.append((name, n["depth"], stretch[name], np.mean(outer), np.mean(inner), max(inner)))
    leaves = [dist(p, k) for p in corners[0] for k in range(4)]
    print(f"{folder}: {len(rows)} split nodes, {len(corners[0])} leaves; leaf corners {np.mean(leaves):.3f}% apart "
          f"on average (max {max(leaves):.3f}%), % of mesh 1's diagonal")

    def table(key, label):
        groups = defaultdict(list)
        for r in rows:
            groups[key(r)].append(r)
        print(f"| {label} | split nodes | outer corners apart | inner corners apart (mean / max) | made (inner - outer) |")
        print("|---|---:|---:|---:|---:|")
        for g in sorted(groups):
            rs = groups[g]
            print(f"| {g} | {len(rs)} | {np.mean([r[3] for r in rs]):.3f}% | {np.mean([r[4] for r in rs]):.3f} / "
                  f"{max(r[5] for r in rs):.3f}% | {np.mean([r[4] - r[3] for r in rs]):+.3f}% |")

    table(lambda r: r[1], "depth")
    bands = [(0, 3, "<= 3"), (3, 6, "3-6"), (6, 20, "6-20"), (20, 100, "20-100"), (100, 1e300, "> 100")]
    table(lambda r: next(f"{i}: {b[2]}" for i, b in enumerate(bands) if b[0] < r[2] <= b[1] or (i == 0 and r[2] <= b[1])),
          "stretch")
    if "--nodes" in sys.argv:
        print("| node | depth | stretch | outer | inner (mean / max) |")
        print("|---|---:|---:|---:|---:|")
        for r in sorted(rows, key=lambda r: (r[1], r[0])):
            print(f"| {r[0]} | {r[1]} | {r[2]:.1f} | {r[3]:.3f}% | {r[4]:.3f} / {r[5]:.3f}% |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
