"""Weak-scaling benchmark of meshlap.distributed (issue 14): a unit sphere with a fixed number
of points per rank and a fixed number of entries per row, on 1 and 2 MPI ranks.

    python benchmarks/bench_distributed.py             # runs mpiexec -n 1 and -n 2, updates RESULTS.md
    python benchmarks/bench_distributed.py --quick     # 5,000 points per rank, prints only
    mpiexec -n 2 python benchmarks/bench_distributed.py --rank-job 40000   # one job, JSON on stdout
    python benchmarks/bench_distributed.py --eigs 100000 --k 20 --default  # issue 38's: the kernel's defaults

The sphere has n = P · (points per rank) Fibonacci points and h = c/n, so that a row holds
the same number of entries whatever P (r² = 4h ln 1e8 and the area per point both scale as
1/n). Each rank runs one numba thread (NUMBA_NUM_THREADS=1): the ranks are the parallelism.
Per rank it records own rows, halo points (with mass, received from other ranks), stored
entries, the halo bytes of one product (8 per halo value: PETSc's ghost scatter for the
stored matrix receives the columns its rows reference, the shell receives the halo), and the
time of: the build (partition, halo, count, fill, MPIAIJ assembly), one stored product
(MatMult, best of 5 batches of 10), one matrix-free product (best of 3) and a Chebyshev heat flow, and the
rank's peak resident memory (both operators and the Python/PETSc runtime).
"""

from __future__ import annotations

import argparse
import ctypes
import json
import math
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
# h·n held fixed: r²·n/4 = 4·20·ln(1e8)/4 ≈ 370 entries per row on the unit sphere
H_TIMES_N = 20.0


def rank_job(per_rank: int) -> None:
    import scipy.sparse as sp
    from mpi4py import MPI

    import meshlap
    from meshlap import distributed
    from meshlap.assembly import grid as kernel

    comm = MPI.COMM_WORLD
    size, rank = comm.Get_size(), comm.Get_rank()
    n = per_rank * size
    h = H_TIMES_N / n
    # every rank makes its own chunk of the points; masses from the whole mesh on rank 0
    # would not be weak scaling, so each rank takes the sphere's uniform mass 4π/n
    V, _ = meshlap.shapes.sphere(n, seed=0)
    a, b = n * rank // size, n * (rank + 1) // size
    V = V[a:b]
    mass = np.full(len(V), 4 * np.pi / n)

    def timed(fn, repeat, inner=1):
        # best of `repeat` batches of `inner` back-to-back calls, per call
        best = np.inf
        for _ in range(repeat):
            comm.Barrier()
            t0 = time.perf_counter()
            for _ in range(inner):
                out = fn()
            comm.Barrier()
            best = min(best, (time.perf_counter() - t0) / inner)
        return best, out

    def local_best(fn, repeat):
        best = np.inf
        for _ in range(repeat):
            t0 = time.perf_counter()
            fn()
            best = min(best, time.perf_counter() - t0)
        return best

    # warm the compiled code and PETSc on a small problem so that the memory and time below
    # are the operator's, not the first call's
    distributed.laplacian(V[:200], mass=mass[:200], correction="none", h=h, comm=comm, scattered=True)
    rss0 = _rss_now()
    t_build, op = timed(lambda: distributed.laplacian(V, mass=mass, correction="none", h=h, comm=comm,
                                                        scattered=True), 1)
    build_peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 - rss0
    # glibc keeps the build's freed temporaries for reuse; hand them back to see what stays
    ctypes.CDLL("libc.so.6").malloc_trim(0)
    kept = _rss_now() - rss0
    rss1 = _rss_now()
    t_free_build, free = timed(lambda: distributed.laplacian(V, mass=mass, correction="none", h=h, comm=comm,
                                                             scattered=True, matrix_free=True), 1)
    ctypes.CDLL("libc.so.6").malloc_trim(0)
    free_kept = _rss_now() - rss1
    x, y = op.L.createVecs()
    x.setArray(op.V[:, 0].copy())
    t_mult, _ = timed(lambda: op.L.mult(x, y), 5, 10)
    xf, yf = free.L.createVecs()
    xf.setArray(free.V[:, 0].copy())
    t_free, _ = timed(lambda: free.L.mult(xf, yf), 3)
    err = np.abs(y.getArray() + 2 * op.V[:, 0]).max()
    # the same products' local work alone (no communication, no waiting for the other rank)
    indptr, cols, vals = op.L.getValuesCSR()
    used, local_cols = np.unique(cols, return_inverse=True)
    A = sp.csr_matrix((vals, local_cols, indptr), shape=(op.n_local, len(used)))
    xl = np.random.default_rng(0).standard_normal(len(used))
    t_mult_local = local_best(lambda: A @ xl, 10)
    fl = np.random.default_rng(0).standard_normal(len(free._Vloc))
    t_free_local = local_best(lambda: kernel.apply(free._Vloc, free._grid, h, fl, rows=free._rows), 3)
    t_heat, _ = timed(lambda: distributed.heat_flow(op, op.V[:, 2], 0.05), 1)
    # the columns PETSc's ghost scatter fetches: the off-process block's columns
    ghosts = _ghost_count(op)
    info = {
        "rank": rank, "ranks": size, "n": n, "h": h, "rows": op.n_local, "halo": op.n_halo,
        "ghosts": ghosts, "nnz": int(op._counts.sum()), "t_build": t_build,
        "t_free_build": t_free_build, "t_mult": t_mult, "t_free": t_free, "t_heat": t_heat,
        "t_mult_local": t_mult_local, "t_free_local": t_free_local,
        "lap_err": float(err),
        "rss": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024,
        "build_peak": build_peak, "kept": kept, "free_kept": free_kept,
    }
    rows = comm.gather(info)
    if rank == 0:
        print(json.dumps(rows))


def _rss_now() -> int:
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def _ghost_count(op) -> int:
    # distinct off-rank columns of the own rows: what MatMult's scatter receives
    indptr, cols, _ = op.L.getValuesCSR()
    lo, hi = op.offset, op.offset + op.n_local
    return int(np.unique(cols[(cols < lo) | (cols >= hi)]).size)


def run(ranks: int, per_rank: int) -> list[dict]:
    env = dict(os.environ, NUMBA_NUM_THREADS="1", OMP_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1",
               OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    cmd = ["mpiexec", "--oversubscribe", "-n", str(ranks), sys.executable, __file__, "--rank-job",
           str(per_rank)]
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def table(results: list[list[dict]]) -> list[str]:
    lines = ["| ranks | points | rank | own rows | halo points | entries | halo bytes / product | "
             "build | stored product (local work) | matrix-free product (local work) | heat flow t=0.05 | "
             "peak RSS |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for res in results:
        for r in res:
            lines.append(
                f"| {r['ranks']} | {r['n']:,} | {r['rank']} | {r['rows']:,} | {r['halo']:,} | "
                f"{r['nnz'] / 1e6:.1f} M | {8 * r['ghosts'] / 1024:.0f} KiB | {r['t_build']:.2f} s | "
                f"{1e3 * r['t_mult']:.1f} ms ({1e3 * r['t_mult_local']:.1f} ms) | "
                f"{1e3 * r['t_free']:.0f} ms ({1e3 * r['t_free_local']:.0f} ms) | {r['t_heat']:.2f} s | "
                f"{r['rss'] / 2**20:.0f} MiB |")
    return lines


# the nodes of the projection (docs/distributed.md): memory for the operator, cores, memory
# bandwidth and link speed
NODE_MEMORY, NODE_CORES, NODE_BANDWIDTH, LINK = 200e9, 64, 200e9, 12.5e9


def projection(one: dict) -> list[str]:
    """The measured per-entry and per-point costs of the 1-rank run, scaled to 10⁸ and 10⁹."""
    E = one["nnz"] / one["rows"]
    held, peak = one["kept"] / one["nnz"], one["build_peak"] / one["nnz"]
    free_point = one["free_kept"] / one["rows"]
    free_ns, build_ns = one["t_free_local"] / one["nnz"], one["t_build"] / one["nnz"]
    lines = [f"Projection (E = {E:.0f} entries per row; per entry {held:.1f} B held, {peak:.1f} B at the "
             f"build's peak, build {1e9 * build_ns:.0f} ns and matrix-free product {1e9 * free_ns:.1f} ns "
             f"per core; matrix-free {free_point:.0f} B per point; nodes with {NODE_MEMORY / 1e9:.0f} GB "
             f"for the operator, {NODE_CORES} cores, {NODE_BANDWIDTH / 1e9:.0f} GB/s, "
             f"{LINK * 8 / 1e9:.0f} Gbit/s links):", "",
             "| points | stored entries | stored bytes | nodes (build peak) | points per rank | "
             "halo per rank | halo per node, time on the link | stored product (bandwidth) | build | "
             "matrix-free: memory, product on the same nodes |", "|---|---|---|---|---|---|---|---|---|---|"]
    for n in (1e8, 1e9):
        entries = n * E
        nodes = math.ceil(entries * peak / NODE_MEMORY)
        p = n / (nodes * NODE_CORES)
        halo = 4 * math.sqrt(E * p / math.pi)
        halo_node = 4 * math.sqrt(E * n / nodes / math.pi)
        t_stored = entries / nodes * held / NODE_BANDWIDTH
        t_build = entries * build_ns / (nodes * NODE_CORES)
        t_free = entries * free_ns / (nodes * NODE_CORES)
        lines.append(
            f"| 10^{round(math.log10(n))} | {entries:.2g} | {entries * held / 1e12:.2f} TB | {nodes} | "
            f"{p:,.0f} | {halo:,.0f} points, {8 * halo / 1e3:.0f} KB | {halo_node:,.0f} points, "
            f"{8 * halo_node / LINK * 1e3:.2f} ms | {t_stored:.2f} s | {t_build:.0f} s | "
            f"{n * free_point / 1e9:.0f} GB, {t_free:.1f} s |")
    return lines


# -- the distributed eigensolver (issue 19) --------------------------------------------------
def _eigs_mesh(n: int):
    import meshlap

    return meshlap.shapes.sphere(n, kind="random", seed=0)


def eigs_job(n: int, k: int, serial: bool, matrix_free: bool, h_edges: float | None,
             default: bool = False) -> None:
    """One eigensolver run on a random n-vertex sphere, JSON on stdout: ``spectral.eigs`` on the
    single-machine operator (``serial``), or the distributed LOBPCG on all ranks of COMM_WORLD;
    stored or ``matrix_free``; at the paper's default h, or h = h_edges · ē² (ē the mean edge).
    ``default``: the kernel with every argument left to its defaults (``operator="kernel"`` on
    the single machine: what ``distributed.laplacian`` builds), and ``distributed.eigs(op, k)`` as
    a user calls it (issue 38)."""
    import igl

    import meshlap

    V, F = _eigs_mesh(n)
    kw = {} if default else {"correction": "none", "matrix_free": matrix_free}
    # the kernel, as distributed.laplacian builds it (the default's FEM pencil is not distributed)
    serial_kw = {"operator": "kernel"} if default else {}
    if h_edges is not None:
        kw["h"] = h_edges * float(igl.edge_lengths(V, F).mean()) ** 2
    t0 = time.perf_counter()
    if serial:
        from meshlap import spectral

        op = meshlap.laplacian(V, F, **kw, **serial_kw)
        nnz, rank, size = op.nnz, 0, 0  # 0 when matrix-free
    else:
        from mpi4py import MPI

        from meshlap import distributed
        from meshlap.distributed import lobpcg as distributed_eigs

        comm = MPI.COMM_WORLD
        op = distributed.laplacian(V, F, comm=comm, **kw)
        nnz = comm.allreduce(int(op._counts.sum()), op=MPI.SUM)
        rank, size = comm.Get_rank(), comm.Get_size()
        comm.Barrier()
    t1 = time.perf_counter()
    info: dict = {}
    if serial:
        lam, _ = spectral.eigs(op, k, info=info)
    elif default:
        lam, _ = distributed.eigs(op, k, info=info)
        comm.Barrier()
    else:
        lam, _ = distributed_eigs.eigs(op, k, mesh=(V, F), info=info)
        comm.Barrier()
    t2 = time.perf_counter()
    row = {"n": n, "k": k, "ranks": size, "rank": rank, "h": float(op.h), "nnz": int(nnz), "t_build": t1 - t0,
           "t_eigs": t2 - t1, "iterations": info.get("iterations"), "block": info.get("block"),
           "method": info.get("method"), "check": info.get("check_seconds"),
           "lam": [float(x) for x in lam],
           "rss": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024}
    rows = [row] if serial else comm.gather(row)
    if rank == 0:
        print(json.dumps(rows))


def run_eigs(n: int, k: int, ranks: int, matrix_free: bool = False,
             h_edges: float | None = None, default: bool = False) -> list[dict]:
    """``eigs_job`` in a subprocess: ranks = 0 for the single machine (numba on every core),
    else mpiexec with one numba thread per rank."""
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    job = [sys.executable, __file__, "--eigs-job", str(n), str(k)]
    job += ["--matrix-free"] if matrix_free else []
    job += ["--default"] if default else []
    job += ["--h-edges", str(h_edges)] if h_edges is not None else []
    if ranks == 0:
        cmd = [*job, "--serial"]
    else:
        env.update(NUMBA_NUM_THREADS="1", OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
        cmd = ["mpiexec", "--oversubscribe", "-n", str(ranks), *job]
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def eigs_section(n: int, k: int, matrix_free: bool = False, h_edges: float | None = None,
                 ranks: tuple[int, ...] = (0, 1, 2), default: bool = False) -> list[str]:
    """Single machine, 1 and 2 ranks on the same operator: the table and the cost per iteration."""
    uptime = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    runs = {r: run_eigs(n, k, r, matrix_free, h_edges, default) for r in ranks}
    uptime_after = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    lam0 = np.array(runs[0][0]["lam"])
    scale = np.maximum(np.abs(lam0), lam0[1])
    one, nnz = runs[0][0], runs[2][0]["nnz"]
    flag, kind = (" --matrix-free", "matrix-free ") if matrix_free else ("", "")
    flag += f" --h-edges {h_edges:g}" if h_edges is not None else ""
    width = "default h" if h_edges is None else f"h = {h_edges:g} ē²"
    what = (f"the paper's {kind}operator (`correction=\"none\"`, {width} = {one['h']:.3g})" if not default
            else f"the kernel with its defaults (`meshlap.laplacian(V, F, operator=\"kernel\")` and "
            f"`distributed.laplacian(V, F)`, h = {one['h']:.3g})")
    call = ("`distributed.eigs(op, k)` with every default (the mesh the operator was built from)" if default
            else "`distributed.lobpcg.eigs(op, k, mesh=(V, F))`")
    flag += " --default" if default else ""
    lines = [f"`python benchmarks/bench_distributed.py --eigs {n} --k {k}{flag}`: {k} eigenpairs of "
             f"{what} on a random {n:,}-vertex unit sphere, {nnz / n:.0f} entries per row "
             f"({nnz / 1e6:.0f} M). "
             f"Single machine: `spectral.eigs` with numba on both cores; distributed: {call}, one numba "
             "thread per rank. Every run's pairs verified (issue 38); the method whose pairs were "
             "returned and the check's time in the last columns.", "",
             f"Load: before `{uptime}`; after `{uptime_after}`.", "",
             "| run | rank | build | eigs | iterations | eigs per iteration | max rel. eigenvalue diff "
             "vs single machine | peak RSS | returned by | check |", "|---" * 10 + "|"]
    for r, res in runs.items():
        for row in res:
            err = float((np.abs(np.array(row["lam"]) - lam0) / scale).max())
            it = row["iterations"]
            per = f"{row['t_eigs'] / it:.2f} s" if it else "–"
            name = "single machine" if r == 0 else f"{r} rank" + ("s" if r > 1 else "")
            check = f"{row['check']:.2f} s" if row.get("check") is not None else "–"
            lines.append(f"| {name} | {row['rank'] if r else '–'} | {row['t_build']:.1f} s | "
                         f"{row['t_eigs']:.1f} s | {it or '–'} | {per} | {err:.1e} | "
                         f"{row['rss'] / 2**30:.2f} GiB | {row.get('method') or '–'} | {check} |")
    t0, t2 = one["t_eigs"], max(row["t_eigs"] for row in runs[2])
    it2 = runs[2][0]["iterations"]
    cost = t2 / it2 / (nnz / 2)
    one_rank = f"; 1 rank / single machine: {runs[1][0]['t_eigs'] / t0:.2f}×" if 1 in runs else ""
    lines += ["", f"2 ranks / single machine: {t2 / t0:.2f}×{one_rank}. Cost per iteration on 2 ranks "
              f"(eigs time, start included, over the iterations): {t2 / it2:.2f} s, "
              f"{1e9 * cost:.1f} ns per entry of a rank's rows, "
              f"for a block of {runs[2][0]['block']} vectors."]
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--per-rank", type=int, default=40_000)
    ap.add_argument("--rank-job", type=int)
    ap.add_argument("--eigs", type=int, help="eigensolver benchmark on a random sphere of this size")
    ap.add_argument("--k", type=int, default=50)
    ap.add_argument("--eigs-job", type=int, nargs=2)
    ap.add_argument("--serial", action="store_true")
    ap.add_argument("--matrix-free", action="store_true")
    ap.add_argument("--runs", type=int, nargs="+", default=[0, 1, 2],
                    help="with --eigs: the runs, 0 = single machine (always), else ranks")
    ap.add_argument("--h-edges", type=float,
                    help="h = this times the squared mean edge (default: the paper's h)")
    ap.add_argument("--default", action="store_true",
                    help="with --eigs: the kernel's defaults and distributed.eigs(op, k) (issue 38)")
    args = ap.parse_args()
    if args.rank_job:
        rank_job(args.rank_job)
        return
    if args.eigs_job:
        eigs_job(*args.eigs_job, serial=args.serial, matrix_free=args.matrix_free, h_edges=args.h_edges,
                 default=args.default)
        return
    if args.eigs:
        lines = eigs_section(args.eigs, args.k, args.matrix_free, args.h_edges,
                             tuple(sorted({0, 2, *args.runs})), args.default)
        print("\n".join(lines))
        if not args.quick:
            sys.path.insert(0, str(HERE))
            from results_file import write_section

            title = "Distributed eigensolver" + (" (the kernel's defaults)" if args.default else "")
            write_section(title + (f", {args.eigs:,} points" if args.eigs >= 1_000_000 else ""), lines)
        return
    per_rank = 5_000 if args.quick else args.per_rank
    run(1, 2000)  # warm numba's cache before timing anything
    uptime = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    results = [run(p, per_rank) for p in (1, 2)]
    uptime_after = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    one, two = results
    eff_mult = one[0]["t_mult"] / max(r["t_mult"] for r in two)
    eff_free = one[0]["t_free"] / max(r["t_free"] for r in two)
    eff_build = one[0]["t_build"] / max(r["t_build"] for r in two)
    eff_mult_local = one[0]["t_mult_local"] / max(r["t_mult_local"] for r in two)
    eff_free_local = one[0]["t_free_local"] / max(r["t_free_local"] for r in two)
    lines = [
        f"`python benchmarks/bench_distributed.py` (per rank {per_rank:,} points, h = {H_TIMES_N:g}/n, "
        "one numba thread per rank, Open MPI 4.1 / PETSc 3.18 from Debian).",
        "",
        f"Load: before `{uptime}`; after `{uptime_after}`. The machine has 2 cores, shared with other "
        "jobs, so 2 ranks compete with them; the ratios are what count.",
        "",
        *table(results),
        "",
        f"Weak-scaling efficiency (1-rank time / slowest of 2 ranks, ideal 1.0): build {eff_build:.2f}, "
        f"stored product {eff_mult:.2f} (local work {eff_mult_local:.2f}), matrix-free product "
        f"{eff_free:.2f} (local work {eff_free_local:.2f}). The local work is the product without its "
        "halo exchange (scipy CSR on the rank's rows for the stored matrix, the compiled kernel for "
        "the shell); the gap to the full product is the exchange plus waiting for a rank that the "
        "busy machine has descheduled. "
        f"max |L x + 2x| = {max(r['lap_err'] for res in results for r in res):.3f} "
        "(truncation and O(h) bias).",
        "",
        f"Per stored entry and core (1 rank): build {1e9 * one[0]['t_build'] / one[0]['nnz']:.0f} ns, "
        f"stored product {1e9 * one[0]['t_mult_local'] / one[0]['nnz']:.2f} ns, matrix-free product "
        f"{1e9 * one[0]['t_free_local'] / one[0]['nnz']:.1f} ns. Memory of the stored build per entry "
        f"(resident over the process before it): {one[0]['kept'] / one[0]['nnz']:.1f} B held "
        f"after the build (after malloc_trim), {one[0]['build_peak'] / one[0]['nnz']:.1f} B at its peak; "
        f"the matrix-free operator holds {one[0]['free_kept'] / one[0]['rows']:.0f} B per point.",
    ]
    lines += ["", *projection(one[0])]
    print("\n".join(lines))
    if not args.quick:
        sys.path.insert(0, str(HERE))
        from results_file import write_section

        write_section("Distributed (MPI) weak scaling", lines)


if __name__ == "__main__":
    main()
