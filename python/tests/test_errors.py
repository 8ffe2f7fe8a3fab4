"""Bad input raises the documented exception, with the tools' messages; never a crash."""

import json

import numpy as np
import pytest

import qs
from conftest import EXAMPLES, icosphere, run_tool, tool_error, write_obj


def test_hierarchy():
    for e in (qs.UsageError, qs.InvalidInput, qs.IoError, qs.SolverError, qs.InternalError):
        assert issubclass(e, qs.Error)
    assert issubclass(qs.InvalidInput, ValueError)
    assert issubclass(qs.IoError, OSError)
    assert issubclass(qs.SolverError, RuntimeError)
    assert not issubclass(qs.UsageError, ValueError)


V, F = icosphere(1)


@pytest.mark.parametrize("vertices, faces, match", [
    (V[:, :2].copy(), F, r"vertices: expected shape \(n, 3\), got \(42, 2\)"),
    (V.reshape(-1), F, r"vertices: expected shape \(n, 3\), got \(126,\)"),
    (V, F.reshape(-1, 1), r"faces: expected shape \(m, 3\)"),
    (V.astype(np.complex128), F, "vertices: expected float64"),
    (V.astype(str), F, "vertices: expected float64"),
    (V, F.astype(np.float64), "faces: expected int32"),
    (V, F.astype(bool), "faces: expected int32"),
    (np.where(np.arange(42)[:, None] == 5, np.nan, V), F, r"vertices\[5, 0\] is nan"),
    (np.where(np.arange(42)[:, None] == 3, np.inf, V), F, r"vertices\[3, 0\] is infinite"),
    (V, np.where(F == 7, 42, F).astype(np.int32), "= 42 is not a vertex index: expected 0 to 41"),
    (V, np.where(F == 7, -1, F).astype(np.int64), "= -1 is not a vertex index"),
    (V, np.where(F == 7, 2 ** 40, F).astype(np.uint64), "= 1099511627776 is not a vertex index"),
    (np.hstack([V, V])[:, ::2], F, "not C-contiguous"),
    (V, np.asfortranarray(F), "not C-contiguous"),
    (V.tolist(), F, "expected a numpy array, got list"),
])
def test_bad_arrays_raise(vertices, faces, match):
    with pytest.raises(qs.InvalidInput, match=match):
        qs.Mesh(vertices, faces)


def test_float32_and_int64_are_accepted():
    m = qs.Mesh(V.astype(np.float32), F.astype(np.int64))
    assert m.accepted and m.vertices.dtype == np.float64 and m.faces.dtype == np.int32


def test_rejected_mesh_message_is_qs_dissects(tmp_path, tools):
    open_faces = F[1:]  # a hole: rejected
    write_obj(tmp_path / "open.obj", V, open_faces)
    m = qs.read_mesh(str(tmp_path / "open.obj"))
    assert not m.accepted and "boundary" in m.report
    code, _, err = run_tool("qs-dissect", tmp_path / "open.obj", "-o", tmp_path / "out")
    assert code == 2
    with pytest.raises(qs.InvalidInput) as e:
        qs.dissect([m])
    assert str(e.value) == tool_error(err, "qs-dissect")
    with pytest.raises(qs.InvalidInput, match="mesh rejected"):
        qs.dissect([qs.Mesh(V, open_faces)])


def test_inspect_is_qs_inspects(tools, tmp_path):
    write_obj(tmp_path / "open.obj", V, F[1:])
    for path in [EXAMPLES / "spot_2k.obj", tmp_path / "open.obj"]:
        _, out, _ = run_tool("qs-inspect", path, "--json", cwd=tmp_path)
        tool = json.loads(out)[0]
        mine = qs.inspect(str(path))
        assert mine["validation"] == tool["validation"]
        assert mine["read"] == tool["read"]


def test_missing_and_malformed_files(tools, tmp_path):
    code, _, err = run_tool("qs-dissect", tmp_path / "nothing.obj", "-o", tmp_path / "out")
    assert code == 3
    with pytest.raises(qs.IoError) as e:
        qs.read_mesh(tmp_path / "nothing.obj")
    assert isinstance(e.value, OSError)
    assert str(e.value) == tool_error(err, "qs-dissect")
    (tmp_path / "bad.obj").write_text("v 0 0 0\nv 1 0 0\nf 1 2 x\n")
    with pytest.raises(qs.InvalidInput, match="bad.obj"):
        qs.read_mesh(tmp_path / "bad.obj")
    with pytest.raises(qs.InvalidInput, match="extension"):
        qs.read_mesh(tmp_path / "mesh.xyz")


def test_bad_landmarks(tools, tmp_path):
    mesh_file = str(EXAMPLES / "spot_2k.obj")
    m = qs.read_mesh(mesh_file)
    with pytest.raises(qs.IoError):
        qs.read_landmarks(tmp_path / "none.json", m)
    bad = tmp_path / "bad.landmarks.json"
    bad.write_text('{"seeds": [0, 1, 2, 99999]}')
    code, _, err = run_tool("qs-dissect", mesh_file, "--landmarks", bad, "-o", tmp_path / "out")
    assert code == 2
    with pytest.raises(qs.InvalidInput) as e:
        qs.read_landmarks(str(bad), m)
    assert str(e.value) == tool_error(err, "qs-dissect")
    with pytest.raises(qs.InvalidInput):
        qs.dissect([m], landmarks=[qs.Landmarks(seeds=[0, 1, 2, 99999])])
    with pytest.raises(qs.InvalidInput, match="3 coordinates"):
        qs.Landmarks(seeds=[(0, 0), 1, 2, 3])
    with pytest.raises(qs.InvalidInput, match="not finite"):
        qs.Landmarks(features={"nose": (0, float("nan"), 0)})
    with pytest.raises(qs.InvalidInput, match="seed"):
        qs.Landmarks(seeds=[1, 2, 3]).resolve(m)
    with pytest.raises(qs.UsageError, match="one per mesh"):
        qs.dissect([m, m], landmarks=[None])
    with pytest.raises(qs.InvalidInput, match="every mesh needs them"):
        qs.dissect([m, m], landmarks=[qs.Landmarks(seeds=[0, 100, 200, 300]), None])


def test_wrong_types_raise():
    with pytest.raises(qs.UsageError):
        qs.dissect(["spot.obj"])
    with pytest.raises(qs.InvalidInput, match="no mesh"):
        qs.dissect([])
    with pytest.raises(qs.UsageError, match="threads"):
        qs.dissect([qs.Mesh(V, F)], threads=-1)
    with pytest.raises(qs.UsageError, match="progress"):
        qs.dissect([qs.Mesh(V, F)], progress=3)


def test_dissection_folder_errors(tmp_path):
    with pytest.raises(qs.IoError):
        qs.Dissection.load(tmp_path / "none")
    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "dissection.json").write_text("{")
    with pytest.raises(qs.InvalidInput):
        qs.Dissection.load(tmp_path / "d")


def test_save_never_replaces_an_input(tmp_path):
    v, f = icosphere(2)
    (tmp_path / "dissection.json").write_text("the input")  # an input by its name
    m = qs.Mesh(v, f, name=str(tmp_path / "dissection.json"))
    d = qs.dissect([m], max_depth=1)
    with pytest.raises(qs.UsageError, match="is an input"):
        d.save(tmp_path)
