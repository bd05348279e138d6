"""Interactive 3D views: a k3d widget in Jupyter, and standalone HTML that works offline.

* :func:`show` draws a mesh (or a point cloud, ``F=None``) coloured by one function, or a
  grid of copies coloured by several; in Jupyter the returned ``k3d`` plot displays itself
  and turns with the mouse.
* :func:`show_modes` draws the first eigenfunctions of an operator.
* :func:`save_html` writes a plot as one HTML file with k3d's JavaScript embedded in it: it
  opens in any browser with WebGL, with no network and no Python.

k3d is optional: ``pip install "meshlap[view]"``. These functions are also
:mod:`meshlap.plot`'s ``show``, ``show_modes`` and ``save_html``.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .errors import MeshError
from .geometry.validation import check_faces, check_function, check_vertices
from .upright import colour_range, parse_up, to_z_up

__all__ = ["save_html", "show", "show_modes"]

# copies in a grid are this many bounding-box sizes apart
_GAP = 1.3


def _k3d() -> Any:
    try:
        import k3d
    except ImportError as exc:
        raise ImportError('the interactive viewer needs k3d: pip install "meshlap[view]"') from exc
    return k3d


def _colormap(k3d: Any, name: str) -> Any:
    maps = k3d.colormaps.matplotlib_color_maps
    for key in (name, name[:1].upper() + name[1:], name.capitalize()):
        if hasattr(maps, key):
            return getattr(maps, key)
    raise MeshError(f"unknown colormap {name!r}; use a matplotlib name such as 'viridis' or 'RdBu_r'")


def show(V: Any, F: Any = None, f: Any = None, *, titles: Sequence[str] | None = None,
         cmap: str = "viridis", vmin: float | None = None, vmax: float | None = None,
         symmetric: bool = False, up: str = "auto", ncols: int = 4, point_size: float | None = None,
         height: int = 512) -> Any:
    """An interactive view of a mesh or point cloud coloured by per-vertex values.

    Parameters
    ----------
    V : (n, 3) array_like
        Vertex positions (or points).
    F : faces, optional
        Faces of any size (drawn as fans of triangles); None draws the points.
    f : (n,) or (n, m) array_like, optional
        One value per vertex, or m functions drawn side by side in a grid of copies.
    titles : list of str, optional
        A label under each copy.
    cmap : str, default "viridis"
        A matplotlib colormap name (k3d carries its own copies: matplotlib is not needed).
    vmin, vmax : float, optional
        Colour range; default the range of each function.
    symmetric : bool, default False
        Centre each colour range on 0 (for signed functions such as eigenfunctions).
    up : str, default "auto"
        The direction drawn up, as in :func:`meshlap.plot.plot_mesh`.
    ncols : int, default 4
        Copies per row.
    point_size : float, optional
        Point diameter for clouds; default from the cloud's spacing.
    height : int, default 512
        Height of the widget in pixels.

    Returns
    -------
    k3d.plot.Plot
        Displays itself in Jupyter; :func:`save_html` writes it to a file.

    Examples
    --------
    >>> import meshlap
    >>> V, F = meshlap.shapes.sphere(300, seed=0)
    >>> plot = show(V, F, V[:, :2], titles=["x", "y"])   # two copies, two labels
    >>> len(plot.objects)
    4
    """
    k3d = _k3d()
    V = check_vertices(V)
    if V.shape[1] != 3:
        raise MeshError(f"the viewer draws points in 3D; V has {V.shape[1]} columns")
    tris = None if F is None else check_faces(F, len(V)).triangles()
    P = to_z_up(V, "+z" if F is None and up == "auto" else parse_up(up, V, tris))
    Phi = None if f is None else check_function(f, len(V), name="f").reshape(len(V), -1)
    m = 1 if Phi is None else Phi.shape[1]
    if titles is not None and len(titles) != m:
        raise MeshError(f"got {len(titles)} titles for {m} functions")
    lo, hi = P.min(axis=0), P.max(axis=0)
    step = _GAP * float((hi - lo).max())
    ncols = max(1, min(int(ncols), m))
    if point_size is None:
        point_size = 0.6 * float((hi - lo).max()) / np.sqrt(len(V))
    nrows = -(-m // ncols)
    plot = k3d.plot(grid_visible=False, axes_helper=0, height=int(height), menu_visibility=False,
                    camera_auto_fit=True, camera=_camera(hi - lo, step, ncols, nrows))
    colors = _colormap(k3d, cmap)
    for j in range(m):
        # copies in rows along x, the rows down along z (up), all seen from the front (-y)
        offset = np.array([(j % ncols) * step, 0.0, -(j // ncols) * step])
        Q = (P - lo + offset).astype(np.float32)
        style: dict[str, Any] = {"color": 0xBFBFC7}
        if Phi is not None:
            style = {"attribute": Phi[:, j].astype(np.float32), "color_map": colors,
                     "color_range": colour_range(Phi[:, j], vmin, vmax, symmetric)}
        if tris is None:
            plot += k3d.points(Q, point_size=point_size, shader="3d", **style)
        else:
            plot += k3d.mesh(Q, tris.astype(np.uint32), side="double", **style)
        if titles is not None:
            below = offset + [(hi - lo)[0] / 2, 0.0, -0.08 * step]
            plot += k3d.text(titles[j], position=below.tolist(), reference_point="ct", label_box=False,
                             color=0x333333, size=0.8, is_html=True)
    return plot


def _camera(extent: np.ndarray, step: float, ncols: int, nrows: int) -> list[float]:
    # k3d's camera: eye, target, up; far enough back (field of view 60°) to see every copy
    target = np.array([(ncols - 1) * step + extent[0], extent[1], -(nrows - 1) * step + extent[2]]) / 2
    span = max((ncols - 1) * step + extent[0], 1.6 * ((nrows - 1) * step + extent[2]))
    eye = target + 1.2 * span * np.array([0.0, -1.0, 0.3])
    return [*eye.tolist(), *target.tolist(), 0.0, 0.0, 1.0]


def show_modes(op: Any, k: int = 6, *, eig: tuple[np.ndarray, np.ndarray] | None = None,
               **kwargs: Any) -> Any:
    """The first ``k`` non-constant eigenfunctions of an operator, side by side.

    Parameters
    ----------
    op : MeshLaplacian or any operator with ``V``
        A mesh's, point cloud's or volume's operator (a volume is drawn by its hull).
    k : int, default 6
        Number of eigenfunctions (the constant one is skipped).
    eig : (eigenvalues, eigenvectors), optional
        From :func:`meshlap.spectral.eigs`, when already computed (at least k + 1 pairs).
    **kwargs
        Passed to :func:`show` (``cmap``, ``ncols``, ``up``, ...).

    Returns
    -------
    k3d.plot.Plot

    Examples
    --------
    >>> import meshlap
    >>> V, F = meshlap.shapes.sphere(500, seed=0)
    >>> plot = show_modes(meshlap.laplacian(V, F), 3)
    >>> [obj.text for obj in plot.objects if hasattr(obj, "text")][0]   # 2 on the inscribed polyhedron
    'φ1  λ = 2.013'
    """
    from .inputs import boundary_triangles
    from .spectral import eigs

    if not hasattr(op, "V"):
        raise MeshError("this operator does not carry its vertices (saved with mesh=False?)")
    lam, phi = eigs(op, k + 1) if eig is None else eig
    if phi.shape[1] < k + 1:
        raise MeshError(f"eig holds {phi.shape[1]} eigenpairs; show_modes(k={k}) needs {k + 1}")
    F = getattr(op, "faces", None)
    cells = getattr(getattr(op, "geometry", None), "cells", None)
    if F is None and getattr(op, "dim", 2) == 3 and cells is not None:
        F = boundary_triangles(cells)
    kwargs.setdefault("cmap", "RdBu_r")
    kwargs.setdefault("symmetric", True)
    return show(op.V[:, :3], F, phi[:, 1:k + 1],
                titles=[f"φ{i}  λ = {lam[i]:.4g}" for i in range(1, k + 1)], **kwargs)


def save_html(plot: Any, path: str | os.PathLike) -> Path:
    """Write a :func:`show` plot as standalone HTML: k3d's JavaScript and the data in one file.

    The page needs no network and no Python: open it in a browser with WebGL.

    Parameters
    ----------
    plot : k3d.plot.Plot
        From :func:`show` or :func:`show_modes`.
    path : str or path-like
        Target file, ending in ``.html``.

    Returns
    -------
    Path
        The file written.

    Examples
    --------
    >>> import meshlap, pathlib, tempfile
    >>> V, F = meshlap.shapes.sphere(300, seed=0)
    >>> path = save_html(show(V, F, V[:, 2]), pathlib.Path(tempfile.mkdtemp()) / "height.html")
    >>> path.stat().st_size > 100_000                     # k3d's JavaScript is in the file
    True
    """
    if not hasattr(plot, "get_snapshot"):
        raise MeshError(f"save_html needs a plot from meshlap.plot.show; got {type(plot).__name__}")
    path = Path(path)
    if path.suffix.lower() not in (".html", ".htm"):
        raise MeshError(f"save_html writes .html files; got {path.name!r}")
    path.write_text(plot.get_snapshot(), encoding="utf-8")
    return path
