"""The default's fitted point-wise rows are fitted on first use, once, with the build's bits (i19l)."""

import pickle
import threading
import time

import numpy as np
import pytest

import meshlap
from meshlap import corrections, heat, spectral, store


def kernel_laplacian(*args, **kwargs):
    # the heat-kernel operator these tests are about (the default of meshes is the FEM pencil)
    return meshlap.laplacian(*args, **{"operator": "kernel", **kwargs})

@pytest.fixture
def counted(monkeypatch):
    # every fit of the rows, counted (and slowed, so that threads asking at once overlap)
    calls = []
    fit = corrections.rowchoice.choose_rows

    def slow(*args, **kwargs):
        calls.append(threading.get_ident())
        time.sleep(0.2)
        return fit(*args, **kwargs)

    monkeypatch.setattr(corrections.rowchoice, "choose_rows", slow)
    return calls


def same(A, B):
    return all(np.array_equal(getattr(A, x), getattr(B, x)) for x in ("data", "indices", "indptr"))


@pytest.fixture(scope="module")
def sphere():
    return meshlap.shapes.sphere(1500, kind="random", seed=0)


def test_spectra_and_heat_flow_do_not_fit_the_rows(sphere, counted):
    V, F = sphere
    op = kernel_laplacian(V, F)
    lam, _ = spectral.eigs(op, 6)
    u = heat.heat_flow(op, V[:, 0], 1e-3)
    assert not counted and op._built.rows_pending and np.isfinite(u).all()
    assert abs(lam[1] - 2) < 0.01  # the pencil alone gave the spectrum
    # the first product fits them; what needs them later reuses them
    f = np.exp(V[:, 0])
    Lf = op @ f
    assert len(counted) == 1 and not op._built.rows_pending
    assert op.pointwise_choice is not None and op.L.nnz < 0.1 * op.L_sym.nnz
    assert np.array_equal(op.matvec(f), Lf) and np.array_equal(op.as_linear_operator() @ f, Lf)
    assert np.array_equal(op.dot(f), Lf)
    assert len(counted) == 1


def test_lazy_rows_have_the_bits_of_a_fit_at_build_time(sphere):
    V, F = sphere
    lazy, eager = kernel_laplacian(V, F), kernel_laplacian(V, F).fit_rows()
    spectral.eigs(lazy, 4)  # other work between the build and the first use
    L, choice = corrections.rowchoice.choose_rows(V, k=2)  # what the build fitted before (355b277)
    assert same(lazy.L, eager.L) and same(lazy.L, L) and same(lazy.L_sym, eager.L_sym)
    assert np.array_equal(lazy.pointwise_choice.degree, choice.degree)
    f = np.sin(3 * V)
    assert np.array_equal(lazy @ f, eager @ f) and np.array_equal(lazy @ f, L @ f)
    # float32: the rows cast as at build time
    single = kernel_laplacian(V, F, dtype=np.float32)
    assert single.L.dtype == np.float32 and np.array_equal(single.L.data, L.data.astype(np.float32))


def test_threads_asking_at_once_fit_once(sphere, counted):
    V, F = sphere
    op = kernel_laplacian(V, F)
    f = V[:, 0] ** 2
    start, out = threading.Barrier(6), [None] * 6

    def use(i):
        start.wait()
        out[i] = op @ f if i % 2 else op.L @ f

    threads = [threading.Thread(target=use, args=(i,)) for i in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(counted) == 1
    assert all(np.array_equal(y, out[0]) for y in out)


def test_repr_does_not_fit(sphere, counted):
    V, F = sphere
    op = kernel_laplacian(V, F)
    repr(op), op._repr_html_()
    assert not counted and op._fit_pending() and op._built.held_rows is None
    held = op.nbytes
    assert op.fit_rows() is op and len(counted) == 1
    assert not op._fit_pending() and np.median(op.pointwise_choice.degree) == 6
    assert op.nbytes > held  # the rows are held now
    op.fit_rows()
    assert len(counted) == 1
    # the paper's operator and the moment rows have nothing to fit
    for kw in ({"h": op.h, "correction": "none"}, {"pointwise": True}):
        other = kernel_laplacian(V, F, **kw)
        assert not other._fit_pending() and other._built.held_pencil is None
        # their rows come with the pencil: asking for them builds it
        assert other.fit_rows()._built.held_pencil is not None and not other._built.pencil_pending
    assert len(counted) == 1


def test_saving_and_pickling_fit_the_rows(sphere, counted, tmp_path):
    V, F = sphere
    op = kernel_laplacian(V, F)
    back = store.load_operator(store.save_operator(tmp_path / "op", op))
    assert len(counted) == 1 and same(back.L, op.L) and same(back.L_sym, op.L_sym)
    f = np.cos(2 * V)
    assert np.array_equal(back @ f, op @ f) and len(counted) == 1
    # a pickle, too, holds the rows (fitted before it is written), and the copy its own lock
    fresh = kernel_laplacian(V, F)
    again = pickle.loads(pickle.dumps(fresh))
    assert len(counted) == 2 and same(again.L, op.L) and not again._built.rows_pending
    assert again._built._rows._lock is not fresh._built._rows._lock and np.array_equal(again @ f, op @ f)


def test_progress_reports_the_fit_at_first_use(sphere):
    V, F = sphere
    seen = []
    op = kernel_laplacian(V, F, progress=lambda frac, stage: seen.append((frac, stage)))
    assert seen[-1] == (1.0, "done") and not [s for _, s in seen if s.startswith("point-wise")]
    seen.clear()
    op @ V
    stages = list(dict.fromkeys(s for _, s in seen))
    assert stages[0] == "point-wise rows" and stages[1] == "point-wise rows: queries"
    assert stages[-2:] == ["point-wise rows: assemble", "done"] and seen[-1][0] == 1.0
