"""Saved operators come back bit for bit: every kind, every matrix, spectra and heat (issue 21)."""

import numpy as np
import pytest
import scipy.sparse as sp

import meshlap
from meshlap import io
from meshlap.heat import heat_flow
from meshlap.spectral import eigs

V, F = meshlap.shapes.sphere(600, kind="random", seed=0)
KINDS = {
    "default": lambda: meshlap.laplacian(V, F),
    "paper": lambda: meshlap.laplacian(V, F, correction="none"),
    "float32": lambda: meshlap.laplacian(V, F, h=0.02, dtype=np.float32, correction="none"),
    "cloud": lambda: meshlap.point_cloud_laplacian(meshlap.samples.sphere_points(600)),
    "curve": lambda: meshlap.laplacian(*meshlap.samples.circle(80, d=3)[:2]),
    "volume": lambda: meshlap.laplacian(*meshlap.samples.cube_tetrahedra(4), k=3),
    "cotangent": lambda: meshlap.baselines.cotangent(V, F),
}


def same_csr(A, B):
    return all(np.array_equal(getattr(A, a), getattr(B, a)) for a in ("data", "indices", "indptr"))


@pytest.mark.parametrize("kind", KINDS)
def test_every_kind_round_trips_bit_for_bit(kind, tmp_path):
    op = KINDS[kind]()
    back = io.load_operator(io.save_operator(tmp_path / kind, op))
    f = np.sin(3 * op.V) if hasattr(op, "V") else np.sin(3 * V)
    assert np.array_equal(back @ f, op @ f)
    for name in ("L", "S", "M"):
        assert same_csr(getattr(back, name), getattr(op, name)), name
    assert back.L.dtype == op.L.dtype
    assert np.array_equal(back.mass, op.mass)
    for name in ("h", "tol", "radius", "h_auto", "correction", "decision"):
        assert getattr(back, name) == getattr(op, name, None if name != "h_auto" else False), name
    d = getattr(op, "decision", None)  # the repr says what was built
    built = op.name if d is None else f"{d.operator} pencil, {d.rows} rows"
    assert repr(back).startswith(f"SavedLaplacian({built}, vertices=")
    if hasattr(op, "geometry"):
        assert np.array_equal(back.V, op.V) and back.dim == op.dim
        assert back.geometry.source == op.geometry.source
    twice = io.load_operator(io.save_operator(tmp_path / f"{kind}-again", back))  # a loaded one saves too
    assert same_csr(twice.S, op.S) and np.array_equal(twice @ f, op @ f)
    lam, phi = eigs(op, 6)
    lam2, phi2 = eigs(back, 6)
    assert np.array_equal(lam2, lam) and np.array_equal(phi2, phi)
    assert lam[1] > 0.1  # a real spectrum, not zeros
    if hasattr(op, "h"):
        assert np.array_equal(heat_flow(back, f[:, 0], 0.01), heat_flow(op, f[:, 0], 0.01))


def test_default_operator_keeps_its_point_wise_rows(tmp_path):
    # op @ f applies the point-wise rows; the spectra use the symmetric pencil: both are saved,
    # the moment rows' vertex pencil as values only on their sparsity pattern; the fitted rows'
    # (the default) and a Galerkin pencil with patterns of their own
    moments = meshlap.laplacian(V, F, pointwise=True, quadrature="vertex")
    with np.load(io.save_operator(tmp_path / "moments", moments)) as data:
        assert "sym_data" in data and "sym_indices" not in data
    op = KINDS["default"]()
    path = io.save_operator(tmp_path / "op", op)
    with np.load(path) as data:
        assert "sym_data" in data and "sym_indices" in data
    back = io.load_operator(path)
    f = V[:, 0] ** 2
    assert np.abs((back.L_sym - back.L) @ f).max() > 1e-3  # two different matrices
    assert np.array_equal(back @ f, op @ f)
    assert back.nbytes == op.nbytes
    assert abs(sp.load_npz(path) @ f - op @ f).max() == 0  # scipy reads the applied matrix


def test_matrix_free_operator_is_rebuilt(tmp_path):
    op = meshlap.laplacian(V, F, h=0.02, matrix_free=True)
    back = io.load_operator(io.save_operator(tmp_path / "free", op))
    assert back.matrix_free and back.moment_scale == op.moment_scale
    assert np.array_equal(back @ V, op @ V) and back.options.pointwise == "fit"  # the fitted rows
    plain = meshlap.laplacian(V, F, h=0.02, matrix_free=True, pointwise=False)  # the kernel's rows
    again = io.load_operator(io.save_operator(tmp_path / "plain", plain))
    assert again.options.pointwise is False and np.array_equal(again @ V, plain @ V)
    assert np.array_equal(eigs(back, 4)[0], eigs(op, 4)[0])
    with pytest.raises(meshlap.MeshError, match="mesh=True"):
        io.save_operator(tmp_path / "free2", op, mesh=False)
    square = meshlap.point_cloud_laplacian(np.random.default_rng(1).random((300, 2)), matrix_free=True)
    back = io.load_operator(io.save_operator(tmp_path / "square", square))  # with its mirror images
    assert back.neumann and back.boundary_rows == square.boundary_rows > 0
    assert np.array_equal(eigs(back, 3)[0], eigs(square, 3)[0])


def test_wrong_arguments_and_versions(tmp_path):
    op = meshlap.laplacian(V, F, h=0.02, correction="none")
    with pytest.raises(meshlap.MeshError, match="the file comes first"):
        io.save_operator(op, tmp_path / "x.npz")
    with pytest.raises(meshlap.MeshError, match="path must be a str"):
        io.save_operator(3, op)
    with pytest.raises(meshlap.MeshError, match="needs an operator with L and mass"):
        io.save_operator(tmp_path / "x.npz", V)
    path = io.save_operator(tmp_path / "op.npz", op)
    with np.load(path) as data:
        arrays = dict(data)
    for version, word in ((99, "a newer"), ("two", "is not a number"), (None, "an older")):
        if version is None:
            del arrays["meshlap_format"]
        else:
            arrays["meshlap_format"] = np.array(version)
        np.savez(tmp_path / "tampered.npz", **arrays)
        with pytest.raises(io.OperatorFormatError, match=word):
            io.load_operator(tmp_path / "tampered.npz")


def test_a_file_with_the_former_resolution_report_loads(tmp_path):
    # files saved while the kernel carried a resolution report (JSON under "resolution") are of
    # the same layout: they load, bit for bit, and the report is not read
    op = meshlap.laplacian(V, F, operator="kernel")
    with np.load(io.save_operator(tmp_path / "op", op)) as data:
        arrays = dict(data)
    assert "resolution" not in arrays
    arrays["resolution"] = np.array('{"spacing": 0.1, "verdict": "resolved"}')
    np.savez(tmp_path / "old.npz", **arrays)
    back = io.load_operator(tmp_path / "old.npz")
    assert np.array_equal(back @ V, op @ V) and same_csr(back.S, op.S)
    assert not hasattr(back, "resolution")
