"""Matplotlib figures for notebooks and reports: meshes coloured by a per-vertex scalar,
rows of eigenfunctions, log-log convergence plots and spectra.

Only matplotlib is needed (``pip install "meshlap[plot]"``); nothing here needs a display
or a GPU, so the functions work under the Agg backend in CI. Each returns the matplotlib
object it drew on, to be shown in a notebook or saved with ``fig.savefig``.

The interactive views :func:`show`, :func:`show_modes` and :func:`save_html` (k3d in
Jupyter, standalone HTML) live in :mod:`meshlap.viewer` and are imported here too.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .errors import MeshError
from .geometry.validation import check_faces, check_function, check_vertices
from .upright import colour_range, parse_up, to_z_up, up_axis
from .viewer import save_html, show, show_modes

__all__ = ["plot_convergence", "plot_functions", "plot_mesh", "plot_spectrum", "save_html", "show",
           "show_modes", "slope", "up_axis"]


def _pyplot():
    try:
        import matplotlib.pyplot as plt
    except ImportError as exc:  # matplotlib is an optional dependency
        raise ImportError('plotting needs matplotlib: pip install "meshlap[plot]"') from exc
    return plt


def _shading(tri: np.ndarray, light: np.ndarray) -> np.ndarray:
    # Lambert shading from a light direction, on both sides of the surface (meshes are not
    # always consistently oriented), kept within [0.45, 1] so colours stay readable.
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    norm = np.linalg.norm(n, axis=1)
    cos = np.abs(n @ light) / np.where(norm > 0, norm, 1.0)
    return 0.45 + 0.55 * cos


def _view_light(elev: float, azim: float) -> np.ndarray:
    # The direction towards the viewer, slightly raised: light comes from over the shoulder.
    e, a = np.radians(elev + 25), np.radians(azim - 20)
    return np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])


def plot_mesh(
    V: Any,
    F: Any,
    values: Any = None,
    *,
    ax: Any = None,
    cmap: str = "viridis",
    vmin: float | None = None,
    vmax: float | None = None,
    symmetric: bool = False,
    view: tuple[float, float] = (20.0, -30.0),
    up: str = "auto",
    colorbar: bool = True,
    title: str | None = None,
    shade: bool = True,
    edgecolor: str = "none",
    figsize: tuple[float, float] = (5.0, 5.0),
) -> Any:
    """Draw a surface mesh, optionally coloured by a scalar per vertex.

    Each (fan-)triangle takes the mean of its corners' values; faces are lit from the
    viewer's side so that the shape reads even where the scalar is flat.

    Parameters
    ----------
    V : (n, 3) array_like
        Vertex positions.
    F : (m, k) array_like, list of polygons or Polygons, or None
        Faces; polygons are drawn as fans of triangles. None draws the vertices as dots
        (a point cloud).
    values : (n,) array_like, optional
        Scalar per vertex (an eigenfunction, the curvature, an error). Without it the
        mesh is drawn in grey.
    ax : mpl_toolkits.mplot3d.axes3d.Axes3D, optional
        Axes made with ``projection="3d"``; a new figure is made when omitted.
    cmap : str
        Colormap name; ``"RdBu_r"`` suits signed values such as eigenfunctions.
    vmin, vmax : float, optional
        Colour range; default the range of ``values``.
    symmetric : bool
        Centre the colour range on 0 (``vmax = -vmin = max |values|``).
    view : (elev, azim)
        Camera angles in degrees.
    up : str, default "auto"
        Which direction points up: an axis with an optional sign (``"y"``, ``"-z"``), or
        ``"auto"`` to take it from the mesh (:func:`up_axis`: the side it stands on). Many
        scanned meshes (the Stanford bunny, spot) have y up, CAD parts often z.
    colorbar, title, shade, edgecolor, figsize
        Presentation.

    Returns
    -------
    Axes3D
        The axes drawn on; ``ax.figure.savefig(...)`` writes it out.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import meshlap
    >>> from meshlap.plot import plot_mesh
    >>> V, F = meshlap.shapes.sphere(200, seed=0)
    >>> ax = plot_mesh(V, F, V[:, 2], title="height")
    >>> ax.get_title()
    'height'
    """
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    plt = _pyplot()
    V = check_vertices(V)
    # without faces (a point cloud, a curve) every vertex is drawn as a dot
    tris = np.arange(len(V))[:, None] if F is None else check_faces(F, len(V)).triangles()
    V = to_z_up(V, "+z" if F is None and up == "auto" else parse_up(up, V, F))
    if ax is None:
        fig = plt.figure(figsize=figsize)
        ax = fig.add_subplot(projection="3d")
    P = V[tris]
    light = _view_light(*view)
    if values is None:
        rgb = np.tile([0.75, 0.75, 0.78], (len(tris), 1))
        mappable = None
    else:
        f = check_function(values, len(V), name="values")
        if f.ndim != 1:
            raise MeshError(f"values must be one scalar per vertex, shape ({len(V)},); got {f.shape}")
        face_value = f[tris].mean(axis=1)
        lo, hi = colour_range(f, vmin, vmax, symmetric)
        import matplotlib as mpl

        norm = mpl.colors.Normalize(lo, hi)
        cm = mpl.colormaps[cmap]
        rgb = cm(norm(face_value))[:, :3]
        mappable = mpl.cm.ScalarMappable(norm=norm, cmap=cm)
        mappable.set_array(f)
    if F is None:
        ax.scatter(*V.T, c=np.clip(rgb, 0, 1), s=max(1.0, 3000.0 / len(V)), depthshade=shade)
    else:
        if shade:
            rgb = rgb * _shading(P, light)[:, None]
        coll = Poly3DCollection(P, facecolors=np.clip(rgb, 0, 1), edgecolors=edgecolor, linewidths=0.2)
        ax.add_collection3d(coll)
    lo_xyz, hi_xyz = V.min(axis=0), V.max(axis=0)
    centre, half = (lo_xyz + hi_xyz) / 2, (hi_xyz - lo_xyz).max() / 2
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_box_aspect((1, 1, 1), zoom=1.3)  # the default leaves wide margins around the mesh
    ax.view_init(*view)
    ax.set_axis_off()
    if title is not None:
        ax.set_title(title)
    if colorbar and mappable is not None:
        ax.figure.colorbar(mappable, ax=ax, shrink=0.6, pad=0.02)
    return ax


def plot_functions(
    V: Any,
    F: Any,
    functions: Any,
    *,
    titles: Sequence[str] | None = None,
    ncols: int = 4,
    cmap: str = "RdBu_r",
    symmetric: bool = True,
    size: float = 3.0,
    **kwargs: Any,
) -> Any:
    """A grid of copies of one mesh, each coloured by one function (e.g. eigenfunctions).

    Parameters
    ----------
    V, F
        The mesh.
    functions : (n, k) array_like
        One function per column.
    titles : list of str, optional
        One title per function.
    ncols : int
        Panels per row.
    cmap, symmetric
        Colours; the default suits signed functions such as eigenfunctions.
    size : float
        Inches per panel.
    **kwargs
        Passed to :func:`plot_mesh` (``view``, ``up``, ``shade``, ...).

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import meshlap
    >>> V, F = meshlap.shapes.sphere(100, seed=0)
    >>> fig = plot_functions(V, F, V, titles=["x", "y", "z"])
    >>> len(fig.axes)
    3
    """
    plt = _pyplot()
    V = check_vertices(V)
    Phi = check_function(functions, len(V), name="functions")
    Phi = Phi.reshape(len(V), -1)
    k = Phi.shape[1]
    if titles is not None and len(titles) != k:
        raise MeshError(f"got {len(titles)} titles for {k} functions")
    ncols = max(1, min(ncols, k))
    nrows = -(-k // ncols)
    fig = plt.figure(figsize=(size * ncols, size * nrows))
    for j in range(k):
        ax = fig.add_subplot(nrows, ncols, j + 1, projection="3d")
        plot_mesh(V, F, Phi[:, j], ax=ax, cmap=cmap, symmetric=symmetric, colorbar=False,
                  title=None if titles is None else titles[j], **kwargs)
    fig.subplots_adjust(left=0, right=1, bottom=0, top=0.92, wspace=0, hspace=0.05)
    return fig


def slope(x: Any, y: Any) -> float:
    """Least-squares slope of log y against log x: the rate in y ≈ C xᵖ.

    Examples
    --------
    >>> round(slope([10, 100, 1000], [1.0, 0.1, 0.01]), 6)
    -1.0
    """
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if x.shape != y.shape or x.ndim != 1 or len(x) < 2:
        raise MeshError(f"slope needs two 1-d arrays of equal length >= 2; got {x.shape} and {y.shape}")
    if np.any(x <= 0) or np.any(y <= 0):
        raise MeshError("slope needs positive values on a log-log scale")
    return float(np.polyfit(np.log(x), np.log(y), 1)[0])


def plot_convergence(
    ns: Any,
    errors: Mapping[str, Any],
    *,
    ax: Any = None,
    xlabel: str = "vertices n",
    ylabel: str = "max error",
    title: str | None = None,
    reference: float | None = None,
    figsize: tuple[float, float] = (5.0, 4.0),
) -> Any:
    """Log-log plot of errors against mesh size, with the fitted rate of each curve.

    Parameters
    ----------
    ns : (p,) array_like
        Mesh sizes (or any positive abscissa, e.g. 1/h).
    errors : dict of str to (p,) array_like
        One error curve per method, e.g. ``{"BSW": ..., "COT": ...}``.
    ax : matplotlib Axes, optional
        Where to draw; a new figure is made when omitted.
    xlabel, ylabel, title
        Labels.
    reference : float, optional
        Also draw a dashed line of slope ``reference`` (e.g. -0.5) through the first
        point of the first curve.

    Returns
    -------
    matplotlib.axes.Axes

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> ax = plot_convergence([100, 400, 1600], {"BSW": [0.4, 0.2, 0.1]}, reference=-0.5)
    >>> ax.get_legend_handles_labels()[1]
    ['BSW (slope -0.50)', 'slope -0.5']
    """
    plt = _pyplot()
    x = np.asarray(ns, dtype=float)
    if not errors:
        raise MeshError("errors is empty: pass at least one curve, e.g. {'BSW': [...]}")
    if ax is None:
        _, ax = plt.subplots(figsize=figsize)
    for label, e in errors.items():
        e = np.asarray(e, dtype=float)
        if e.shape != x.shape:
            raise MeshError(f"curve {label!r} has {e.shape} values for {x.shape} sizes")
        ax.loglog(x, e, "o-", label=f"{label} (slope {slope(x, e):.2f})")
    if reference is not None:
        y0 = float(np.asarray(next(iter(errors.values())), dtype=float)[0])
        ax.loglog(x, y0 * (x / x[0]) ** reference, "k--", lw=1, label=f"slope {reference:g}")
    # tick the sizes themselves: log-scale minor labels overlap on short ranges
    from matplotlib.ticker import NullFormatter

    ax.set_xticks(x, [f"{v:,.0f}" if v >= 1 and float(v).is_integer() else f"{v:g}" for v in x])
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title is not None:
        ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    return ax


def plot_spectrum(
    eigenvalues: Mapping[str, Any],
    *,
    ax: Any = None,
    reference: Any = None,
    title: str | None = None,
    figsize: tuple[float, float] = (5.0, 4.0),
) -> Any:
    """Eigenvalues against their index, one curve per method.

    Parameters
    ----------
    eigenvalues : dict of str to (k,) array_like
        E.g. ``{"BSW": lam_bsw, "COT": lam_cot}``. Signs are drawn as given; meshlap's
        eigenvalues are <= 0 (L ≈ +Δ).
    reference : (k,) array_like, optional
        Exact values, drawn as black crosses.

    Returns
    -------
    matplotlib.axes.Axes

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> ax = plot_spectrum({"BSW": [0, -2, -2, -2]}, reference=[0, -2, -2, -2])
    >>> len(ax.lines)
    2
    """
    plt = _pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=figsize)
    for label, lam in eigenvalues.items():
        lam = np.asarray(lam, dtype=float)
        ax.plot(np.arange(len(lam)), lam, ".-", label=label)
    if reference is not None:
        ref = np.asarray(reference, dtype=float)
        ax.plot(np.arange(len(ref)), ref, "kx", label="exact")
    ax.set_xlabel("index i")
    ax.set_ylabel("eigenvalue λᵢ")
    if title is not None:
        ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend()
    return ax
