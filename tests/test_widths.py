"""The curvature cap's sums: compiled, and equal to the bit to the numpy expression they
replaced (meshlap.widths)."""

import numpy as np

import meshlap
from meshlap import widths


def _edges_with_repeats(n, rng):
    # face sides of a random sphere, again reversed, a point joined to 40 others, an edge from a
    # point to itself
    V, F = meshlap.shapes.sphere(n, kind="random", seed=4)
    e = meshlap.geometry.validation.check_faces(F, n).edges()
    hub = np.column_stack([np.zeros(40, dtype=np.int64), rng.choice(np.arange(1, n), 40, replace=False)])
    return V, np.vstack([e, e[::-1, ::-1], hub, [[7, 7]]])


def test_curvature_sums_equal_the_bincounts():
    rng = np.random.default_rng(5)
    V, e = _edges_with_repeats(1500, rng)
    n = len(V)
    for P, N in ((V, V + 0.01 * rng.normal(size=V.shape)), (V[:, :2], rng.normal(size=(n, 2)))):
        d2 = ((P[e[:, 0]] - P[e[:, 1]]) ** 2).sum(axis=1)
        dn2 = ((N[e[:, 0]] - N[e[:, 1]]) ** 2).sum(axis=1)
        num, den = np.zeros(n), np.zeros(n)
        widths._curvature_sums(np.ascontiguousarray(P), np.ascontiguousarray(N), e, num, den)
        assert np.array_equal(num, np.bincount(e[:, 0], dn2, n) + np.bincount(e[:, 1], dn2, n))
        assert np.array_equal(den, np.bincount(e[:, 0], d2, n) + np.bincount(e[:, 1], d2, n))
