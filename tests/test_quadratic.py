"""The seven-node quadratic elements that eigs solves on a mesh (meshlap.quadratic)."""

import numpy as np
import pytest

import meshlap
from meshlap import quadratic, spectral, store


def _grid(nx: int, ny: int) -> tuple[np.ndarray, np.ndarray]:
    # the unit square, nx by ny rectangles, each cut along its diagonal
    x, y = np.meshgrid(np.linspace(0, 1, nx + 1), np.linspace(0, 1, ny + 1), indexing="ij")
    V = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    a = (i * (ny + 1) + j).ravel()
    b, c, d = a + ny + 1, a + ny + 2, a + 1
    return V, np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])


def _square_error(lam: np.ndarray) -> float:
    exact = np.sort([np.pi**2 * (p * p + q * q) for p in range(5) for q in range(5)])[1:10]
    return float(np.max(np.abs(lam[1:10] - exact) / exact))


def test_element_matrices_are_exact_for_quadratics_and_the_mass_for_cubics():
    K, w = quadratic.element_matrices(np.array([[1.0, np.sqrt(2), 1.0]]))  # (0,0), (1,0), (0,1)
    nodes = np.array([[0, 0], [1, 0], [0, 1], [0.5, 0], [0.5, 0.5], [0, 0.5], [1 / 3, 1 / 3]])
    x, y = nodes.T
    assert (x**2) @ K[0] @ (x**2) == pytest.approx(1 / 3, rel=1e-12)  # ∫ |∇x²|² = ∫ 4x²
    assert (x * y) @ K[0] @ (x * y) == pytest.approx(1 / 6, rel=1e-12)  # ∫ x² + y²
    assert w[0] @ x**3 == pytest.approx(1 / 20, rel=1e-12)  # ∫ x³
    assert w[0] @ (x * y**2) == pytest.approx(1 / 60, rel=1e-12)
    assert np.abs(K[0].sum(axis=1)).max() < 1e-12 and np.linalg.eigvalsh(K[0]).min() > -1e-12
    flat = quadratic.element_matrices(np.array([[1.0, 2.0, 1.0]]))  # a collapsed triangle: nothing
    assert not flat[0].any() and not flat[1].any()


def test_the_neumann_square_converges_at_fourth_order():
    # π²(p² + q²): linear elements halve the mesh for a quarter of the error, these for a
    # sixteenth (measured 0.28% -> 0.016% at 6 -> 12 squares a side; linear 18.9% -> 5.0%)
    errors = [_square_error(spectral.eigs(meshlap.laplacian(*_grid(n, n)), 10)[0]) for n in (6, 12)]
    assert errors[1] < 0.001 and errors[0] / errors[1] > 12, errors


def test_long_elements_are_what_they_fix():
    # 3 rectangles across, 40 along: triangles 13 times longer than wide, as on CAD cylinders;
    # linear elements are 46% off (modes across the long sides), these 0.48%
    V, F = _grid(3, 40)
    op = meshlap.laplacian(V, F)
    info: dict = {}
    lam, phi = spectral.eigs(op, 10, info=info)
    linear, _ = spectral.eigs(op, 10, elements="linear")
    assert op.decision.elements == "quadratic" and info["elements"] == "quadratic" and info["complete"]
    assert _square_error(lam) < 0.1 * _square_error(linear), (_square_error(lam), _square_error(linear))
    np.testing.assert_allclose(phi.T @ op.M @ phi, np.eye(10), atol=1e-10)


def test_copies_read_their_representatives_values():
    V, F = meshlap.shapes.sphere(600, seed=4)
    top = V[F].mean(axis=1)[:, 2] > 0
    Fd = np.where(top[:, None], F + len(V), F)
    with pytest.warns(meshlap.MeshWarning, match="duplicate"):
        op = meshlap.laplacian(np.vstack([V, V]), Fd)
    lam, phi = spectral.eigs(op, 6)
    ref, _ = spectral.eigs(meshlap.laplacian(V, F), 6)
    np.testing.assert_allclose(lam, ref, atol=1e-7)
    used = np.unique(Fd[top])
    np.testing.assert_allclose(phi[used], phi[used - len(V)], atol=1e-12)


def test_clouds_keep_their_pencil_and_bad_values_are_named():
    cloud = meshlap.point_cloud_laplacian(meshlap.samples.sphere_points(400, seed=0))
    assert cloud.decision.elements == "linear"
    with pytest.raises(meshlap.MeshError, match="triangle or polygon mesh"):
        spectral.eigs(cloud, 4, elements="quadratic")
    with pytest.raises(meshlap.MeshError, match="elements must be"):
        spectral.eigs(meshlap.laplacian(*_grid(3, 3)), 4, elements="cubic")


def test_a_saved_operator_solves_the_same_elements(tmp_path):
    V, F = meshlap.shapes.sphere(400, seed=2)
    op = meshlap.laplacian(V, F)
    back = store.load_operator(store.save_operator(tmp_path / "op", op))
    bare = store.load_operator(store.save_operator(tmp_path / "bare", op, mesh=False))
    assert back.elements == "quadratic" and bare.elements == "linear"
    np.testing.assert_allclose(spectral.eigs(back, 6)[0], spectral.eigs(op, 6)[0], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(spectral.eigs(bare, 6)[0], spectral.eigs(op, 6, elements="linear")[0],
                               rtol=1e-9, atol=1e-9)


def test_the_command_line_names_the_elements(capsys, tmp_path):
    from meshlap import cli, io

    V, F = meshlap.shapes.sphere(500, seed=1)
    path = io.write_mesh(tmp_path / "s.obj", V, F)
    op = meshlap.laplacian(*io.read_mesh(path))
    for elements in ("auto", "linear"):
        argv = ["eigs", str(path), "-k", "5", "--elements", elements, "-o", str(tmp_path / "e.npz")]
        assert cli.main(argv) == 0
        expected = spectral.eigs(op, 5, elements=elements)[0]
        np.testing.assert_allclose(np.load(tmp_path / "e.npz")["eigenvalues"], expected, rtol=1e-7, atol=1e-9)
    capsys.readouterr()


def test_the_policy_records_why_and_where_it_stops():
    from meshlap.tuned import QUADRATIC_MAX_UNKNOWNS

    V, F = meshlap.shapes.sphere(500, seed=0)
    d = meshlap.laplacian(V, F).decision
    assert d.elements == "quadratic" and d.measured["quadratic unknowns"] == 500 + 2.5 * len(F)
    assert meshlap.laplacian(V, F, mass="blend").elements == "linear"  # a named mass: its own pencil
    assert meshlap.laplacian(V, F, operator="kernel").elements == "linear"
    big = meshlap.laplacian(*meshlap.shapes.sphere(17_000, seed=0)).decision  # 102,000 unknowns
    assert big.elements == "linear" and big.measured["quadratic unknowns"] > QUADRATIC_MAX_UNKNOWNS
