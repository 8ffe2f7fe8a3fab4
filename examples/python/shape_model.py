#!/usr/bin/env python3
"""A statistical shape model with qs and numpy.

Dissects a set of closed genus-0 meshes together, remeshes them with one connectivity (vertex i
is the same point of the common structure on every shape), aligns the remeshes by generalized
Procrustes (similarity), and runs PCA on the vertex positions. Writes the mean shape and, for the
first modes, the mean moved by -2 and +2 standard deviations, as OBJ files, and model.npz (mean,
modes, standard deviations, the one face list).

    PYTHONPATH=build/python python3 examples/python/shape_model.py [-o OUT] [--level N] [MESH ...]

Without meshes it takes the heads of ../shared/meshes (max_planck_11k, igea_17k,
mannequin_head_23k). Their files hold them in different poses, in which automatic seeds do not
correspond (the first mode then mixes a face with the back of a head), so the example places the
four seeds itself from each head's pose (POSES: where the face looks, which way is up): the nose
tip, the crown, the back of the head and the bottom of the neck, a loop through the plane of
symmetry. Meshes with landmark files beside them (<stem>.landmarks.json) use those; other meshes
get automatic seeds, which correspond when the shapes share one pose.
"""

import argparse
import os
import sys
import time

import numpy as np

import qs

HERE = os.path.dirname(os.path.abspath(__file__))
SHARED = os.path.normpath(os.path.join(HERE, "..", "..", "..", "shared", "meshes"))
HEADS = ["max_planck_11k.obj", "igea_17k.off", "mannequin_head_23k.off"]
# The default heads' poses in their files: (the direction the face looks, up).
POSES = {"max_planck_11k": ((0, 0, -1), (0, 1, 0)), "igea_17k": ((1, 0, 0), (0, 1, 0)),
         "mannequin_head_23k": ((0, -1, 0), (0, 0, 1))}


def head_seeds(mesh, forward, up):
    """Four seeds in loop order through a head's plane of symmetry: the nose tip (furthest
    forward), the crown (highest), the back of the head (furthest back, above the nose tip) and
    the bottom of the neck (lowest), as vertex ids."""
    v = np.asarray(mesh.vertices)
    f, u = v @ np.asarray(forward, float), v @ np.asarray(up, float)
    nose = int(np.argmax(f))
    crown = int(np.argmax(u))
    above = np.flatnonzero(u >= u[nose])
    back = int(above[np.argmin(f[above])])
    bottom = int(np.argmin(u))
    return qs.Landmarks(seeds=[nose, crown, back, bottom], name="pose seeds of " + mesh.name)


def write_obj(path, vertices, faces):
    with open(path, "w") as out:
        np.savetxt(out, vertices, fmt="v %.9g %.9g %.9g")
        np.savetxt(out, faces + 1, fmt="f %d %d %d")


def similarity(source, target):
    """The least-squares similarity (Umeyama) taking source onto target, applied to source."""
    ms, mt = source.mean(0), target.mean(0)
    s, t = source - ms, target - mt
    u, sig, vt = np.linalg.svd(s.T @ t)
    d = np.sign(np.linalg.det(u @ vt))
    fix = np.diag([1.0, 1.0, d])
    rot = u @ fix @ vt
    scale = (sig * np.diag(fix)).sum() / (s ** 2).sum()
    return scale * s @ rot + mt


def procrustes(shapes, iterations=10):
    """Generalized Procrustes: every shape moved onto the running mean (unit size, centred)."""
    mean = shapes[0] - shapes[0].mean(0)
    mean /= np.linalg.norm(mean)
    for _ in range(iterations):
        aligned = [similarity(x, mean) for x in shapes]
        new = np.mean(aligned, axis=0)
        new -= new.mean(0)
        new /= np.linalg.norm(new)
        if np.linalg.norm(new - mean) < 1e-12:
            break
        mean = new
    return np.array(aligned)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("meshes", nargs="*", help="closed genus-0 meshes (default: three heads of the shared meshes)")
    ap.add_argument("-o", "--output", default="out/shape_model", help="output folder (default: out/shape_model)")
    ap.add_argument("--level", type=int, default=4, help="remesh level (default 4)")
    ap.add_argument("--modes", type=int, default=2, help="modes written as meshes (default 2)")
    args = ap.parse_args()
    files = args.meshes or [os.path.join(SHARED, m) for m in HEADS]
    os.makedirs(args.output, exist_ok=True)

    t0 = time.perf_counter()
    meshes = [qs.read_mesh(f) for f in files]
    landmarks = []
    for f, m in zip(files, meshes):
        lm = os.path.splitext(f)[0] + ".landmarks.json"
        stem = os.path.splitext(os.path.basename(f))[0]
        if os.path.exists(lm):
            landmarks.append(qs.read_landmarks(lm, m))
        elif stem in POSES:
            landmarks.append(head_seeds(m, *POSES[stem]))
        else:
            landmarks.append(None)
    if any(l is None for l in landmarks):
        landmarks = None  # every mesh or none
    d = qs.dissect(meshes, landmarks=landmarks,
                   progress=lambda stage, f: print("\r  %-20s %3d%%" % (stage, 100 * f), end="", flush=True))
    print()
    t1 = time.perf_counter()
    d.save(os.path.join(args.output, "dissection"))
    r = qs.remesh(d, level=args.level)
    t2 = time.perf_counter()
    print("dissected %d meshes into %d common patches (%.2f s); level-%d remesh: %d vertices, %d faces each (%.2f s)"
          % (len(meshes), d.num_patches, t1 - t0, args.level, len(r.vertex_patch), len(r.faces), t2 - t1))

    # PCA on the aligned positions: X is (shapes, 3V).
    shapes = procrustes([p.copy() for p in r.positions])
    x = shapes.reshape(len(shapes), -1)
    mean = x.mean(0)
    u, s, vt = np.linalg.svd(x - mean, full_matrices=False)
    sd = s / np.sqrt(max(len(shapes) - 1, 1))
    modes = min(args.modes, len(shapes) - 1)
    variance = sd ** 2 / max((sd ** 2).sum(), 1e-300)
    faces = np.asarray(r.faces)
    write_obj(os.path.join(args.output, "mean.obj"), mean.reshape(-1, 3), faces)
    for k in range(modes):
        for sign, tag in ((-2, "minus2sd"), (2, "plus2sd")):
            write_obj(os.path.join(args.output, "mode%d_%s.obj" % (k + 1, tag)),
                      (mean + sign * sd[k] * vt[k]).reshape(-1, 3), faces)
    np.savez(os.path.join(args.output, "model.npz"), mean=mean.reshape(-1, 3), modes=vt[:modes].reshape(modes, -1, 3),
             sd=sd[:modes], faces=faces, names=np.array(d.files))
    t3 = time.perf_counter()
    print("PCA of %d shapes: %s of the variance in the first %d modes; wrote mean.obj, %d mode meshes and model.npz "
          "to %s (%.2f s; total %.2f s)" % (len(shapes), ", ".join("%.1f%%" % (100 * v) for v in variance[:modes]),
                                           modes, 2 * modes, args.output, t3 - t2, t3 - t0))
    return 0


if __name__ == "__main__":
    sys.exit(main())
