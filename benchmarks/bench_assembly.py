"""Assembly benchmark (issue 5): build time, memory and application of the Belkin–Sun–Wang
operator, against the straightforward scipy build and one product with the finished matrix.

    python benchmarks/bench_assembly.py            # full run, updates benchmarks/RESULTS.md
    python benchmarks/bench_assembly.py --quick    # small meshes only, prints, writes nothing
    python benchmarks/bench_assembly.py --default-vs-paper   # the default / the paper's, per use (issue 19)

Meshes: the unit sphere with 16,000 vertices at h = 0.01 (47 M entries, 2,945 per row), the
Stanford bunny at the automatic h = (2·mean edge)², and a 1,000,000-vertex sphere at
h = (mean edge)² (a few hundred entries per row). Times are wall clock with the process's
CPU time beside them; ratios come from the same process, so they hold on a busy machine
better than the absolute numbers. Peak memory is measured in a fresh subprocess per build
as the rise of the resident set's high-water mark (VmHWM, reset through
/proc/self/clear_refs) over the resident set before the build.

The first touch of never-used memory is slow on some virtual machines (up to 1 s per
400 MB); every build is repeated after a warm-up and the best time is kept.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import igl
import numpy as np
from results_file import RESULTS, write_section

import meshlap
from meshlap import shapes
from meshlap.baselines import bsw_scipy

HERE = Path(__file__).resolve().parent
BUNNY = HERE.parent / "tests" / "data" / "stanford-bunny.obj"


# -- meshes ------------------------------------------------------------------------------
def load(name: str) -> tuple[np.ndarray, np.ndarray, float | None, str]:
    """(V, F, h, description) for a benchmark mesh."""
    if name == "sphere16k":
        V, F = shapes.sphere(16_000, seed=0)
        return V, F, 0.01, "unit sphere, 16,000 vertices, h = 0.01"
    if name == "sphere2k":
        V, F = shapes.sphere(2_000, seed=0)
        return V, F, 0.01, "unit sphere, 2,000 vertices, h = 0.01"
    if name == "bunny":
        V, F = igl.read_triangle_mesh(str(BUNNY))
        return V, F.astype(np.int64), None, "Stanford bunny, automatic h = (2·mean edge)²"
    if name == "sphere1M":
        V, F = shapes.sphere(1_000_000, seed=0)
        h = meshlap.default_h(V, F) / 4  # sqrt(h) = mean edge
        return V, F, h, "unit sphere, 1,000,000 vertices, h = (mean edge)²"
    raise ValueError(name)


# -- measuring ----------------------------------------------------------------------------
def timed(fn, repeat: int = 1):
    """Best (wall, cpu) seconds over `repeat` calls, and the last result."""
    best, out = (math.inf, math.inf), None
    for _ in range(repeat):
        out = None  # free the previous result first: memory is part of what is measured
        t, c = time.perf_counter(), time.process_time()
        out = fn()
        best = min(best, (time.perf_counter() - t, time.process_time() - c))
    return best, out


def _status_kib(field: str) -> int:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    raise KeyError(field)


def child(name: str, which: str) -> None:
    """Run one build in this (fresh) process and print its peak memory rise as JSON."""
    import resource

    V, F, h, _ = load(name)
    small_V, small_F = shapes.sphere(500, seed=0)
    meshlap.laplacian(small_V, small_F, h=0.05, correction="none")  # load the compiled kernels
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")  # reset VmHWM to the current resident set
        before = _status_kib("VmRSS")
        reset = True
    except OSError:  # no procfs: ru_maxrss is monotonic, so this can overstate the peak
        before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        reset = False
    t0 = time.perf_counter()
    if which == "ours":
        op = meshlap.laplacian(V, F, h=h, correction="none").assemble()  # its matrix: on first use
        nbytes = op.nbytes
    else:
        op = bsw_scipy(V, F, h=h)
        nbytes = op.L.data.nbytes + op.L.indices.nbytes + op.L.indptr.nbytes
    seconds = time.perf_counter() - t0
    peak = _status_kib("VmHWM") if reset else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print(json.dumps({"peak_rise": (peak - before) * 1024, "csr_bytes": int(nbytes), "seconds": seconds,
                      "mesh_bytes": int(V.nbytes + F.nbytes)}))


def peak_memory(name: str, which: str) -> dict:
    out = subprocess.run([sys.executable, __file__, "--child", name, which], capture_output=True,
                         text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def spmv_time(L, f, repeat: int = 5) -> float:
    return timed(lambda: L @ f, repeat)[0][0]


# -- the cases ----------------------------------------------------------------------------
def bench_mesh(name: str, baseline: bool, repeat: int) -> dict:
    V, F, h, what = load(name)
    # warm-up: compiled kernels loaded, memory touched once
    meshlap.laplacian(V, F, h=h, correction="none").assemble()
    # with and without a progress callback, alternating so that both see the same load
    # Each build starts with the previous result freed, so both variants reuse the same memory.
    calls, t_prog, best, op = [], math.inf, (math.inf, math.inf), None
    for _ in range(repeat):
        op = None
        # the build: construction and the matrix, made on first use (assemble)
        (t, _), _ = timed(lambda: meshlap.laplacian(V, F, h=h, progress=lambda *a: calls.append(a),
                                                    correction="none").assemble())
        t_prog = min(t_prog, t)
        b, op = timed(lambda: meshlap.laplacian(V, F, h=h, correction="none").assemble())
        best = min(best, b)
    t_build, c_build = best
    f = np.cos(3 * op.V[:, 0]) + op.V[:, 1]
    t_spmv = spmv_time(op.L, f)
    row = {
        "name": name, "what": what, "n": op.n_vertices, "nnz": op.nnz, "h": op.h,
        "per_row": op.nnz / op.n_vertices, "mib": op.nbytes / 2**20,
        "build": t_build, "build_cpu": c_build, "spmv": t_spmv, "build_progress": t_prog,
        "progress_calls": len(calls) // repeat,
    }
    V64 = op.V
    (t_cot, _), _ = timed(lambda: igl.cotmatrix(V64, F), 2)
    row["cotmatrix"] = t_cot
    if baseline:
        (t_base, c_base), ref = timed(lambda: bsw_scipy(V, F, h=h), 1)
        row["baseline"], row["baseline_cpu"] = t_base, c_base
        diff = abs(ref.L - op.L).max() / abs(op.L).max()
        row["baseline_rel_diff"] = float(diff)
        del ref
    del op
    return row


def bench_large(name: str) -> dict:
    (t_mesh, _), (V, F, h, what) = timed(lambda: load(name))
    (t_build, c_build), op = timed(lambda: meshlap.laplacian(V, F, h=h, correction="none").assemble(), 2)
    f = np.cos(3 * op.V[:, 0]) + op.V[:, 1]
    t_spmv = spmv_time(op.L, f, 3)
    ref = op @ f
    nnz, nbytes, per_row = op.nnz, op.nbytes, op.nnz / op.n_vertices
    del op
    free = meshlap.laplacian(V, F, h=h, matrix_free=True, correction="none")
    (t_apply, c_apply), got = timed(lambda: free @ f, 2)
    (t_cot, _), _ = timed(lambda: igl.cotmatrix(free.V, F), 2)
    return {
        "name": name, "what": what, "n": len(V), "nnz": nnz, "h": h, "per_row": per_row,
        "mib": nbytes / 2**20, "build": t_build, "build_cpu": c_build, "spmv": t_spmv,
        "apply": t_apply, "apply_cpu": c_apply, "cotmatrix": t_cot, "mesh_seconds": t_mesh,
        "apply_rel_diff": float(np.abs(got - ref).max() / np.abs(ref).max()),
    }


# -- report -------------------------------------------------------------------------------
def table(rows: list[dict], mem: dict) -> list[str]:
    out = [
        "| mesh | vertices | entries (per row) | CSR | build (CPU) | scipy baseline | "
        "baseline / build | one SpMV | build / SpMV | peak memory / (CSR + mesh) | "
        "libigl cotmatrix |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        m = mem.get(r["name"])
        ratio_mem = f"{m['peak_rise'] / (m['csr_bytes'] + m['mesh_bytes']):.2f}" if m else "–"
        base = f"{r['baseline']:.2f} s" if "baseline" in r else "–"
        speedup = f"**{r['baseline'] / r['build']:.1f}×**" if "baseline" in r else "–"
        out.append(
            f"| {r['what']} | {r['n']:,} | {r['nnz'] / 1e6:.1f} M ({r['per_row']:,.0f}) | "
            f"{r['mib']:,.0f} MiB | {r['build']:.3f} s ({r['build_cpu']:.2f} s) | {base} | {speedup} | "
            f"{r['spmv'] * 1e3:.1f} ms | **{r['build'] / r['spmv']:.1f}×** | {ratio_mem} | "
            f"{r['cotmatrix']:.3f} s |"
        )
    return out


def default_vs_paper(n: int = 16000, repeat: int = 3, h_edges: float | None = None) -> dict:
    """The default against the paper's operator at the same h on a random n-vertex sphere, best
    of ``repeat`` each by CPU time (wall beside it; the variants alternate, so that a change of
    load falls on each), with the stages (wall and CPU seconds) timed through the progress
    callback. Both operators build their parts on first use (i20p): each is timed at
    construction alone, and with what a use reads: the first ``op @ f`` (the default's fitted
    rows; the paper's L, its pencil), ``op.L_sym`` (the default's symmetric pencil), or both.
    ``h_edges``: h = h_edges · ē² for both (ē the mean edge) instead of the default's own h; the
    warm-up is then a 2,000-vertex sphere, so that a large n is built only ``repeat`` times each."""
    import meshlap

    V, F = meshlap.shapes.sphere(n, kind="random", seed=0)
    if h_edges is None:
        h = meshlap.laplacian(V, F).assemble().fit_rows().h  # also the warm-up
        meshlap.laplacian(V, F, h=h, correction="none").assemble()
    else:
        h = h_edges * float(igl.edge_lengths(V, F).mean()) ** 2
        small = meshlap.shapes.sphere(2000, kind="random", seed=0)
        meshlap.laplacian(*small, h=h * n / 2000).assemble().fit_rows()  # compiles what the builds below run
        meshlap.laplacian(*small, h=h * n / 2000, correction="none").assemble()
    out = {"n": n, "h": h, "h_edges": h_edges, "repeat": repeat}
    # the kernel's compiled code loaded before its timed builds
    meshlap.laplacian(*meshlap.shapes.sphere(2000, kind="random", seed=0), operator="kernel").assemble()
    default_kw = {} if h_edges is None else {"h": h}
    paper_kw = {"h": h, "correction": "none"}
    # a zonal function g(x) on the unit sphere: Δ g = (1 − x²) g'' − 2x g' (not a polynomial,
    # which the fitted rows would reproduce exactly)
    x = V[:, 0]
    f, lap = np.exp(x), (1 - x**2 - 2 * x) * np.exp(x)
    uses = {"": lambda op: None, " + first op @ f": lambda op: op @ f, " + L_sym": lambda op: op.L_sym,
            " + both": lambda op: (op @ f, op.L_sym)}
    variants = [("paper", paper_kw, ""), ("paper + first op @ f", paper_kw, " + first op @ f"),
                *((f"default{use}", default_kw, use) for use in uses),
                # the corrected kernel, a named builder (its options: bench_accuracy.py's last table)
                ("kernel + both", {"h": h, "operator": "kernel"}, " + both")]
    for _ in range(repeat):
        for name, kw, use in variants:
            marks = []

            def note(fraction, stage, marks=marks):
                marks.append((stage, time.perf_counter(), time.process_time()))

            t, c = time.perf_counter(), time.process_time()
            op = meshlap.laplacian(V, F, progress=note, **kw)
            uses[use](op)
            wall, cpu = time.perf_counter() - t, time.process_time() - c
            # the CPU ratio is the steadier figure on a shared machine: the best run by CPU
            if name not in out or cpu < out[name][1]:
                stages = {}  # stage: (wall, CPU) seconds, from its mark to the next
                ends = marks[1:] + [("end", t + wall, c + cpu)]
                for (stage, a, ca), (_, b, cb) in zip(marks, ends, strict=True):
                    w0, c0 = stages.get(stage, (0.0, 0.0))
                    stages[stage] = (w0 + b - a, c0 + cb - ca)
                # measured after the timing (builds what the variant did not)
                err = float(np.linalg.norm(op @ f - lap) / np.linalg.norm(lap))
                out[name] = (wall, cpu, stages, op.nnz, err)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small meshes only; writes nothing")
    ap.add_argument("--no-write", action="store_true", help="print only")
    ap.add_argument("--default-vs-paper", action="store_true",
                    help="only the default build against the paper's (random 16k sphere)")
    ap.add_argument("--n", type=int, default=16000, help="--default-vs-paper: vertices")
    ap.add_argument("--h-edges", type=float, default=None,
                    help="--default-vs-paper: h = this times the squared mean edge (default: the default's)")
    ap.add_argument("--repeat", type=int, default=3, help="--default-vs-paper: builds of each")
    ap.add_argument("--child", nargs=2, metavar=("MESH", "WHICH"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(*args.child)
        return
    if args.default_vs_paper:
        write_default_vs_paper(default_vs_paper(args.n, args.repeat, args.h_edges),
                               args.no_write or args.n != 16000 or args.h_edges is not None)
        return
    import numba

    names = ["sphere2k"] if args.quick else ["sphere16k", "bunny"]
    rows, mem, base_mem = [], {}, {}
    for name in names:
        rows.append(bench_mesh(name, baseline=True, repeat=3))
        mem[name] = peak_memory(name, "ours")
        base_mem[name] = peak_memory(name, "scipy")
        r, m, b = rows[-1], mem[name], base_mem[name]
        print(f"{name}: {r['nnz']:,} entries ({r['per_row']:.0f}/row); build {r['build']:.3f} s "
              f"(cpu {r['build_cpu']:.2f} s), baseline {r['baseline']:.2f} s -> "
              f"{r['baseline'] / r['build']:.1f}x faster; SpMV {r['spmv'] * 1e3:.1f} ms -> build = "
              f"{r['build'] / r['spmv']:.1f} SpMV; peak memory {m['peak_rise'] / 2**20:.0f} MiB = "
              f"{m['peak_rise'] / (m['csr_bytes'] + m['mesh_bytes']):.2f} x (CSR + mesh), "
              f"baseline {b['peak_rise'] / 2**20:.0f} MiB; cotmatrix {r['cotmatrix']:.3f} s; "
              f"max |baseline - ours| / max|L| = {r['baseline_rel_diff']:.1e}; with a progress "
              f"callback ({r['progress_calls']} calls) {r['build_progress']:.3f} s", flush=True)
    large = None
    if not args.quick:
        large = bench_large("sphere1M")
        print(f"sphere1M: mesh {large['mesh_seconds']:.1f} s; {large['nnz']:,} entries "
              f"({large['per_row']:.0f}/row, {large['mib']:,.0f} MiB); build {large['build']:.2f} s "
              f"(cpu {large['build_cpu']:.2f} s); SpMV {large['spmv']:.3f} s; matrix-free apply "
              f"{large['apply']:.2f} s (cpu {large['apply_cpu']:.2f} s, rel. diff "
              f"{large['apply_rel_diff']:.1e}); cotmatrix {large['cotmatrix']:.3f} s", flush=True)
        mem["sphere1M"] = peak_memory("sphere1M", "ours")
        m = mem["sphere1M"]
        print(f"sphere1M: peak memory {m['peak_rise'] / 2**20:,.0f} MiB = "
              f"{m['peak_rise'] / (m['csr_bytes'] + m['mesh_bytes']):.2f} x (CSR + mesh)", flush=True)
    if args.quick or args.no_write:
        return
    lines = [
        "Command: `python benchmarks/bench_assembly.py` "
        f"({numba.get_num_threads()} threads, {os.cpu_count()} CPUs, numba {numba.__version__}; "
        f"written {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}).",
        "",
        "Build = `meshlap.laplacian(V, F, h)` end to end (validation, masses, grid, count and fill "
        "passes), best of 3 after a warm-up, wall clock with CPU time in parentheses. Baseline = "
        "`meshlap.baselines.bsw_scipy` (cKDTree.sparse_distance_matrix → COO → CSR). SpMV = one "
        "`L @ f` with scipy. Peak memory = rise of the peak resident set during one build in a "
        "fresh process. Ratios are measured in the same run.",
        "",
        *table(rows + ([large] if large else []), mem),
        "",
        "Peak memory of the scipy baseline build: "
        + ", ".join(f"{n} {b['peak_rise'] / 2**20:,.0f} MiB "
                    f"({b['peak_rise'] / (b['csr_bytes'] + b['mesh_bytes']):.1f} × its CSR + mesh)"
                    for n, b in base_mem.items()) + ".",
    ]
    lines += [
        "",
        "First build in a fresh process (the peak-memory run, whose arrays land on pages the "
        "process has never touched; this virtual machine's page faults cost up to 1 s per 400 MB): "
        + ", ".join(f"{n} {m['seconds']:.2f} s" for n, m in mem.items() if "seconds" in m)
        + ". The table's build times reuse memory freed by the previous build, as repeated "
        "builds in one session do.",
    ]
    lines += [
        "",
        "Progress reporting: the same builds with a progress callback take "
        + ", ".join(f"{r['name']} {r['build_progress']:.3f} s ({r['progress_calls']} calls; "
                    f"{r['build_progress'] / r['build']:.2f} × the build without)" for r in rows) + ".",
    ]
    if large:
        lines += [
            "",
            f"1,000,000 vertices: the mesh (Fibonacci points, scipy ConvexHull) takes "
            f"{large['mesh_seconds']:.1f} s; the stored build {large['build']:.2f} s for "
            f"{large['nnz'] / 1e6:.0f} M entries; one SpMV {large['spmv']:.3f} s; the matrix-free "
            f"operator applies L in {large['apply']:.2f} s (CPU {large['apply_cpu']:.2f} s) without "
            f"storing it, equal to the stored product to {large['apply_rel_diff']:.0e} (relative).",
        ]
    write_section("Assembly", lines)
    print(f"wrote the Assembly section of {RESULTS}")


#: Below this line the section is written by hand (before/after runs against another commit,
#: per-stage timings); --default-vs-paper rewrites the table above it and keeps the rest.
HAND_WRITTEN = "<!-- written by hand below this line; --default-vs-paper keeps it -->"


def _kept_notes(title: str) -> list[str]:
    # the hand-written part of the subsection ``### title``, from its marker to the next heading
    text = RESULTS.read_text() if RESULTS.exists() else ""
    start = text.find(f"### {title}\n")
    ends = [e for e in (text.find("\n### ", start + 1), text.find("\n## ", start + 1)) if e >= 0]
    section = text[start:min(ends, default=len(text))] if start >= 0 else ""
    if HAND_WRITTEN not in section:
        return []
    return ["", HAND_WRITTEN, "", *section.split(HAND_WRITTEN, 1)[1].strip("\n").splitlines()]


def write_default_vs_paper(r: dict, no_write: bool) -> None:
    (pw, pc), (qw, qc) = r["paper"][:2], r["paper + first op @ f"][:2]
    names = [k for k in r if isinstance(r[k], tuple) and k != "paper"]
    # the stages of the default's construction and both uses ("done" after each part)
    parts = ", ".join(f"{k} {w:.3f} s ({c:.2f} s)" for k, (w, c) in r["default + both"][2].items()
                      if k != "done")
    at = "" if r["h_edges"] is None else f" ({r['h_edges']:g} ē²)"
    print(f"random sphere {r['n']:,}, h = {r['h']:.4g}{at}, best of {r['repeat']} by CPU; the paper's "
          f"construction {pw:.3f} s (CPU {pc:.2f} s), + first op @ f (its pencil) {qw:.3f} s "
          f"(CPU {qc:.2f} s, {r['paper'][3]:,} entries); against the latter:", flush=True)
    for name in names:
        w, c, _, nnz, err = r[name]
        print(f"  {name}: {w:.3f} s (CPU {c:.2f} s): {w / qw:.2f}x wall, {c / qc:.2f}x CPU; "
              f"op @ exp(x) error {err:.2e}", flush=True)
    print(f"  stages of the default + both, wall (CPU): {parts}", flush=True)
    if no_write:
        return
    title = "Default build against the paper's operator"
    rows = [f"| {name.replace('op @ f', '`op @ f`').replace('L_sym', '`op.L_sym`')} | {w:.3f} s ({c:.2f} s) "
            f"| {nnz:,} | {'**' if name.startswith('default +') else ''}{w / qw:.2f}×"
            f"{'**' if name.startswith('default +') else ''} | {c / qc:.2f}× | {err:.2e} |"
            for name, (w, c, _, nnz, err) in ((k, r[k]) for k in names)]
    write_section(title, [
        "Command: `python benchmarks/bench_assembly.py --default-vs-paper` (written "
        f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}).",
        "",
        f"`meshlap.shapes.sphere({r['n']}, kind='random', seed=0)`; the default `meshlap.laplacian(V, F)` "
        f"(h = {r['h']:.4g}) against the paper's `meshlap.laplacian(V, F, h=h, correction='none')`, "
        f"best of {r['repeat']} each (by CPU time) after a warm-up, alternating in the same process; the "
        "stages timed by the progress callback. Both build their parts on first use: the default its "
        "fitted rows at the first `op @ f` (`op.L`) and its symmetric pencil at the first `op.L_sym` "
        "(`op.S`, spectra, heat flow, smoothing; `op.assemble()`); the paper's operator its one matrix "
        "at either. Each row is the construction and the uses named, against the paper's construction "
        f"and first `op @ f` ({qw:.3f} s, {qc:.2f} s CPU; its construction alone {pw:.3f} s, {pc:.2f} s). "
        "The last row is the corrected kernel (`operator=\"kernel\"`, same h) with both uses. Error: "
        "relative L2 error of `op @ f` against the exact Δ eˣ = (1 − x² − 2x) eˣ on the unit sphere.",
        "",
        "| construction + use | time (CPU) | entries | / paper's, wall | / paper's, CPU "
        "| `op @ f` error, f = eˣ |",
        "|---|---|---|---|---|---|",
        *rows,
        "",
        f"The default's stages, construction + first `op @ f` + `op.L_sym`, wall (CPU): {parts}.",
        *_kept_notes(title),
    ])


if __name__ == "__main__":
    main()
