"""Eigenpairs of a mesh Laplacian, the sphere's exact spectrum, and the heat kernel signature.

Every function takes any operator with the common surface ``.L, .M, .S, .mass, .n_vertices``
and ``op @ f``: a :class:`~meshlap.MeshLaplacian` (Belkin–Sun–Wang, SoCG 2008) or a
:class:`~meshlap.baselines.SparseLaplacian` such as the cotangent scheme. The problem is
``-S φ = λ M φ`` with ``S = M L`` symmetric negative semidefinite: λ ≥ 0, φ M-orthonormal.

On a sparse pencil :func:`eigs` factors it (shift-invert); on a volume whose factorization
counts more than ``_multigrid.MAX_FACTOR_WORK`` multiply-adds (a bulky one's fills as n^(4/3)),
it runs LOBPCG (Knyazev 2001) preconditioned by multigrid (:mod:`meshlap._multigrid`), and
factors after all where the V-cycle stalls (a graded or anisotropic volume) and what its
iterations still need would cost more than the counted factorization (``_multigrid.Stall``). The
heat-kernel operator keeps hundreds to thousands of entries per row, whose LU fills in badly
(94 s for 36 pairs of a 16,000-vertex sphere at h = 0.0025); there LOBPCG is preconditioned by
the same mesh's cotangent Laplacian, equal to the kernel at low frequencies. At high
frequencies the kernel's symbol saturates, (1 - exp(-hω²))/h ≤ 1/h, while the cotangent one
grows like ω²; 1/g(x) = 1/x + h/2 + O(h²x), g the symbol as a function of the cotangent
eigenvalue x, gives the preconditioner

    T = (K + σM)⁻¹ + ½ D⁻¹,    K = -C (cotangent stiffness),  D = diag(-S) ≈ M/h,

whose product with the operator stays within a factor of about two of the identity at every
frequency. The iteration itself (and the meaning of ``tol``: the eigenvalues' accuracy) is in
:mod:`meshlap._lobpcg`. See ``benchmarks/RESULTS.md`` ("Eigenpairs") for the measured times.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np
import scipy.sparse as sp

from . import _eigcheck, _ldl, _lobpcg, _multigrid, _parts, _shiftinvert, quadratic
from ._jit import in_blocks, jit, one_blas_thread
from .errors import MeshError
from .fem import expand_copies
from .geometry import spatial_order
from .geometry.topology import duplicate_vertices
from .geometry.validation import check_faces, check_k, check_solver, check_vertices
from .progress import ProgressLike, make_progress, onward
from .samples import sphere_eigenvalue

__all__ = ["eigs", "sphere_eigenvalue", "heat_kernel_signature", "apply_block"]

_METHODS = ("auto", "lobpcg", "shift-invert", "dense")
# Largest system solved densely: a sparse pencil's, where shift-invert costs as much (300 rows;
# above, O(n³) falls behind: 1,100 rows 68-82 ms against 12-35 ms for k = 6-40, RESULTS.md's
# "eigs: dense or shift-invert", `bench_eigs.py --dense-crossover`). A dense-row pencil's
# alternative is LOBPCG, whose products cost n² per vector and iteration against eigh's n³, so
# the crossover grows with the block: _DENSE_PER_VECTOR rows per vector (measured crossovers
# about 800 rows for 10 vectors, 1,700 for 20, 4,000 for 44; the same section), up to
# _DENSE_FALLBACK. Then the row density above which a sparse LU fills in badly.
_DENSE_SPARSE = 300
_DENSE_PER_VECTOR = 80
_SPARSE_ROW_MAX = 40
# the fallbacks after a failed check: dense up to this many vertices with mass, shift-invert
# for a dense-row operator up to this many entries (5.1 M: 65 s on 2 cores, LOBPCG 18 s)
_DENSE_FALLBACK = 4000
_FALLBACK_NNZ = 8_000_000
# the cotangent start's residual, relative: the operator's own iterations do not depend on it
# below ~0.3, as the start's error is then the two operators' difference (36 eigenpairs of a
# 16k sphere: 7 iterations from a start to 0.3, 0.1, 0.03, 0.01 or 0.001, which took 5-8)
_START_TOL = 0.1


# -- products with the operator ----------------------------------------------------------------
def symmetric_L(op: Any) -> Any:
    """The L of the operator's symmetric pencil (``op.L_sym``; ``op.L`` for operators that
    keep one matrix): what spectra and heat flow iterate with."""
    L = getattr(op, "L_sym", None)  # op.L only where there is none: reading it fits the rows
    return op.L if L is None else L


def apply_block(op: Any, X: np.ndarray) -> np.ndarray:
    """``L_sym @ X`` (the symmetric pencil's L) for a block of functions, with a parallel CSR
    product when L is stored.

    scipy's sparse-times-dense product runs on one thread; this one splits rows over
    meshlap's threads and accepts CSR rows in any column order (the operator stores its
    diagonal first). A matrix-free pencil recomputes its kernel (``op.sym_product``).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(300, seed=0)
    >>> op = meshlap.laplacian(V, F, h=0.02, correction="none")
    >>> bool(np.allclose(apply_block(op, V), op @ V))
    True
    """
    X = np.asarray(X, dtype=np.float64)
    vector = X.ndim == 1
    X2 = np.ascontiguousarray(X.reshape(len(X), -1))
    L = None if getattr(op, "matrix_free", False) else symmetric_L(op)
    if sp.issparse(L) and L.format == "csr":
        Y = _lobpcg.csr_times(L, X2)
    else:  # a matrix-free pencil (its op @ f may apply the fitted rows), a LinearOperator
        Y = np.asarray(op.sym_product(X2) if hasattr(op, "sym_product") else op @ X2)
    return Y.ravel() if vector else Y


# -- the problem on the vertices with mass ------------------------------------------------------
@jit()
def _take(start, stop, indptr, indices, data, rows, newcol, fill, out_indptr, out_indices,
          out_data):  # pragma: no cover - compiled
    # rows[r] of the matrix as row r, columns renumbered by newcol (-1: dropped); fill=False
    # counts each row's entries into out_indptr[r + 1]
    for r in range(start, stop):
        w = rows[r]
        q = out_indptr[r] if fill else 0
        cnt = 0
        for p in range(indptr[w], indptr[w + 1]):
            c = newcol[indices[p]]
            if c >= 0:
                if fill:
                    out_indices[q + cnt] = c
                    out_data[q + cnt] = data[p]
                cnt += 1
        if not fill:
            out_indptr[r + 1] = cnt


def _ordered_L(op: Any, P: np.ndarray) -> tuple[sp.csr_matrix, np.ndarray] | None:
    # L_sym on the vertices with mass, rows and columns in spatial order: (matrix, order of P)
    # for LOBPCG's block products; None without a stored L, positions or room for the copy
    L = None if getattr(op, "matrix_free", False) else symmetric_L(op)
    V = getattr(op, "V", None)
    if not sp.issparse(L) or L.format != "csr" or V is None or len(V) != L.shape[0]:
        return None
    from .assembly import available_memory

    if 3 * L.nnz * (L.data.itemsize + L.indices.itemsize) > available_memory():
        return None
    order = spatial_order(np.asarray(V, dtype=np.float64)[P])
    rows = P[order]
    newcol = np.full(L.shape[0], -1, dtype=np.int64)
    newcol[rows] = np.arange(len(rows))
    indptr = np.zeros(len(rows) + 1, dtype=np.int64)
    args = (L.indptr, L.indices, L.data, rows, newcol)
    if len(P) == L.shape[0]:
        indptr[1:] = np.diff(L.indptr)[rows]
    else:
        in_blocks(_take, len(rows), *args, False, indptr, indptr, L.data)
    np.cumsum(indptr, out=indptr)
    indices = np.empty(int(indptr[-1]), dtype=L.indices.dtype)
    data = np.empty(int(indptr[-1]), dtype=np.float64)
    in_blocks(_take, len(rows), *args, True, indptr, indices, data)
    B = sp.csr_matrix((len(rows), len(rows)))
    B.data, B.indices, B.indptr = data, indices, indptr.astype(L.indptr.dtype)
    B.has_sorted_indices = False
    return B, order


def _check_mass(op: Any) -> tuple[np.ndarray, np.ndarray]:
    mass = np.asarray(op.mass, dtype=np.float64)
    if mass.shape != (op.n_vertices,) or not np.isfinite(mass).all() or (mass < 0).any():
        raise MeshError("op.mass must hold one finite, non-negative mass per vertex")
    P = np.flatnonzero(mass > 0)
    if len(P) == 0:
        raise MeshError("every vertex has zero mass: the mesh has no surface")
    return mass, P


def _restricted_S(op: Any, P: np.ndarray) -> sp.csr_matrix:
    if getattr(op, "matrix_free", False):  # solved densely (a small problem): S column by column
        unit = np.zeros((op.n_vertices, len(P)))
        unit[P, np.arange(len(P))] = 1.0
        return sp.csr_matrix(op.mass[P, None] * apply_block(op, unit)[P])
    S = op.S if len(P) == op.n_vertices else op.S[P][:, P]
    return sp.csr_matrix(S, dtype=np.float64)


def _extend(op: Any, P: np.ndarray, Phi_P: np.ndarray) -> np.ndarray:
    """Fill eigenvectors at zero-mass vertices with the kernel-weighted mean of their row of L.

    For the heat-kernel operator this is the λ → 0 limit of the Nyström extension
    φ(w) = Σ_p L_wp φ(p) / (Σ_p L_wp - λ): the eigenfunction of the integral operator
    read off at a point that carries no mass. Where a row sees no vertex with mass (the
    cotangent Laplacian at unreferenced vertices) the value is 0.
    """
    n = op.n_vertices
    Phi = np.zeros((n, Phi_P.shape[1]))
    Phi[P] = Phi_P
    if len(P) == n:
        return Phi
    Z = np.setdiff1d(np.arange(n), P)
    ind = np.zeros((n, 1))
    ind[P] = 1.0
    LY = apply_block(op, np.hstack([Phi, ind]))[Z]
    num, den = LY[:, :-1], LY[:, -1]
    ok = den > 1e-12 * max(float(np.abs(den).max()), 1e-300)
    Phi[Z[ok]] = num[ok] / den[ok, None]
    return Phi


def _normalize_signs(Phi: np.ndarray) -> np.ndarray:  # reproducible: the largest entry is positive
    s = np.sign(Phi[np.argmax(np.abs(Phi), axis=0), np.arange(Phi.shape[1])])
    return Phi * np.where(s == 0, 1.0, s)


# -- preconditioner from the cotangent Laplacian -----------------------------------------------
def _mesh_of(op: Any, mesh: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray | None] | None:
    # (positions, triangles, each vertex's representative among coincident copies, None: unknown)
    if mesh is not None:
        V, F = mesh
        V = check_vertices(V, "mesh[0]")
        if len(V) != op.n_vertices:
            raise MeshError(f"mesh has {len(V)} vertices but the operator has {op.n_vertices}")
        return V, check_faces(F, len(V), "mesh[1]").triangles(), None
    geo = getattr(op, "geometry", None)
    if hasattr(op, "V") and getattr(op, "faces", None) is not None:  # not for curves, volumes, clouds
        rep = None if geo is None else geo.copies()  # (cached)
        return op.V, op.faces.triangles(), np.arange(len(op.V)) if geo is not None and rep is None else rep
    # a point cloud's local Delaunay triangles (meshlap.geometry.pointcloud; its copies are merged)
    cells = getattr(geo, "cells", None)
    if cells is not None and cells.shape[1] == 3 and len(cells) and op.V.shape[1] == 3:
        return op.V, cells, np.arange(len(op.V))
    return None


def _cot_stiffness(V: np.ndarray, T: np.ndarray, P: np.ndarray, rep: Any = None) -> sp.csc_matrix | None:
    """K = -C on the vertices with mass, from the non-degenerate triangles welded (``rep``, each
    vertex's representative: default found here), each copy tied to its point as the FEM pencil
    ties it (an untied copy's zero row stalled LOBPCG for 200 iterations on exported meshes)."""
    import igl

    rep = duplicate_vertices(V) if rep is None else rep
    T = rep[T]
    area = 0.5 * igl.doublearea(V, T)
    good = area > 1e-12 * max(float(area.mean()), 1e-300)
    if not good.any():
        return None
    with np.errstate(all="ignore"):
        C = igl.cotmatrix(V, np.ascontiguousarray(T[good], dtype=np.int64))
    K = sp.csc_matrix(-expand_copies(sp.csr_matrix(C), np.ones(len(V)), rep)[0])[P][:, P]
    return K if np.isfinite(K.data).all() else None


# -- the public solver ------------------------------------------------------------------------
def eigs(
    op: Any,
    k: int = 20,
    *,
    method: str = "auto",
    tol: float = 1e-8,
    maxiter: int = 200,
    extra: int | None = None,
    mesh: tuple[Any, Any] | None = None,
    seed: int = 0,
    progress: ProgressLike = None,
    count: bool | None = None,
    info: dict | None = None,
    elements: str = "auto",
) -> tuple[np.ndarray, np.ndarray]:
    r"""The k smallest eigenpairs of ``-S φ = λ M φ`` (the symmetric form of -L), verified.

    Parameters
    ----------
    op : MeshLaplacian or SparseLaplacian
        Any operator with ``.L, .M, .S, .mass, .n_vertices`` and ``op @ f``.
    k : int, default 20
        Number of eigenpairs.
    method : {"auto", "lobpcg", "shift-invert", "dense"}
        ``"lobpcg"``: preconditioned LOBPCG; the preconditioner is the cotangent Laplacian of
        the same mesh plus a diagonal term (module notes), used when the operator carries its
        mesh (``op.V``, ``op.faces``) or ``mesh`` is given, otherwise the diagonal alone.
        ``"shift-invert"``: :func:`scipy.sparse.linalg.eigsh` with a sparse LU of ``-S + σM``
        (slow where it fills in: the heat kernel, a volume). ``"dense"``: :func:`scipy.linalg.eigh`.
        ``"auto"``: dense up to 300 vertices (where S has more than 40 entries per row, up to
        80 per vector of LOBPCG's block, ``k + extra``, at most 4,000), shift-invert up to 40
        entries per row, else LOBPCG;
        LOBPCG with multigrid on a volume whose factorization would cost more than
        ``_multigrid.MAX_FACTOR_WORK`` multiply-adds (module notes).
    tol : float, default 1e-8
        Relative accuracy of the eigenvalues (Notes); eigenvectors are then accurate to about
        ``√tol``. Passed to eigsh for shift-invert. 0 (as for eigsh), or anything below machine
        precision, asks for machine precision.
    maxiter : int, default 200
        LOBPCG iterations before its pairs go to the check as they are.
    extra : int, optional
        Guard vectors carried along by LOBPCG. Default: at least ``max(4, k // 10)``, and as
        many as close the cluster of the k-th eigenvalue in the cotangent start.
    mesh : (V, F), optional
        Mesh for the cotangent preconditioner when ``op`` does not carry one (e.g.
        :func:`meshlap.baselines.bsw_scipy`). Polygons are fan-triangulated.
    seed : int, default 0
        Seed of the random start vectors (the result does not depend on it beyond ``tol``).
    progress : bool or callable, optional
        ``True`` draws a bar on stderr; a callable gets ``(fraction, stage)`` with the stage
        names "preconditioner", "cotangent start (iteration i)", "LOBPCG (iteration i)",
        "shift-invert", "shift-invert: factoring", "Lanczos", "Lanczos, deflated", "inertia
        count", "dense", "part i of n" (several parts) and "done".
    count : bool, optional
        Prove that no eigenvalue below the k-th is missing by counting the eigenvalues below a
        shift σ just above it (Sylvester's inertia of a sparse LDLᵀ of ``-S - σM``). Default:
        for sparse pencils (at most 40 entries per row), where the factorization costs about
        what the solve does; ``True`` also for the heat-kernel operator (its LU fills in:
        minutes at 16,000 vertices), and a result that cannot be counted then raises.
    info : dict, optional
        Filled with what was checked: ``method`` (the one whose pairs were returned),
        ``tried``, ``iterations``, ``residuals`` (‖-Sφ - λMφ‖ in the M⁻¹ norm), ``bounds``
        (each eigenvalue's error bound over ``tol`` times its scale, all ≤ 1),
        ``orthogonality`` (largest entry of ``|ΦᵀMΦ - I|``), ``count``, ``shift`` and
        ``complete`` (whether the count, or a dense solve, showed the k values are the lowest),
        ``elements``, ``uncertified`` (what roundoff left the check, relative: MeshWarning > 1e-3);
        on a sparse pencil of several connected parts, solved part by part (:mod:`meshlap._parts`),
        ``parts`` too.
    elements : {"auto", "linear", "quadratic"}, default "auto"
        "linear": the pairs of ``op``'s pencil (S, M); "quadratic": of the seven-node elements
        on the same triangles (:mod:`meshlap.quadratic`), read at the vertices, M-orthonormal;
        "auto": ``op.elements`` (quadratic for the default on a polygon mesh).

    Returns
    -------
    lam : (k,) ndarray
        Eigenvalues, ascending (≈ 0 first on a closed or bounded mesh).
    phi : (n, k) ndarray
        Eigenvectors with ``phi.T @ M @ phi = I``, signs fixed so that the entry of largest
        magnitude is positive.

    Raises
    ------
    meshlap.EigenError
        When no solver's pairs pass the check, with the best ones and their bounds.

    Notes
    -----
    Every returned pair is checked with fresh products (:mod:`meshlap._eigcheck`): the block
    is M-orthonormal and each eigenvalue's error bound from its residual (Kato–Temple over its
    cluster, Bauer–Fike where no gap is known) is within ``tol · max(λ, λ_k / 100, 1% of
    4π/area, roundoff's floor)``. Pairs that fail are recomputed (LOBPCG wider, shift-invert,
    dense up to 4,000 vertices, matrix-free too), else :class:`meshlap.EigenError` (docs/spectral.md).
    Vertices with zero mass have no row in the problem; φ there is the kernel-weighted mean
    of its neighbours (the λ → 0 Nyström extension), or 0 where that row of L is empty.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(2000, seed=0)
    >>> op = meshlap.laplacian(V, F, h=0.005, correction="none")
    >>> lam, phi = eigs(op, 9)
    >>> np.round(lam, 1)      # l(l+1) = 0, 2, 6 with multiplicities 1, 3, 5
    array([0. , 2. , 2. , 2. , 5.9, 5.9, 5.9, 5.9, 5.9])
    >>> bool(np.allclose(phi.T @ op.M @ phi, np.eye(9)))
    True
    """
    if method not in _METHODS:
        raise MeshError(f"method must be one of {', '.join(_METHODS)}; got {method!r}")
    tol = check_solver(tol, maxiter, extra, seed)
    if count not in (None, True, False):
        raise MeshError(f"count must be None, True or False; got {count!r}")
    if elements not in ("auto", "linear", "quadratic"):
        raise MeshError(f"elements must be 'auto', 'linear' or 'quadratic'; got {elements!r}")
    mass, P = _check_mass(op)
    n_p = len(P)
    k = check_k(k, n_p)
    if elements == "auto":
        elements = getattr(op, "elements", "linear")
    if info is not None:
        info["elements"] = elements
    if elements == "quadratic":  # the same pairs' better approximation, verified on its own pencil
        lam, X = eigs(quadratic.fine_pencil(op), k, method=method, tol=tol, maxiter=maxiter, extra=extra,
                      seed=seed, progress=progress, count=count, info=info, elements="linear")
        if info is not None:
            info["elements"] = "quadratic"
        return lam, _normalize_signs(quadratic.at_vertices(op, X))
    m = mass[P]
    matrix_free = getattr(op, "matrix_free", False)
    nnz = 0 if matrix_free else symmetric_L(op).nnz
    sparse = not matrix_free and nnz <= _SPARSE_ROW_MAX * op.n_vertices
    # made on first use: S on the vertices with mass, and L_sym there in spatial order (for
    # LOBPCG's products and the check's)
    S_P = functools.cache(lambda: _restricted_S(op, P))
    if sparse and (parts := _parts.part_labels(S_P()))[0] > 1:
        # the spectrum is the union of the parts': each solved and checked at its own scale,
        # without the other parts' copies of its values (meshlap._parts)
        solve = functools.partial(eigs, method=method, tol=tol, maxiter=maxiter, extra=extra, seed=seed,
                                  count=count)
        report = onward(make_progress(progress))  # a part asked again starts the bar's rest
        lam, X = _parts.by_part(S_P(), parts[1], m, k, solve, info, report)
        if report is not None:
            report(1.0, "done")
        return lam, _normalize_signs(_extend(op, P, X))
    volume = _ldl.supernodal(op)  # a large one's factor fills as n^(4/3): LOBPCG with multigrid
    multigrid = sparse and _multigrid.replaces_factor(op) and method in ("auto", "lobpcg")
    stall = _multigrid.Stall(lambda: _ldl.least_work(op.S)) if multigrid and not matrix_free else None
    adapt = extra is None
    extra = max(4, k // 10) if extra is None else int(extra)
    if method == "auto":
        dense_max = _DENSE_SPARSE if sparse else min(_DENSE_PER_VECTOR * (k + extra), _DENSE_FALLBACK)
        method = ("dense" if n_p <= dense_max
                  else "shift-invert" if sparse and not multigrid else "lobpcg")
    if method == "lobpcg" and 3 * (k + extra) >= n_p:
        method = "dense"

    report = onward(make_progress(progress))  # a retry starts its stages over
    if report is not None and method != "lobpcg":
        report(0.0, method)
    spatial = functools.cache(lambda: None if sparse else _ordered_L(op, P))

    def dense(want: int):
        S = S_P().toarray()
        lam, X = _eigcheck.lumped_eigh(-0.5 * (S + S.T), m, [0, min(2 * want, n_p - 1)])
        return lam, X, 0

    def lobpcg(wide: bool):
        def run(want: int):
            # past k, all that the count asked for converge (λ_k's ties, or values skipped)
            goal = max(k, min(want, n_p // 3 - extra))
            more = max(extra, k // 2) if wide else extra
            ceiling = (lambda lam: _eigcheck.count_ceiling(lam, k, tol, floor)) if counted else None
            return _eigs_lobpcg(op, P, m, goal, tol, 2 * maxiter if wide else maxiter, more, mesh, seed,
                                adapt and not wide, spatial(), report, S_P if sparse else None, ceiling,
                                multigrid, None if wide else stall)
        return run

    exact = _eigcheck.Attempt("dense", dense, exact=True)
    # one factorization for every run: a retry asked for more pairs reuses it (3-D: most of the time)
    inverse = functools.cache(lambda: _shiftinvert.shift_operator(S_P(), m, 1e-3 * _scale_shift(m), volume,
                                                                  report))
    runs: list = []

    def shift_invert(want: int):
        # a retry (the count found more below σ, or λ_k's ties go on) keeps the earlier pairs;
        # where no count will show that none is missing, deflated runs look for skipped values
        run = _shiftinvert.shift_invert if counted else _shiftinvert.without_skips
        lam, X, it = run(*inverse(), m, want, tol, seed, runs[-1] if runs else None, report)
        runs.append((lam, X))
        return lam, X, it

    shift = _eigcheck.Attempt("shift-invert", shift_invert)
    wider = _eigcheck.Attempt("lobpcg (wider)", lobpcg(True))
    ladder = {"dense": [exact], "shift-invert": [shift],
              "lobpcg": [_eigcheck.Attempt("lobpcg (multigrid)" if multigrid else "lobpcg", lobpcg(False)),
                         wider]}[method]
    if method != "shift-invert" and not matrix_free and (sparse or nnz <= _FALLBACK_NNZ):
        # where a factorization fits, it comes before twice the iterations that did not converge;
        # after multigrid's, only where the V-cycle stalled (Stall): else its cost is why it ran
        if stall is not None:
            ladder.insert(1, shift._replace(when=lambda: stall.fired))
            ladder.append(shift._replace(when=lambda: not stall.fired))
        else:
            ladder.insert(1 if method == "lobpcg" and not multigrid else len(ladder), shift)
    if method != "dense" and n_p <= _DENSE_FALLBACK:  # matrix-free: n columns cost less than LOBPCG wider
        ladder.insert(1 if matrix_free else len(ladder), exact)
    if method == "shift-invert" and n_p > _DENSE_FALLBACK:
        ladder.append(wider)
    counted = (sparse and not multigrid if count is None else count) and not matrix_free  # a count factors
    counter = (lambda sigma: _eigcheck.count_below(-S_P(), m, sigma, volume, report)) if counted else None

    def apply_A(X: np.ndarray) -> np.ndarray:
        if spatial() is not None:  # the block's rows read from cache, as in LOBPCG
            B, order = spatial()
            out = np.empty_like(X)
            out[order] = _lobpcg.csr_times(B, X[order], -m[order])
            return out
        # a sparse pencil by scipy's product: no compiled kernel to load for the check alone
        if sparse:
            return -(S_P() @ X)
        full = X if n_p == op.n_vertices else np.zeros((op.n_vertices, X.shape[1]))
        full[P] = X
        return -m[:, None] * np.asarray(apply_block(op, full))[P]

    stiff = 0.0 if matrix_free else float(np.abs(symmetric_L(op).diagonal()[P]).max())  # max S_ii / m_i
    scale = _scale_shift(m)
    floor = _eigcheck.roundoff_floor(stiff, tol, scale)
    checked = {} if info is None else info
    with one_blas_thread():  # the check's Gram matrices share rows among meshlap's threads
        lam, X = _eigcheck.first_verified(ladder, k, apply_A, m, tol, floor, counter, bool(count),
                                          info=checked)
    bound = None
    if sparse and floor > 0.01 * scale:  # what roundoff left these pairs' residuals, not any vector's
        absolute = abs(S_P())
        rho = _eigcheck.residual_roundoff(lambda Y: absolute @ Y, m, X)
        bound = _eigcheck.certified(lam, checked["residuals"], checked["bounds"], tol, floor, rho)
    _eigcheck.warn_roundoff(lam, tol, floor, scale, stiff, info, bound)
    if report is not None:
        report(1.0, "done")
    return lam, _normalize_signs(_extend(op, P, X))


def _scale_shift(m: np.ndarray) -> float:  # 4π/area: 1 on the unit sphere (λ₁ = 2)
    return 4.0 * math.pi / float(m.sum())


def _eigs_lobpcg(op, P, m, k, tol, maxiter, extra, mesh, seed, adapt, ordered, report=None, own=None,
                 ceiling=None, multigrid=False, give_up=None):
    n, n_p = op.n_vertices, len(P)
    nb, full = k + extra, n_p == n
    if report is not None:
        report(0.0, "preconditioner")
    # the iteration runs in spatial order where L is stored: the same problem, permuted, whose
    # block products read the block from cache
    order = slice(None) if ordered is None else ordered[1]
    m, minus_m = m[order], -m[order]

    def apply_A(Xp: np.ndarray) -> np.ndarray:
        if ordered is not None:
            return _lobpcg.csr_times(ordered[0], Xp, minus_m)
        if full:
            return -m[:, None] * apply_block(op, Xp)
        X = np.zeros((n, Xp.shape[1]))
        X[P] = Xp
        return -m[:, None] * apply_block(op, X)[P]

    # diag(-S) on the vertices with mass, -m_w L_ww; ≈ m_w / h for the heat-kernel operator,
    # which is what a matrix-free operator offers
    if getattr(op, "matrix_free", False):
        diag = m / op.h
    else:
        diag = -m * np.asarray(symmetric_L(op).diagonal())[P][order]
    sigma = _scale_shift(m)
    geo = _mesh_of(op, mesh)
    K = None if geo is None else _cot_stiffness(geo[0], geo[1], P, geo[2])
    if K is None and own is not None:  # no mesh (quadratic elements, a user's pencil) but sparse:
        K = sp.csc_matrix(-own())     # its own stiffness, the exact preconditioner
    if K is not None and ordered is not None:
        K = sp.csc_matrix(K[order][:, order])
    T = _lobpcg.CotPreconditioner(K, m, diag, sigma, _multigrid.Multigrid if multigrid else None)
    rng = np.random.default_rng(seed)

    def random(c: int) -> np.ndarray:
        return rng.standard_normal((n_p, c))[order]
    with one_blas_thread():
        if K is None or multigrid:  # the start's inverse iteration wants exact solves
            X0 = random(nb)
        else:
            # start from the cotangent eigenvectors, found cheaply with the exact preconditioner
            # (the same factorization, without ½ D⁻¹), to a residual of _START_TOL; the start's
            # first step of inverse iteration saves 1-3 of its iterations (k = 20, 36, 50 on the
            # 16k sphere, spot, fandisk and the bunny)
            Kr = sp.csr_matrix(K)
            X0, _ = _lobpcg.cotangent_start(lambda Y: _lobpcg.csr_times(Kr, Y), m, T.lu.solve, random, k, nb,
                                            n_p, _START_TOL, 10, adapt=adapt, cheap=True,
                                            report=_lobpcg.lobpcg_progress(report, "cotangent start", 0.05,
                                                                           0.2))
        out = _lobpcg.lobpcg(apply_A, m, T, X0, k, tol, maxiter, least=0.01 * sigma, ceiling=ceiling,
                             report=_lobpcg.lobpcg_progress(report, "LOBPCG", 0.2, 1.0), give_up=give_up)
    X = out.X  # the whole block: the values past k give the check the gap above λ_k
    if ordered is not None:
        X = X[np.argsort(order)]  # back to the order of P
    return out.lam, X, out.iterations


# -- heat kernel signature ----------------------------------------------------------------------
def heat_kernel_signature(op: Any | None = None, t: Any = 1.0, k: int = 100, *,
                          eig: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    r"""Heat kernel signature HKS(x, t) = Σ_i exp(-λ_i t) φ_i(x)² (Sun, Ovsjanikov, Guibas 2009).

    The diagonal of the heat kernel exp(tL), from the k smallest eigenpairs; accurate where
    exp(-λ_k t) is negligible.

    Parameters
    ----------
    op : operator, optional
        The Laplacian; not needed when ``eig`` is given.
    t : float or (T,) array_like
        Times (> 0).
    k : int, default 100
        Eigenpairs to compute when ``eig`` is not given.
    eig : (lam, phi), optional
        Precomputed eigenpairs from :func:`eigs`.

    Returns
    -------
    (n,) or (n, T) ndarray

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(800, seed=0)
    >>> hks = heat_kernel_signature(meshlap.laplacian(V, F, h=0.01), t=[1.0], k=16)
    >>> bool(abs(hks.mean() - (1 + 3 * np.exp(-2)) / (4 * np.pi)) < 2e-3)   # l ≤ 1 dominate
    True
    """
    if eig is None:
        if op is None:
            raise MeshError("heat_kernel_signature needs an operator or precomputed eig=(lam, phi)")
        eig = eigs(op, k)
    lam, phi = (np.asarray(a, dtype=np.float64) for a in eig)
    if lam.ndim != 1 or phi.ndim != 2 or phi.shape[1] != len(lam):
        raise MeshError(f"eig must be (lam (k,), phi (n, k)); got shapes {lam.shape} and {phi.shape}")
    times = np.asarray(t, dtype=np.float64)
    if not np.isfinite(times).all() or (times <= 0).any():
        raise MeshError(f"t must hold finite times > 0; got {t!r}")
    out = (phi * phi) @ np.exp(-np.outer(np.maximum(lam, 0.0), np.atleast_1d(times)))
    return out[:, 0] if times.ndim == 0 else out
