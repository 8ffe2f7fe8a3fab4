#!/usr/bin/python3
"""Leaf statistics of a qs-dissect folder: per mesh, the patches, how many are left over tau and
the share of the surface they hold, the largest over-tau leaf's share, and (with --top N) the N
largest over-tau leaves with their stretch, stop reason and face count.

  usage: bench/leafstats.py DISSECTION_DIR [--top N]

Areas are those of the chart's faces (the cut mesh), so shares add up to 1 per mesh. Needs numpy
(Debian: python3-numpy; use /usr/bin/python3).
"""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from qs_chart import read_chart  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('dir')
    ap.add_argument('--top', type=int, default=0, help='list the N largest leaves over tau')
    a = ap.parse_args()
    try:
        d = json.load(open(os.path.join(a.dir, 'dissection.json')))
    except (OSError, ValueError) as e:
        sys.exit(f'leafstats: {a.dir}: no readable dissection.json ({e})')
    tau = d['options']['tau']
    for m in d['meshes']:
        positions, faces = read_chart(os.path.join(a.dir, m['chart']))
        P = np.array(positions)
        V = np.array([f for f, _ in faces], dtype=np.int64).reshape(-1, 3)
        patch = np.array([p for _, p in faces], dtype=np.int64)
        A = 0.5 * np.linalg.norm(np.cross(P[V[:, 1]] - P[V[:, 0]], P[V[:, 2]] - P[V[:, 0]]), axis=1)
        area = np.bincount(patch, weights=A, minlength=len(m['patches'])) / A.sum()
        over = [i for i, p in enumerate(m['patches']) if p['stretch'] is None or p['stretch'] > tau]
        over.sort(key=lambda i: -area[i])
        big = area[over[0]] if over else 0.0
        print(f"{os.path.basename(m['file'])}: {len(m['patches'])} patches, {len(over)} over tau "
              f"({100 * sum(area[i] for i in over):.0f}% of area), largest over-tau leaf {100 * big:.1f}% of area, "
              f"max stretch {m['max_stretch'] if m['max_stretch'] is None else format(m['max_stretch'], '.4g')}")
        for i in over[:a.top]:
            p = m['patches'][i]
            print(f"  {p['name']:>18} {100 * area[i]:5.2f}%  stretch {p['stretch'] if p['stretch'] is None else format(p['stretch'], '.3g')}  "
                  f"{p.get('stop_reason', '')}  {p['faces']} faces")


if __name__ == '__main__':
    main()
