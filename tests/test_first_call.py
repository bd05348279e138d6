"""The first call on a fresh cache: what it compiles, what it costs, and that it says so once.

The builds run in subprocesses with an empty cache folder of their own (XDG_CACHE_HOME), as on
a new machine, then again on the now warm cache, where nothing is compiled and nothing is said.
Costs are process CPU time (``time.process_time``), which a busy machine inflates far less
than wall time.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import pytest

import meshlap
from meshlap.assembly import variable

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = """
import json, threading, time
from numba.core import event

compiled, lapack, depth = [], [], threading.local()

class Kernels(event.Listener):  # the meshlap kernels compiled, outermost only, with their options
    def on_start(self, ev):
        depth.n = getattr(depth, "n", 0) + 1
        d = ev.data["dispatcher"]
        mod = getattr(d.py_func, "__module__", "")
        if depth.n == 1 and mod.startswith("meshlap."):
            compiled.append([f"{mod}.{d.py_func.__name__}", bool(d.targetoptions.get("parallel"))])
        if mod == "numba.np.linalg":  # at any depth: numba's LAPACK bindings and their checks
            lapack.append(d.py_func.__name__)
    def on_end(self, ev):
        depth.n -= 1

event.register("numba:compile", Kernels())
cpu = time.process_time
t0 = cpu()
import meshlap
V, F = meshlap.shapes.sphere(500, seed=0)
P = meshlap.samples.sphere_points(500)
t1 = cpu(); meshlap.laplacian(V, F); t2 = cpu()
mesh = list(compiled)
meshlap.point_cloud_laplacian(P); t3 = cpu()
print(json.dumps(dict(cpu=[t1 - t0, t2 - t1, t3 - t2], mesh=mesh, cloud=compiled[len(mesh):], lapack=lapack)))
"""


def first_calls(cache):
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(XDG_CACHE_HOME=str(cache), PYTHONPATH=os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")]))
    done = subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True, text=True,
                          timeout=900, check=True)
    return json.loads(done.stdout.splitlines()[-1]), done.stderr


@pytest.mark.slow
def test_first_build_on_a_fresh_cache(tmp_path):
    out, err = first_calls(tmp_path)
    imported, mesh, cloud = out["cpu"]
    print(f"fresh cache, CPU time: import {imported:.1f} s, first default mesh build (500 vertices) "
          f"{mesh:.1f} s, then the first point-cloud build (500 points) {cloud:.1f} s; compiled "
          f"{[k for k, _ in out['mesh']]} and {[k for k, _ in out['cloud']]}")
    notices = [line for line in err.splitlines() if line.startswith("meshlap: compiling kernels")]
    assert len(notices) == 1 and str(tmp_path) in notices[0], err
    assert any((tmp_path / "meshlap" / "numba").rglob("*.nbi"))  # the kernels were cached there
    kernels = out["mesh"] + out["cloud"]
    # numba's parallel=True costs 2-5x the compile time of the same kernel run on meshlap's
    # threads (meshlap._jit); one specialization per kernel: none compiled twice
    assert not [k for k, parallel in kernels if parallel], kernels
    assert len({k for k, _ in kernels}) == len(kernels), kernels
    assert 1 <= len(out["mesh"]) <= 4 and len(out["cloud"]) <= 3, kernels
    # the frames' eigenvectors and the metric's inverse are hand-written (meshlap._dense):
    # numba's np.linalg.eigh and inv compiled 7 more functions, 2 s of CPU on a busy machine
    assert not out["lapack"], out["lapack"]
    # the mesh compiles the kernel rows and the fitted point-wise rows (_fit_kernel._rows, 8-11 s
    # of it): 11.9 s of CPU on a quiet 2-core machine, 12-18 s with a load of 6-9; numba's
    # parallel=True made it 34-37 s. The cloud reuses the mesh's kernels and compiles its
    # masses (3.6 s quiet, 4-7 s loaded)
    assert mesh < 20.0 and cloud < 10.0
    out, err = first_calls(tmp_path)
    print(f"warm cache, CPU time: mesh {out['cpu'][1]:.2f} s, cloud {out['cpu'][2]:.2f} s")
    assert "compiling" not in err and not out["mesh"] and not out["cloud"]
    assert out["cpu"][1] < mesh / 2


def test_threads_do_not_change_the_result():
    # each row is written by one thread in a fixed order: bit for bit the same on one thread
    V, F = meshlap.shapes.plane(700, seed=3)  # with a boundary: mirror images too
    ops = []
    before = numba.get_num_threads()
    try:
        for threads in (1, 2):
            numba.set_num_threads(threads)
            ops.append(meshlap.laplacian(V, F))
    finally:
        numba.set_num_threads(before)
    for name in ("L", "L_sym"):
        a, b = getattr(ops[0], name), getattr(ops[1], name)
        assert np.array_equal(a.indptr, b.indptr) and np.array_equal(a.indices, b.indices)
        assert np.array_equal(a.data, b.data)


@pytest.mark.parametrize("index_dtype", [np.int32, np.int64])
def test_rows_sorted_as_argsort_sorts_them(index_dtype):
    # the hand-written pair sort against numpy's, on rows from empty to a few thousand entries
    rng = np.random.default_rng(1)
    lengths = [0, 1, 2, 15, 16, 17, 33, 1000, 4099]
    indptr = np.concatenate([[0], np.cumsum(lengths)])
    indices = np.concatenate([rng.permutation(5 * m)[:m] for m in lengths]).astype(index_dtype)
    data = rng.normal(size=len(indices))
    want_i, want_d = indices.copy(), data.copy()
    for a, b in zip(indptr[:-1], indptr[1:], strict=True):
        order = np.argsort(indices[a:b])
        want_i[a:b], want_d[a:b] = indices[a:b][order], data[a:b][order]
    variable.sort_rows(indptr, indices, data)
    assert np.array_equal(indices, want_i) and np.array_equal(data, want_d)
