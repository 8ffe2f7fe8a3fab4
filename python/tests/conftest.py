"""Shared fixtures: the built tools, the example meshes, small generated meshes."""

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

SOURCE = Path(os.environ.get("QS_SOURCE_DIR", Path(__file__).resolve().parents[2])).resolve()
TOOLS = Path(os.environ.get("QS_TOOLS", SOURCE / "build" / "tools")).resolve()
EXAMPLES = SOURCE / "examples"


def run_tool(name, *args, cwd=None):
    """Runs a built tool; returns (exit code, stdout, stderr)."""
    p = subprocess.run([str(TOOLS / name), *map(str, args)], cwd=cwd, capture_output=True, text=True, timeout=120)
    return p.returncode, p.stdout, p.stderr


def tool_error(stderr, tool):
    """The message of a tool's one-line error 'tool: kind error: message' (message may span lines)."""
    prefix = tool + ": "
    assert stderr.startswith(prefix), stderr
    rest = stderr[len(prefix):]
    message = rest.split(" error: ", 1)[1]
    assert message.endswith("\n")
    return message[:-1]  # the tool ends the message with a newline


def icosphere(subdivisions, axes=(1.0, 0.8, 0.6)):
    """A closed genus-0 triangle mesh: an icosahedron subdivided and projected onto an ellipsoid."""
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    verts = [np.array(p, float) / np.linalg.norm(p) for p in v]
    faces = f
    for _ in range(subdivisions):
        mid = {}

        def m(a, b):
            k = (min(a, b), max(a, b))
            if k not in mid:
                p = verts[a] + verts[b]
                verts.append(p / np.linalg.norm(p))
                mid[k] = len(verts) - 1
            return mid[k]

        nf = []
        for a, b, c in faces:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = nf
    return np.array(verts) * np.array(axes), np.array(faces, dtype=np.int32)


def write_obj(path, vertices, faces):
    with open(path, "w") as out:
        for p in vertices:
            out.write("v %.17g %.17g %.17g\n" % tuple(p))
        for a, b, c in faces:
            out.write("f %d %d %d\n" % (a + 1, b + 1, c + 1))


def read_obj(path):
    """(vertices as float64, faces as int32 0-based) of a triangle OBJ."""
    v, f = [], []
    for line in open(path):
        s = line.split()
        if not s:
            continue
        if s[0] == "v":
            v.append([float(x) for x in s[1:4]])
        elif s[0] == "f":
            f.append([int(x.split("/")[0]) - 1 for x in s[1:4]])
    return np.array(v), np.array(f, dtype=np.int32)


@pytest.fixture(scope="session")
def tools():
    if not (TOOLS / "qs-dissect").exists():
        pytest.fail("the tools are not built in %s (set QS_TOOLS)" % TOOLS)
    return TOOLS
