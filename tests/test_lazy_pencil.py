"""The symmetric pencil is built on first use, once, with an eager build's bits (issue 19, i20p)."""

import pickle
import threading
import time
import warnings

import numpy as np
import pytest

import meshlap
from meshlap import assembly, pencil, shapes, spectral, store


def kernel_laplacian(*args, **kwargs):
    # the heat-kernel operator these tests are about (the default of meshes is the FEM pencil)
    return meshlap.laplacian(*args, **{"operator": "kernel", **kwargs})



@pytest.fixture
def kernel_rows(monkeypatch):
    # every assembly of kernel rows, counted
    calls = []
    real = assembly.assemble
    monkeypatch.setattr(assembly, "assemble", lambda *a, **k: calls.append(a[3]) or real(*a, **k))
    return calls


@pytest.fixture
def pencils(monkeypatch):
    # every build of a pencil, counted (and slowed, so that threads asking at once overlap)
    calls = []
    real = pencil.assemble

    def slow(*args, **kwargs):
        calls.append(threading.get_ident())
        time.sleep(0.2)
        return real(*args, **kwargs)

    monkeypatch.setattr(pencil, "assemble", slow)
    return calls


def same(A, B):
    return all(np.array_equal(getattr(A, x), getattr(B, x)) for x in ("data", "indices", "indptr"))


@pytest.fixture(scope="module")
def sphere():
    return shapes.sphere(1500, kind="random", seed=0)


def test_op_at_f_never_assembles_kernel_rows(sphere, kernel_rows):
    V, F = sphere
    op = kernel_laplacian(V, F)
    f = np.sin(3 * V[:, 0])
    Lf = op @ f
    assert kernel_rows == [] and op._built.pencil_pending and np.isfinite(Lf).all()
    assert op.pointwise and op.L.shape == (len(V), len(V)) and kernel_rows == []
    assert op._built.held_pencil is None  # not held: nothing to read without building it
    # the pencil on first use, once: the Richardson rows, then nothing more
    assert op.L_sym.nnz > 0 and [k.dog for k in kernel_rows] == [True]
    assert op.assemble() is op and spectral.eigs(op, 3)[0][1] > 1.9 and len(kernel_rows) == 1
    assert op._built.held_pencil is not None and np.array_equal(op @ f, Lf)


def test_facts_of_the_pencil_build_it(sphere, kernel_rows):
    V, F = sphere
    for fact in ("correction", "psd_margin", "moment_scale", "quadrature", "S", "nnz"):
        op = kernel_laplacian(V, F)
        assert op._built.pencil_pending
        getattr(op, fact)
        assert not op._built.pencil_pending and op._built.rows_pending, fact
    # the rows on the kernel's stencil and the paper's operator come with the pencil
    for kw in ({"pointwise": True}, {"h": 0.01, "correction": "none"},
               {"h": 0.01, "matrix_free": True, "correction": "none"}):
        op = kernel_laplacian(V, F, **kw)
        assert op._built.pencil_pending
        op @ V[:, 0]
        assert not op._built.pencil_pending, kw


def test_threads_asking_for_the_pencil_build_it_once(sphere, pencils):
    V, F = sphere
    op = kernel_laplacian(V, F)
    start, out = threading.Barrier(6), [None] * 6
    asks = [lambda: op.L_sym, lambda: op.S, lambda: spectral.eigs(op, 3)[0], lambda: op.correction,
            lambda: op.assemble().L_sym, lambda: op.psd_margin]

    def use(i):
        start.wait()
        out[i] = asks[i]()

    threads = [threading.Thread(target=use, args=(i,)) for i in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(pencils) == 1 and out[0] is out[4] is op.L_sym and out[3] == "richardson"
    assert abs(out[2][1] - 2) < 0.01 and out[5] == op.psd_margin


def test_pickle_and_save_of_an_unassembled_operator_hold_both_parts(sphere, tmp_path):
    V, F = sphere
    eager = kernel_laplacian(V, F).assemble().fit_rows()
    f = np.cos(2 * V)
    copy = pickle.loads(pickle.dumps(kernel_laplacian(V, F)))
    assert not copy._built.pencil_pending and not copy._built.rows_pending
    assert copy._built._pencil._lock is not eager._built._pencil._lock
    assert same(copy.L_sym, eager.L_sym) and same(copy.L, eager.L) and np.array_equal(copy @ f, eager @ f)
    assert copy.psd_margin == eager.psd_margin and copy.moment_scale == eager.moment_scale
    # the rows first, then the pencil: the bits of the other order
    rows_first = kernel_laplacian(V, F)
    assert np.array_equal(rows_first @ f, eager @ f) and same(rows_first.L_sym, eager.L_sym)
    back = store.load_operator(store.save_operator(tmp_path / "op", kernel_laplacian(V, F)))
    assert same(back.L_sym, eager.L_sym) and same(back.L, eager.L)


def test_the_fallback_warns_at_first_use_pointing_at_the_user():
    # 2,000 random vertices at h = 0.3 ē²: the check falls back to the plain kernel (test_accuracy)
    V, F = shapes.sphere(2000, kind="random", seed=1)
    h = 0.3 * meshlap.geometry.from_mesh(V, F).spacing ** 2
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        op = kernel_laplacian(V, F, h=h)  # nothing said at construction
    with pytest.warns(meshlap.MeshWarning, match="not negative semidefinite") as seen:
        spectral.eigs(op, 4)  # asked for deep in the package: the warning names this line
    assert {w.filename for w in seen} == {__file__}
    assert op.correction == "none"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        op.assemble()  # once


def test_max_memory_is_refused_at_construction(sphere, kernel_rows, pencils):
    V, F = sphere
    nnz = kernel_laplacian(V, F).L_sym.nnz
    kernel_rows.clear()
    pencils.clear()
    with pytest.raises(meshlap.OperatorTooLargeError, match="at least about"):
        kernel_laplacian(V, F, max_memory=8 * nnz)
    assert kernel_rows == [] and pencils == []  # refused before any row
    assert kernel_laplacian(V, F, max_memory=64 * nnz).L_sym.nnz == nnz


@pytest.mark.parametrize("kw", [{}, {"correction": "none"}, {"pointwise": True}, {"matrix_free": True}])
def test_an_operator_let_go_frees_its_matrices_at_once(sphere, kw):
    # no reference cycle holds the parts (a bound method of Built in its own Once did): the
    # matrices go with the last reference, not at the next garbage collection
    import gc
    import weakref

    V, F = sphere
    if kw.get("matrix_free"):
        kw = {**kw, "correction": "none"}
    gc.collect()
    gc.disable()
    try:
        op = kernel_laplacian(V, F, **kw)
        op @ V[:, 0]
        op.assemble()
        parts = weakref.ref(op._built)
        del op
        assert parts() is None
    finally:
        gc.enable()
