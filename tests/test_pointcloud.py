"""Point clouds: masses from local Delaunay stars, the operator's surface, messy input, and the
accuracy targets of issue 13 (sphere, circle, flat torus, S³)."""

import math
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import ConvexHull

import meshlap
from meshlap import curvature, heat, samples, shapes, spectral
from meshlap.geometry import noise, pointcloud, stars
from meshlap.geometry.mass import vertex_mass

SPHERE_L = np.repeat(np.arange(4), 2 * np.arange(4) + 1)
SPHERE_EIGS = (SPHERE_L * (SPHERE_L + 1)).astype(float)


def _sphere_errors(P, h_eig, h_pw, denoise=False):
    """(max relative error of the first 16 eigenvalues, E2 of L x²) on a unit-sphere cloud, of
    the plain kernel (the paper's operator) at the given widths."""
    U = P / np.linalg.norm(P, axis=1, keepdims=True)
    geo = pointcloud.point_cloud_geometry(P, denoise=denoise)
    lam = spectral.eigs(meshlap.MeshLaplacian(geo, h=h_eig, correction="none"), 16, tol=1e-4)[0]
    exact = 2 - 6 * U[:, 0] ** 2
    Lf = meshlap.MeshLaplacian(geo, h=h_pw, correction="none") @ U[:, 0] ** 2
    return (np.abs(lam[1:] / SPHERE_EIGS[1:] - 1).max(),
            np.linalg.norm(Lf - exact) / np.linalg.norm(exact))


# -- masses --------------------------------------------------------------------------------------
def test_masses_match_the_true_triangulation():
    P = samples.sphere_points(16000, "random", seed=3)
    m, info = pointcloud.point_masses(P)
    _, F = shapes._hull_mesh(P)  # the convex hull is the points' spherical Delaunay triangulation
    true = vertex_mass(P, F)
    assert m.sum() == pytest.approx(4 * math.pi, rel=2e-3)
    # 99% agree to 0.1%; the few others sit in near-cocircular spots where the tangent-plane
    # Delaunay star flips an edge of the spherical one (rms 2-5%; robust-laplacian's: 23%)
    dev = np.abs(m / true - 1)
    assert np.percentile(dev, 99) < 0.002 and np.sqrt(np.mean(dev**2)) < 0.08
    assert info["insecure"] == info["outliers"] == info["duplicates"] == 0
    assert len(info["triangles"]) == pytest.approx(2 * len(P), rel=0.01)


@pytest.mark.parametrize("k", [2, 3])
def test_compiled_stars_match_qhull(k):
    rng = np.random.default_rng(k)
    for _ in range(50):
        U = rng.normal(size=(30, k))
        U /= np.linalg.norm(U, axis=1).max()
        ref, _, _ = stars._star_k(U, k)
        got = (stars._star2(U, 30, np.empty((24, 2), np.int64))[0] if k == 2
               else stars._star3(U, 30)[0])
        assert got == pytest.approx(ref, rel=1e-12)


def test_planar_cloud_has_open_boundary_cells():
    P = np.random.default_rng(0).uniform(size=(3000, 2))
    with warnings.catch_warnings():
        warnings.simplefilter("error", meshlap.MeshWarning)  # an open boundary is not messy
        m, info = pointcloud.point_masses(P)  # d = k = 2: the tangent plane is the plane itself
    hull = ConvexHull(P)
    # the local stars leave out the global triangulation's long slivers along the hull
    assert m.sum() == pytest.approx(hull.volume, rel=0.005) and m.sum() < hull.volume
    assert set(hull.vertices) <= set(np.flatnonzero(info["boundary"]))


def _grid(spacing=0.05):
    x, y = np.meshgrid(np.arange(0, 4 + 1e-9, spacing), np.arange(0, 1 + 1e-9, spacing))
    return np.c_[x.ravel(), y.ravel(), np.zeros(x.size)]


def test_a_lattice_cloud_keeps_its_area():
    # a regular grid's squares are cocircular: each point's star split them its own way, leaving
    # triangles in one or two of their corners' stars (the FEM pencil's area 3.17 of 4, Neumann
    # eigenvalues 1-5 up to 8% low); the stars now see the points moved by 1e-9 of the spacing,
    # alike for all, and split them alike (measured: area 4.0004, eigenvalues within 0.23%)
    op = meshlap.point_cloud_laplacian(_grid())
    assert op.mass.sum() == pytest.approx(4.0, rel=1e-3)
    exact = np.sort([(np.pi / 4) ** 2 * a * a + np.pi ** 2 * b * b for a in range(8) for b in range(3)])[1:6]
    lam = np.sort(meshlap.spectral.eigs(op, 6)[0])[1:]
    assert np.abs(lam / exact - 1).max() < 0.005


def test_a_notch_the_sampling_leaves_empty_stays_empty():
    # the grid above with a slot 0.4 wide and 0.8 deep cut out of it: the points along its sides
    # are on the hull of their first 16 neighbours, and their stars stay those local ones (a
    # wider search closed them across the slot, which the FEM pencil then filled)
    P = _grid()
    slot = (np.abs(P[:, 0] - 2.0) < 0.16) & (P[:, 1] > 0.22)
    op = meshlap.point_cloud_laplacian(P[~slot])
    assert op.mass.sum() == pytest.approx(4.0 - 0.4 * 0.8, rel=0.01)  # measured 3.7029



def _annulus_neumann(a: float, b: float, count: int) -> np.ndarray:
    """The first nonzero Neumann eigenvalues of the annulus a < r < b: k² where
    J'_m(ka) Y'_m(kb) = J'_m(kb) Y'_m(ka), each m > 0 twice."""
    from scipy.optimize import brentq
    from scipy.special import jvp, yvp

    out = []
    for m in range(8):
        f = lambda k, m=m: jvp(m, k * a) * yvp(m, k * b) - jvp(m, k * b) * yvp(m, k * a)  # noqa: E731
        ks = np.linspace(0.05, 12.0, 2400)
        fs = f(ks)
        for i in np.flatnonzero(np.sign(fs[:-1]) != np.sign(fs[1:])):
            out += [brentq(f, ks[i], ks[i + 1]) ** 2] * (1 if m == 0 else 2)
    return np.sort(out)[:count]


def _annulus_points(r0, rim):
    # 3,000 i.i.d. points of the annulus r0 < r < 1 in the plane z = 0, and its two rims sampled
    # evenly (200 points outside, ``rim`` inside)
    rng = np.random.default_rng(0)
    X = rng.uniform(-1.0, 1.0, (6000, 2))
    X = X[(np.hypot(*X.T) > r0) & (np.hypot(*X.T) < 1.0)][:3000]
    t, u = np.linspace(0, 2 * np.pi, 200, endpoint=False), np.linspace(0, 2 * np.pi, rim, endpoint=False)
    X = np.vstack([X, np.c_[np.cos(t), np.sin(t)], r0 * np.c_[np.cos(u), np.sin(u)]])
    return np.c_[X, np.zeros(len(X))]


def _annulus_cloud(r0, rim):
    P = _annulus_points(r0, rim)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", meshlap.MeshWarning)
        S = pointcloud.point_masses(P)[1]["stars"]
        lam = np.sort(spectral.eigs(meshlap.point_cloud_laplacian(P), 9)[0])
    area = 0.5 * np.linalg.norm(np.cross(P[S[:, 1]] - P[S[:, 0]], P[S[:, 2]] - P[S[:, 0]]), axis=1).sum() / 3
    return area, np.max(np.abs(lam[1:9] / _annulus_neumann(r0, 1.0, 8) - 1))


@pytest.mark.parametrize("r0, rim_points", [(0.5, 100), (0.15, 30)])
def test_a_holes_rim_is_boundary_with_its_length(r0, rim_points, tmp_path):
    # A cloud's boundary is where its star soup ends, a hole's rim as well as the outer rim (before,
    # only points whose Voronoi cell stays open: none of the hole's, so a flux there was dropped
    # and φ = 0), each point's share half its star's open edges (before, √mass: the outer rim
    # 3.85 long for 2π). φ = log r: φ = 0 at r = 1, ∂φ/∂n = -1/r0 on the hole's rim.
    from meshlap.solve import boundary_measure, poisson

    P = _annulus_points(r0, rim_points)
    r = np.hypot(P[:, 0], P[:, 1])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", meshlap.MeshWarning)
        op = meshlap.point_cloud_laplacian(P)
    share = boundary_measure(op)
    hole, outside = np.isclose(r, r0), np.isclose(r, 1.0)
    assert op.geometry.boundary[hole].mean() >= 0.95 and op.geometry.boundary[outside].all()
    assert not op.geometry.boundary[(r > r0 + 0.1) & (r < 0.9)].any()
    # the lengths to 1% (measured: the hole's 0.01% and 0.17% short, its rim polygon's; the outer
    # rim's within 0.01%)
    assert share[r < r0 + 0.1].sum() == pytest.approx(2 * np.pi * r0, rel=0.01)
    assert share[r > 0.9].sum() == pytest.approx(2 * np.pi, rel=0.01)
    rim = np.flatnonzero(op.geometry.boundary)  # as a user splits it: by radius
    outer, inner = rim[r[rim] > (1 + r0) / 2], rim[r[rim] < (1 + r0) / 2]
    phi = poisson(op, 0.0, dirichlet=(outer, np.zeros(len(outer))),
                  neumann=(inner, np.full(len(inner), -1 / r0)))
    error = np.abs(phi - np.log(r))
    if rim_points == 30:  # a saved and reloaded cloud has the same boundary lengths
        back = meshlap.io.load_operator(meshlap.io.save_operator(tmp_path / "annulus", op))
        assert np.array_equal(boundary_measure(back), share)
    # measured: median 9.5e-5 and 2.9e-4, at most 0.0018 and 0.024 beside the hole (Dirichlet data
    # on both rims leave 0.0014 and 0.012)
    assert np.median(error) < 1e-3
    assert error.max() < 0.03 * abs(np.log(r0))


def test_a_concave_rim_gets_no_slivers_across_it():
    # An annulus's inner rim is concave: its points' first stars are never secured, and their
    # triangles between nearly collinear rim points lay slivers across the hole (0.23% more area,
    # the first 8 Neumann eigenvalues 1.8% off). A sliver's circumdisc is far wider than the
    # sampling leaves empty: the area to 1e-4, the eigenvalues within 0.5% (0.26% measured).
    area, error = _annulus_cloud(0.5, 100)
    assert area == pytest.approx(0.75 * np.pi, rel=1e-4)
    assert error < 0.005


def test_a_hole_the_search_spans_stays_open():
    # A hole 9 spacings across: 256 neighbours reach over it, secure its rim points' stars and
    # close it (1.5% more area, the Neumann eigenvalues 8.1% off). An empty circumdisc holding 69
    # points at the sampling's density (i.i.d. leaves one above 15 with odds 1e-3) is a hole: the
    # area to 1e-3 (2e-4 measured), the eigenvalues within 0.5% (0.34%).
    area, error = _annulus_cloud(0.15, 30)
    assert area == pytest.approx(np.pi * (1 - 0.15**2), rel=1e-3)
    assert error < 0.005


def test_a_lopsided_neighbourhood_keeps_its_closed_star():
    # a random sphere's points on the hull of their first 16 neighbours: their wider stars are
    # their neighbours' own triangles, which the FEM pencil keeps (the first, open, star alone had
    # doubled the error: 0.38%; measured now 0.20%)
    op = meshlap.point_cloud_laplacian(samples.sphere_points(16000, "random", seed=0))
    lam = np.sort(spectral.eigs(op, 16, tol=1e-8)[0])
    assert np.abs(lam[1:] / SPHERE_EIGS[1:] - 1).max() < 0.003
    # and no boundary, nor any length of it: a closed surface (bench_cloud_boundary.py: none at
    # 1,000,000 points either)
    assert not op.geometry.boundary.any() and not meshlap.solve.boundary_measure(op).any()


def _thick_tube(a=0.5, r1=1.5, r2=2.5, height=3.0):
    # the surface of a thick-walled tube (a nut without its thread), sampled in rings a apart:
    # its wall is two spacings thick, so a bore point's first 16 neighbours reach the outer wall
    points, label = [], []
    for r, wall in ((r1, 1), (r2, 2)):
        nt, nz = round(2 * np.pi * r / a), round(height / a)
        for i in range(nz + 1):
            t = (np.arange(nt) + 0.5 * (i % 2)) * 2 * np.pi / nt
            points.append(np.column_stack([r * np.cos(t), r * np.sin(t), np.full(nt, i * height / nz)]))
            label += [wall] * nt
    for z in (0.0, height):  # the annular ends
        for r in np.arange(r1 + a, r2 - a / 2, a):
            t = np.arange(round(2 * np.pi * r / a)) * 2 * np.pi / round(2 * np.pi * r / a) + 0.3
            points.append(np.column_stack([r * np.cos(t), r * np.sin(t), np.full(len(t), z)]))
            label += [0] * len(t)
    return np.vstack(points), np.array(label)


def test_the_far_wall_of_a_thin_solid_is_not_in_a_star():
    # a steep chord to one of the first neighbours, far above the rest of them, crosses the solid:
    # with it in the stars, 468 triangles joined the bore's middle to the outer wall, the masses
    # summed to 77% of the area and λ1 was 28% low
    P, wall = _thick_tube()
    m, info = pointcloud.point_masses(P)
    stars = info["stars"]
    bore = (wall == 1) & (P[:, 2] > 0.9) & (P[:, 2] < 2.1)
    assert not (bore[stars].any(axis=1) & (wall[stars] == 2).any(axis=1)).any()
    area = 2 * np.pi * 3.0 * (1.5 + 2.5) + 2 * np.pi * (2.5**2 - 1.5**2)
    assert m.sum() == pytest.approx(area, rel=0.1)  # measured 0.914
    # linear FEM on the revolved profile, 64,000 vertices (16,000: the same to 4 digits)
    lam = np.sort(spectral.eigs(meshlap.point_cloud_laplacian(P), 4)[0])
    assert lam[1:3] == pytest.approx([0.24357, 0.24357], rel=0.1)  # measured 0.2263, 0.2294

# -- the operator's surface ----------------------------------------------------------------------
def test_operator_surface_on_a_cloud():
    P = samples.sphere_points(1500, "random", seed=0)
    op = meshlap.point_cloud_laplacian(P)
    assert op.h_auto and op.geometry.faces is None
    assert (op.geometry.source, op.geometry.dim, op.geometry.ambient_dim) == ("point cloud", 2, 3)
    assert op.h == pytest.approx(op.geometry.default_h)
    S = op.S
    assert abs(S - S.T).max() < 1e-14 * abs(S).max()
    assert np.linalg.eigvalsh(-S.toarray()).min() > -1e-10 * abs(S).max()
    lam, phi = spectral.eigs(op, 4)  # LOBPCG preconditioned by the local Delaunay triangles
    assert lam[1:] == pytest.approx([2, 2, 2], rel=0.05)
    u = heat.heat_flow(op, P[:, 0], 0.1)  # x decays like exp(-2t)
    assert np.linalg.norm(u) / np.linalg.norm(P[:, 0]) == pytest.approx(math.exp(-0.2), rel=0.01)
    Hn = curvature.mean_curvature_normal(op)
    assert np.median(np.linalg.norm(Hn, axis=1)) == pytest.approx(1.0, rel=0.02)
    with pytest.raises(meshlap.MeshError, match="mean_curvature_normal"):
        curvature.mean_curvature(op)


@pytest.mark.parametrize("d", [2, 3])
@pytest.mark.parametrize("kind", ["uniform", "random"])
def test_circle_cloud(d, kind):
    # i.i.d. angles: gaps vary, so the kernel must average over more of them (h = 0.003 spans
    # ~60 points); the bias is then 0.3%. The eigenvalues average the sampling noise out, and
    # a smaller h (5e-4) keeps the O(h m²) bias of m = 4 at 0.3%.
    n, h, h_eig = (1000, None, None) if kind == "uniform" else (4000, 3e-3, 5e-4)
    V, _, theta = samples.circle(n, d=d, kind=kind, seed=1)
    geo = pointcloud.point_cloud_geometry(V, k=1)
    op = meshlap.MeshLaplacian(geo, h=h)
    f = np.sin(theta)
    assert np.abs(op @ f + f).max() < 0.01  # L sin θ = -sin θ point-wise to 1%
    op = meshlap.MeshLaplacian(geo, h=h_eig)
    lam = spectral.eigs(op, 9, method="dense" if n <= 1000 else "auto")[0]
    m2 = np.array([0, 1, 1, 4, 4, 9, 9, 16, 16.0])
    assert np.abs(lam[1:] / m2[1:] - 1).max() < 0.01


@pytest.mark.parametrize("d", [2, 3])
def test_a_curve_clouds_default_is_fem_on_its_1d_stars(d):
    """Every point's segments to its nearest neighbours on either side along its tangent are
    its 1-D star; the default builds linear FEM on them, as on a surface cloud's triangles. On
    4,000 i.i.d. points of the unit circle the first eight eigenvalues m² are 2.1e-5 off (the
    polyline through them: 5.4e-6); the kernel the default built before was 2.4% off."""
    V, _, theta = samples.circle(4000, d=d, kind="random", seed=1)
    op = meshlap.point_cloud_laplacian(V, k=1)
    assert op.decision.operator == "fem" and op.geometry.cells.shape[1] == 2
    lam = spectral.eigs(op, 9)[0]
    m2 = np.array([1, 1, 4, 4, 9, 9, 16, 16.0])
    assert abs(lam[0]) < 1e-8 and np.abs(lam[1:] / m2 - 1).max() < 1e-4
    f = np.sin(theta)
    assert np.abs(op @ f + f).max() < 1e-6  # the fitted point-wise rows


def test_a_curve_clouds_stars_end_at_its_ends_and_keep_its_parts_apart():
    """An open curve's cloud ends where its points do (Neumann: (mπ/ℓ)²), and two circles five
    radii apart have two zero eigenvalues."""
    x = np.r_[0.0, np.sort(np.random.default_rng(0).uniform(0, 1, 1998)), 1.0]
    op = meshlap.point_cloud_laplacian(np.c_[x, 0.3 * x, 0 * x], k=1)
    length = math.hypot(1.0, 0.3)
    lam = spectral.eigs(op, 6)[0]
    assert np.abs(lam[1:] / (np.pi * np.arange(1, 6) / length) ** 2 - 1).max() < 1e-4
    V, _, _ = samples.circle(2000, d=3, kind="random", seed=2)
    with pytest.warns(meshlap.MeshWarning, match="2 pieces"):
        op = meshlap.point_cloud_laplacian(np.vstack([V, V + [5.0, 0, 0]]), k=1)
    lam = spectral.eigs(op, 6)[0]
    assert np.abs(lam[:2]).max() < 1e-8 and np.abs(lam[2:] - 1).max() < 1e-4


@pytest.mark.parametrize("shape", ["hook", "spiral", "half circle"])
def test_a_curve_clouds_stars_do_not_close_its_opening(shape):
    """An end point's search widens until it finds a neighbour on its open side: across a
    hook's opening (220 spacings), to the next arm of a spiral (22) or nowhere. A gap that
    i.i.d. sampling would leave with odds below 1e-3 is a hole, so the stars are the chain
    through the points (2,999 segments), the spectrum the polyline's, and the ends' masses
    half their one segment (a hook's had half its opening, 0.16, before)."""
    rng = np.random.default_rng(0)
    t = np.sort(rng.uniform(*{"hook": (0, 1.9 * np.pi), "spiral": (2, 30), "half circle": (0, np.pi)}[shape],
                            3000))
    P = np.c_[t * np.cos(t), t * np.sin(t)] / 10 if shape == "spiral" else np.c_[np.cos(t), np.sin(t)]
    op = meshlap.point_cloud_laplacian(P, k=1)
    chain = np.c_[np.arange(2999), np.arange(1, 3000)]
    assert np.array_equal(op.geometry.cells, chain)
    length = np.linalg.norm(np.diff(P, axis=0), axis=1).sum()  # the ends' masses hold no hole
    assert abs(op.geometry.mass.sum() / length - 1) < 1e-3
    assert np.flatnonzero(op.geometry.boundary).tolist() == [0, 2999]
    lam, ref = spectral.eigs(op, 6)[0], spectral.eigs(meshlap.laplacian(P, chain), 6)[0]
    assert np.abs(lam[1:] / ref[1:] - 1).max() < 1e-4


# -- messy clouds --------------------------------------------------------------------------------
def test_duplicates_share_the_mass():
    P = samples.sphere_points(2000, "random", seed=0)
    m0, _ = pointcloud.point_masses(P)
    Q = np.vstack([P, P[:10], P[:10] + 1e-12])
    with pytest.warns(meshlap.MeshWarning, match="20 duplicate"):
        m, info = pointcloud.point_masses(Q)
    assert info["duplicates"] == 20
    assert m.sum() == pytest.approx(m0.sum(), rel=1e-12)
    assert m[:10] == pytest.approx(m0[:10] / 3, rel=1e-12)
    op = meshlap.point_cloud_laplacian(Q, h=0.02)  # still a valid operator
    assert np.isfinite(op.L.data).all()


def test_outlier_gets_no_mass(tmp_path):
    P = np.vstack([samples.sphere_points(2000, "random", seed=0), [[5.0, 5.0, 5.0]]])
    with pytest.warns(meshlap.MeshWarning, match="1 outlier"):
        m, info = pointcloud.point_masses(P)
    assert m[-1] == 0 and info["outliers"] == 1
    assert m[:-1].sum() == pytest.approx(4 * math.pi, rel=0.01)
    # nor a star: the FEM pencil's spectrum is the cloud's without it (the outlier's own star,
    # 50 high over a unit square, had given it mass 0.86 and λ1 = 0.002 in place of 10.56)
    rng = np.random.default_rng(0)
    Q = np.c_[rng.uniform(size=(500, 2)), np.zeros(500)]
    with pytest.warns(meshlap.MeshWarning, match="1 outlier"):
        op = meshlap.point_cloud_laplacian(np.r_[Q, [[0.5, 0.5, 50.0]]])
    assert not (op.M.diagonal()[-1] > 1e-6 * op.M.diagonal()[:-1].mean())
    np.testing.assert_allclose(spectral.eigs(op, 4)[0][1:], spectral.eigs(
        meshlap.point_cloud_laplacian(Q), 4)[0][1:], rtol=1e-6)
    with pytest.raises(meshlap.MeshError, match="500 lies in no element .*outlier"):  # heat starts nowhere
        meshlap.geodesics.geodesic_distance(op, [500])
    # nor reaches it: off the surface, no distance (a neighbours' fit had read 0.27)
    d = meshlap.geodesics.geodesic_distance(op, [0])
    assert d[500] == np.inf and np.isfinite(d[:500]).all()
    planar = np.linalg.norm(Q[:, :2] - Q[0, :2], axis=1)
    assert np.abs(d[:500] - planar).max() < 0.05
    path = tmp_path / "outlier.npz"
    meshlap.io.save_operator(path, op)
    np.testing.assert_array_equal(meshlap.geodesics.geodesic_distance(meshlap.io.load_operator(path), [0]), d)


def test_degenerate_neighbourhoods():
    line = np.column_stack([np.linspace(0, 1, 50), np.zeros(50), np.zeros(50)])
    with pytest.raises(meshlap.MeshError, match="collinear.*k=2"):
        pointcloud.point_masses(line)
    # a plane with a straight whisker: the whisker's points have collinear neighbours, and the
    # wider ones that reach the plane leave it steeply (the whisker is not on it)
    rng = np.random.default_rng(0)
    plane = np.column_stack([rng.uniform(size=(2000, 2)), np.zeros(2000)])
    whisker = np.column_stack([np.full(40, 3.0), np.full(40, 3.0), np.linspace(0, 1, 40)])
    with pytest.warns(meshlap.MeshWarning, match="no 2-dimensional neighbourhood"):
        m, _ = pointcloud.point_masses(np.vstack([plane, whisker]))
    assert np.isfinite(m).all() and (m >= 0).all()


_CLOUD50 = np.random.default_rng(0).uniform(size=(50, 3))


@pytest.mark.parametrize(
    ("P", "kw", "match"),
    [
        (np.zeros((3, 3)), {}, "at least 4 distinct"),
        (np.eye(3)[:2], {}, "at least 4 distinct"),
        (np.zeros((10, 2)), {"k": 3}, "cannot sample a 3-dimensional"),
        (np.full((10, 3), np.nan), {}, "NaN"),
        (np.zeros(10), {}, r"shape \(n, d\)"),
        (np.ones((10, 3)), {"k": 0}, "positive integer"),
        # these were accepted: every point an outlier (mass 0), none, nothing merged, a float K
        (_CLOUD50, {"outlier_ratio": 0}, "outlier_ratio must be a number > 1"),
        (_CLOUD50, {"outlier_ratio": np.nan}, "outlier_ratio must be a number > 1"),
        (_CLOUD50, {"merge_tol": -1.0}, "merge_tol must be a finite number >= 0"),
        (_CLOUD50, {"neighbors": 3.5}, "neighbors must be an integer"),
    ],
)
def test_bad_clouds_name_the_problem(P, kw, match):
    with pytest.raises(meshlap.MeshError, match=match):
        meshlap.point_cloud_laplacian(P, **kw)


# -- the targets (16,000 points) ---------------------------------------------------------
@pytest.mark.slow
@pytest.mark.parametrize(("kind", "h_eig", "eig_bound"), [
    # uniform: h = 0.001, the kernel's O(h) bias on l = 3 is 5h = 0.5%
    ("uniform", 1e-3, 0.01),
    # random: the issue asks 1%; measured 1.25% here, of which 1.0% is the plain kernel's O(h)
    # bias on l = 3 (a smaller h raises the sampling error instead). correction="richardson"
    # closes the gap: test_sphere_eigenvalues_with_the_bias_correction
    ("random", 2e-3, 0.015),
])
def test_sphere_clouds(kind, h_eig, eig_bound):
    e4 = _sphere_errors(samples.sphere_points(4000, kind, seed=1), h_eig, 8e-3)
    e16 = _sphere_errors(samples.sphere_points(16000, kind, seed=1), h_eig, 8e-3)
    assert e16[0] < eig_bound and e16[1] < 0.03
    assert e16[0] < e4[0] and e16[1] < e4[1]


@pytest.mark.slow
def test_sphere_noisy():
    e4 = _sphere_errors(samples.sphere_points(4000, "noisy", seed=1), 4e-3, 8e-3)
    P = samples.sphere_points(16000, "noisy", seed=1)
    e16 = _sphere_errors(P, 4e-3, 8e-3)
    assert e16[0] < 0.03 and e16[1] < 0.1
    assert e16[0] < e4[0] and e16[1] < e4[1]
    # the noise scales the kernel's weights by ~(1 + σ²/h)^(-1/2); projecting the points onto
    # their local tangent planes first removes most of it
    d16 = _sphere_errors(P, 2e-3, 8e-3, denoise=True)
    assert d16[0] < 0.012 and d16[1] < 0.1


@pytest.mark.slow
@pytest.mark.parametrize(("kind", "target"), [("random", 0.01), ("noisy", 0.03)])
def test_sphere_eigenvalues_with_the_bias_correction(kind, target):
    # correction="richardson" (2 L_{h/2} − L_h, opt-in on point clouds) removes the O(h) bias
    # that keeps the plain kernel above the 1% on random points. Noise acts like a
    # bias that grows as h shrinks, so the noisy cloud is denoised first.
    P = samples.sphere_points(16000, kind, seed=1)
    errors = {}
    for correction in ("none", "richardson"):
        op = meshlap.point_cloud_laplacian(P, h=4e-3, correction=correction, denoise=kind == "noisy")
        assert op.correction == correction and (correction == "none" or op.psd_margin > -1e-6)
        lam = spectral.eigs(op, 16, tol=1e-4)[0]
        errors[correction] = np.abs(lam[1:] / SPHERE_EIGS[1:] - 1).max()
    assert errors["richardson"] < target and errors["richardson"] < errors["none"] / 2, errors


def test_arc_distance_needs_normals():
    # the corrected default reaches clouds too; arc distances only where a normal exists
    P, _, _ = samples.flat_torus_points(400, seed=0)  # k = 2 in R⁴: codimension 2
    with pytest.raises(meshlap.MeshError, match="arc_distance needs normals"):
        meshlap.point_cloud_laplacian(P, arc_distance=True)
    op = meshlap.point_cloud_laplacian(samples.sphere_points(800, "random", seed=0), operator="kernel")
    assert op.correction == "richardson" and op.arc_distance and op.pointwise


@pytest.mark.slow
def test_flat_torus_in_r4():
    P, _, _ = samples.flat_torus_points(16000, seed=0)
    op = meshlap.point_cloud_laplacian(P, h=6e-3, correction="none")
    assert op.geometry.mass.sum() == pytest.approx(4 * math.pi**2, rel=0.005)
    lam = spectral.eigs(op, 9, tol=1e-5)[0]
    assert np.abs(lam[1:] / np.array([1, 1, 1, 1, 2, 2, 2, 2]) - 1).max() < 0.01


@pytest.mark.slow
def test_three_sphere_cloud_within_two_percent():
    # the target for S³ ⊂ R⁴ (k = 3): eigenvalue 3 (×4) within 2%; at 16,000 points
    # the coarse 3-D spacing leaves it 2.0% low, at 24,000 points (h = 0.007) 1.6%, at 32,000
    # 1.3% (benchmarks/RESULTS.md); eigenvalues to 1e-3 are enough to tell 2%
    P = samples.three_sphere_points(24000, seed=0)
    op = meshlap.point_cloud_laplacian(P, h=0.007, k=3, correction="none")
    lam = spectral.eigs(op, 5, tol=1e-3)[0]
    assert np.abs(lam[1:5] / 3 - 1).max() < 0.02


def test_three_sphere_cloud():
    # S³ ⊂ R⁴ with k = 3: the volume 2π², and the 4-fold first eigenvalue 3, here on 3,000
    # points whose coarse spacing (0.2) leaves the paper's operator at h = 0.01 9.5% off and
    # the default (h = 4a² = 0.022) 6.3%; 2% needs ~16,000 points (benchmarks/RESULTS.md)
    P = samples.three_sphere_points(3000, seed=0)
    paper = meshlap.point_cloud_laplacian(P, h=0.01, k=3, correction="none")
    assert paper.mass.sum() == pytest.approx(2 * math.pi**2, rel=0.01)
    lam = spectral.eigs(paper, 6, tol=1e-5)[0]
    assert np.abs(lam[1:5] / 3 - 1).max() < 0.1
    assert np.ptp(lam[1:5]) < 0.03 * 3 and lam[5] > 1.5 * lam[4]
    op = meshlap.point_cloud_laplacian(P, k=3)
    assert op.correction == "richardson"
    assert np.abs(spectral.eigs(op, 6, tol=1e-5)[0][1:5] / 3 - 1).max() < 0.08


def test_a_volume_clouds_stars_from_one_tetrahedralization_equal_the_searched_ones(monkeypatch):
    # secure stars come from the whole cloud's Delaunay tetrahedralization instead of one Qhull
    # call per point (8,000 cube points: 51 s -> 2.8 s); they must be the stars the search
    # finds, so the masses equal those with the shortcut switched off, boundary flags too
    rng = np.random.default_rng(3)
    P = rng.random((1500, 3))
    m, info = pointcloud.point_masses(P, 3)
    rows_seen = []

    def none_secure(X, rows, far):
        rows_seen.append(len(rows))
        return np.zeros(len(rows)), np.zeros(len(rows), dtype=bool)

    monkeypatch.setattr(pointcloud, "_global_stars3", none_secure)
    m0, info0 = pointcloud.point_masses(P, 3)
    assert rows_seen and rows_seen[0] > 500  # most stars needed more than the first neighbours
    np.testing.assert_allclose(m, m0, rtol=1e-12, atol=0)
    assert (info["boundary"] == info0["boundary"]).all()
    # the boundary's stars are local (no hull slivers): measured 0.7% below the hull's volume
    assert m.sum() == pytest.approx(ConvexHull(P).volume, rel=0.01)


@pytest.mark.slow
def test_noisy_cloud_default_is_denoised_and_beats_the_papers_operator():
    # 1% radial noise on 16,000 points: noise ratio 0.078 > NOISY, so the default projects the
    # points first; measured 9 eigenvalues 0.29% off (the kernel without the projection 5.6%,
    # the paper's operator 2.0%)
    P = samples.sphere_points(16000, "noisy", seed=0, noise=0.01)
    op = meshlap.point_cloud_laplacian(P)
    assert "denoised" in op.geometry.notes and np.abs(np.linalg.norm(op.V, axis=1) - 1).std() < 0.005
    paper = meshlap.point_cloud_laplacian(P, correction="none", denoise=False)
    errors = [np.abs(spectral.eigs(o, 10, tol=1e-6)[0][1:] / SPHERE_EIGS[1:10] - 1).max()
              for o in (op, paper)]
    assert errors[0] < 0.01 and errors[0] < errors[1] / 3, errors
    clean = meshlap.point_cloud_laplacian(samples.sphere_points(4000, "random", seed=0))
    assert clean.geometry.notes == ""  # clean samples are left where they are


def test_curvature_is_not_read_as_noise():
    # 1,000 random points of a torus of radii 1 and 0.4 bend by (aκ)² ≈ 0.1 over a neighbourhood:
    # a plane's residual read that as noise (0.033 > NOISY) and the default projected them; the
    # quadratic fit's residual is 1.5e-4. Noise stays noise: 1% normal noise on 4,000 points of
    # the sphere and of the torus, 0.030 and 0.027, over NOISY, and cubic fits leave it all
    assert noise.noise_reading(samples.torus_points(1000, "random")).ratio < 1e-3
    assert noise.noise_reading(samples.torus_points(1000, "jittered")).ratio < 1e-3
    for P in (samples.sphere_points(4000, "noisy", seed=0), samples.torus_points(4000, noise=0.01)):
        geo = pointcloud.point_cloud_geometry(P)
        reading = geo._cache["noise_reading"]
        assert "denoised" in geo.notes and 0.024 < reading.ratio < 0.035 and reading.unexplained > 0.95


def test_a_coarse_samplings_missed_shape_is_not_noise():
    # every 4th of spot's 2,930 vertices: the quadratic fits leave vertex-scale shape (σ̂²/a² =
    # 0.027, over NOISY) that cubic fits explain (they leave 0.29 of it, where noise keeps its
    # share at 1), so the cloud stays where it is and gets FEM on its stars
    V = meshlap.io.read_mesh(str(Path(__file__).parent / "data" / "spot.obj"))[0]
    reading = noise.noise_reading(V[::4])
    assert reading.ratio > noise.NOISY and reading.unexplained < 0.8, reading
    op = meshlap.point_cloud_laplacian(V[::4])
    assert op.geometry.notes == "" and op.decision.operator == "fem"
    assert op.decision.measured["share cubic fits leave"] < 0.8


def test_coarse_torus_cloud_keeps_its_width_and_its_accuracy():
    # the same 1,000 torus points: the curvature cap took the width to 0.13-0.2 of 4a² (0.84 mean
    # edges, where the point masses no longer integrate the kernel), 33% off (36% projected);
    # stopped at half the default, 5.0% against robust-laplacian's 6.7% (benchmarks/RESULTS.md)
    P = samples.torus_points(1000, "random")
    op = meshlap.point_cloud_laplacian(P, operator="kernel")
    assert op.geometry.notes == ""
    hv = op.widths.per_point(len(P))
    assert hv.min() >= meshlap.tuned.CLOUD_CAP_FLOOR * op.h * (1 - 1e-12) and hv.max() < op.h
    lam = spectral.eigs(op, 10, tol=1e-6)[0]
    assert np.abs(lam[1:] / samples.torus_eigenvalues(10)[1:] - 1).max() < 0.055  # measured 5.01%



def test_two_sheets_across_the_air_stay_apart():
    """Two random discs of 1,500 points, 0.3 apart (about 7 spacings): the stars' widened search
    reaches the other disc, whose points project onto this one's tangent plane; they take no
    part in the star (their chords leave it at more than 60°), so the FEM cells keep the discs
    apart: two zero eigenvalues, then the Neumann disc's 1.841² = 3.39 (twice per disc).
    Before, 83 stars crossed and λ₂ was 2.9."""
    rng = np.random.default_rng(0)

    def disc(z):
        r, t = np.sqrt(rng.uniform(0, 1, 1500)), rng.uniform(0, 2 * np.pi, 1500)
        return np.c_[r * np.cos(t), r * np.sin(t), np.full(1500, z)]

    P = np.vstack([disc(0.0), disc(0.3)])
    with pytest.warns(meshlap.MeshWarning, match=r"2 pieces .*\(1,500, 1,500 points\)"):
        op = meshlap.point_cloud_laplacian(P)
    lam = meshlap.spectral.eigs(op, 4)[0]
    assert op.decision.operator == "fem"
    assert abs(lam[1]) < 1e-8 * lam[2] and 3.2 < lam[2] < 3.6


def test_circumradii_of_known_simplices():
    # a segment, a 3-4-5 and an equilateral triangle in R³, a flat one, a regular tetrahedron
    segment = np.array([[[0.0, 0, 0], [2, 0, 0]]])
    triangles = np.array([[[0.0, 0, 0], [3, 0, 0], [0, 4, 0]],
                          [[0.0, 0, 1], [1, 0, 1], [0.5, 3**0.5 / 2, 1]],
                          [[0.0, 0, 0], [1, 1, 1], [2, 2, 2]]])
    tet = np.array([[[1.0, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]])  # edge 2√2
    assert stars._circumradii(segment) == pytest.approx([1.0])
    assert stars._circumradii(triangles)[:2] == pytest.approx([2.5, 3**-0.5])
    assert np.isinf(stars._circumradii(triangles)[2])
    assert stars._circumradii(tet) == pytest.approx([3**0.5])


def test_a_face_without_points_is_a_hole():
    # A 20-gon prism's points, 11 rings of 20 (cylinder-ngon's vertices): its caps carry no
    # points and are 6.4 spacings across, far wider than the sampling leaves empty, so the cloud
    # is the open tube of radius 1 and length 2.85 (before, the search closed most of them: area 21.9).
    t = np.arange(20) * 2 * np.pi / 20
    P = np.vstack([np.c_[np.cos(t), np.full(20, y), np.sin(t)] for y in np.linspace(-1.425, 1.425, 11)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", meshlap.MeshWarning)
        S = pointcloud.point_masses(P)[1]["stars"]
        lam = np.sort(spectral.eigs(meshlap.point_cloud_laplacian(P), 6)[0])
    area = 0.5 * np.linalg.norm(np.cross(P[S[:, 1]] - P[S[:, 0]], P[S[:, 2]] - P[S[:, 0]]), axis=1).sum() / 3
    assert area == pytest.approx(40 * np.sin(np.pi / 20) * 2.85, rel=0.05)  # the side: 3.4% over
    axial = (np.pi / 2.85) ** 2
    open_tube = np.array([1.0, 1.0, axial, 1 + axial, 1 + axial])  # m² + (πj/ℓ)², radius 1
    assert np.max(np.abs(lam[1:6] / open_tube - 1)) < 0.06  # 4.4% measured


def test_pieces_no_star_joins_are_counted_and_named():
    # two unit spheres 3 apart: two pieces, each its own zero eigenvalue, said at the build; one
    # sphere: one piece, no warning. A duplicate point joins its point's piece
    P = meshlap.samples.sphere_points(800)
    with warnings.catch_warnings():
        warnings.simplefilter("error", meshlap.MeshWarning)
        one = meshlap.point_cloud_laplacian(P)
    assert one.decision.measured["parts"] == 1
    Q = np.vstack([P, P + [3.0, 0.0, 0.0], P[:1]])
    with pytest.warns(meshlap.MeshWarning, match=r"falls into 2 pieces .*\(801, 800 points\).* 2 zero"):
        two = meshlap.point_cloud_laplacian(Q)
    assert two.decision.measured["parts"] == 2
    lam = meshlap.spectral.eigs(two, 4)[0]
    assert np.all(np.abs(lam[:2]) < 1e-8) and lam[2] == pytest.approx(2.0, rel=0.02)
    m, info = pointcloud.point_masses(Q)
    count, label = info["pieces"]
    assert count == 2 and label[-1] == label[0] != label[800]


def test_pieces_a_bare_band_leaves_are_joined_by_the_kernel_the_warning_names():
    # a 41 × 41 grid of the unit square without the three columns at x = 0.5: its stars stop at
    # the band (two pieces), the kernel's support reaches across it (one), as on a CAD part's
    # vertices, whose faces carry none inside
    g = np.linspace(0, 1, 41)
    X, Y = np.meshgrid(g, g)
    keep = np.abs(X - 0.5) > 3 / 80
    P = np.column_stack([X[keep], Y[keep], np.zeros(keep.sum())])
    with pytest.warns(meshlap.MeshWarning, match="falls into 2 pieces.*or operator='kernel'"):
        stars_only = meshlap.point_cloud_laplacian(P)
    assert stars_only.decision.measured["parts"] == 2
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", meshlap.MeshWarning)
        kernel = meshlap.point_cloud_laplacian(P, operator="kernel")
    lam = spectral.eigs(kernel, 2)[0]
    assert abs(lam[0]) < 1e-8 < 0.1 < lam[1]  # one piece; λ1 measured 7.6 (the whole square: π²)


def test_a_ribbon_cloud_keeps_the_stars_which_a_cad_parts_outlines_would_trade_for_the_kernel():
    # three rows of 100 points, a 10 × 0.2 strip: the stars end at 67% of the points, as they do
    # along a CAD part's bare faces (trimesh's fixed_top, where the kernel bridges the faces: 4.6%
    # off against the stars' 100%). The points do not tell the two apart; here the kernel smears
    # across the strip's width, so the default keeps the stars
    robust_laplacian = pytest.importorskip("robust_laplacian")
    x, y = np.linspace(0, 10, 100), np.linspace(0, 20 / 99, 3)
    X, Y = np.meshgrid(x, y)
    P = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    exact = np.sort([(np.pi * i / 10) ** 2 + (np.pi * j / y[-1]) ** 2 for i in range(12) for j in range(2)])

    def error(lam):
        return np.abs(np.sort(lam)[1:10] / exact[1:10] - 1).max()

    op = meshlap.point_cloud_laplacian(P)
    assert op.decision.operator == "fem"
    L, M = robust_laplacian.point_cloud_laplacian(P)
    robust = error(np.linalg.eigvals(np.linalg.solve(M.toarray(), L.toarray())).real)
    kernel = error(spectral.eigs(meshlap.point_cloud_laplacian(P, operator="kernel"), 10)[0])
    default = error(spectral.eigs(op, 10)[0])
    assert default <= 1.5 * robust < kernel  # measured 0.0072, 0.023, 0.265


def test_a_grid_on_a_curved_surface_gets_one_diagonal_per_quad():
    # a torus sampled on its (u, v) grid: every quad is an isosceles trapezoid, cocircular, and
    # each star, Delaunay in its own tangent plane, split it its own way, so the soup held both
    # splits: 10% too much area, 14% off on λ1..λ9 (robust-laplacian 15%). One split for all
    # stars gives the grid's own triangles: linear FEM on them
    u, v = np.meshgrid(np.arange(80) * 2 * np.pi / 80, np.arange(40) * 2 * np.pi / 40, indexing="ij")
    ring = 1 + 0.4 * np.cos(v)
    P = np.column_stack([(ring * np.cos(u)).ravel(), (ring * np.sin(u)).ravel(), (0.4 * np.sin(v)).ravel()])
    i, j = np.meshgrid(np.arange(80), np.arange(40), indexing="ij")
    a, b = (i * 40 + j).ravel(), (((i + 1) % 80) * 40 + j).ravel()
    c, d = (((i + 1) % 80) * 40 + (j + 1) % 40).ravel(), (i * 40 + (j + 1) % 40).ravel()
    F = np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    area = 4 * np.pi**2 * 0.4
    op = meshlap.point_cloud_laplacian(P)
    mesh = meshlap.laplacian(P, F)
    assert op.M.sum() == pytest.approx(mesh.M.sum(), rel=1e-9)   # the grid's area, 0.3% under the torus's
    assert mesh.M.sum() == pytest.approx(area, rel=0.01)
    ref = spectral.eigs(mesh, 10)[0]
    grid = spectral.eigs(mesh, 10, elements="linear")[0]
    lam = spectral.eigs(op, 10)[0]
    assert np.abs(lam[1:] / ref[1:] - 1).max() <= 1.05 * np.abs(grid[1:] / ref[1:] - 1).max()  # 0.55% both


@pytest.mark.parametrize("rings, per", [(19, 40), (29, 60)])
def test_a_latitude_longitude_grid_gets_its_grids_triangles(rings, per):
    # each ring's quads with the next are cocircular (both splits overlapped: 32% more area than
    # the sphere's), and a pole's ring is equidistant from it: its first 16 neighbours, an
    # arbitrary 16 of the ring, tilted its plane 1.4° at 29 x 60, so its star was no fan (3.3% off
    # on λ1..λ9 against the grid's 0.95%), and a star of more than 24 triangles lost the rest
    P, F = samples.latitude_longitude_sphere(rings, per)
    op = meshlap.point_cloud_laplacian(P)
    mesh = meshlap.laplacian(P, F)
    assert op.M.sum() == pytest.approx(mesh.M.sum(), rel=1e-9)  # the grid's area, 0.3-0.7% under the sphere's
    exact = np.array([2, 2, 2, 6, 6, 6, 6, 6, 12])
    grid = spectral.eigs(mesh, 10, elements="linear")[0]
    lam = spectral.eigs(op, 10)[0]
    assert np.abs(lam[1:] / exact - 1).max() <= 1.02 * np.abs(grid[1:] / exact - 1).max()  # 2.1%, 0.95% both


@pytest.mark.parametrize("n", [10, 2**21])
def test_star_triangle_keys_round_trip(n):
    # integer keys below 2^21 points, the rows' bytes beyond (three indices would overflow int64)
    from meshlap.geometry.stars import _triangle_keys, _triangles_of

    t = np.array([[0, 1, 2], [n - 3, n - 2, n - 1], [0, 1, 2]])
    keys = _triangle_keys(t, n)
    assert keys[0] == keys[2] and keys[0] != keys[1]
    assert (_triangles_of(np.unique(keys), n) == t[:2]).all()


@pytest.mark.parametrize("lines, per", [(11, 101), (6, 41), (5, 81)])
def test_a_scan_line_cloud_gets_the_stars_of_its_grid(lines, per):
    # points 8-20x denser along their lines than across (a scanner's lines): the first 16
    # neighbours of most points lie on their own line, which fixes no tangent plane, so theirs
    # comes from a doubled neighbourhood that reaches the next lines. The stars are then the
    # grid's triangles, and the spectrum linear FEM's on them. Before, the lines' middles took
    # no star: two pieces at 11 x 101 (error 100%), 53% at 6 x 41, "all collinear" at 5 x 81
    x, y = np.linspace(0, 1, per), np.linspace(0, 1, lines)
    X, Y = np.meshgrid(x, y)
    P = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    a = np.arange(per - 1)[None, :] + per * np.arange(lines - 1)[:, None]
    a = a.ravel()
    F = np.vstack([np.column_stack([a, a + 1, a + per + 1]), np.column_stack([a, a + per + 1, a + per])])
    exact = np.sort([np.pi**2 * (i * i + j * j) for i in range(8) for j in range(8)])

    def error(lam):
        return np.abs(np.sort(lam)[1:10] / exact[1:10] - 1).max()

    op = meshlap.point_cloud_laplacian(P)
    assert op.decision.operator == "fem"
    assert op.geometry.mass.sum() == pytest.approx(1.0, rel=0.01)
    grid = error(spectral.eigs(meshlap.laplacian(P, F), 10, elements="linear")[0])
    assert error(spectral.eigs(op, 10)[0]) <= 1.05 * grid  # measured 0.072/0.071, 0.171/0.171, 0.308/0.308


def _thin_box(n, height, seed):
    # n random points on the surface of [0, 1]² × [0, height], uniform by area
    rng = np.random.default_rng(seed)
    face = rng.choice(6, n, p=np.array([1, 1, height, height, height, height]) / (2 + 4 * height))
    u, v = rng.random(n), rng.random(n)
    sides = [(u, v, 0 * u), (u, v, 0 * u + height), (u, 0 * u, v * height), (u, 0 * u + 1, v * height),
             (0 * u, u, v * height), (0 * u + 1, u, v * height)]
    which = [face == f for f in range(6)]
    return np.column_stack([np.select(which, [s[i] for s in sides]) for i in range(3)])


def test_the_two_faces_of_a_thin_box_are_not_glued():
    # a box 0.08 thick sampled by 3,000 points: its top and bottom faces are 2.9 spacings apart,
    # and where a star takes a point of the other face (not steeply enough to drop it) the stiffness
    # glued them: λ1..λ9 72-92% off; without those triangles (geometry.sheets.bridges) 11-14%
    ref = spectral.eigs(meshlap.point_cloud_laplacian(_thin_box(30000, 0.08, 1)), 10)[0]  # 9 spacings apart
    lam = spectral.eigs(meshlap.point_cloud_laplacian(_thin_box(3000, 0.08, 0)), 10)[0]
    assert np.abs(lam[1:] / ref[1:] - 1).max() < 0.2  # measured 0.137


def test_the_whole_cloud_is_asked_for_its_neighbours_once(monkeypatch):
    # the duplicate test, the first round of stars and the outlier test share one k-d query of
    # every point (on 1,000,000 points the three took 14.4 s, the one 7.9 s with the later rounds);
    # with duplicates the distinct points are asked once more
    P = shapes.fibonacci_sphere(2000)
    sizes = []
    plain = pointcloud._neighbours

    def counted(tree, Q, K):
        sizes.append(len(Q))
        return plain(tree, Q, K)

    monkeypatch.setattr(pointcloud, "_neighbours", counted)
    m, _ = pointcloud.point_masses(P)
    assert sizes.count(len(P)) == 1 and m.sum() == pytest.approx(4 * math.pi, rel=0.01)
    sizes.clear()
    m2, _ = pointcloud.point_masses(np.vstack([P, P[:10]]))
    assert sizes[:2] == [len(P) + 10, len(P)] and sizes.count(len(P)) == 1
    assert np.allclose(m2[10:len(P)], m[10:], rtol=1e-6)
