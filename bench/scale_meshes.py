#!/usr/bin/env python3
"""Meshes for bench/scale.sh, built by script (no third-party modules).

  scale_meshes.py cone K OUT.off          double cone: a ring of K vertices, two apexes of valence K
  scale_meshes.py subdivide N IN OUT.off  N steps of 1->4 midpoint subdivision (OBJ or OFF in)
"""
import sys


def read_mesh(path):
    verts, faces = [], []
    with open(path, encoding="utf-8", errors="replace") as f:
        if path.lower().endswith(".off"):
            toks = []
            for line in f:
                line = line.split("#", 1)[0].strip()
                if line:
                    toks.extend(line.split())
            if toks[0].upper().endswith("OFF"):
                toks = toks[1:]
            nv, nf = int(toks[0]), int(toks[1])
            i = 3
            for _ in range(nv):
                verts.append(tuple(float(t) for t in toks[i:i + 3]))
                i += 3
            for _ in range(nf):
                n = int(toks[i])
                idx = [int(t) for t in toks[i + 1:i + 1 + n]]
                i += 1 + n
                for k in range(1, n - 1):
                    faces.append((idx[0], idx[k], idx[k + 1]))
        else:
            for line in f:
                p = line.split()
                if not p:
                    continue
                if p[0] == "v":
                    verts.append(tuple(float(t) for t in p[1:4]))
                elif p[0] == "f":
                    idx = [int(t.split("/")[0]) for t in p[1:]]
                    idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                    for k in range(1, len(idx) - 1):
                        faces.append((idx[0], idx[k], idx[k + 1]))
    return verts, faces


def write_off(path, verts, faces):
    with open(path, "w", encoding="ascii") as f:
        f.write("OFF\n%d %d 0\n" % (len(verts), len(faces)))
        f.write("".join("%.9g %.9g %.9g\n" % v for v in verts))
        f.write("".join("3 %d %d %d\n" % t for t in faces))


def subdivide(verts, faces):
    verts = list(verts)
    mid = {}

    def m(a, b):
        key = (a, b) if a < b else (b, a)
        i = mid.get(key)
        if i is None:
            pa, pb = verts[a], verts[b]
            i = len(verts)
            verts.append(((pa[0] + pb[0]) / 2, (pa[1] + pb[1]) / 2, (pa[2] + pb[2]) / 2))
            mid[key] = i
        return i

    out = []
    for a, b, c in faces:
        ab, bc, ca = m(a, b), m(b, c), m(c, a)
        out += [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]
    return verts, out


def cone(k):
    import math
    verts = [(0.0, 0.0, 1.0), (0.0, 0.0, -1.0)]
    for i in range(k):
        t = 2 * math.pi * i / k
        verts.append((math.cos(t), math.sin(t), 0.0))
    faces = []
    for i in range(k):
        a, b = 2 + i, 2 + (i + 1) % k
        faces.append((0, a, b))
        faces.append((1, b, a))
    return verts, faces


def main(argv):
    if len(argv) == 4 and argv[1] == "cone":
        write_off(argv[3], *cone(int(argv[2])))
    elif len(argv) == 5 and argv[1] == "subdivide":
        verts, faces = read_mesh(argv[3])
        for _ in range(int(argv[2])):
            verts, faces = subdivide(verts, faces)
        write_off(argv[4], verts, faces)
    else:
        sys.stderr.write(__doc__)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
