"""The example script examples/python/shape_model.py runs and writes a model a user can load."""

import os
import subprocess
import sys

import numpy as np

import qs
from conftest import EXAMPLES, SOURCE


def test_shape_model_example_runs_and_writes_its_model(tmp_path):
    out = tmp_path / "model"
    meshes = [EXAMPLES / "spot_2k.obj", EXAMPLES / "koala_7k.obj"]  # with their landmark files
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    p = subprocess.run([sys.executable, str(SOURCE / "examples" / "python" / "shape_model.py"), "-o", str(out),
                        "--level", "2", *map(str, meshes)], capture_output=True, text=True, timeout=240, env=env)
    assert p.returncode == 0, p.stderr
    assert "PCA of 2 shapes" in p.stdout
    model = np.load(out / "model.npz")
    faces = model["faces"]
    assert model["mean"].shape[1] == 3 and model["modes"].shape == (1, *model["mean"].shape)
    assert faces.min() == 0 and faces.max() == len(model["mean"]) - 1
    # The mean and the mode meshes are closed meshes of the one face list that qs accepts.
    for name in ("mean.obj", "mode1_minus2sd.obj", "mode1_plus2sd.obj"):
        m = qs.read_mesh(str(out / name))
        assert np.array_equal(np.asarray(m.faces), faces)
        assert m.accepted and np.isfinite(np.asarray(m.vertices)).all()
