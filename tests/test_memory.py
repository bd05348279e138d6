"""The memory guard counts every matrix a build holds, not only L (issue 19)."""

import numpy as np
import pytest

import meshlap
from meshlap import shapes
from meshlap.assembly import MemoryGuard


def nbytes(A):
    return A.data.nbytes + A.indices.nbytes + A.indptr.nbytes


def test_guard_refuses_a_build_whose_total_exceeds_max_memory():
    # a square: mirror images (a second matrix) and point-wise rows (a third value array)
    V, F = shapes.plane(600, seed=4)
    op = meshlap.laplacian(V, F)
    assert op.boundary_rows > 0 and op.L is not op.L_sym
    nnz = op.L_sym.nnz
    held = nbytes(op.L_sym) + op.L.data.nbytes  # what the operator keeps (L shares a pattern)
    guard = MemoryGuard.for_build(len(V), np.dtype(np.float64), 1, 0.1, images=True, pointwise=True)
    peak = guard.bytes_for(nnz)
    assert nbytes(op.L_sym) < held < peak  # L alone < what is kept < the peak of the build
    # 20 bytes an entry: enough for L alone and for the former count (two value arrays, one
    # pattern), not for the build's peak of 32 bytes an entry
    with pytest.raises(meshlap.OperatorTooLargeError, match="every matrix the build keeps"):
        meshlap.laplacian(V, F, max_memory=int(22 * nnz))
    again = meshlap.laplacian(V, F, max_memory=int(peak * 1.01))
    assert again.L_sym.nnz == nnz
    # the paper's operator holds one matrix: the same budget is plenty
    assert meshlap.laplacian(V, F, h=op.h, correction="none", max_memory=int(22 * nnz)).nnz > 0


def test_guard_counts_by_build():
    g = MemoryGuard.for_build(10, np.dtype(np.float32), 1 << 30, 0.1, images=False, pointwise=False)
    assert g.bytes_for(100) == 100 * (4 + 4) + 11 * 4
    g = MemoryGuard.for_build(10, np.dtype(np.float32), 1 << 30, 0.1, images=True, pointwise=True)
    # float32 rows, the float64 work copy with images and its cast, float32 point-wise values
    assert g.values == 4 + 8 + 4 + 4 and g.patterns == 2
    g = MemoryGuard.for_build(10, np.dtype(np.float64), 1 << 30, 0.1, images=False, pointwise=True,
                              own_pattern=True)
    assert (g.values, g.patterns) == (16, 2)
