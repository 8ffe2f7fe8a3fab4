"""Long calls: progress callback, the GIL released, Ctrl-C through the library's cancel flag; metro."""

import json
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import qs
from conftest import EXAMPLES, icosphere, run_tool


def test_progress_callback_gets_stages():
    v, f = icosphere(3)
    seen = []
    qs.dissect([qs.Mesh(v, f), qs.Mesh(v * [1.2, 1, 1], f)], max_depth=2,
               progress=lambda stage, fraction: seen.append((stage, fraction)))
    stages = {s for s, _ in seen}
    assert {"seed loops", "quinary subdivision", "refine maps"} <= stages, stages
    assert all(0 <= x <= 1 for _, x in seen)


def test_progress_callback_exception_stops_the_call():
    v, f = icosphere(3)

    def stop(stage, fraction):
        raise ZeroDivisionError("stop here")

    with pytest.raises(ZeroDivisionError, match="stop here"):
        qs.dissect([qs.Mesh(v, f)], progress=stop)


def test_gil_is_released_during_a_dissect():
    v, f = icosphere(5)  # 20k faces: a few tenths of a second
    mesh = qs.Mesh(v, f)
    done = threading.Event()
    ticks = 0

    def work():
        qs.dissect([mesh], threads=1)
        done.set()

    t = threading.Thread(target=work)
    start = time.perf_counter()
    t.start()
    while not done.is_set():
        ticks += 1
        time.sleep(0.005)
    t.join()
    elapsed = time.perf_counter() - start
    # Holding the GIL through the call would leave this loop a tick or two.
    assert ticks >= min(10, int(elapsed / 0.02)), (ticks, elapsed)


CHILD = r"""
import sys, time, qs
sys.path.insert(0, sys.argv[1])
from conftest import icosphere
v, f = icosphere(6)
meshes = [qs.Mesh(v, f), qs.Mesh(v * [1.3, 1, 0.9], f)]
def progress(stage, fraction):
    if not getattr(progress, "told", False):
        progress.told = True
        print("started", flush=True)
t = time.perf_counter()
try:
    qs.dissect(meshes, progress=progress, threads=1)
    print("finished", flush=True)
except KeyboardInterrupt:
    print("interrupted %.3f" % (time.perf_counter() - t), flush=True)
"""


def test_ctrl_c_interrupts_a_long_dissect():
    env = dict(os.environ)
    p = subprocess.Popen([sys.executable, "-c", CHILD, os.path.dirname(__file__)], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env=env)
    try:
        line = p.stdout.readline()
        assert line.strip() == "started", line + p.stderr.read()
        time.sleep(0.3)
        sent = time.perf_counter()
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=30)
        waited = time.perf_counter() - sent
    finally:
        if p.poll() is None:
            p.kill()
    assert out.startswith("interrupted"), out + err
    assert p.returncode == 0
    assert waited < 5, waited


def test_metro_matches_qs_metro(tools):
    a, b = EXAMPLES / "spot_2k.obj", EXAMPLES / "fish_blub_2k.obj"
    code, out, err = run_tool("qs-metro", a, b, "--samples", "5000", "--json")
    assert code == 0, err
    tool = json.loads(out)
    r = qs.metro(str(a), str(b), samples=5000)
    flat = json.dumps(tool)
    for key in ("mean", "rms", "max"):
        assert repr(r[key]) in flat or ("%.17g" % r[key]) in flat, (key, r[key], flat[:500])
    assert r["a_to_b"]["samples"] == 5000
    with pytest.raises(qs.InvalidInput, match="A = "):
        v, f = icosphere(1)
        qs.metro(qs.Mesh(v, f[:0]), qs.Mesh(v, f))
