"""Plot helpers: what is drawn (faces, colours, rates), under the Agg backend."""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import igl  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

import meshlap  # noqa: E402
from meshlap import plot  # noqa: E402

DATA = Path(__file__).parent / "data"


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def test_plot_mesh_colours_faces_by_corner_mean(tmp_path):
    V, F = meshlap.shapes.sphere(200, seed=0)
    f = V[:, 2] ** 3
    ax = plot.plot_mesh(V, F, f, shade=False, cmap="viridis", title="z³")
    (coll,) = [c for c in ax.collections if isinstance(c, Poly3DCollection)]
    colours = coll.get_facecolor()[:, :3]
    assert len(colours) == len(F)
    norm = matplotlib.colors.Normalize(f.min(), f.max())
    expected = matplotlib.colormaps["viridis"](norm(f[F].mean(axis=1)))[:, :3]
    # matplotlib may hold the faces in depth order: compare the colours as multisets
    by_rows = lambda c: c[np.lexsort(c.T[::-1])]  # noqa: E731
    np.testing.assert_allclose(by_rows(colours), by_rows(expected), atol=1e-12)
    assert ax.get_title() == "z³" and len(ax.figure.axes) == 2  # mesh and colorbar
    out = tmp_path / "mesh.png"
    ax.figure.savefig(out, dpi=40)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_plot_mesh_symmetric_range_polygons_and_shading():
    V, F = meshlap.shapes.sphere(100, seed=1)
    quads = [[0, 1, 2, 3]] + F[2:].tolist()
    ax = plot.plot_mesh(V, quads, V[:, 0] + 0.5, symmetric=True, colorbar=False, up="y")
    (coll,) = [c for c in ax.collections if isinstance(c, Poly3DCollection)]
    assert len(coll.get_facecolor()) == 2 + len(F) - 2  # the quad is drawn as two triangles
    assert len(ax.figure.axes) == 1
    lit = plot.plot_mesh(V, F, colorbar=False)  # grey and shaded: brightness varies
    grey = [c for c in lit.collections if isinstance(c, Poly3DCollection)][0].get_facecolor()[:, 0]
    assert 0.3 < grey.min() < grey.max() <= 0.78


def test_plot_mesh_rejects_bad_values():
    V, F = meshlap.shapes.sphere(50, seed=0)
    with pytest.raises(meshlap.MeshError, match="values must have shape"):
        plot.plot_mesh(V, F, np.ones(49))
    with pytest.raises(meshlap.MeshError, match="one scalar per vertex"):
        plot.plot_mesh(V, F, V)
    with pytest.raises(meshlap.MeshError, match="up must be"):
        plot.plot_mesh(V, F, up="w")


@pytest.mark.parametrize(("name", "up"), [("stanford-bunny", "+y"), ("spot", "+y")])
def test_up_axis_of_real_meshes(name, up):
    # both stand on their feet with y up (the bunny on a flat base, spot on four hooves)
    V, F = igl.read_triangle_mesh(str(DATA / f"{name}.obj"))
    assert plot.up_axis(V, F) == up


@pytest.mark.parametrize("up", ["+x", "-x", "+y", "-y", "+z", "-z"])
def test_up_axis_finds_the_base_whatever_the_orientation(up):
    # a half sphere stands on its flat cut: rotated so that the cut faces -up, it is found
    V, F = meshlap.shapes.sphere(800, seed=2)
    V[:, 2] = np.maximum(V[:, 2], -0.3)
    R = plot.to_z_up(np.eye(3), up)  # drawing takes W to W @ R, a rotation
    assert np.linalg.det(R) == pytest.approx(1.0)
    W = V @ R.T  # the half sphere turned so that it stands on its cut with `up` up
    assert plot.up_axis(W, F) == up
    np.testing.assert_allclose(plot.to_z_up(W, up), V, atol=1e-12)  # drawn upright again


def test_up_axis_without_a_base_is_z():
    V, F = meshlap.shapes.sphere(500, seed=0)
    assert plot.up_axis(V, F) == "+z"
    V, F = meshlap.shapes.torus(800, seed=0)  # lies flat: top and bottom alike
    assert plot.up_axis(V, F) == "+z"


def test_plot_functions_grid():
    V, F = meshlap.shapes.sphere(80, seed=0)
    fig = plot.plot_functions(V, F, np.column_stack([V, V[:, 0] * V[:, 1]]), titles=list("abcd"), ncols=3)
    assert len(fig.axes) == 4 and [ax.get_title() for ax in fig.axes] == list("abcd")
    with pytest.raises(meshlap.MeshError, match="2 titles for 3 functions"):
        plot.plot_functions(V, F, V, titles=["x", "y"])


def test_convergence_plot_reports_fitted_rates():
    ns = np.array([250, 1000, 4000, 16000])
    errs = {"BSW": 3.0 * ns ** -0.5, "COT": 0.2 + 0 * ns}
    ax = plot.plot_convergence(ns, errs, reference=-0.5, title="sphere")
    labels = ax.get_legend_handles_labels()[1]
    assert labels == ["BSW (slope -0.50)", "COT (slope 0.00)", "slope -0.5"]
    np.testing.assert_allclose(ax.lines[2].get_ydata(), errs["BSW"])  # the reference passes through BSW
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    assert plot.slope(ns, 7 * ns**1.25) == pytest.approx(1.25)
    with pytest.raises(meshlap.MeshError, match="positive"):
        plot.slope([1, 2], [0, 1])
    with pytest.raises(meshlap.MeshError, match="curve 'x' has"):
        plot.plot_convergence(ns, {"x": [1, 2]})


def test_spectrum_plot():
    ax = plot.plot_spectrum({"BSW": [0, -1.9, -2.1]}, reference=[0, -2, -2], title="sphere")
    assert len(ax.lines) == 2 and ax.get_title() == "sphere"
