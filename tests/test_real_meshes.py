"""Every real mesh we ship (tests/data) builds with its default h and
gives a sound operator: nothing NaN, zero row sums, masses that add up to the area,
S = M L symmetric, and L applied to the coordinates along the surface normal (it is the
mean-curvature normal, Δx = -2H n)."""

import math
import warnings
from pathlib import Path

import igl
import numpy as np
import pytest

import meshlap
from meshlap import topology
from meshlap.geometry.validation import MeshWarning

DATA = Path(__file__).parent / "data"
BUNNY = DATA / "stanford-bunny.obj"  # checked by test_bunny
# the clean closed surfaces, named: tests/data holds other files with other tests
MESHES = [DATA / name for name in ("fandisk.obj", "spot-quads.obj", "spot.obj")]


def read(path):
    V, _, _, F, _, _ = igl.readOBJ(str(path))  # keeps quads as quads
    return V, F


def build(V, F, **kw):
    # the MeshWarnings about the mesh itself
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        op = meshlap.laplacian(V, F, **kw)
    return op, [w for w in seen if issubclass(w.category, MeshWarning)]


def check_sound(op, V):
    """The checks every real mesh must pass, with the numbers they were measured at."""
    L, m = op.L_sym, op.mass
    assert np.isfinite(L.data).all() and np.isfinite(m).all()
    # vertices in no face: the FEM pencil gives each a tiny mass and a stiff mode of its own
    used = np.zeros(len(m), dtype=bool)
    used[op.faces.indices] = True
    rows = np.asarray(L.sum(axis=1)).ravel()[used]
    assert np.all(np.abs(rows) <= 1e-12 * np.abs(L.diagonal()[used]) + 1e-300)
    m = m * used
    if getattr(op, "area_scale", None) is not None:  # the area the noise left adds, divided out
        m = m / op.area_scale
    # masses against libigl's areas of a fan triangulation (exact for triangles; spot's
    # slightly non-planar quads have a vector area 0.16% below their fan area)
    # on the positions the pencil was built on (a scan whose noise the default took out: after the step)
    area = igl.doublearea(op.pencil_points, op.faces.triangles()).sum() / 2
    tight = op.faces.uniform_size == 3
    assert abs(m.sum() - area) <= (1e-12 if tight else 5e-3) * area
    # S = M L symmetric <=> its columns sum to zero as its rows do: m^T L f = 0 for every f
    LV = L @ V  # op @ f (op.L) applies the point-wise rows, not symmetric in M
    assert np.abs(m @ LV).max() <= 1e-13 * np.abs(m[:, None] * LV).sum()
    LV = op @ V
    # L x is the mean-curvature normal: along the vertex normal (measured medians 0.92-0.99)
    used = m > 0
    N = igl.per_vertex_normals(V, op.faces.triangles())[used]
    cos = np.abs((LV[used] * N).sum(axis=1)) / np.linalg.norm(LV[used], axis=1)
    assert np.median(cos) > 0.85


@pytest.mark.parametrize("path", MESHES, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_real_mesh_builds_sound(path):
    V, F = read(path)
    op, warned = build(V, F)
    assert op.h_auto and op.h == pytest.approx(meshlap.default_h(V, F))
    check_sound(op, V)
    report = topology.diagnose(V, F)
    # spot, spot-quads and fandisk are clean closed surfaces: no warning, no boundary
    assert warned == [] and report.problems == []
    assert report.n_components == 1 and report.n_boundary_loops == 0


def test_spot_quads_and_triangles_agree():
    V, Fq = read(DATA / "spot-quads.obj")
    W, Ft = read(DATA / "spot.obj")
    assert Fq.shape[1] == 4 and Ft.shape[1] == 3 and np.array_equal(V, W)
    q, t = meshlap.vertex_mass(V, Fq), meshlap.vertex_mass(W, Ft)
    # same vertices, quads cut in two: total areas within 0.2%, vertex masses within a few %
    assert abs(q.sum() - t.sum()) < 2e-3 * t.sum()
    assert np.median(np.abs(q - t) / t) < 0.05
    h = meshlap.default_h(W, Ft)
    f = np.sin(3 * V[:, 0]) + V[:, 1] ** 2
    Lq, Lt = meshlap.laplacian(V, Fq, h=h,
            correction="none") @ f, meshlap.laplacian(W, Ft, h=h, correction="none") @ f
    assert np.linalg.norm(Lq - Lt) < 0.05 * np.linalg.norm(Lt)


@pytest.fixture(scope="module")
def bunny():
    V, F = read(BUNNY)
    op, warned = build(V, F)
    return V, F, op, warned


@pytest.mark.slow
def test_bunny(bunny):
    V, F, op, warned = bunny
    assert V.shape == (35947, 3) and F.shape == (69451, 3)
    # one warning for the build, naming the 1,113 vertices no face uses
    assert len(warned) == 1 and "1,113 unreferenced vertices" in str(warned[0].message)
    check_sound(op, V)
    unref = topology.unreferenced_vertices(V, F)
    # the FEM pencil gives each a tiny mass (a mode of its own, far above the rest)
    assert len(unref) == 1113 and np.all(op.mass[unref] <= 1e-5 * np.median(op.mass))
    # L is defined at the unreferenced vertices too: finite, averaging their neighbours
    f = V[:, 1]
    Lf = op @ f
    assert np.isfinite(Lf[unref]).all() and np.count_nonzero(Lf[unref]) > 1000
    report = topology.diagnose(V, F)
    assert report.n_boundary_loops == 5 and report.n_components == 1
    assert len(report.duplicates) == 0 and len(report.nonmanifold) == 0 and len(report.zero_area) == 0
    # the boundary band: vertices within 5√h of the five holes
    band = topology.near_boundary(V, F, op.h)
    assert band[topology.boundary_vertices(V, F)].all()
    E = topology.boundary_edges(V, F)
    dist = segment_distance(V, V[E[:, 0]], V[E[:, 1]])
    r = 5 * math.sqrt(op.h)
    assert np.all(dist[band] <= r) and np.all(band[dist <= r * (1 - 1 / 32)])
    assert 0.05 < band.mean() < 0.2  # measured: 12.4% of the vertices (the base hole is wide)


def segment_distance(P, A, B):
    """Distance from every point to the nearest of the segments [A_k, B_k], brute force."""
    out = np.full(len(P), np.inf)
    for a, b in zip(A, B, strict=True):
        t = np.clip((P - a) @ (b - a) / ((b - a) @ (b - a)), 0, 1)
        out = np.minimum(out, np.linalg.norm(P - (a + t[:, None] * (b - a)), axis=1))
    return out
