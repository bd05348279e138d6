"""The memory guard counts every matrix a build holds, not only L (issue 19)."""

import math

import numpy as np
import pytest

import meshlap
from meshlap import shapes
from meshlap.assembly import MemoryGuard


def kernel_laplacian(*args, **kwargs):
    # the heat-kernel operator these tests are about (the default of meshes is the FEM pencil)
    return meshlap.laplacian(*args, **{"operator": "kernel", **kwargs})


def nbytes(A):
    return A.data.nbytes + A.indices.nbytes + A.indptr.nbytes


def test_guard_refuses_a_build_whose_total_exceeds_max_memory():
    # a square: mirror images (a second matrix) and point-wise rows (a third value array)
    V, F = shapes.plane(600, seed=4)
    op = kernel_laplacian(V, F)
    assert op.boundary_rows > 0 and op.L is not op.L_sym
    nnz = op.L_sym.nnz
    held = nbytes(op.L_sym) + op.L.data.nbytes  # what the operator keeps (L shares a pattern)
    guard = MemoryGuard.for_build(len(V), np.dtype(np.float64), 1, 0.1, images=True, pointwise=True)
    peak = guard.bytes_for(nnz)
    assert nbytes(op.L_sym) < held < peak  # L alone < what is kept < the peak of the build
    # 20 bytes an entry: enough for L alone and for the former count (two value arrays, one
    # pattern), not for the build's peak of 32 bytes an entry
    with pytest.raises(meshlap.OperatorTooLargeError, match="every matrix the build keeps"):
        kernel_laplacian(V, F, max_memory=int(22 * nnz))
    again = kernel_laplacian(V, F, max_memory=int(peak * 1.01))
    assert again.L_sym.nnz == nnz
    # the paper's operator holds one matrix: the same budget is plenty
    assert kernel_laplacian(V, F, h=op.h, correction="none", max_memory=int(22 * nnz)).nnz > 0


def test_guard_counts_by_build():
    g = MemoryGuard.for_build(10, np.dtype(np.float32), 1 << 30, 0.1, images=False, pointwise=False)
    assert g.bytes_for(100) == 100 * (4 + 4) + 11 * 4
    g = MemoryGuard.for_build(10, np.dtype(np.float32), 1 << 30, 0.1, images=True, pointwise=True)
    # float32 rows, the float64 work copy with images and its cast, float32 point-wise values
    assert g.values == 4 + 8 + 4 + 4 and g.patterns == 2
    g = MemoryGuard.for_build(10, np.dtype(np.float64), 1 << 30, 0.1, images=False, pointwise=True,
                              own_pattern=True)
    assert (g.values, g.patterns) == (16, 2)


def test_the_chord_count_bounds_the_arc_kernels_estimate():
    # construction estimates the arc kernel's rows from chords, without normals, where that
    # fits (arc factor >= 1: no row holds more pairs by arcs); the arc count decides otherwise
    from meshlap import assembly
    from meshlap.assembly import Kernel, variable
    from meshlap.widths import Widths

    V, F = shapes.sphere(2000, kind="random", seed=1)
    g = meshlap.geometry.from_mesh(V, F)
    h = 0.02  # wide on the unit sphere: arcs drop pairs that chords keep
    w = Widths(h, np.full(len(V), h), False)
    kern = Kernel(2, dog=True)
    grid = assembly.grid.build_grid(V, g.mass, assembly.cutoff_radius(h, kern.tol))
    chord = variable.count_entries(V, grid, w.h_vertex, kern.tol, None)
    arc = variable.count_entries(V, grid, w.h_vertex, kern.tol, g.normals())
    assert (arc <= chord).all() and (arc < chord).any()
    mean_c = assembly._sampled(V, g.mass, w, kern, None, chords=True)[4]
    arcs = Kernel(2, dog=True, normals=g.normals())
    mean_a = assembly._sampled(V, g.mass, w, arcs, None)[4]
    assert mean_a < mean_c
    asked = []

    def normals():
        asked.append(1)
        return g.normals()

    def refuse(entries):  # a budget of 12 bytes an entry (float64, int32 indices)
        guard = MemoryGuard(len(V), np.dtype(np.float64), 0, h)
        guard.max_memory = math.ceil(guard.bytes_for(entries))
        assembly.refuse_early(V, g.mass, w, kern, guard, normals)

    refuse(mean_c)  # fits by chords: no normals
    assert asked == []
    refuse(0.5 * (mean_a + mean_c))  # not by chords, by arcs: no refusal
    assert asked == [1]
    with pytest.raises(meshlap.OperatorTooLargeError, match="at least about"):
        refuse(0.5 * mean_a)
