#!/usr/bin/env python3
"""Pick corresponding landmarks on the quadruped examples (spot_2k, cat_16k, koala_7k).

Writes examples/<stem>.landmarks.json for each mesh (found automatically by qs-dissect beside the
mesh). Plain Python 3, no dependencies; deterministic.

    python3 examples/pick_landmarks.py [--markers DIR]

--markers DIR also writes DIR/<stem>.markers.obj: the mesh plus a small octahedron at every
landmark (seeds and features), to check the picks with qs-render.

Orientation. Every mesh stands on its feet with +y up (ground at min y); the direction the head
faces differs and was read off renders (qs-render --view 1,0,0 / 0,1,0 / 0,0,1) and is printed
with the bounding box and principal axes:
    spot_2k   head towards -z  (its highest vertices, the horns, are at z < 0)
    cat_16k   head towards -x  (play-bow stretch: front legs flat on the ground, rump and tail up)
    koala_7k  head towards +z
With up U and forward F, the animal's left is L = U x F (right-handed), so "left" means the
same thing in every mesh.

Picks, in the body frame (h = height, f = forward, l = left):
  feet     toe tips. The ground contact region (h below the lowest point + 3% of the height) is
           split front/hind at the widest gap along f, each half left/right at the middle of its
           l range (the cat's two front legs lie side by side on the ground); in each quadrant
           the largest connected piece is the paw and its most forward vertex the toe tip.
  nose     the vertex nearest the centre of the frontal cap (the most forward 2% of the length,
           among vertices above 12% of the height, i.e. above the cat's stretched front paws).
  ears     in the head (not below the nose, within 25% of the length behind it), on each side
           the vertex maximizing |l - l_nose| + 0.5 (h - h_nose): out and up, i.e. the cat's
           and koala's ear tips and spot's ears (not its horns, which are near the midline).
  tail     the vertex geodesically (along edges) farthest from the nose among those above 25% of
           the height: the cat's tail tip, spot's tail, the koala's rump (it has no real tail).
  seeds    the 4 toe tips: s0 left front, s1 left hind, s2 right hind, s3 right front. The seed
           loop runs along each leg and across the chest, the belly sides and the crotch, so
           seed patch 1 is the underside (belly, inner sides of the legs) and patch 0 the rest
           (back, flanks, head, tail, outer sides of the legs); the feet correspond exactly.
           (A belt around the torso, as in scripts/cat-lion-landmarks.sh, does not work here:
           the cat's two front paws, side by side at the end of its stretched front legs, map
           within 1e-3 of each other in the front patch, so front-foot features cannot be
           aligned with the other meshes, and without them the front legs do not correspond.)
Features: nose, left_ear, right_ear, tail. Only the picks are made here; check the set with
    build/tools/qs-dissect examples/spot_2k.obj examples/cat_16k.obj examples/koala_7k.obj -o OUT
(exit 0, every feature at the same patch and uv in the three meshes) and render OUT/*.chart.ply.
"""
import heapq
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))

MESHES = {
    # stem: (up axis, forward axis) as unit vectors
    "spot_2k": ((0, 1, 0), (0, 0, -1)),
    "cat_16k": ((0, 1, 0), (-1, 0, 0)),
    "koala_7k": ((0, 1, 0), (0, 0, 1)),
}


def load_obj(path):
    verts, faces = [], []
    with open(path) as fh:
        for line in fh:
            if line.startswith("v "):
                verts.append(tuple(float(x) for x in line.split()[1:4]))
            elif line.startswith("f "):
                idx = [int(t.split("/")[0]) for t in line.split()[1:]]
                idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                for k in range(1, len(idx) - 1):
                    faces.append((idx[0], idx[k], idx[k + 1]))
    return verts, faces


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dist(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


def principal_axes(verts):
    """Centroid and eigen-decomposition of the vertex covariance (Jacobi): [(variance, direction)]
    by decreasing variance. Also used by bench/real_self_pairs.sh."""
    n = len(verts)
    c = [sum(v[k] for v in verts) / n for k in range(3)]
    a = [[sum((v[i] - c[i]) * (v[j] - c[j]) for v in verts) / n for j in range(3)] for i in range(3)]
    e = [[1.0 if i == j else 0.0 for j in range(3)] for i in range(3)]
    for _ in range(50):
        p, q = max(((0, 1), (0, 2), (1, 2)), key=lambda pq: abs(a[pq[0]][pq[1]]))
        if abs(a[p][q]) < 1e-15:
            break
        th = 0.5 * math.atan2(2 * a[p][q], a[q][q] - a[p][p])
        cs, sn = math.cos(th), math.sin(th)
        for k in range(3):
            akp, akq = a[k][p], a[k][q]
            a[k][p], a[k][q] = cs * akp - sn * akq, sn * akp + cs * akq
        for k in range(3):
            apk, aqk = a[p][k], a[q][k]
            a[p][k], a[q][k] = cs * apk - sn * aqk, sn * apk + cs * aqk
        for k in range(3):
            ekp, ekq = e[k][p], e[k][q]
            e[k][p], e[k][q] = cs * ekp - sn * ekq, sn * ekp + cs * ekq
    vals = [a[i][i] for i in range(3)]
    order = sorted(range(3), key=lambda i: -vals[i])
    return c, [(vals[i], tuple(e[k][i] for k in range(3))) for i in order]


def components(subset, faces):
    """Connected pieces of a vertex subset, joined by mesh edges inside the subset."""
    parent = {v: v for v in subset}

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for f in faces:
        for a, b in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0])):
            if a in parent and b in parent:
                ra, rb = find(a), find(b)
                if ra != rb:
                    parent[ra] = rb
    groups = {}
    for v in subset:
        groups.setdefault(find(v), []).append(v)
    return sorted(groups.values(), key=len, reverse=True)


def geodesic_from(src, verts, faces):
    """Dijkstra distances along mesh edges from vertex src."""
    nbr = [set() for _ in verts]
    for f in faces:
        for a, b in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0])):
            nbr[a].add(b)
            nbr[b].add(a)
    d = [math.inf] * len(verts)
    d[src] = 0.0
    heap = [(0.0, src)]
    while heap:
        du, u = heapq.heappop(heap)
        if du > d[u]:
            continue
        for w in nbr[u]:
            dw = du + dist(verts[u], verts[w])
            if dw < d[w]:
                d[w] = dw
                heapq.heappush(heap, (dw, w))
    return d


def pick(stem):
    verts, faces = load_obj(os.path.join(HERE, stem + ".obj"))
    up, fwd = MESHES[stem]
    left = cross(up, fwd)
    H = [dot(v, up) for v in verts]
    Fw = [dot(v, fwd) for v in verts]
    Lf = [dot(v, left) for v in verts]
    n = len(verts)
    hmin, hmax = min(H), max(H)
    height = hmax - hmin
    length = max(Fw) - min(Fw)
    lo = [min(v[k] for v in verts) for k in range(3)]
    hi = [max(v[k] for v in verts) for k in range(3)]
    c, axes = principal_axes(verts)
    print(f"{stem}: {n} vertices, bbox {lo} .. {hi}")
    axes = [(val, tuple(round(x, 3) for x in d)) for val, d in axes]
    print(f"  centroid {[round(x, 3) for x in c]}, principal axes (variance, direction): {axes}")
    print(f"  up {up}, forward {fwd}, left {left}; height {height:.3f}, length {length:.3f}")

    # feet: the ground contact region split into 4 quadrants: front/hind at the widest gap
    # between ground vertices along f, then left/right at the middle of each pair's l range
    ground = sorted((i for i in range(n) if H[i] < hmin + 0.03 * height), key=lambda i: Fw[i])
    gap = max(range(1, len(ground)), key=lambda k: Fw[ground[k]] - Fw[ground[k - 1]])
    print(f"  ground region: {len(ground)} vertices, front/hind gap at f {Fw[ground[gap - 1]]:.3f} .. {Fw[ground[gap]]:.3f}")
    feet = {}
    for part, name in ((ground[gap:], "front"), (ground[:gap], "hind")):
        l_split = 0.5 * (min(Lf[i] for i in part) + max(Lf[i] for i in part))
        for side, sign in (("left", 1), ("right", -1)):
            quad = [i for i in part if sign * (Lf[i] - l_split) > 0]
            paw = components(set(quad), faces)[0]
            # toe tip: the most forward vertex of the paw's ground contact
            feet[f"{side}_{name}_foot"] = max(paw, key=lambda i: (Fw[i], -i))

    # nose: the centre of the frontal cap (the most forward 2% of the length, above the paws)
    above = [i for i in range(n) if H[i] > hmin + 0.12 * height]
    f_top = max(Fw[i] for i in above)
    cap = [i for i in above if Fw[i] > f_top - 0.02 * length]
    cen = [sum(verts[i][d] for i in cap) / len(cap) for d in range(3)]
    nose = min(cap, key=lambda i: (dist(verts[i], cen), i))
    # ears: in the head (not below the nose, within 25% of the length behind it), on each side
    # the vertex farthest out, tilted upwards (ears, not spot's horns, which are nearer the midline)
    head = [i for i in range(n) if H[i] >= H[nose] and Fw[i] > Fw[nose] - 0.25 * length]
    ears = {
        "left_ear": max((i for i in head if Lf[i] > Lf[nose]),
                        key=lambda i: (Lf[i] - Lf[nose] + 0.5 * (H[i] - H[nose]), -i)),
        "right_ear": max((i for i in head if Lf[i] < Lf[nose]),
                         key=lambda i: (Lf[nose] - Lf[i] + 0.5 * (H[i] - H[nose]), -i)),
    }

    # tail: the far end of the body, the vertex geodesically farthest from the nose among those
    # above the legs (h above 25% of the height): the cat's tail tip, spot's tail, the koala's rump
    g = geodesic_from(nose, verts, faces)
    tail = max((i for i in range(n) if H[i] > hmin + 0.25 * height), key=lambda i: (g[i], -i))

    # seeds: the 4 toe tips, left front, left hind, right hind, right front: the seed loop runs
    # along the legs and across chest, belly sides and crotch, so patch 1 is the underside (belly
    # and the inner sides of the legs) and patch 0 everything else; each leg is cut lengthwise
    seeds = [feet["left_front_foot"], feet["left_hind_foot"], feet["right_hind_foot"],
             feet["right_front_foot"]]

    features = {"nose": nose}
    features.update(ears)
    features["tail"] = tail
    for name, i in list(zip(("s0", "s1", "s2", "s3"), seeds)) + list(features.items()):
        print(f"  {name:18s} {i:6d}  h {H[i] - hmin:7.3f}  f {Fw[i]:7.3f}  l {Lf[i]:7.3f}")
    return verts, faces, seeds, features


def write_markers(path, verts, faces, ids):
    diag = dist([min(v[k] for v in verts) for k in range(3)], [max(v[k] for v in verts) for k in range(3)])
    r = 0.025 * diag
    with open(path, "w") as fh:
        for v in verts:
            fh.write("v %.6f %.6f %.6f\n" % v)
        for f in faces:
            fh.write("f %d %d %d\n" % (f[0] + 1, f[1] + 1, f[2] + 1))
        base = len(verts)
        octa_f = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]
        for i in ids:
            x, y, z = verts[i]
            for d in ((r, 0, 0), (-r, 0, 0), (0, r, 0), (0, -r, 0), (0, 0, r), (0, 0, -r)):
                fh.write("v %.6f %.6f %.6f\n" % (x + d[0], y + d[1], z + d[2]))
            for f in octa_f:
                fh.write("f %d %d %d\n" % (base + f[0] + 1, base + f[1] + 1, base + f[2] + 1))
            base += 6


def main():
    markers = None
    if len(sys.argv) == 3 and sys.argv[1] == "--markers":
        markers = sys.argv[2]
        os.makedirs(markers, exist_ok=True)
    elif len(sys.argv) != 1:
        sys.exit(__doc__)
    for stem in MESHES:
        verts, faces, seeds, features = pick(stem)
        out = os.path.join(HERE, stem + ".landmarks.json")
        with open(out, "w") as fh:
            fh.write('{\n  "seeds": [%s],\n  "features": {\n' % ", ".join(map(str, seeds)))
            fh.write(",\n".join('    "%s": %d' % kv for kv in features.items()))
            fh.write("\n  }\n}\n")
        print(f"  wrote {out}")
        if markers:
            write_markers(os.path.join(markers, stem + ".markers.obj"), verts, faces,
                          seeds + list(features.values()))


if __name__ == "__main__":
    main()
