"""qs: consistent quad dissections of genus-0 meshes, from Python.

The same pipeline as the command-line tools, over the same library, with numpy arrays in and out::

    import qs
    a = qs.read_mesh("examples/spot_2k.obj")
    b = qs.read_mesh("examples/cat_16k.obj")
    la = qs.read_landmarks("examples/spot_2k.landmarks.json", a)
    lb = qs.read_landmarks("examples/cat_16k.landmarks.json", b)
    d = qs.dissect([a, b], landmarks=[la, lb])      # qs-dissect's defaults
    d.save("out/sc/dissection")                     # the files qs-dissect writes
    r = qs.remesh(d, level=4)                       # one face list, a position array per mesh
    r.faces, r.positions[0], r.positions[1]

Errors are exceptions of one hierarchy, with the tools' messages: qs.Error, and under it
qs.UsageError (exit code 1), qs.InvalidInput (a ValueError; 2), qs.IoError (an OSError; 3),
qs.SolverError (a RuntimeError; 4), qs.InternalError (a RuntimeError; 70).

Long calls (dissect, remesh, bake, merge, metro, correspondence_error) release the GIL, stop on Ctrl-C (KeyboardInterrupt) and take
an optional progress callback progress(stage: str, fraction: float). Reference: docs/python.md.
"""

import json as _json
import os as _os

from . import _qs
from ._qs import Error, UsageError, InvalidInput, IoError, SolverError, InternalError, Mesh

__all__ = [
    "Error", "UsageError", "InvalidInput", "IoError", "SolverError", "InternalError",
    "Mesh", "read_mesh", "inspect", "Landmarks", "read_landmarks",
    "dissect", "Dissection", "remesh", "Remesh", "bake", "morph", "merge", "metro", "correspondence_error",
    "DISSECT_DEFAULTS",
]

Mesh.__doc__ = """A triangle mesh: Mesh(vertices, faces, name="mesh").

vertices: (n, 3) float64 (or float32) array, C-contiguous, finite.
faces: (m, 3) int32 (or int64) array of 0-based vertex indices, C-contiguous, in range.
name: how the mesh is named in reports and in dissection.json; its stem names the chart file
(<stem>.chart.ply) and the remesh output (<stem>.obj).

Any other array raises qs.InvalidInput (a ValueError) saying what was expected. The mesh is
validated on construction as qs-inspect does it (closed, manifold, one component, genus 0):
.accepted tells the verdict and .report the text qs-inspect prints; a rejected mesh can still be
measured (qs.metro) but dissect raises qs.InvalidInput with that report.

Attributes: vertices, faces (read-only views of the mesh as given), name, accepted, report.
"""


def read_mesh(path):
    """Reads a mesh file (.obj .off .ply .stl; format by extension) and validates it.

    Returns a qs.Mesh named by the path as given (as qs-dissect names its inputs). Raises
    qs.IoError when the file cannot be read, qs.InvalidInput for a parse error (naming the line
    or byte offset). A mesh that parses but is rejected (open, non-manifold, genus > 0) is
    returned with .accepted False; see .report.
    """
    return _qs.read_mesh(_os.fspath(path))


def inspect(mesh):
    """What qs-inspect --json says of a mesh: a dict with "read" (format, polygons
    triangulated, notes), "validation" (counts, components, genus, problems with their kinds,
    counts and first ids, "accepted") and "accepted".

    mesh: a qs.Mesh, or a path (read with qs.read_mesh).
    """
    if not isinstance(mesh, Mesh):
        mesh = read_mesh(mesh)
    return _json.loads(mesh._inspect_json())


class Landmarks:
    """Landmarks of one mesh: Landmarks(seeds=None, features=None, name="python").

    seeds: None (automatic seeds) or 4 references, in loop order.
    features: None or {name: reference}; features correspond across a set by name.
    A reference is a vertex index (int), a point (x, y, z) placed at the closest surface point,
    or a dict as in a landmark file: {"vertex": i}, {"point": [x, y, z]}, {"face": f,
    "bary": [a, b, c]} (docs/landmarks.md). Ids refer to the mesh as given.
    name: names them in messages and as the seed source in dissection.json.

    They are checked against a mesh when used (qs.dissect) or by .resolve(mesh); a bad
    reference raises qs.InvalidInput naming the landmark. qs.read_landmarks reads a file.
    """

    def __init__(self, seeds=None, features=None, name="python", _impl=None):
        if _impl is not None:
            self._impl = _impl
            return
        doc = {}
        if seeds is not None:
            doc["seeds"] = [_reference(s, "seeds[%d]" % i) for i, s in enumerate(seeds)]
        if features is not None:
            if not isinstance(features, dict):
                raise InvalidInput("features: expected a dict {name: reference}, got %s" % type(features).__name__)
            doc["features"] = {str(k): _reference(v, "features[%r]" % k) for k, v in features.items()}
        self._impl = _qs._landmarks_from_text(_json.dumps(doc, allow_nan=False), str(name))

    @property
    def source(self):
        """The landmark file, or the name given."""
        return self._impl.source

    def resolve(self, mesh):
        """The landmarks placed on `mesh`: {"seeds": [...], "features": [...]}, each with its
        name, face, bary, position (and vertex, snap_distance when they apply), as qs-inspect
        --json gives them. Raises qs.InvalidInput for a reference that does not fit the mesh."""
        return _json.loads(self._impl._resolve_json(mesh))

    def __repr__(self):
        return "<qs.Landmarks from %s>" % self.source


def _reference(r, where):
    import numbers
    if isinstance(r, bool):
        raise InvalidInput("%s: expected a vertex index, a point (x, y, z) or a dict, got a bool" % where)
    if isinstance(r, numbers.Integral):
        return int(r)
    if isinstance(r, dict):
        return r
    try:
        p = [float(x) for x in r]
    except (TypeError, ValueError):
        raise InvalidInput("%s: expected a vertex index, a point (x, y, z) or a dict, got %r" % (where, r)) from None
    if len(p) != 3:
        raise InvalidInput("%s: a point needs 3 coordinates, got %d" % (where, len(p)))
    if not all(x == x and abs(x) != float("inf") for x in p):
        raise InvalidInput("%s: the point %r is not finite" % (where, tuple(p)))
    return {"point": p}


def read_landmarks(path, mesh):
    """Reads a landmark file (.json or MeshLab .pp) for `mesh` and checks it against the mesh.

    Returns qs.Landmarks (their seed source in dissection.json is the path as given). Raises
    qs.IoError when the file cannot be read, qs.InvalidInput for a malformed file or a landmark
    that does not fit the mesh (the messages of qs-inspect and qs-dissect).
    """
    return Landmarks(_impl=_qs._read_landmarks(_os.fspath(path), mesh))


def _defaults():
    return _json.loads(_qs._config_json("{}"))


#: The dissection's options and their defaults (qs-dissect's), by the names of --config.
DISSECT_DEFAULTS = _defaults()


class Dissection:
    """A dissected set: the same quad patches on every mesh, each mapped onto the unit square.

    Made by qs.dissect or read by Dissection.load(folder). Attributes: files (the meshes' names),
    chart_files, num_patches, patch_names, report (qs-dissect's text report; empty when loaded),
    maps, folded_faces, folder (where it was saved or loaded from, else None).
    """

    def __init__(self, impl):
        self._impl = impl

    @classmethod
    def load(cls, folder):
        """Reads a dissection folder (dissection.json and its chart PLYs), as qs-remesh does.
        Raises qs.IoError for missing files, qs.InvalidInput for an inconsistent folder."""
        return cls(_qs._load_dissection(_os.fspath(folder)))

    def save(self, folder):
        """Writes <stem>.chart.ply per mesh and dissection.json into `folder`, all or nothing:
        the files qs-dissect writes for the same input (dissection.json names the meshes and
        landmark files by the names they were given). Raises qs.UsageError when a file would
        replace an input, qs.IoError when the folder cannot be written."""
        self._impl.save(_os.fspath(folder))

    def chart(self, i):
        """Mesh i's chart: {"vertices": (n, 3), "faces": (m, 3) int32, "face_uv": (m, 3, 2) the
        corners' (u, v) in their patch, "face_patch": (m,) int32 index into patch_names}. The
        chart is the input surface with the cut vertices added (input vertices first)."""
        return self._impl._chart(i)

    def check_bijective(self):
        """Raises qs.SolverError (qs-dissect's exit 4 message) when uv faces stay folded."""
        self._impl.check_bijective()

    files = property(lambda self: self._impl.files)
    chart_files = property(lambda self: self._impl.chart_files)
    num_patches = property(lambda self: self._impl.num_patches)
    patch_names = property(lambda self: self._impl.patch_names)
    report = property(lambda self: self._impl.report)
    maps = property(lambda self: self._impl.maps)
    folded_faces = property(lambda self: self._impl.folded_faces)
    folder = property(lambda self: self._impl.folder)

    def __len__(self):
        return len(self._impl.files)

    def __repr__(self):
        return "<qs.Dissection: %d meshes, %d patches%s>" % (
            len(self), self.num_patches, "" if self.folder is None else ", folder " + self.folder)


def dissect(meshes, landmarks=None, *, threads=0, progress=None, allow_folded=False, **options):
    """Dissects meshes together: one union quinary tree, the same quad patches on every mesh.

    meshes: qs.Mesh objects (qs.read_mesh or qs.Mesh(...)), accepted by validation.
    landmarks: None (automatic seeds for every mesh) or one qs.Landmarks (or None) per mesh, in
      order. Seeds correspond by order, features by name; either every mesh has seeds or none.
      Landmark files beside the meshes are not looked up: read them with qs.read_landmarks.
    threads: 0 for all hardware threads; the result does not depend on it.
    progress: None or a callable progress(stage, fraction); stages "registration" (one surface
      in other poses only), "seed loops", "quinary subdivision", "leaf repairs", "refine maps".
    allow_folded: return a result whose uv faces stay folded instead of raising qs.SolverError
      (qs-dissect writes such a result, then exits with 4).
    **options: the dissection's options by their --config names, defaults as in qs-dissect
      (listed below and in qs.DISSECT_DEFAULTS); e.g. tau=2.5, max_depth=7, same_pose=True,
      refine_maps=False. An unknown name or a value out of range raises qs.UsageError.

    Returns a qs.Dissection. Raises qs.InvalidInput for a rejected mesh or landmarks that do not
    fit, qs.SolverError when a map fails, KeyboardInterrupt on Ctrl-C.

    Options (name, default, what it does):
    """
    meshes = list(meshes)
    if landmarks is not None:
        landmarks = list(landmarks)
        for i, l in enumerate(landmarks):
            if l is not None and not isinstance(l, Landmarks):
                raise UsageError("landmarks[%d]: expected qs.Landmarks or None, got %s" % (i, type(l).__name__))
        impls = [None if l is None else l._impl for l in landmarks]
    else:
        impls = []
    for i, m in enumerate(meshes):
        if not isinstance(m, Mesh):
            raise UsageError("meshes[%d]: expected qs.Mesh, got %s" % (i, type(m).__name__))
    try:
        options_json = _json.dumps(options, allow_nan=False)
    except (TypeError, ValueError) as e:
        raise UsageError("options: %s" % e) from None
    d = Dissection(_qs._dissect(meshes, impls, options_json, int(threads), progress))
    if not allow_folded:
        d.check_bijective()
    return d


dissect.__doc__ = dissect.__doc__.rstrip(" ") + "".join("    " + line + "\n" for line in _qs._describe_config().splitlines() if line.strip())


class Remesh:
    """Semi-regular remeshes of a dissected set with one face list.

    faces: (m, 3) int32, the one face list; positions: a (n, 3) float64 array per mesh, in the
    dissection's order (read-only views). vertex_patch (n,) and vertex_uv (n, 2): where each
    vertex lies in the common structure. quads: (k, 4) int32 with quads=True, else None.
    outputs: the file names save() writes; report: qs-remesh's text report; meshes: per mesh
    its remesh.json object (angles, vertex density, error with error=True); folder: where it was
    saved (qs.bake(..., out=DIR) needs it), else None.
    """

    def __init__(self, impl):
        self._impl = impl

    faces = property(lambda self: self._impl.faces)
    positions = property(lambda self: self._impl.positions)
    vertex_patch = property(lambda self: self._impl.vertex_patch)
    vertex_uv = property(lambda self: self._impl.vertex_uv)
    quads = property(lambda self: self._impl.quads)
    outputs = property(lambda self: self._impl.outputs)
    report = property(lambda self: self._impl.report)
    folder = property(lambda self: self._impl.folder)
    meshes = property(lambda self: _json.loads(self._impl._meshes_json))

    def mesh(self, i):
        """Mesh i of the set as a qs.Mesh (named by its output's stem)."""
        return Mesh(self.positions[i], self.faces, name=self.outputs[i].rsplit(".", 1)[0])

    def save(self, folder):
        """Writes <stem>.obj|.ply per mesh and remesh.json, as qs-remesh does. The dissection
        must have been saved or loaded (remesh.json names its folder), else qs.UsageError."""
        self._impl.save(_os.fspath(folder))

    def __repr__(self):
        return "<qs.Remesh: %d meshes, %d vertices, %d faces>" % (
            len(self.outputs), len(self.vertex_patch), len(self.faces))


def remesh(dissection, level=4, *, uniform=False, cells="aniso", adaptive=None, max_level=6, quads=False,
           diagonals="angle", grid_relax=0.0, format="obj", error=False, metro_samples=20000, threads=0,
           progress=None):
    """Semi-regular remeshes of a dissection, one face list for the whole set (qs-remesh).

    level: n, about 2 P 4^n faces (P patches) spread by area: the even remesh (default 4).
    uniform: the square grid instead, (2^n+1)^2 samples per patch (qs-remesh --uniform).
    cells: even remesh: "aniso" (cells split in u or v alone, default) or "square".
    adaptive: an error bound (fraction of the diagonal) for the adaptive remesh instead of a
      level; max_level: its finest level (default 6).
    quads, diagonals ("angle" or "pattern"), grid_relax (0): options of the uniform grid.
    format: "obj" or "ply", for save(). error: measure each remesh against its original (Metro);
    metro_samples: its samples per direction (default 20000; 0: qs-metro's full count).
    threads, progress: as for qs.dissect.

    Returns a qs.Remesh. Raises qs.UsageError for options that do not fit together (as
    qs-remesh's messages), KeyboardInterrupt on Ctrl-C.
    """
    if not isinstance(dissection, Dissection):
        raise UsageError("remesh: expected a qs.Dissection, got %s" % type(dissection).__name__)
    if adaptive is not None:
        if level not in (None, 4) and level is not None:
            raise UsageError("give a level or adaptive, not both")
        mode, level, eps = "adaptive", -1, float(adaptive)
    else:
        if level is None:
            raise UsageError("give a level or adaptive")
        uniform = uniform or quads or diagonals != "angle" or grid_relax != 0
        mode, eps = ("uniform" if uniform else "even"), 0.0
        if uniform and cells != "aniso":
            raise UsageError("cells is an option of the even remesh; drop it with uniform=True")
    return Remesh(_qs._remesh(dissection._impl, mode, int(level), cells, eps, int(max_level), bool(quads),
                              diagonals, float(grid_relax), format, bool(error), int(metro_samples), int(threads),
                              progress))


def bake(remesh, dissection, *, size=256, tiles="area", space="tangent", green="opengl", gutter=4, out=None,
         formats=(), samples=100000, threads=0, progress=None):
    """Normal-map atlases of the originals on their remeshes (qs-bake), in memory and, with
    `out`, written as qs-bake writes them.

    remesh: a qs.Remesh; dissection: the qs.Dissection it was made from.
    size: S, texels per patch side (tiles="area": of a patch of average area; default 256).
    tiles: "area" (tile sides grow with the square root of each patch's area, largest over the
      set; shelf-packed) or "uniform" (every tile S x S in a grid).
    space: "tangent" or "object"; green: "opengl" (+Y up) or "directx" (tangent space only).
    gutter: texels around each tile (default 4).
    out: None, or a folder to write qs-bake's files into, all or nothing: per mesh
      <stem>_normal.png (and <stem>_normal16.png / <stem>_normal.exr with formats=("png16",
      "exr")), <stem>.glb, and bake.json: the bytes qs-bake REMESH --size S ... -o OUT writes.
      The remesh must have been saved (bake.json names its folder), else qs.UsageError.
    formats, samples: with out: the extra map files and the shading check's points per mesh
      (qs-bake's --format and --samples; default 100000, 0: none).

    Returns {"images": per mesh {"normals": (H, W, 3) float32 unit vectors, "rgb8": (H, W, 3)
    uint8, the content of qs-bake's <stem>_normal.png, and with out and samples > 0 "shading",
    bake.json's shading check}, "tiles": per patch (x, y, side), "width", "height", "grid"}; one
    layout for the whole set. Progress stages: "bake" (with out: the mesh's stem).
    """
    if not isinstance(remesh, Remesh) or not isinstance(dissection, Dissection):
        raise UsageError("bake: expected a qs.Remesh and the qs.Dissection it was made from")
    if isinstance(formats, str):
        formats = [formats]
    return _qs._bake(remesh._impl, dissection._impl, int(size), tiles, space, green, int(gutter),
                     [str(f) for f in formats], int(samples), None if out is None else _os.fspath(out), int(threads),
                     progress)


def morph(shapes, *, frames=None, path=None, weights=None, align="none", glb=None, bake=None):
    """Frames of a morph between shapes with one connectivity (qs-morph's frames and blend), and
    with `glb` its GLB as qs-morph --glb writes it.

    shapes: a qs.Remesh (its positions), a merge result (qs.merge) or a list of (n, 3) arrays.
    path: shape indices to pass through (default: every shape in order); frames: K frames
      uniform in the path parameter (default 10 per leg + 1, so every stop is a frame).
    weights: instead of frames, one blend with these barycentric weights (one per shape,
      >= 0, summing to 1).
    align: "none", "rigid" or "similarity": every shape placed on the path's first (the first
      shape with weights) by the least-squares fit over corresponding vertices, before blending.
    glb: None or a file: writes the GLB of qs-morph REMESH --glb FILE [--path ...] [--weights ...]
      [--align ...] [--bake DIR] (the same bytes): the path's first shape as the mesh, one morph
      target per other shape, default weights from `weights`, an animation along the path (1 s
      per leg). Needs shapes to be a qs.Remesh (the targets are named by its output stems).
    bake: with glb, a qs-bake output folder (qs.bake(..., out=DIR)): the base shape's normal map,
      atlas UVs and tangents go into the GLB.

    Returns a list of (n, 3) float64 arrays (one with weights); the faces are the remesh's.
    """
    if isinstance(shapes, Remesh):
        positions = shapes.positions
    elif isinstance(shapes, dict) and "positions" in shapes:
        positions = shapes["positions"]
    else:
        positions = list(shapes)
    if glb is None and bake is not None:
        raise UsageError("bake needs glb (the normal map goes into the GLB)")
    if glb is not None and not isinstance(shapes, Remesh):
        raise UsageError("glb needs a qs.Remesh (its faces and output names make the GLB)")
    n = len(positions)
    if weights is not None:
        if frames is not None or path is not None:
            raise UsageError("give weights or frames/path, not both")
        weights = [float(w) for w in weights]
        result = _qs._morph(positions, [], 0, weights, align)
        stops = list(range(n))
    else:
        stops = list(range(n)) if path is None else [int(p) for p in path]
        if frames is None:
            frames = 10 * (len(stops) - 1) + 1
        result = _qs._morph(positions, stops, int(frames), None, align)
    if glb is not None:
        _qs._morph_glb(shapes._impl, stops, weights, align, _os.fspath(glb), None if bake is None else _os.fspath(bake))
    return result


def merge(dissection, pair=(0, 1), *, sliver_degrees=1.0, fan=False, threads=0, progress=None):
    """The exact morph of two dissected meshes (qs-merge): the overlay of their charts, one
    connectivity whose positions lie on the first mesh's surface (t = 0) and on the second's (t = 1).

    pair: the two meshes, by index in the dissection (default (0, 1)).
    sliver_degrees: merged faces with a smaller corner angle count as slivers (default 1).
    fan: cut the overlay polygons by fans instead of the cut that maximizes the smallest angle.

    Returns {"faces": (m, 3) int32, "positions": [(n, 3) at t = 0, (n, 3) at t = 1],
    "vertex_patch", "vertex_uv", "stats"}; qs.morph(result, frames=11) gives the frames.
    """
    if not isinstance(dissection, Dissection):
        raise UsageError("merge: expected a qs.Dissection, got %s" % type(dissection).__name__)
    a, b = pair
    return _qs._merge(dissection._impl, int(a), int(b), float(sliver_degrees), bool(fan), int(threads), progress)


def metro(a, b, *, samples=0, vertices=True, seed=1, threads=0, progress=None):
    """Metro distance between two surfaces (qs-metro A B): sampled on each, measured to the
    other's nearest surface point. Meshes need not be closed or manifold.

    a, b: qs.Mesh or paths. samples: surface samples per direction (0, the default: max(100000,
    2 x the larger face count)). vertices: also measure at every vertex (the maximum only).
    seed: the sampling's seed (1; the same seed gives the same numbers).

    Returns a dict of absolute distances: mean, rms, max (two-sided), diagonal (a's bounding-box
    diagonal: percentages are of it), area_a, area_b, and a_to_b / b_to_a with mean, rms, max,
    max_at, samples, vertex_samples.
    """
    if not isinstance(a, Mesh):
        a = read_mesh(a)
    if not isinstance(b, Mesh):
        b = read_mesh(b)
    return _qs._metro(a, b, int(samples), bool(vertices), int(seed), int(threads), progress)


def correspondence_error(dissection, maps=None, *, samples=100000, seed=1, level=0, vertex_errors=False, threads=0,
                         progress=None):
    """How far a dissection's map is from the exact one (qs-metro --correspondence): the first
    mesh A against every other mesh B, on meshes with ground truth (docs/correspondence.md).

    dissection: a qs.Dissection. Its meshes are the files it names (looked up as written, then in
      and beside its folder, as qs-metro does; an unsaved dissection: as written).
    maps: None (<stem>.map.json beside each mesh when present) or one map file per mesh, in the
      dissection's order, None for a mesh whose own face list is its domain.
    samples: points sampled on A per pair, uniformly per unit area (default 100000).
    seed: the sampling's seed (1). level: 0 maps by the charts; n >= 1 through B's uniform
      level-n remesh. vertex_errors: also give the errors at each of A's vertices.

    Returns a list, one dict per pair (A, B), with the keys and numbers of qs-metro
    --correspondence --json's "pairs": "a", "b", "samples", "diagonal_of_b", "dissection" and
    "baseline" (each mean_percent, median_percent, p95_percent, max_percent: % of B's bounding-box
    diagonal), "same_patch_share", "corner_distance_mean_percent", "corner_distance_max_percent",
    "distortion" (on, dissection_mean, dissection_median, dissection_folded_faces, truth_mean,
    truth_median, truth_folded_faces), "baseline_landmarks", "truth_tolerance_percent",
    "truth_tolerance_mean_percent"; with level >= 1 also "remesh_alone" (as "dissection": an exact
    map's error through that remesh); with vertex_errors=True also "vertex_error",
    "vertex_baseline_error" ((n,) float64, % of the diagonal), "vertex_patch" and
    "vertex_exact_patch" ((n,) int32; -1 for an unused vertex).

    Raises qs.IoError for a mesh or map file that cannot be found or read, qs.InvalidInput for a
    map that does not fit its mesh, meshes without a common domain or fewer than 2 meshes,
    qs.UsageError for bad options, KeyboardInterrupt on Ctrl-C.
    """
    if not isinstance(dissection, Dissection):
        raise UsageError("correspondence_error: expected a qs.Dissection, got %s" % type(dissection).__name__)
    if maps is None:
        names = []
    else:
        names = ["-" if m is None else _os.fspath(m) for m in maps]
        if len(names) != len(dissection):
            raise UsageError("maps: %d given for %d meshes (one per mesh in the dissection's order, None for a mesh "
                             "without a map)" % (len(names), len(dissection)))
    return _qs._correspondence(dissection._impl, names, int(samples), int(seed), int(level), bool(vertex_errors),
                               int(threads), progress)
