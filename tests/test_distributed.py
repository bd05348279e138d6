"""meshlap.distributed under mpiexec: exact equality with the single-machine matrix, products,
heat flow, implicit steps and eigenpairs on 2 and 3 ranks.

The checks themselves live in tests/distributed_worker.py, run by `mpiexec --oversubscribe`
as a subprocess (one MPI job per test); they are skipped, with the reason, only where
mpiexec, mpi4py, petsc4py or slepc4py are missing (install: .ci/install-mpi).
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).parent
MISSING = [m for m in ("mpi4py", "petsc4py", "slepc4py") if importlib.util.find_spec(m) is None]
MPIEXEC = shutil.which("mpiexec")
needs_mpi = pytest.mark.skipif(
    bool(MISSING) or MPIEXEC is None,
    reason=f"MPI stack absent ({', '.join(MISSING + ([] if MPIEXEC else ['mpiexec']))}); "
    "install it with .ci/install-mpi",
)


def mpirun(n: int, *checks: str, timeout: float = 600) -> list[str]:
    """Run the named worker checks on n ranks; return rank 0's "ok" lines."""
    env = dict(os.environ)
    # one numba thread per rank (the ranks share the cores), and Open MPI as root in CI
    env.update(NUMBA_NUM_THREADS="1", OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1",
               OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    cmd = [MPIEXEC, "--oversubscribe", "-n", str(n), sys.executable, str(HERE / "distributed_worker.py"),
           *checks]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env, cwd=HERE.parent)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, f"mpiexec -n {n} {' '.join(checks)} failed:\n{out[-6000:]}"
    ok = [line for line in proc.stdout.splitlines() if line.startswith("ok ")]
    assert [line.split(":")[0][3:] for line in ok] == list(checks), out[-6000:]
    for line in ok:
        print(f"[{n} ranks] {line}")
    return ok


@needs_mpi
@pytest.mark.parametrize("n", [2, 3])
def test_matrix_equals_serial_exactly(n):
    """Gathered MPIAIJ == meshlap.laplacian(...).L bit for bit: a k-d split, slabs r/3 wide with
    one rank empty, and a lattice of spacing exactly r handed in by rank 0 alone."""
    mpirun(n, "exact", "thin", "r_apart", "balance", "saved")


@needs_mpi
@pytest.mark.parametrize("n", [2, 3])
def test_corrected_default_equals_serial(n):
    """The single machine's default (Richardson kernel, curvature-capped widths, arc distances,
    mirror images, moment scale, fitted point-wise rows) on n ranks: gathered matrices to 1e-12
    relative, eigenvalues to 1e-10, for a mesh with boundary and a point cloud; and from scattered
    input (chunks of points, shares of the faces) by global reductions; a mesh of two parts with
    no pairs between them, whole and as a scattered triangle soup (copies welded across ranks)."""
    mpirun(n, "corrected_plane", "corrected_cloud", "corrected_scattered", "corrected_parts",
           "scattered_parts")


@needs_mpi
def test_fitted_rows_on_noisy_input_equal_serial():
    """The default's fitted rows on 2 ranks where the data are noisy (a mesh, a denoised cloud):
    the single machine's rows entry for entry."""
    mpirun(2, "fitted_noisy")


@needs_mpi
@pytest.mark.parametrize("n", [2, 3])
def test_fitted_rows_on_coincident_copies_equal_serial(n):
    """An exporter's latitude-longitude sphere (poles repeated per column, copies without mass
    owned by other ranks): the fitted rows on distinct points, entry for entry as the single
    machine's; before, every rank raised "h must be finite and positive"."""
    mpirun(n, "copies")


@needs_mpi
def test_fixed_degree_rows_equal_serial():
    """pointwise_degree=4 on 2 ranks: the single machine's rows of degree 4 on the kernel's
    stencil (a plane with boundary, a sphere), entry for entry."""
    mpirun(2, "fixed_degree")


@needs_mpi
def test_example_job():
    """examples/distributed_job.py, the whole job, on 2 ranks (stored and matrix-free)."""
    env = dict(os.environ, NUMBA_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1",
               OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    for extra in ([], ["--matrix-free"]):
        cmd = [MPIEXEC, "--oversubscribe", "-n", "2", sys.executable,
               str(HERE.parent / "examples" / "distributed_job.py"), "3000", *extra]
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600, env=env)
        assert proc.returncode == 0, proc.stdout + proc.stderr
        assert "heat flow t = 0.25" in proc.stdout
        assert ("first 9 eigenvalues" in proc.stdout) != bool(extra)


@needs_mpi
def test_products_heat_and_curvature():
    """Apply, Chebyshev heat flow and mean curvature to 1e-12 of the serial code; the matrix-free
    shell to 1e-12 of the stored matrix; backward Euler (PETSc CG) to 1e-8."""
    mpirun(2, "apply", "implicit")


@needs_mpi
def test_eigenpairs_small():
    """SLEPc eigenvalues of a 2,500-vertex sphere to 1e-8 of spectral.eigs; two copies of a
    sphere, whose doubled eigenvalues a single Krylov–Schur run skipped, to 1e-9 of dense."""
    mpirun(3, "eigs_small")
    mpirun(2, "eigs_copies")  # 2 ranks: where one run skipped a copy (3 ranks did not)


@needs_mpi
@pytest.mark.parametrize("n", [2, 3])
def test_lobpcg_matches_serial(n):
    """meshlap.distributed.lobpcg (no factorization) against spectral.eigs on the gathered
    matrix: a mesh with boundary, a matrix-free point cloud, a mesh with 208 zero-mass
    vertices; eigenvalues to 1e-8 relative, their error bound recomputed from the residuals."""
    mpirun(n, "lobpcg_plane", "lobpcg_cloud", "lobpcg_zero_mass")


@needs_mpi
@pytest.mark.parametrize("n", [2, 3])
def test_lobpcg_pairs_are_verified(n):
    """Issue 38: pairs that fail the check are recomputed (the gathered solve) or raise
    meshlap.EigenError on every rank; never returned."""
    mpirun(n, "lobpcg_verified")


@needs_mpi
@pytest.mark.parametrize("n", [2, 3])
def test_lobpcg_global_preconditioner_iterations(n):
    """The global (MUMPS) cotangent preconditioner: on n ranks at most the 1-rank iteration
    count + 1 (8,000-vertex sphere, k = 20), fewer than block Jacobi's, the smoothed start in at
    most 4 iterations; without MUMPS, or when
    its factorization fails, block Jacobi with the same eigenvalues (a failure warns)."""
    mpirun(n, "lobpcg_global_iterations", "lobpcg_fallback")


@needs_mpi
def test_lobpcg_clear_errors():
    from mpi4py import MPI

    import meshlap
    from meshlap import distributed
    from meshlap.distributed import lobpcg as distributed_eigs

    V, F = meshlap.shapes.sphere(300, seed=0)
    op = distributed.laplacian(V, F, h=0.02, comm=MPI.COMM_SELF)  # the default
    with pytest.raises(meshlap.MeshError, match="mesh has 10 vertices"):
        distributed_eigs.eigs(op, 4, mesh=(V[:10], F))
    with pytest.raises(meshlap.MeshError, match="mesh must be"):
        distributed_eigs.eigs(op, 4, mesh=V)
    with pytest.raises(meshlap.MeshError, match="tol"):
        distributed_eigs.eigs(op, 4, tol=2.0)
    with pytest.raises(meshlap.MeshError, match="maxiter must be a positive integer"):
        distributed_eigs.eigs(op, 4, maxiter=0)
    with pytest.raises(meshlap.MeshError, match="preconditioner"):
        distributed_eigs.eigs(op, 4, mesh=(V, F), preconditioner="jacobi")
    with pytest.raises(meshlap.MeshError, match="method"):
        distributed.eigs(op, 4, method="krylov")
    with pytest.raises(meshlap.MeshError, match="shift-invert"):
        distributed.eigs(op, 4, blr=1e-10)
    with pytest.raises(meshlap.MeshError, match="preconditioner"):  # passed through to LOBPCG
        distributed.eigs(op, 4, mesh=(V, F), preconditioner="jacobi")
    with pytest.raises(meshlap.MeshError, match="LOBPCG's"):
        distributed.eigs(op, 4, method="shift-invert", preconditioner="local")
    zero = distributed.laplacian(V, mass=np.where(np.arange(300) < 3, 1.0, 0.0), correction="none", h=0.02,
                                 comm=MPI.COMM_SELF)
    with pytest.raises(meshlap.MeshError, match="k"):
        distributed_eigs.eigs(zero, 4)


@needs_mpi
@pytest.mark.slow
def test_eigenpairs_with_zero_mass_vertices():
    """First 20 eigenvalues of spot with 300 zero-mass vertices to 1e-8 relative of
    spectral.eigs, on 2 ranks; the matrix bit for bit."""
    mpirun(2, "eigs_spot")


@needs_mpi
def test_global_grid_matches_kernel():
    """The distributed visiting order rests on reproducing kernel.build_grid's lo/cell/dims."""
    from mpi4py import MPI

    from meshlap import distributed
    from meshlap.assembly import grid as kernel

    rng = np.random.default_rng(0)
    for n, radius in [(50, 0.3), (2000, 0.01), (10, 1e-6), (300, np.inf)]:
        V = rng.standard_normal((n, 3))
        mass = rng.random(n) * (rng.random(n) > 0.2)
        g = kernel.build_grid(V, mass, radius)
        lo, cell, dims = distributed.comm._global_grid(MPI.COMM_SELF, V, mass, radius)
        assert np.array_equal(lo, g.lo) and cell == g.cell and np.array_equal(dims, g.dims)


@needs_mpi
def test_clear_errors():
    from mpi4py import MPI

    import meshlap
    from meshlap import distributed

    V, F = meshlap.shapes.sphere(100, seed=0)
    with pytest.raises(meshlap.MeshError, match="pass F"):
        distributed.laplacian(V, correction="none", h=0.01, comm=MPI.COMM_SELF)
    with pytest.raises(meshlap.MeshError, match="h is required"):
        distributed.laplacian(V, mass=np.ones(100), correction="none", comm=MPI.COMM_SELF)
    with pytest.raises(meshlap.MeshError, match="zero mass"):
        distributed.laplacian(V, mass=np.zeros(100), correction="none", h=0.01, comm=MPI.COMM_SELF)
    with pytest.raises(meshlap.MeshError, match="partition"):
        distributed.laplacian(V, F, correction="none", h=0.01, comm=MPI.COMM_SELF, partition=np.full(100, 3))
    # meshlap.laplacian's names: "paper" is correction="none", the single-machine pencils are named
    paper = distributed.laplacian(V, F, operator="paper", h=0.01, comm=MPI.COMM_SELF).to_scipy()
    none = distributed.laplacian(V, F, correction="none", h=0.01, comm=MPI.COMM_SELF).to_scipy()
    assert (paper != none).nnz == 0
    with pytest.raises(meshlap.MeshError, match="single-machine"):
        distributed.laplacian(V, F, operator="fem", comm=MPI.COMM_SELF)


def test_rest_of_meshlap_never_imports_it():
    code = ("import sys, meshlap, meshlap.cli, meshlap.heat, meshlap.spectral; "
            "mods = ('meshlap.distributed', 'mpi4py', 'petsc4py', 'slepc4py'); "
            "bad = [m for m in mods if m in sys.modules]; assert not bad, bad")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=HERE.parent)


def test_missing_stack_names_the_install(monkeypatch):
    from meshlap import distributed

    monkeypatch.setitem(sys.modules, "petsc4py", None)  # import fails as if absent
    with pytest.raises(ImportError, match="install-mpi"):
        distributed.laplacian(np.zeros((3, 3)), mass=np.ones(3), correction="none", h=0.1)


def test_mpi4py_without_an_mpi_library_names_the_install(monkeypatch):
    """mpi4py 4 from PyPI imports on a machine without MPI and raises RuntimeError when MPI is
    first touched: that is a missing install too, not a crash inside mpi4py."""
    import types

    from meshlap import distributed

    fake = types.ModuleType("mpi4py")

    def no_library(name):
        raise RuntimeError("cannot load MPI library\nlibmpi.so: cannot open shared object file")

    fake.__getattr__ = no_library
    monkeypatch.setitem(sys.modules, "mpi4py", fake)
    monkeypatch.delitem(sys.modules, "mpi4py.MPI", raising=False)
    with pytest.raises(ImportError, match="no MPI library.*cannot load MPI library.*install-mpi"):
        distributed.laplacian(np.zeros((3, 3)), mass=np.ones(3), correction="none", h=0.1)


def test_kernel_row_subsets_match_full_build():
    """kernel.fill_csr(rows=...) and kernel.apply(rows=...), which each rank uses for its own
    rows, give exactly the full build's rows."""
    from meshlap import shapes
    from meshlap.assembly import grid as kernel

    V, _ = shapes.sphere(800, seed=0)
    mass = np.random.default_rng(0).random(len(V)) * (np.arange(len(V)) % 7 > 0)
    h = 0.01
    grid = kernel.build_grid(V, mass, kernel.cutoff_radius(h, 1e-8))
    counts = kernel.count_entries(V, grid)
    indptr = np.concatenate([[0], np.cumsum(counts)])
    ind, dat = kernel.fill_csr(V, grid, h, indptr, np.int64, np.float64)
    rows = np.arange(0, len(V), 3)
    sub = np.zeros(len(V), np.int64)
    sub[rows] = kernel.count_entries(V, grid, rows=rows)
    sub_ptr = np.concatenate([[0], np.cumsum(sub)])
    ind_s, dat_s = kernel.fill_csr(V, grid, h, sub_ptr, np.int64, np.float64, rows=rows)
    for w in rows:
        a, b = slice(indptr[w], indptr[w + 1]), slice(sub_ptr[w], sub_ptr[w + 1])
        assert np.array_equal(ind[a], ind_s[b]) and np.array_equal(dat[a], dat_s[b])
    f = np.column_stack([V[:, 0], np.sin(3 * V[:, 1])])
    assert np.array_equal(kernel.apply(V, grid, h, f, rows=rows)[rows], kernel.apply(V, grid, h, f)[rows])


@needs_mpi
def test_progress_of_distributed_build_and_eigs():
    from mpi4py import MPI

    import meshlap
    from meshlap import distributed

    V, F = meshlap.shapes.sphere(1500, seed=0)
    seen = []
    op = distributed.laplacian(V, F, comm=MPI.COMM_SELF, progress=lambda f, s: seen.append((f, s)))
    stages = [s for _, s in seen]
    assert stages == ["partition", "kernel rows", "kernel rows", "semidefinite check", "moment scale",
                      "point-wise rows", "PETSc matrices", "done"], stages
    assert [f for f, _ in seen] == sorted(f for f, _ in seen)
    seen.clear()
    lam, _ = distributed.eigs(op, 6, mesh=(V, F), progress=lambda f, s: seen.append((f, s)))
    names = [s.split(" (")[0] for _, s in seen]
    assert names[0] == "preconditioner" and names[-1] == "done" and "LOBPCG" in names
    assert [f for f, _ in seen] == sorted(f for f, _ in seen) and seen[-1][0] == 1.0
    seen.clear()  # LOBPCG given 3 iterations fails its check: the next solver's stages go on from there
    info = {}
    distributed.eigs(op, 6, mesh=(V, F), maxiter=3, info=info, progress=lambda f, s: seen.append((f, s)))
    assert len(info["tried"]) > 1, info["tried"]
    assert [f for f, _ in seen] == sorted(f for f, _ in seen) and seen[-1][0] == 1.0
