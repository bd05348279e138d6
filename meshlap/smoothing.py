"""Smoothing with the heat flow: of functions on a mesh, and of the surface itself.

Function smoothing is the implicit heat step of :mod:`meshlap.heat`: each step of size τ
multiplies the component of frequency λ by 1/(1 + τλ), a low-pass filter that removes noise
and keeps the smooth part. Surface smoothing applies the same step to the coordinates:
ΔX = -2Hn, so the heat flow of X is the mean curvature flow (implicit form of Desbrun,
Meyer, Schröder and Barr, SIGGRAPH 1999), with the operator rebuilt from the moving surface
at every step or held fixed at the initial one.

Called without a time step, :func:`mean_curvature_flow` denoises: the flow is taken relative
to the fitted surface (the vertices move by their mean curvature in excess of the one the
point-wise fitted rows give, so noise is removed and the shape's own curvature is not), along
the normals, with a time step from the noise the fits measure (:data:`~meshlap.tuned.DENOISE_DT`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .errors import MeshError
from .geometry.frames import vertex_normals
from .geometry.mass import _mean_edge_length, paper_width
from .geometry.validation import check_faces, check_int, check_vertices
from .heat import ImplicitHeat
from .policy import decide
from .tuned import DENOISE_DT, DENOISE_H, DENOISE_STEPS

__all__ = ["smooth_function", "mean_curvature_flow", "enclosed_volume"]


def smooth_function(op: Any, f: Any, t: float, steps: int = 1, **kwargs: Any) -> np.ndarray:
    """Denoise a function on the mesh: ``steps`` implicit heat steps of size ``t/steps``.

    The eigencomponent of frequency λ is damped by (1 + tλ/steps)^-steps (→ exp(-tλ)), so
    noise, which lives at high frequencies, is removed while components with λ ≪ 1/t stay.

    Parameters
    ----------
    op : MeshLaplacian or SparseLaplacian
        The Laplacian.
    f : (n,) or (n, m) array_like
        Function(s) to smooth.
    t : float
        Total diffusion time (> 0); about the squared length scale that is averaged out.
    steps : int, default 1
        Number of implicit steps.
    **kwargs
        ``solver``, ``rtol``, ``mesh``: see :class:`~meshlap.heat.ImplicitHeat`.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(2000, seed=0)
    >>> clean = V[:, 2]
    >>> noisy = clean + 0.2 * np.random.default_rng(0).standard_normal(len(V))
    >>> u = smooth_function(meshlap.laplacian(V, F, h=0.01), noisy, t=0.03, steps=3)
    >>> bool(np.abs(u - clean).std() < 0.5 * np.abs(noisy - clean).std())
    True
    """
    steps = check_int(steps, "steps", 1)
    try:
        t = float(t)
    except (TypeError, ValueError) as exc:
        raise MeshError(f"t must be a positive number; got {t!r}") from exc
    return ImplicitHeat(op, t / steps, **kwargs).step(f, steps)


def enclosed_volume(V: Any, F: Any) -> float:
    """Signed volume enclosed by a closed, consistently oriented mesh (divergence theorem).

    Faces of any size are fan-triangulated. Positive for outward-facing faces.

    Examples
    --------
    >>> import meshlap
    >>> V, F = meshlap.shapes.sphere(2000, seed=0)
    >>> round(enclosed_volume(V, F), 2)        # 4π/3 = 4.19, less the flat facets
    4.18
    """
    V = check_vertices(V)
    T = check_faces(F, len(V)).triangles()
    a, b, c = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def mean_curvature_flow(
    V: Any,
    F: Any,
    dt: float | None = None,
    steps: int | None = None,
    *,
    laplacian: Callable[[np.ndarray, Any], Any] | None = None,
    rebuild: bool | None = None,
    h: float | None = None,
    keep_volume: bool = False,
    normal: bool | None = None,
    denoise: bool | None = None,
    **kwargs: Any,
) -> tuple[np.ndarray, dict[str, Any]]:
    r"""Smooth a surface by implicit mean curvature flow, ``(M - dt S) X' = M X`` per step.

    With ``denoise`` (the default when ``dt`` is not given) the flow is taken relative to the
    fitted surface, ``(M - dt S) X' = M (X - dt L̂ X)``, L̂ the operator's point-wise fitted
    rows (``op.L``): L̂X is the mean curvature normal −2Ĥn of the surface the local fits see
    through the noise, so the vertices move by their mean curvature in excess of it. Noise is
    removed and the shape is not shrunk (a clean sphere stays put; the plain flow shrinks it
    as R² − 4t, which on a real mesh is most of its error). The denoising defaults:

    * **time step** ``dt = 4σ̂²`` (:data:`~meshlap.tuned.DENOISE_DT`), σ̂ the normal noise the fitted rows
      measure on the input (``info["noise"]``, the median of ``op.pointwise_choice.noise``);
      :data:`~meshlap.tuned.DENOISE_STEPS` = 2 steps, so the flow diffuses over √(2·8σ̂²) = 4σ̂. Only
      where the library reads noise (``meshlap.laplacian(V, F).decision.denoise``); elsewhere dt = 0:
      a clean mesh does not move, nor a coarse one whose fits leave residuals that are not noise.
    * the Galerkin pencil at h = ē²/4 (:data:`~meshlap.tuned.DENOISE_H`) on triangle meshes, the vertex pencil
      at that width on other faces; the operator built once (``rebuild=False``);
    * ``normal=True``.

    Measured on fandisk and spot with Gaussian normal noise of 0.15, 0.3 and 0.5 mean edges
    (benchmarks/bench_smoothing.py, RMS distance of the vertices to their clean positions):
    the defaults are 8-15% below the cotangent flow at its best single time step.

    Parameters
    ----------
    V : (n, 3) array_like
        Vertex positions.
    F : faces
        Faces of any size.
    dt : float, optional
        Time step (> 0). A sphere of radius R shrinks as R² - 4t under the plain flow.
        Default (denoising only): 4σ̂².
    steps : int, optional
        Number of steps; default 2 when denoising, else 1.
    laplacian : callable, optional
        ``laplacian(V, F) -> operator``; default the Belkin–Sun–Wang operator with ``h``
        (``meshlap.laplacian(V, F, h=h)``, h fixed at the first step's value when not given;
        with ``denoise``, h = ē²/4 and the Galerkin pencil). Pass
        ``meshlap.baselines.cotangent`` for the cotangent flow (not with ``denoise``, which
        needs the fitted rows).
    rebuild : bool, optional
        Rebuild the operator from the current positions at every step (default, except when
        denoising); ``False`` keeps the first one (faster, and the flow is then linear: it
        stays a smoothing filter).
    h : float, optional
        Kernel width for the default operator.
    keep_volume : bool, default False
        After every step, scale the surface about its centroid back to the enclosed volume
        it had before the step (Desbrun et al.), which removes the flow's shrinking.
    normal : bool, optional
        Keep only each vertex's motion along the normal of the stepped surface (default when
        denoising). The flow moves a surface along its normal (ΔX = −2Hn); the tangential part
        of a discrete step comes from the sampling and drags vertices along the surface.
    denoise : bool, optional
        Take the flow relative to the fitted surface, as above; default True exactly when
        ``dt`` is not given, so an explicit ``dt`` keeps the plain flow.
    **kwargs
        ``solver``, ``rtol``: see :class:`~meshlap.heat.ImplicitHeat`.

    Returns
    -------
    V : (n, 3) ndarray
        Smoothed positions.
    info : dict
        ``"volume"``: enclosed volume at the start and after every step ((steps + 1,) array,
        for closed oriented meshes); ``"volume_drift"``: relative volume change of the flow
        itself over all steps (before any ``keep_volume`` rescaling); ``"h"``: kernel width
        used (None for a custom operator); ``"dt"``: the time step; ``"noise"``: σ̂ (None
        unless denoising).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(1500, seed=0)
    >>> W, info = mean_curvature_flow(V, F, dt=0.01, steps=2, h=0.02)
    >>> r = np.linalg.norm(W, axis=1).mean()          # sqrt(1 - 4·0.02) = 0.959
    >>> bool(abs(r - np.sqrt(1 - 0.08)) < 0.005), bool(info["volume_drift"] < 0)
    (True, True)
    >>> X = V * (1 + 0.03 * np.random.default_rng(0).standard_normal((len(V), 1)))
    >>> W, info = mean_curvature_flow(X, F)           # denoise: dt = 4σ̂², 2 steps
    >>> err = lambda P: np.abs(np.linalg.norm(P, axis=1) - 1).mean()
    >>> bool(err(W) < 0.5 * err(X)), bool(abs(np.linalg.norm(W, axis=1).mean() - 1) < 1e-3)
    (True, True)
    """
    X = check_vertices(V).copy()
    faces = check_faces(F, len(X))
    auto = denoise is None and dt is None
    denoise = dt is None if denoise is None else bool(denoise)
    if dt is None and not denoise:
        raise MeshError("dt is needed for the plain flow (denoise=False)")
    if dt is not None and not (isinstance(dt, (int, float, np.number)) and np.isfinite(dt) and dt > 0):
        raise MeshError(f"dt must be a positive number; got {dt!r}")
    steps = (DENOISE_STEPS if denoise else 1) if steps is None else steps
    steps = check_int(steps, "steps", 0)
    normal = denoise if normal is None else bool(normal)
    rebuild = not denoise if rebuild is None else bool(rebuild)
    if laplacian is None:
        laplacian, h = _default_laplacian(X, faces, h, denoise)
    op = laplacian(X, faces)
    sigma = None
    if denoise:
        sigma = _fitted_noise(op)
        # by default only what the library reads as noise (the FEM pencil's test): the fits of a
        # coarse clean mesh leave residuals too, and flowing them shrank the decimated knight 31%
        clean = auto and not decide(op.geometry).denoise
        dt = (0.0 if clean else DENOISE_DT * sigma**2) if dt is None else dt
    volume = [enclosed_volume(X, faces)]
    kept = 1.0
    step = None
    for i in range(steps if dt > 0 else 0):  # a clean mesh measured by the fits has dt = 0
        if rebuild and i > 0:
            op = laplacian(X, faces)
        if step is None or rebuild:
            step = ImplicitHeat(op, dt, **kwargs)
        # relative to the fitted surface: its own mean curvature normal L̂X is not flowed
        Y = step(X - dt * (op.L @ X) if denoise else X)
        if normal:
            n = vertex_normals(Y, faces)
            Y = X + ((Y - X) * n).sum(axis=1, keepdims=True) * n
        X = Y
        vol = enclosed_volume(X, faces)
        kept *= vol / volume[-1] if volume[-1] != 0 else float("nan")
        if keep_volume and vol * volume[-1] > 0:
            c = X.mean(axis=0)
            X = c + (X - c) * (volume[-1] / vol) ** (1.0 / 3.0)
            vol = enclosed_volume(X, faces)
        volume.append(vol)
    return X, {"volume": np.array(volume), "volume_drift": float(kept - 1.0), "h": h, "dt": float(dt),
               "noise": sigma}


def _default_laplacian(X: np.ndarray, faces: Any, h: float | None, denoise: bool) -> tuple[Callable, float]:
    from .builders import laplacian as bsw

    h0 = paper_width(_mean_edge_length(X, faces))  # meshlap.default_h without building a Geometry
    if not denoise:
        h = h0 if h is None else h
        return (lambda P, Q: bsw(P, Q, h=h)), h
    h = DENOISE_H * h0 / 4 if h is None else h
    quadrature = "galerkin" if (faces.sizes == 3).all() else "vertex"

    def build(P: np.ndarray, Q: Any) -> Any:
        return bsw(P, Q, h=h, quadrature=quadrature)

    return build, h


def _fitted_noise(op: Any) -> float:
    # the fitted rows' normal noise σ̂; only they tell the fitted surface's curvature apart
    choice = getattr(op, "pointwise_choice", None)
    if choice is None:
        raise MeshError("denoise takes the flow relative to the fitted rows (pointwise='fit', the default "
                        "of meshlap.laplacian); this operator has none: pass dt and denoise=False")
    return float(np.median(choice.noise))
