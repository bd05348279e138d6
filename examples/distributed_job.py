"""The whole distributed job: build the operator over MPI ranks, apply it, run heat flow,
mean curvature and the first eigenpairs, and check them against the unit sphere's truth.

    OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 \\
        mpiexec --oversubscribe -n 2 python examples/distributed_job.py [n_points] [--matrix-free]

Rank 0 makes (or would read) the mesh and computes the masses; it hands the points to the
operator alone (``scattered=True``, the other ranks pass nothing), and the k-d split moves
them to their owners. For inputs too large for one rank, each rank passes its own chunk of
points and masses instead. Results stay distributed; rank 0 gathers only what it prints.
"""

from __future__ import annotations

import sys
import time

import numpy as np
from mpi4py import MPI

import meshlap
from meshlap import distributed
from meshlap.spectral import sphere_eigenvalue


def main(argv: list[str]) -> None:
    comm = MPI.COMM_WORLD
    rank = comm.Get_rank()
    n = int(next((a for a in argv if a.isdigit()), 8000))
    matrix_free = "--matrix-free" in argv

    h = None
    if rank == 0:
        V, F = meshlap.shapes.sphere(n, seed=0)
        mass = meshlap.vertex_mass(V, F)
        h = meshlap.default_h(V, F)             # (2·mean edge)², as the serial build
    else:
        V, mass = np.zeros((0, 3)), np.zeros(0)
    h = comm.bcast(h, root=0)

    t0 = time.perf_counter()
    op = distributed.laplacian(V, mass=mass, correction="none", h=h, comm=comm, scattered=True,
                               matrix_free=matrix_free)
    t_build = time.perf_counter() - t0
    rows = comm.gather((op.n_local, op.n_halo))
    if rank == 0:
        print(op)
        print(f"built in {t_build:.2f} s; (own rows, halo points) per rank: {rows}")

    # on the unit sphere Δx = -2x and H·n = x (H = 1): mean curvature from L applied to X
    X = op.V                                    # own points, in the operator's order
    area = comm.allreduce(float(op.mass.sum()), op=MPI.SUM)

    def rms(E):  # the area-weighted root mean square over all ranks' points
        return np.sqrt(comm.allreduce(float(op.mass @ (E * E).sum(axis=1)), op=MPI.SUM) / area)

    err_lap = rms(op.apply(X) + 2 * X)
    err_h = rms(distributed.mean_curvature_normal(op) - X)

    # heat flow: z is a degree-1 harmonic, exp(tL) z ≈ exp(-2t) z (the continuous
    # operator's eigenvalue at this h is 2 up to e^{-1/h})
    t = 0.25
    u = distributed.heat_flow(op, X[:, 2], t)
    num = comm.allreduce(float(u @ (op.mass * X[:, 2])), op=MPI.SUM)
    den = comm.allreduce(float(X[:, 2] @ (op.mass * X[:, 2])), op=MPI.SUM)
    # one backward-Euler step of τ: 1 / (1 + 2τ) on the same harmonic
    v = distributed.implicit_heat(op, X[:, 2], tau=t, pc="jacobi" if matrix_free else "gamg")
    num_v = comm.allreduce(float(v @ (op.mass * X[:, 2])), op=MPI.SUM)
    if rank == 0:
        print(f"RMS of L x + 2x: {err_lap:.4f}; of H n - x: {err_h:.4f}")
        print(f"heat flow t = {t}: decay {num / den:.5f} (exp(-2t) = {np.exp(-2 * t):.5f}); "
              f"backward Euler {num_v / den:.5f} (1/(1+2t) = {1 / (1 + 2 * t):.5f})")
        assert err_lap < 0.05 and err_h < 0.025
        assert abs(num / den - np.exp(-2 * t)) < 2e-3 and abs(num_v / den - 1 / (1 + 2 * t)) < 2e-3

    if not matrix_free:
        lam, phi = distributed.eigs(op, 9)
        if rank == 0:
            # the continuous heat-kernel operator's eigenvalues at this h (l(l+1) minus the O(h) bias)
            exact = np.repeat([sphere_eigenvalue(l, h) for l in range(3)], [1, 3, 5])  # noqa: E741
            print("first 9 eigenvalues:", np.round(lam, 4), "| continuous operator:", np.round(exact, 4))
            assert np.abs(lam - exact).max() < 0.05
        full = op.gather(phi[:, 1], root=0)     # one eigenvector, on rank 0 only
        if rank == 0:
            print(f"gathered eigenvector 1: {full.shape[0]:,} values")


if __name__ == "__main__":
    try:
        main(sys.argv[1:])
    except BaseException:
        # one failing rank must not leave the others waiting in a collective
        import traceback

        traceback.print_exc()
        MPI.COMM_WORLD.Abort(1)
