"""qs.dissect / Dissection / qs.remesh against qs-dissect and qs-remesh on the same input."""

import filecmp
import json

import numpy as np
import pytest

import qs
from conftest import EXAMPLES, read_obj, run_tool, icosphere, write_obj

MESHES = [str(EXAMPLES / "spot_2k.obj"), str(EXAMPLES / "koala_7k.obj")]
LANDMARKS = [str(EXAMPLES / "spot_2k.landmarks.json"), str(EXAMPLES / "koala_7k.landmarks.json")]


@pytest.fixture(scope="module")
def runs(tmp_path_factory, tools):
    """The tools' folders and the module's, for the same meshes and landmark files."""
    tmp = tmp_path_factory.mktemp("pipeline")
    tool, py = tmp / "tool", tmp / "py"
    code, _, err = run_tool("qs-dissect", *MESHES, "--landmarks", *LANDMARKS, "-o", tool / "dissection", "-q")
    assert code == 0, err
    code, _, err = run_tool("qs-remesh", tool / "dissection", "--level", "4", "-o", tool / "remesh-L4", "-q")
    assert code == 0, err
    meshes = [qs.read_mesh(m) for m in MESHES]
    landmarks = [qs.read_landmarks(l, m) for l, m in zip(LANDMARKS, meshes)]
    d = qs.dissect(meshes, landmarks=landmarks)
    r_unsaved = qs.remesh(d, level=4)
    d.save(py / "dissection")
    r = qs.remesh(d, level=4)
    r.save(py / "remesh-L4")
    return {"tool": tool, "py": py, "d": d, "r": r, "r_unsaved": r_unsaved}


def same_files(a, b):
    names = sorted(p.name for p in a.iterdir())
    assert names == sorted(p.name for p in b.iterdir())
    for n in names:
        assert filecmp.cmp(a / n, b / n, shallow=False), n
    return names


def test_dissection_saved_is_what_qs_dissect_writes(runs):
    names = same_files(runs["tool"] / "dissection", runs["py"] / "dissection")
    assert names == ["dissection.json", "koala_7k.chart.ply", "spot_2k.chart.ply"]
    d = runs["d"]
    assert d.files == MESHES and d.chart_files == ["spot_2k.chart.ply", "koala_7k.chart.ply"]
    doc = json.load(open(runs["tool"] / "dissection" / "dissection.json"))
    assert len(doc["meshes"]) == 2
    assert d.num_patches == len(d.patch_names) > 4
    assert "patches" in d.report and d.folded_faces == 0


def test_remesh_matches_qs_remesh_objs(runs):
    r = runs["r"]
    assert r.faces.dtype == np.int32 and r.faces.shape[1] == 3
    assert len(r.positions) == 2
    for i, stem in enumerate(["spot_2k", "koala_7k"]):
        v, f = read_obj(runs["tool"] / "remesh-L4" / (stem + ".obj"))
        assert np.array_equal(r.faces, f)
        assert r.positions[i].dtype == np.float64 and r.positions[i].shape == v.shape
        # The OBJ holds 17 significant digits: the same doubles.
        assert np.array_equal(r.positions[i], v)
    # The same without saving the dissection first.
    assert np.array_equal(runs["r_unsaved"].faces, r.faces)
    for a, b in zip(runs["r_unsaved"].positions, r.positions):
        assert np.array_equal(a, b)


def test_remesh_saved_is_what_qs_remesh_writes(runs):
    same_files(runs["tool"] / "remesh-L4", runs["py"] / "remesh-L4")


def test_remesh_views_are_read_only(runs):
    r = runs["r"]
    with pytest.raises(ValueError):
        r.positions[0][0, 0] = 1.0
    with pytest.raises(ValueError):
        r.faces[0, 0] = 1
    assert r.vertex_patch.shape == (len(r.positions[0]),) and r.vertex_uv.shape == (len(r.positions[0]), 2)
    assert r.outputs == ["spot_2k.obj", "koala_7k.obj"]
    assert r.mesh(1).accepted


def test_load_saves_and_remeshes_the_same(runs, tmp_path):
    d = qs.Dissection.load(runs["tool"] / "dissection")
    assert d.folder == str(runs["tool"] / "dissection")
    r = qs.remesh(d, level=4)
    assert np.array_equal(r.faces, runs["r"].faces)
    assert all(np.array_equal(a, b) for a, b in zip(r.positions, runs["r"].positions))
    d.save(tmp_path / "copy")
    same_files(runs["tool"] / "dissection", tmp_path / "copy")
    c = d.chart(0)
    assert c["faces"].shape[0] == c["face_uv"].shape[0] == c["face_patch"].shape[0]
    assert c["face_patch"].max() == d.num_patches - 1


def test_landmarks_in_python_match_a_landmark_file(tools, tmp_path):
    v, f = icosphere(3)
    write_obj(tmp_path / "blob.obj", v, f)
    seeds = [0, 3, 1, 2]
    lm_file = tmp_path / "blob.landmarks.json"
    lm_file.write_text(json.dumps({"seeds": seeds}))
    code, _, err = run_tool("qs-dissect", tmp_path / "blob.obj", "--landmarks", lm_file, "-o", tmp_path / "tool", "-q",
                            "--tau", "2")
    assert code == 0, err
    m = qs.read_mesh(str(tmp_path / "blob.obj"))
    lm = qs.Landmarks(seeds=seeds, name=str(lm_file))
    assert [s["vertex"] for s in lm.resolve(m)["seeds"]] == seeds
    qs.dissect([m], landmarks=[lm], tau=2).save(tmp_path / "py")
    same_files(tmp_path / "tool", tmp_path / "py")


def test_mesh_from_arrays_dissects_and_remeshes(tmp_path):
    v, f = icosphere(2)
    m = qs.Mesh(v, f, name="blob")
    assert m.accepted and m.vertices.shape == v.shape and np.array_equal(m.faces, f)
    d = qs.dissect([m, qs.Mesh(v * 1.1, f, name="blob2")], max_depth=2)
    assert d.chart_files == ["blob.chart.ply", "blob2.chart.ply"]
    r = qs.remesh(d, level=1, uniform=True)
    assert len(r.positions) == 2 and r.positions[0].shape == r.positions[1].shape


def test_options_by_name_with_defaults():
    assert qs.DISSECT_DEFAULTS["tau"] == 3 and qs.DISSECT_DEFAULTS["max_depth"] == 6
    doc = qs.dissect.__doc__
    for name in qs.DISSECT_DEFAULTS:
        assert name in doc, name
    v, f = icosphere(2)
    with pytest.raises(qs.UsageError, match="taux"):
        qs.dissect([qs.Mesh(v, f)], taux=2)
    with pytest.raises(qs.UsageError, match="max_depth"):
        qs.dissect([qs.Mesh(v, f)], max_depth=99)
    with pytest.raises(qs.UsageError):
        qs.dissect([qs.Mesh(v, f)], tau=float("nan"))


def test_remesh_option_errors(tmp_path):
    v, f = icosphere(2)
    d = qs.dissect([qs.Mesh(v, f)], max_depth=1)
    with pytest.raises(qs.UsageError, match="level 99"):
        qs.remesh(d, level=99)
    with pytest.raises(qs.UsageError, match="format"):
        qs.remesh(d, level=1, format="stl")
    r = qs.remesh(d, level=1)
    with pytest.raises(qs.UsageError, match="save the dissection first"):
        r.save(tmp_path / "r")
    with pytest.raises(qs.UsageError):
        qs.remesh("not a dissection")


def read_png_rgb8(path):
    """An 8-bit RGB, non-interlaced PNG's pixels as (H, W, 3) uint8 (the filters undone)."""
    import struct
    import zlib
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert (depth, colour, interlace) == (8, 2, 0)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride = 3 * width
    out = np.zeros((height, stride), dtype=np.int32)
    prev = np.zeros(stride, dtype=np.int32)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = np.frombuffer(raw, np.uint8, stride, y * (stride + 1) + 1).astype(np.int32)
        cur = np.zeros(stride, dtype=np.int32)
        for x in range(stride):
            a = cur[x - 3] if x >= 3 else 0
            b = prev[x]
            c = prev[x - 3] if x >= 3 else 0
            if f == 0:
                p = 0
            elif f == 1:
                p = a
            elif f == 2:
                p = b
            elif f == 3:
                p = (a + b) // 2
            else:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                p = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            cur[x] = (line[x] + p) & 255
        out[y] = cur
        prev = cur
    return out.reshape(height, width, 3).astype(np.uint8)


@pytest.fixture(scope="module")
def tool_bake(runs):
    """qs-bake's folder for the tool's remesh (size 16, a small shading check, 16-bit PNGs and EXRs too)."""
    folder = runs["tool"] / "bake16"
    code, _, err = run_tool("qs-bake", runs["tool"] / "remesh-L4", "--size", "16", "--samples", "500", "--format",
                            "png16", "--format", "exr", "-o", folder, "-q")
    assert code == 0, err
    return folder


def test_bake_matches_qs_bake_pngs(runs, tool_bake):
    b = qs.bake(runs["r"], runs["d"], size=16)
    bake_json = json.load(open(tool_bake / "bake.json"))
    assert (b["width"], b["height"]) == (bake_json["atlas"]["width"], bake_json["atlas"]["height"])
    assert [list(t) for t in b["tiles"]] == [[p["x"], p["y"], p["width"]] for p in bake_json["atlas"]["patches"]]
    for i, stem in enumerate(["spot_2k", "koala_7k"]):
        png = read_png_rgb8(tool_bake / (stem + "_normal.png"))
        assert np.array_equal(b["images"][i]["rgb8"], png), stem
        n = b["images"][i]["normals"]
        assert n.shape == png.shape and n.dtype == np.float32
    with pytest.raises(qs.UsageError, match="size"):
        qs.bake(runs["r"], runs["d"], size=1)


def test_morph_frames_match_qs_morph(runs, tmp_path):
    code, _, err = run_tool("qs-morph", runs["tool"] / "remesh-L4", "--frames", "5", "--align", "similarity",
                            "-o", tmp_path / "morph", "-q")
    assert code == 0, err
    frames = qs.morph(runs["r"], frames=5, align="similarity")
    files = sorted(p for p in (tmp_path / "morph").iterdir() if p.suffix == ".obj")
    assert len(files) == len(frames) == 5
    for f, mine in zip(files, frames):
        v, faces = read_obj(f)
        assert np.array_equal(faces, runs["r"].faces)
        assert np.allclose(mine, v, rtol=0, atol=1e-12 * np.abs(v).max()), f.name
    mid = qs.morph(runs["r"], weights=[0.5, 0.5])[0]
    assert np.allclose(mid, (runs["r"].positions[0] + runs["r"].positions[1]) / 2)
    with pytest.raises(qs.InvalidInput):
        qs.morph(runs["r"], weights=[0.7, 0.7])
    with pytest.raises(qs.InvalidInput):
        qs.morph([runs["r"].positions[0], runs["r"].positions[1][:-1]])


def test_merge_matches_qs_merge(runs, tmp_path):
    code, _, err = run_tool("qs-merge", runs["tool"] / "dissection", "-o", tmp_path / "merge", "-q")
    assert code == 0, err
    m = qs.merge(runs["d"])
    for i, stem in enumerate(["spot_2k", "koala_7k"]):
        v, f = read_obj(tmp_path / "merge" / (stem + ".obj"))
        assert np.array_equal(m["faces"], f)
        assert np.array_equal(m["positions"][i], v)
    ends = qs.morph(m, frames=2)
    assert np.array_equal(ends[0], m["positions"][0]) and np.array_equal(ends[1], m["positions"][1])
    with pytest.raises(qs.InvalidInput, match="twice"):
        qs.merge(runs["d"], pair=(1, 1))


def test_bake_out_writes_what_qs_bake_writes(runs, tool_bake):
    tool, py = runs["tool"], runs["py"]
    b = qs.bake(runs["r"], runs["d"], size=16, samples=500, formats=["exr", "png16"], out=py / "bake16")
    names = same_files(tool / "bake16", py / "bake16")
    assert names == ["bake.json", "koala_7k.glb", "koala_7k_normal.exr", "koala_7k_normal.png", "koala_7k_normal16.png",
                     "spot_2k.glb", "spot_2k_normal.exr", "spot_2k_normal.png", "spot_2k_normal16.png"]
    doc = json.load(open(py / "bake16" / "bake.json"))
    assert b["images"][0]["shading"] == {k: v for k, v in doc["meshes"][0]["shading"].items() if k != "seed"}
    assert np.array_equal(b["images"][1]["rgb8"], read_png_rgb8(py / "bake16" / "koala_7k_normal.png"))
    with pytest.raises(qs.UsageError, match="save the remesh first"):
        qs.bake(runs["r_unsaved"], runs["d"], size=16, out=py / "nowhere")
    assert not (py / "nowhere").exists()
    with pytest.raises(qs.UsageError, match="format"):
        qs.bake(runs["r"], runs["d"], size=16, formats=["tiff"])


def test_morph_glb_is_what_qs_morph_writes(runs, tool_bake):
    tool, py = runs["tool"], runs["py"]
    code, _, err = run_tool("qs-morph", tool / "remesh-L4", "--glb", tool / "m.glb", "--align", "similarity", "-q")
    assert code == 0, err
    frames = qs.morph(runs["r"], frames=3, align="similarity", glb=py / "m.glb")
    assert len(frames) == 3
    assert open(tool / "m.glb", "rb").read() == open(py / "m.glb", "rb").read()
    # With default weights, and with a bake's normal map.
    code, _, err = run_tool("qs-morph", tool / "remesh-L4", "--glb", tool / "w.glb", "--weights", "0.25,0.75",
                            "--bake", tool_bake, "-o", tool / "morph-w", "-q")
    assert code == 0, err
    qs.morph(runs["r"], weights=[0.25, 0.75], glb=py / "sub" / "w.glb", bake=tool_bake)
    assert open(tool / "w.glb", "rb").read() == open(py / "sub" / "w.glb", "rb").read()
    with pytest.raises(qs.UsageError, match="glb needs a qs.Remesh"):
        qs.morph(list(runs["r"].positions), glb=py / "x.glb")
    with pytest.raises(qs.UsageError, match="bake needs glb"):
        qs.morph(runs["r"], bake=tool_bake)
    with pytest.raises(qs.UsageError):  # the GLB would replace an input
        qs.morph(runs["r"], glb=py / "remesh-L4" / "spot_2k.obj")
