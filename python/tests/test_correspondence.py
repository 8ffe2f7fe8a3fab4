"""qs.correspondence_error against qs-metro --correspondence on a generated family (exact maps)."""

import json

import numpy as np
import pytest

import qs
from conftest import run_tool

SAMPLES = 4000


@pytest.fixture(scope="module")
def family(tmp_path_factory, tools):
    """Two generated shapes with sphere map files, dissected by qs-dissect with their landmarks."""
    tmp = tmp_path_factory.mktemp("correspondence")
    code, _, err = run_tool("qs-family", "generate", "-n", "2", "--seed", "2", "--faces", "1600", "--limbs", "4",
                            "--quiet", "-o", tmp / "fam")
    assert code == 0, err
    meshes = [tmp / "fam" / ("shape%02d.obj" % i) for i in range(2)]
    landmarks = [m.with_suffix("").with_suffix(".landmarks.json") for m in meshes]
    code, _, err = run_tool("qs-dissect", *meshes, "--landmarks", *landmarks, "-o", tmp / "d", "-q")
    assert code == 0, err
    return {"tmp": tmp, "meshes": meshes, "landmarks": landmarks, "folder": tmp / "d"}


def tool_pairs(family, *args):
    code, out, err = run_tool("qs-metro", "--correspondence", family["folder"], "--samples", SAMPLES, "--json", *args)
    assert code == 0, err
    return json.loads(out)["pairs"]


def test_numbers_are_qs_metros(family):
    d = qs.Dissection.load(family["folder"])
    stages = set()
    mine = qs.correspondence_error(d, samples=SAMPLES, progress=lambda stage, f: stages.add(stage))
    assert mine == tool_pairs(family)
    assert stages == {"correspondence"}
    pair = mine[0]
    assert 0 < pair["dissection"]["mean_percent"] <= pair["dissection"]["p95_percent"] <= pair["dissection"]["max_percent"]
    assert pair["distortion"]["dissection_mean"] >= 1 and pair["samples"] == SAMPLES
    # Through the level-2 remesh, with another seed.
    assert qs.correspondence_error(d, samples=SAMPLES, level=2, seed=7) == tool_pairs(family, "--level", "2",
                                                                                      "--seed", "7")


def test_maps_given_and_vertex_errors(family, tmp_path):
    d = qs.Dissection.load(family["folder"])
    maps = [m.with_suffix("").with_suffix(".map.json") for m in family["meshes"]]
    mine = qs.correspondence_error(d, maps=maps, samples=SAMPLES, vertex_errors=True)[0]
    code, out, err = run_tool("qs-metro", "--correspondence", family["folder"], "--samples", SAMPLES, "--json",
                              "--map", *maps, "--error-map", tmp_path / "em")
    assert code == 0, err
    tool = json.loads(out)["pairs"][0]
    em = tool.pop("error_map")
    for k in tool:
        assert mine[k] == tool[k], k
    v = mine["vertex_error"]
    assert v.dtype == np.float64 and v.shape == (em["vertices"],)
    assert v.max() == em["vertex_max_percent"] and np.isclose(v.mean(), em["vertex_mean_percent"], rtol=1e-12)
    assert mine["vertex_patch"].shape == mine["vertex_exact_patch"].shape == v.shape
    assert mine["vertex_patch"].max() < d.num_patches


def test_unsaved_dissection_gives_the_same_numbers(family):
    meshes = [qs.read_mesh(str(m)) for m in family["meshes"]]
    landmarks = [qs.read_landmarks(str(l), m) for l, m in zip(family["landmarks"], meshes)]
    d = qs.dissect(meshes, landmarks=landmarks)
    assert d.folder is None
    mine = qs.correspondence_error(d, samples=SAMPLES)
    assert mine == tool_pairs(family)


def test_bad_calls_raise(family, tmp_path):
    d = qs.Dissection.load(family["folder"])
    # Without their map files the meshes have no common domain (different face lists).
    with pytest.raises(qs.InvalidInput, match="does not have the connectivity"):
        qs.correspondence_error(d, maps=[None, None], samples=10)
    with pytest.raises(qs.UsageError, match="maps: 1 given for 2 meshes"):
        qs.correspondence_error(d, maps=[None], samples=10)
    with pytest.raises(qs.IoError, match="nowhere.map.json"):
        qs.correspondence_error(d, maps=[tmp_path / "nowhere.map.json", None], samples=10)
    # A map of the other mesh.
    maps = [m.with_suffix("").with_suffix(".map.json") for m in family["meshes"]]
    with pytest.raises(qs.InvalidInput):
        qs.correspondence_error(d, maps=maps[::-1], samples=10)
    with pytest.raises(qs.UsageError, match="samples"):
        qs.correspondence_error(d, samples=0)
    with pytest.raises(qs.UsageError, match="level"):
        qs.correspondence_error(d, level=13)
    with pytest.raises(qs.UsageError):
        qs.correspondence_error("not a dissection")
    one = qs.dissect([qs.read_mesh(str(family["meshes"][0]))], max_depth=1)
    with pytest.raises(qs.InvalidInput, match="2 or more"):
        qs.correspondence_error(one)
