"""bench_real.py's helpers (benchmarks/real_corpus.py) on synthetic meshes: midpoint refinement,
linear FEM, the Richardson-extrapolated reference against the sphere's l(l+1), welding, reading
polygon files and the error metric with several parts. The corpus itself is not needed."""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import real_corpus as rc  # noqa: E402

OCTA_V = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
OCTA_F = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
CUBE_TETS = np.array([[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]])
CUBE_V = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=float)
# the sphere's eigenvalues 0, 2 (×3), 6 (×5), 12 (×7)
SPHERE = np.array([0] + [2] * 3 + [6] * 5 + [12] * 7, dtype=float)


def unit(X):
    return X / np.linalg.norm(X, axis=1, keepdims=True)


def volumes(V, C):
    E = V[C[:, 1:]] - V[C[:, :1]]
    return np.abs(np.linalg.det(E)) / 6


def test_refine_triangles_and_tetrahedra():
    V, F = rc.refine(OCTA_V, OCTA_F, 2)
    assert F.shape == (8 * 16, 3) and len(V) == 66  # V - E + F = 2: 66 - 192 + 128
    area = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    assert area.sum() == pytest.approx(8 * np.sqrt(3) / 2, rel=1e-12)  # same surface
    Vt, T = rc.refine(CUBE_V, CUBE_TETS, 2)
    assert T.shape == (6 * 64, 4) and len(Vt) == 125  # the 5 × 5 × 5 lattice
    vol = volumes(Vt, T)
    # Bey's split: the eight children of a tetrahedron have equal volumes
    np.testing.assert_allclose(vol, 1 / 6 / 64, rtol=1e-12)


def test_refine_merges_a_tetrahedral_meshs_coincident_midpoints_and_keeps_a_surfaces():
    """Two unit cubes share the face x = 1, each cut along a different diagonal of it (as the
    cells beside a flat quadrilateral whose zero-volume tetrahedra weld drops): refinement puts
    both diagonals' midpoints at (1, ½, ½), one vertex, not a crack. A surface's coincident
    midpoints (here a sheet given twice) are its own and stay apart."""
    second = np.column_stack([1 + CUBE_V[:, 0], 1 - CUBE_V[:, 1], CUBE_V[:, 2]])  # diagonal (1,1,0)-(2,0,1)
    V, T = rc.weld(np.vstack([CUBE_V, second]), np.vstack([CUBE_TETS, CUBE_TETS + 8]))
    assert len(V) == 12 and len(T) == 12
    Vr, Tr = rc.refine(V, T, 1)
    assert len(Vr) == len(np.unique(Vr.round(12), axis=0)) == 5 * 3 * 3  # the lattice of spacing ½
    assert volumes(Vr, Tr).sum() == pytest.approx(2.0, rel=1e-12)
    Vs, _ = rc.refine(np.vstack([OCTA_V, OCTA_V]), np.vstack([OCTA_F, OCTA_F + 6]), 1)
    assert len(Vs) == 2 * len(rc.refine(OCTA_V, OCTA_F, 1)[0])


def test_p1_fem_exact_on_linear_functions():
    V, F = rc.refine(OCTA_V, OCTA_F, 1)
    K, M = rc.p1_fem(V, F)
    assert abs(K @ np.ones(len(V))).max() < 1e-12
    area = 8 * np.sqrt(3) / 2
    assert M.sum() == pytest.approx(area, rel=1e-12)
    Vt, T = rc.refine(CUBE_V, CUBE_TETS, 1)
    Kt, Mt = rc.p1_fem(Vt, T)
    x = Vt @ np.array([1.0, 2.0, -2.0])  # |∇x|² = 9 on the unit cube
    assert x @ Kt @ x == pytest.approx(9.0, rel=1e-12)
    assert Mt.sum() == pytest.approx(1.0, rel=1e-12)


def test_reference_converges_at_second_order_on_the_sphere():
    V, F = rc.refine(OCTA_V, OCTA_F, 2, project=unit)  # 66 vertices
    errs = []
    for level in range(3):  # 4×, 16×, 64×
        Vl, Fl = rc.refine(V, F, level + 1, project=unit)
        lam = rc.pencil_eigs(*rc.p1_fem(Vl, Fl), 16)
        errs.append(np.abs(lam[1:] - SPHERE[1:]).max() / 2)
    # O(h²): each halving of h divides the error by about 4 (measured 4.13 and 4.03)
    assert 3.8 < errs[0] / errs[1] < 4.4 and 3.8 < errs[1] / errs[2] < 4.2
    r = rc.reference(V, F, 16, project=unit)
    assert r["levels"] == [1, 2] and r["n_fine"] == 1026
    fine = rc.pencil_eigs(*rc.p1_fem(*rc.refine(V, F, 2, project=unit)), 16)
    np.testing.assert_allclose(r["fine"], fine, rtol=1e-9, atol=1e-12)
    ext = np.abs(r["ref"][1:] - SPHERE[1:]).max() / 2
    assert ext < 0.1 * errs[1]  # Richardson removes the h² term (measured 0.042× the 16× level's error)


def test_reference_uses_one_level_less_on_large_meshes(monkeypatch):
    monkeypatch.setitem(rc.FINEST_MAX, 3, 500)
    r = rc.reference(*rc.refine(OCTA_V, OCTA_F, 2, project=unit), 5)
    assert r["levels"] == [0, 1] and r["n_fine"] == 258


def test_spectrum_error_skips_one_zero_per_part():
    ref = np.array([0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10.0])
    lam = ref * 1.02
    assert rc.spectrum_error(lam, ref, 2) == pytest.approx(0.02)
    # an operator that joins the two parts has one zero: its spectrum is shifted against the reference
    joined = np.concatenate([[0], ref[2:] * 1.0, [11]])
    assert rc.spectrum_error(joined, ref, 2) == pytest.approx(1.0)  # 2 against the reference's 1
    assert rc.spectrum_error(lam[:10], ref, 2) == np.inf  # too few eigenvalues


def test_two_spheres_have_two_zero_eigenvalues():
    V, F = rc.refine(OCTA_V, OCTA_F, 2, project=unit)
    V2 = np.vstack([V, V + [2.02, 0, 0]])
    F2 = np.vstack([F, F + len(V)])
    assert rc.parts(F2, len(V2)) == 2
    ref = rc.reference(V2, F2, 11)
    assert np.abs(ref["ref"][:2]).max() < 1e-8 and ref["ref"][2] > 1
    lam = rc.pencil_eigs(*rc.p1_fem(V2, F2), 11)
    # the mesh itself against its refined reference: h² errors of a 66-vertex sphere (measured 6.9%)
    assert 0.05 < rc.spectrum_error(lam, ref["ref"], 2) < 0.09


def test_weld_triangulate_and_read(tmp_path):
    # a unit square as two quads with an unwelded seam, and a stray vertex
    (tmp_path / "sq.obj").write_text(
        "v 0 0 0\nv 0.5 0 0\nv 0.5 1 0\nv 0 1 0\nv 0.5 0 0\nv 1 0 0\nv 1 1 0\nv 0.5 1 0\nv 9 9 9\n"
        "f 1 2 3 4\nf 5/1 6/1 7/1 8/1\n")
    (tmp_path / "sq.off").write_text("OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n")
    m = rc.load(tmp_path / "sq.obj")
    assert len(m.V) == 9 and [len(f) for f in m.faces] == [4, 4]
    assert len(m.Vw) == 6 and m.Cw.shape == (4, 3) and rc.parts(m.Cw, 6) == 1
    V, faces = rc.read(tmp_path / "sq.off")
    assert V.shape == (4, 3) and faces[0].tolist() == [0, 1, 2, 3]
    assert rc.triangulate(faces).tolist() == [[0, 1, 2], [0, 2, 3]]
    K, M = rc.p1_fem(m.Vw, m.Cw)
    assert M.sum() == pytest.approx(1.0)
