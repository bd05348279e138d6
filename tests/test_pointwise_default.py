"""Issue 20: the default ``op @ f`` applies the fitted point-wise rows (width and degree chosen
per point from the data, meshlap.corrections.rowchoice). Key rows of bench_pointwise at 4,000
points, with tolerances about twice the measured values, and a noise sweep on which the default
never loses to the paper's operator."""

import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import meshlap
from meshlap import curvature, shapes, store
from meshlap.errors import MeshWarning


def e2(op, V0, V):
    # the larger over x² and eˣ of ‖Lf − Δf‖/‖Δf‖, f at the (noisy) V, Δf of the clean sphere at V0
    fs = shapes.sphere_functions()
    return max(float(np.linalg.norm(op @ fs[k][0](V) - fs[k][1](V0)) / np.linalg.norm(fs[k][1](V0)))
               for k in ("x^2", "exp(x)"))


def radial(V0, level, seed):
    return V0 * (1 + level * np.random.default_rng(seed).normal(size=(len(V0), 1)))


def quiet(fn, *a, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeshWarning)
        return fn(*a, **kw)


@pytest.fixture(scope="module")
def sphere():
    return shapes.sphere(4000, kind="random", seed=1)


def test_clean_sphere_mesh_and_cloud(sphere):
    V, F = sphere
    mesh, cloud = meshlap.laplacian(V, F), meshlap.point_cloud_laplacian(V)
    old = meshlap.laplacian(V, F, pointwise=True)  # the degree-2 moment rows
    e_mesh, e_cloud = e2(mesh, V, V), e2(cloud, V, V)
    assert e_mesh < 1e-5 and e_cloud < 1e-5, (e_mesh, e_cloud)  # measured 1.6e-6 (degree 6)
    assert e_mesh < 0.01 * e2(old, V, V)
    assert mesh.pointwise_choice is not None and np.median(mesh.pointwise_choice.degree) == 6
    # a compact stencil: op @ f costs less than the kernel's rows
    assert mesh.L.nnz < 0.1 * meshlap.laplacian(V, F, operator="kernel").L_sym.nnz
    assert mesh.L.nnz == 52 * len(V) and (mesh.pointwise_choice.degree == 6).all()


def test_noisy_sphere_mesh_beats_the_paper(sphere):
    V0, F = sphere
    V = radial(V0, 0.01, 11)
    op, paper = quiet(meshlap.laplacian, V, F), quiet(meshlap.laplacian, V, F, correction="none")
    e, ep = e2(op, V0, V), e2(paper, V0, V)
    assert e < 0.35 and e < 0.8 * ep, (e, ep)  # measured 0.18 against 0.33
    choice = op.pointwise_choice
    assert np.median(choice.noise) / choice.spacing > 0.1  # the noise was seen
    assert op.L.nnz <= 100 * len(V)  # the wide rows hold a subsample of their neighbours


def test_noisy_cloud_beats_the_paper(sphere):
    V0, _ = sphere
    V = radial(V0, 0.01, 12)
    op = quiet(meshlap.point_cloud_laplacian, V)
    paper = quiet(meshlap.point_cloud_laplacian, V, correction="none")
    assert "denoised" in op.geometry.notes
    e, ep = e2(op, V0, V), e2(paper, V0, V)
    # the rows fit f where it was sampled (the input points, not the projected ones)
    assert e < 0.3 and e < 0.6 * ep, (e, ep)  # measured 0.16 against 0.40


def test_noise_sweep_never_loses_to_the_paper():
    V0, F = shapes.sphere(3000, kind="random", seed=4)
    for i, level in enumerate((0.0, 0.0005, 0.002, 0.005, 0.01, 0.02)):
        V = radial(V0, level, 20 + i) if level else V0
        op = quiet(meshlap.laplacian, V, F)
        paper = quiet(meshlap.laplacian, V, F, correction="none")
        e, ep = e2(op, V0, V), e2(paper, V0, V)
        assert e <= ep, (level, e, ep)


def test_spot_limit_surface_against_cotangent():
    # bench_pointwise's clean spot row: spot's level-1 Loop mesh pushed to the limit, Δf exact
    # where the limit surface is the regular box spline, 4 level-1 edges or more from spot's
    # vertices of valence ≠ 6. The surface is C² only and its curvature turns within a few
    # spacings near the horns; the cotangent Laplacian is the best peer there
    import igl
    from scipy.spatial import cKDTree

    from meshlap import baselines

    V, F = meshlap.io.read_mesh(Path(__file__).parent / "data" / "spot.obj")
    F = np.asarray(F, dtype=np.int64)
    V = (V - V.mean(axis=0)) * math.sqrt(8 * math.pi / igl.doublearea(V, F).sum())  # area 4π
    V1, F1 = igl.loop(V, F, 1)
    X, N, HN, exact = shapes.loop_limit(V1, F1)
    odd = np.flatnonzero(np.diff(igl.adjacency_matrix(F).tocsr().indptr) != 6)
    edge = np.linalg.norm(X[F1[:, 0]] - X[F1[:, 1]], axis=1).mean()
    keep = cKDTree(X[odd]).query(X)[0] > 4 * edge
    assert exact[keep].all() and keep.sum() > 1500

    def err(op):
        return max(float(np.linalg.norm((op @ f - lap)[keep]) / np.linalg.norm(lap[keep]))
                   for f, lap in shapes.x_functions(X, N, HN).values())

    e, e_cot = err(meshlap.laplacian(X, F1)), err(baselines.cotangent(X, F1))
    e_paper = err(quiet(meshlap.laplacian, X, F1, correction="none"))
    # measured 0.035 against the cotangent's 0.042 and the paper's 0.34 (0.080 before the
    # residual's excess counted as bias)
    assert e < 0.06 and e <= 1.3 * e_cot and e < e_paper, (e, e_cot, e_paper)


def test_options_keep_the_other_rows(sphere):
    V, F = sphere
    assert meshlap.laplacian(V, F, pointwise=True).pointwise_choice is None
    off = meshlap.laplacian(V, F, pointwise=False)
    assert off.L is off.L_sym and not off.pointwise
    assert meshlap.laplacian(V, F, correction="none").pointwise_choice is None
    fixed = meshlap.laplacian(V, F, pointwise_degree=4)
    assert fixed.pointwise_choice is None and fixed.options.pointwise_degree == 4


def test_mean_curvature_from_the_same_rows():
    # H = 1 on the unit sphere, mesh (signed) and cloud (|H|): the fitted rows are far more
    # accurate than the moment rows
    V, F = shapes.sphere(3000, kind="random", seed=2)
    H = curvature.mean_curvature(meshlap.laplacian(V, F))
    H_old = curvature.mean_curvature(meshlap.laplacian(V, F, pointwise=True))
    assert np.abs(H - 1).max() < 1e-4 and np.abs(H - 1).max() < 0.01 * np.abs(H_old - 1).max()
    Hc = np.linalg.norm(curvature.mean_curvature_normal(meshlap.point_cloud_laplacian(V)), axis=1)
    assert np.abs(Hc - 1).max() < 1e-4


def test_save_and_load_bit_identical(tmp_path, sphere):
    V, F = sphere
    op = meshlap.laplacian(V, F)
    back = store.load_operator(store.save_operator(tmp_path / "op", op))
    f = np.exp(V[:, 0])
    assert np.array_equal(back @ f, op @ f)
    for a, b in ((back.L, op.L), (back.L_sym, op.L_sym)):
        assert all(np.array_equal(getattr(a, x), getattr(b, x)) for x in ("data", "indices", "indptr"))


def test_memory_of_the_kernel(sphere):
    # everything held, against L_sym alone: the fitted rows hold ~52 entries where L_sym
    # holds ~1,100 (issue 19's target: at most 1.25)
    V, F = sphere
    op = meshlap.laplacian(V, F, operator="kernel").fit_rows()
    sym = op.L_sym.data.nbytes + op.L_sym.indices.nbytes + op.L_sym.indptr.nbytes
    assert op.nbytes <= 1.25 * sym, op.nbytes / sym


def test_curves_and_volumes_take_the_fitted_rows():
    t = np.sort(np.random.default_rng(0).uniform(0, 2 * math.pi, 800))
    P = np.column_stack([np.cos(t), np.sin(t)])
    E = np.column_stack([np.arange(800), (np.arange(800) + 1) % 800])
    op = quiet(meshlap.laplacian, P, E)
    assert op.pointwise_choice is not None
    assert np.linalg.norm(op @ np.cos(t) + np.cos(t)) / np.linalg.norm(np.cos(t)) < 1e-6
